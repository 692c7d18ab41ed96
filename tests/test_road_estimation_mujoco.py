"""Road-profile estimation on the MuJoCo SUV: the filter's quarter car, the truth, the road file.

Independent references: the corner's parameters read straight from the parameter file; the
truth against the road generator's profile at the wheel's x; the rebuilt wheel position
against the run's recorded enveloped road height; the high-pass against sines; the road
file through `suvtwin classify`'s reader and the CLI.
"""

import json
import tomllib

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.mjcf.kernel import H_NCOL, H_NROW, _envelope
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import PARAMETER_FILE, load_vehicle
from suvtwin.pipeline.cli import main
from suvtwin.pipeline.road_estimation import (
    corner_quarter_car,
    estimate_corner_road,
    highpass,
    road_from_tracks,
    road_under_wheel,
    wheel_path,
)
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import prepare, simulate, write_run
from suvtwin.roads.iso8608 import class_level
from suvtwin.roads.profile import generate_road, read_road

VEHICLE = load_vehicle()
TIRE = load_tire(VEHICLE.tire_file)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    scenario = parse_scenario({
        "duration_s": 6.0, "seed": 3, "speed_kmh": 40.0,
        "road": {"segments": [{"length_m": 110.0, "road_class": "C"}]},
        "noise": {"accel_sprung_mps2": 0.02, "accel_unsprung_mps2": 0.02},
    })
    result = simulate(scenario)
    path = tmp_path_factory.mktemp("run") / "run.parquet"
    write_run(result, path)
    return scenario, result.table, path


def test_corner_quarter_car_is_the_parameter_file_corner():
    with open(PARAMETER_FILE, "rb") as handle:
        p = tomllib.load(handle)
    m, a1, a2 = (p["chassis"][k]["value"] for k in ("mass", "a1", "a2"))
    car, sources = corner_quarter_car(VEHICLE, TIRE, corner="fl", pressure_pa=TIRE.nominal_pressure)
    assert car.sprung_mass == pytest.approx(0.5 * m * a2 / (a1 + a2))
    assert car.unsprung_mass == p["wheel"]["unsprung_mass_front"]["value"]
    assert car.suspension_stiffness == p["suspension"]["spring_rate_front"]["value"]
    assert car.damping == pytest.approx(0.5 * (p["suspension"]["damper_compression_low"]["value"]
                                               + p["suspension"]["damper_rebound_low"]["value"]))
    assert car.tire_stiffness == pytest.approx(TIRE.vertical_stiffness_nominal)  # kt(p0) = kt0
    rear, _ = corner_quarter_car(VEHICLE, TIRE, corner="rr", pressure_pa=TIRE.nominal_pressure)
    assert rear.sprung_mass == pytest.approx(0.5 * m * a1 / (a1 + a2))
    lower, _ = corner_quarter_car(VEHICLE, TIRE, corner="fl", pressure_pa=0.8 * TIRE.nominal_pressure)
    assert lower.tire_stiffness < car.tire_stiffness
    assert set(sources) == {"sprung_mass_kg", "unsprung_mass_kg", "suspension_stiffness_npm", "damping_nspm",
                            "tire_stiffness_npm"}


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"corner": "xx", "pressure_pa": 250e3}, "corner must be one of"),
    ({"corner": "fl", "pressure_pa": 10e3}, "pressure_pa must be in"),
])
def test_corner_quarter_car_bad_input(kwargs, message):
    with pytest.raises(InputError, match=message):
        corner_quarter_car(VEHICLE, TIRE, **kwargs)


def test_truth_is_the_generated_road_at_the_wheel(run):
    scenario, table, _ = run
    truth = road_under_wheel(scenario, table, corner="fl")
    road = generate_road(scenario.road, seed=scenario.road_seed())
    # lane keeping at y = 0: the left wheel runs on the left track's plateau of the heightfield
    assert np.all(np.abs(truth.y - VEHICLE.chassis.track_front / 2) < 0.05)
    np.testing.assert_allclose(truth.raw, road.height(truth.x, 0), atol=1e-6)
    assert np.all(np.diff(truth.x) > 0) and truth.x[-1] - truth.x[0] == pytest.approx(
        40 / 3.6 * (truth.t[-1] - truth.t[0]), rel=0.02)
    # the enveloped truth is the run's record; close to, but smoother than, the raw one
    np.testing.assert_array_equal(truth.enveloped, table["fl_road_z_m"])
    assert np.std(truth.enveloped - truth.raw) < 0.1 * np.std(truth.raw)
    assert np.std(np.diff(truth.enveloped, 2)) < np.std(np.diff(truth.raw, 2))


def test_rebuilt_wheel_position_reproduces_the_recorded_envelope(run):
    scenario, table, _ = run
    x, y = wheel_path(table, VEHICLE, corner="fl")
    prep = prepare(scenario)
    hf = prep.vm.hfield
    hdata = np.asarray(prep.vm.model.hfield_data, dtype=float).reshape(int(hf[H_NROW]), int(hf[H_NCOL]))
    yaw = np.asarray(table["yaw_rad"])
    half, n = VEHICLE.tire.envelope_half_length, VEHICLE.tire.envelope_points
    z = np.array([_envelope(x[k], y[k], np.cos(yaw[k]), np.sin(yaw[k]), half, n, hf, hdata)[0]
                  for k in range(0, x.size, 10)])
    recorded = np.asarray(table["fl_road_z_m"])[::10]
    assert np.max(np.abs(z - recorded)) < 2e-4  # pitch and steer left out: sub-mm
    assert np.std(z - recorded) < 0.01 * np.std(recorded)


def test_filters_run_on_the_suv(run):
    scenario, table, _ = run
    car, _ = corner_quarter_car(VEHICLE, TIRE, corner="fl", pressure_pa=250e3)
    truth = road_under_wheel(scenario, table, corner="fl")
    tab = table.iloc[2000:].reset_index(drop=True)
    kf = estimate_corner_road(tab, car, gd_n0=class_level("C"), measurement_std=0.02,
                              initial_road_m=truth.raw[2000])
    assert kf.weight is None and kf.road.shape == (len(tab),) and np.all(np.isfinite(kf.road))
    assert kf.road[0] == truth.raw[2000]  # known start, eq. 10
    mme = estimate_corner_road(tab, car, gd_n0=class_level("C"), measurement_std=0.02, filter_name="MME&KF")
    assert 1e-8 <= mme.weight <= 1e12 and np.all(np.isfinite(mme.road))
    with pytest.raises(InputError, match="filter must be one of"):
        estimate_corner_road(tab, car, gd_n0=class_level("C"), measurement_std=0.02, filter_name="UKF")
    with pytest.raises(InputError, match="measurement_std"):
        estimate_corner_road(tab, car, gd_n0=class_level("C"), measurement_std=-1.0)


def test_highpass_removes_slow_and_keeps_fast_content():
    dt = 1e-3
    t = np.arange(20000) * dt
    slow, fast = np.sin(2 * np.pi * 0.05 * t), np.sin(2 * np.pi * 5.0 * t)
    out = highpass(slow + fast, dt=dt, cutoff_hz=0.5)
    inner = slice(5000, 15000)
    np.testing.assert_allclose(out[inner], fast[inner], atol=2e-3)
    with pytest.raises(InputError, match="cutoff_hz"):
        highpass(slow, dt=dt, cutoff_hz=600.0)


def test_road_from_tracks_resamples_onto_the_common_stretch():
    xl = np.linspace(0.0, 20.0, 401)
    xr = np.linspace(1.0, 22.0, 301)
    road = road_from_tracks(xl, 0.01 * xl, xr, -0.02 * xr, spacing_m=0.05)
    assert road.x[0] == 1.0 and road.x[-1] == pytest.approx(20.0) and road.spacing_m == pytest.approx(0.05)
    np.testing.assert_allclose(road.z[0], 0.01 * road.x, atol=1e-12)
    np.testing.assert_allclose(road.z[1], -0.02 * road.x, atol=1e-12)
    with pytest.raises(InputError, match="must increase"):
        road_from_tracks(xl[::-1], xl, xr, xr, spacing_m=0.05)


def test_cli_road_estimate_writes_a_road_that_classify_reads(run, tmp_path, capsys):
    _, table, path = run
    out = tmp_path / "est.parquet"
    assert main(["road-estimate", str(path), "--out", str(out), "--class", "C"]) == 0
    road = read_road(out)  # the reader of `suvtwin classify`
    x_left, _ = wheel_path(table, VEHICLE, corner="fl")
    assert road.spacing_m == pytest.approx(0.05)
    assert x_left[2000] - 1e-9 <= road.x[0] and road.x[-1] <= x_left[-1] + 1e-9
    assert np.all(np.isfinite(road.z)) and np.std(road.z[0]) > 0 and np.std(road.z[1]) > 0
    # the left track is the KF's estimate under the front-left wheel, resampled at the wheel's x
    car, _ = corner_quarter_car(VEHICLE, TIRE, corner="fl", pressure_pa=250e3)
    tab = table[table["t_s"] >= table["t_s"][0] + 2.0 - 1e-9].reset_index(drop=True)
    est = estimate_corner_road(tab, car, gd_n0=class_level("C"), measurement_std=0.02)
    np.testing.assert_allclose(road.z[0], np.interp(road.x, x_left[2000:], est.road), atol=1e-12)
    capsys.readouterr()
    assert main(["classify", str(out), "--json", "--band-low", "0.1"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["left"]["class"] in "ABCDEFGH" and result["right"]["class"] in "ABCDEFGH"


@pytest.mark.parametrize(("extra", "message"), [
    (["--class", "Z"], "--class must be one of A–H"),
    (["--filter", "UKF"], "--filter must be one of"),
    (["--measurement-std", "0"], "--measurement-std"),
    (["--axle", "middle"], "--axle must be front or rear"),
    (["--skip", "100"], "skip_s"),
])
def test_cli_road_estimate_bad_input_exits_2_and_writes_nothing(run, tmp_path, capsys, extra, message):
    _, _, path = run
    out = tmp_path / "est.parquet"
    assert main(["road-estimate", str(path), "--out", str(out), *extra]) == 2
    assert message.lower() in capsys.readouterr().err.lower()
    assert not out.exists()


# --- the study, the report section and the campaign --------------------------------------------


@pytest.fixture(scope="module")
def small_study():
    from suvtwin.pipeline.road_estimation import mujoco_study

    return mujoco_study([0], classes=("C",), mass_changes=(0.0,))


def test_study_scores_one_cell_against_its_own_truth(small_study):
    from suvtwin.estimators.road_estimation import error_std_percent

    (row,) = small_study["table"]
    assert row["class"] == "C" and row["paper"] == {"KF": 8.1, "MME&KF": 4.6}
    for key in ("KF|known|raw", "KF|known|enveloped", "KF|known|raw_hp", "MME&KF|known|raw"):
        assert np.isfinite(row[key]["mean"]) and row[key]["std"] == 0.0
    assert "KF|unknown|raw" not in row and "quarter_car|KF|known|raw" not in row  # variants off
    assert row["front_left_delta_m_kg"]["mean"] == 0.0
    ex = small_study["example"]
    assert len(ex["x_m"]) == len(ex["raw_m"]) == len(ex["KF_m"]) == len(ex["MME&KF_m"]) == 1000
    # the example's KF error (every 10th sample) is the cell's error within sampling
    err = error_std_percent(np.asarray(ex["raw_m"]), np.asarray(ex["KF_m"]))
    assert err == pytest.approx(row["KF|known|raw"]["mean"], rel=0.05)


def test_report_section_shows_the_papers_table_beside_ours(small_study, tmp_path):
    from suvtwin.pipeline.report.page import _road_estimation_html

    text = "\n".join(_road_estimation_html(json.loads(json.dumps(small_study))))
    assert "Wang et al. 2017" in text and "<table>" in text and "data:image/png;base64," in text
    row = small_study["table"][0]
    assert f"{row['KF|known|raw']['mean']:.1f} ± 0.0" in text and ">8.1<" in text and ">4.6<" in text
    assert " / ".join("".join(row["classes"][k]) for k in ("truth", "KF", "MME&KF")) in text


def test_campaign_runs_the_study_on_request_and_caches_it(tmp_path, monkeypatch):
    import suvtwin.pipeline.road_estimation as module
    from suvtwin.pipeline.campaign import preset
    from suvtwin.pipeline.campaign.execution import _road_estimation_study

    assert preset("full").road_estimation_seeds == 3 and preset("quick").road_estimation_seeds == 0
    assert _road_estimation_study(preset("quick"), tmp_path) == (None, False)
    calls = []

    def stand_in(seeds, **_):
        calls.append(list(seeds))
        return {"settings": {"seeds": list(seeds)}, "table": [], "example": None, "x": np.float64(1.5)}

    monkeypatch.setattr(module, "mujoco_study", stand_in)
    config = preset("quick", road_estimation_seeds=2)
    study, made = _road_estimation_study(config, tmp_path)
    assert made and calls == [[0, 1]] and study["x"] == 1.5
    study2, made2 = _road_estimation_study(config, tmp_path)
    assert not made2 and study2 == study and len(calls) == 1
    with pytest.raises(InputError, match="road_estimation_seeds"):
        preset("quick", road_estimation_seeds=-1)
