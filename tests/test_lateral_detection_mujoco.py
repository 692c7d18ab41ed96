"""Solmaz's detector on the MuJoCo SUV: the ISO 3888-1 driver, the vehicle mapping, the signals,
the bank's fit, the sensitivity tyre, the CLI, the report section and the campaign setting."""

import json
import math

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.lateral_detection import GRAVITY, lateral_tire_force
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.cli import main
from suvtwin.pipeline.lateral_detection import (
    SENSITIVITY_TIRE,
    case_tire_file,
    cornering_stiffness_table,
    detection_delay,
    detector_signals,
    fit_arctan_tire,
    lane_change_scenario,
    steering_onset,
    truth_model,
    two_track_vehicle,
)
from suvtwin.pipeline.scenario import ISO3888_SECTIONS_M, iso3888_centreline, parse_scenario
from suvtwin.pipeline.simulator import simulate, write_run
from suvtwin.tir import read_tir

# --- the driver's path -------------------------------------------------------------------------


def test_iso3888_centreline_sections():
    x = np.linspace(0.0, 200.0, 8001)
    y = iso3888_centreline(x, start_m=20.0, offset_m=3.5, sign=1.0)
    l1, l2, l3, l4, l5, l6 = ISO3888_SECTIONS_M
    assert (l1, l2, l3, l4, l5 + l6) == (15.0, 30.0, 25.0, 25.0, 30.0)
    assert np.all(y[x <= 20.0 + l1] == 0.0)  # section 1
    in3 = (x >= 20 + l1 + l2) & (x <= 20 + l1 + l2 + l3)
    assert np.allclose(y[in3], 3.5)  # section 3
    assert np.all(y[x >= 20 + l1 + l2 + l3 + l4] == 0.0)  # sections 5-6
    slope = np.gradient(y, x)
    assert np.max(np.abs(np.diff(slope))) < 1e-3  # smooth: no kink
    right = iso3888_centreline(x, start_m=20.0, offset_m=3.5, sign=-1.0)
    assert np.allclose(right, -y)


@pytest.mark.parametrize(
    ("steering", "message"),
    [
        ({"mode": "path"}, "at least 2 points"),
        ({"mode": "path", "path": [[0, 0], [0, 1]]}, "strictly increasing"),
        ({"mode": "path", "path": [[0, 0], [1, 1]]}, "slope"),
        ({"mode": "path", "path": [[0, 0], [100, 60]]}, "±50 m"),
        ({"mode": "iso3888", "iso3888_offset_m": 0}, "steering.iso3888_offset_m"),
        ({"mode": "iso3888", "iso3888_start_m": -1}, "steering.iso3888_start_m"),
        ({"mode": "weave"}, "steering.mode"),
    ],
)
def test_bad_path_settings_name_the_field(steering, message):
    with pytest.raises(InputError, match="steering") as info:
        parse_scenario({"duration_s": 1.0, "road": "flat", "steering": steering})
    assert message in str(info.value)


def test_path_mode_follows_a_tabulated_path():
    path = [[0.0, 0.0], [20.0, 0.0], [60.0, 1.5], [200.0, 1.5]]
    sc = parse_scenario({"duration_s": 8.0, "speed_kmh": 60, "road": "flat", "output_rate_hz": 100,
                         "steering": {"mode": "path", "path": path, "lane_y_m": 0.5}})  # fmt: skip
    cols = simulate(sc).columns
    assert abs(cols["y_m"][-1] - 2.0) < 0.05  # lane_y_m + the path's end
    assert np.max(np.abs(cols["y_m"])) < 2.2 and cols["steer_rad"].max() > 0.005


@pytest.fixture(scope="module")
def lane_change(tmp_path_factory):
    """A 100 km/h ISO 3888-1 lane change to the left, front-right tyre at 150 kPa, 100 kg in the boot."""
    sc = lane_change_scenario(speed_kmh=100.0, pressure_kpa={"fl": 250, "fr": 150, "rl": 250, "rr": 250},
                              load_kg=100.0, load_position_m=(-1.5, 0.0, 0.0))  # fmt: skip
    result = simulate(sc)
    path = tmp_path_factory.mktemp("run") / "dlc.parquet"
    write_run(result, path)
    return sc, result, path


def test_the_lane_change_is_driven_through(lane_change):
    sc, result, _ = lane_change
    cols = result.columns
    x = cols["x_m"] - cols["x_m"][0]
    px, py = sc.steering.reference_path()
    assert np.max(cols["y_m"]) > 2.5 and abs(cols["y_m"][-1]) < 0.3  # out to the offset lane and back
    assert np.max(np.abs(cols["y_m"] - np.interp(x, px, py))) < 3.0  # pure pursuit cuts the corners
    assert abs(np.mean(cols["speed_mps"]) * 3.6 - 100.0) < 1.0
    assert 3.0 < np.max(np.abs(cols["lat_accel_mps2"])) < 8.0


# --- mapping, signals, truth -------------------------------------------------------------------


def test_two_track_vehicle_from_the_parameter_file():
    v = load_vehicle()
    car = two_track_vehicle()
    assert car.mass == pytest.approx(v.total_mass)
    assert car.wheelbase == pytest.approx(v.wheelbase)
    assert car.track == pytest.approx(0.5 * (v.chassis.track_front + v.chassis.track_rear))
    assert car.cog_height < v.chassis.cog_height  # unsprung masses sit lower
    assert car.yaw_inertia == pytest.approx(v.chassis.inertia_yaw_total, rel=1e-3)
    loaded = two_track_vehicle(lane_change_scenario(speed_kmh=90, load_kg=200, load_position_m=(-1.5, 0, 0)))
    assert loaded.mass == pytest.approx(v.total_mass + 200)
    assert loaded.rear_length < car.rear_length and loaded.yaw_inertia > car.yaw_inertia
    # the centre of gravity moves towards the load: x_new = (M x_old + 200 kg · (-1.5 m)) / (M + 200 kg)
    x_old = car.rear_length - v.chassis.a2
    x_new = (car.mass * x_old - 200 * 1.5) / loaded.mass
    assert loaded.rear_length == pytest.approx(v.chassis.a2 + x_new)


def test_signals_add_rolls_gravity_component_for_a_body_fixed_sensor():
    n = 50
    table = pd.DataFrame({"t_s": np.arange(n) * 0.01, "speed_mps": np.full(n, 25.0),
                          "lat_accel_mps2": np.full(n, 4.0), "roll_rad": np.full(n, 0.04),
                          "yaw_rate_radps": np.full(n, 0.1), "steer_rad": np.full(n, 0.01),
                          "x_m": 25.0 * np.arange(n) * 0.01, "y_m": np.zeros(n),
                          "yaw_rad": np.zeros(n)})  # fmt: skip
    body = detector_signals(table, accel="body")
    flat = detector_signals(table, accel="horizontal")
    assert body["lateral_acceleration"] == pytest.approx(4.0 * math.cos(0.04) + GRAVITY * math.sin(0.04))
    assert flat["lateral_acceleration"] == pytest.approx(4.0)
    assert body["dt"] == pytest.approx(0.01) and np.allclose(body["true_sideslip"], 0.0)
    noisy = detector_signals(table, accel="horizontal", noise=(0.05, 0.003), seed=3)
    assert 0.02 < np.std(noisy["lateral_acceleration"]) < 0.08
    with pytest.raises(InputError, match="accel"):
        detector_signals(table, accel="world")
    with pytest.raises(InputError, match="lat_accel_mps2"):
        detector_signals(table.drop(columns="lat_accel_mps2"))


def test_truth_onset_and_delay():
    pressures = {"fl": 250, "fr": 160, "rl": 250, "rr": 130}
    table = pd.DataFrame({f"{c}_pressure_kpa": [p] * 3 for c, p in pressures.items()})
    assert truth_model(table) == 4 + 1  # FR and RR
    steer = np.r_[np.zeros(100), np.linspace(0, 0.02, 100), np.zeros(50)]
    assert steering_onset(steer, 0.01) == pytest.approx(1.1, abs=0.011)
    sel = np.r_[np.full(150, 16), np.full(20, 8), np.full(10, 4), np.full(70, 8)]
    assert detection_delay(sel, 8, 0.01, 1.0) == pytest.approx(0.8)
    assert math.isnan(detection_delay(sel, 4, 0.01, 1.0))


# --- the bank's tyres ----------------------------------------------------------------------------


def test_the_arctan_fit_recovers_known_parameters():
    rng = np.random.default_rng(1)
    fz = rng.uniform(2500, 7000, 2000)
    alpha = rng.uniform(-0.06, 0.06, 2000)
    s = lateral_tire_force(alpha, fz, np.array([1.3, 12000.0, 14.0]))
    tire, info = fit_arctan_tire(fz, alpha, s)
    assert (tire.k1, tire.k2, tire.k3) == pytest.approx((1.3, 12000.0, 14.0), rel=1e-4)
    assert info["rms_n"] < 1e-3 and info["samples"] == 2000
    with pytest.raises(InputError, match="at least 10"):
        fit_arctan_tire(fz[:5], alpha[:5], s[:5])


def _mf_cornering_stiffness(tir, fz, pressure_pa):
    """MF 6.1 eq. 4.E25 evaluated from the .tir's values, independently of suvtwin.mjcf.tire."""
    where = {"FNOMIN": "VERTICAL", "NOMPRES": "OPERATING_CONDITIONS"}
    v = {k: tir.number(where.get(k, "LATERAL_COEFFICIENTS"), k)
         for k in ("FNOMIN", "NOMPRES", "PKY1", "PKY2", "PKY4", "PPY1", "PPY2")}  # fmt: skip
    fz0, p0 = v["FNOMIN"], v["NOMPRES"]
    dpi = (pressure_pa - p0) / p0
    return (
        abs(v["PKY1"])
        * fz0
        * (1 + v["PPY1"] * dpi)
        * np.sin(v["PKY4"] * np.arctan(fz / (v["PKY2"] * (1 + v["PPY2"] * dpi) * fz0)))
    )


def test_sensitivity_tyre_softens_at_low_pressure_and_the_shipped_one_stiffens():
    table = cornering_stiffness_table()
    shipped, softer = table["shipped"], table["softer_deflated"]
    assert all(15.0 < c < 30.0 for c in shipped["change_percent"])  # PPY1 < 0: stiffer when deflated
    assert softer["change_percent"] == pytest.approx([-20.0] * 3, abs=0.3)  # the premise's tyre
    for case, t in table.items():
        tir = read_tir(case_tire_file(case) or load_vehicle().tire_file)
        for fz, k in zip(t["loads_n"], t["stiffness_n_per_rad"], strict=True):
            for p, kp in zip(t["pressures_kpa"], k, strict=True):
                assert kp == pytest.approx(_mf_cornering_stiffness(tir, fz, p * 1e3), rel=2e-3)
    # only PPY1 and PPY2 differ between the two files
    a, b = read_tir(load_vehicle().tire_file), read_tir(case_tire_file("softer_deflated"))
    differ = {k for sec in a.sections for k in a.sections[sec] if a.text(sec, k) != b.text(sec, k)}
    assert differ == {"PPY1", "PPY2"} and case_tire_file("softer_deflated").endswith(SENSITIVITY_TIRE)


# --- CLI, report, campaign -----------------------------------------------------------------------


def test_cli_writes_the_selected_model_over_time(lane_change, tmp_path, capsys):
    _, result, run = lane_change
    out = tmp_path / "det.parquet"
    assert main(["lateral-detect", str(run), "--out", str(out), "--accel", "horizontal", "--seed", "2"]) == 0
    text = capsys.readouterr().out
    assert "final pick: model" in text and "truth: model 4 (FR)" in text
    table = pq.read_table(out)
    names = table.column_names
    assert names[:2] == ["t_s", "selected"] and "cost_model_16" in names and "stiffness_rr_npr" in names
    assert table.num_rows == result.n_samples
    meta = json.loads(table.schema.metadata[b"suvtwin.lateral_detection"])
    assert meta["truth"] == 4 and meta["accel"] == "horizontal" and meta["seed"] == 2
    assert meta["bank"]["deflated_kpa"] == 155.0 and meta["vehicle"]["mass"] > load_vehicle().total_mass
    sel = table.column("selected").to_numpy()
    assert set(np.unique(sel)) <= set(range(1, 17))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (["--accel", "world"], "--accel"),
        (["--deflated-kpa", "60"], "--deflated-kpa"),
        (["--nominal-kpa", "400"], "--nominal-kpa"),
        (["--deflated-kpa", "260"], "below --nominal-kpa"),
        (["--seed", "-1"], "--seed"),
        (["--tire", "missing.tir"], "--tire"),
    ],
)
def test_cli_bad_options_exit_2_and_write_nothing(lane_change, tmp_path, capsys, options, message):
    out = tmp_path / "det.parquet"
    assert main(["lateral-detect", str(lane_change[2]), "--out", str(out), *options]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    from suvtwin.pipeline.lateral_detection import monte_carlo_study

    return monte_carlo_study(2, tmp_path_factory.mktemp("runs"), jobs=1, cases=("softer_deflated",))


def test_study_and_report_section(small_study):
    from suvtwin.pipeline.report.lateral_detection import lateral_detection_html

    case = small_study["cases"]["softer_deflated"]
    assert case["variants"]["esc_body"]["runs"] == 2 and case["simulation"]["failed"] == {}
    assert (
        case["example"]["draw"]["tyre"] == "fl" and len(case["example"]["roll_compensated"]["selected"]) > 100
    )
    text = "\n".join(lateral_detection_html(json.loads(json.dumps(small_study))))
    assert "Solmaz" in text and "Confusion matrix" in text and "PPY1" in text
    assert text.count("data:image/png;base64,") == 2  # Fig. 7 analog and the delay histograms


def test_campaign_runs_the_study_on_request_and_caches_it(tmp_path, monkeypatch):
    import suvtwin.pipeline.lateral_detection as module
    from suvtwin.pipeline.campaign import preset
    from suvtwin.pipeline.campaign.execution import _lateral_detection_study

    assert preset("full").lateral_detection_runs == 100 and preset("quick").lateral_detection_runs == 0
    assert _lateral_detection_study(preset("quick"), tmp_path, 1) == (None, False)
    calls = []

    def stand_in(n, runs_dir, **kw):
        calls.append((n, kw["jobs"]))
        return {"runs_per_case": n, "cases": {}, "x": np.float64(1.5)}

    monkeypatch.setattr(module, "monte_carlo_study", stand_in)
    config = preset("quick", lateral_detection_runs=3)
    study, made = _lateral_detection_study(config, tmp_path, 2)
    assert made and calls == [(3, 2)] and study["x"] == 1.5
    study2, made2 = _lateral_detection_study(config, tmp_path, 2)
    assert not made2 and study2 == study and len(calls) == 1
    with pytest.raises(InputError, match="lateral_detection_runs"):
        preset("quick", lateral_detection_runs=-1)


def test_fitted_axle_characteristics_fold_in_the_compliance_steer():
    # The bank fitted in the detector's coordinates (eq. 8 slip from the steering command, eq. 7 loads)
    # is an effective axle characteristic: a wheel that toes by c·S under its own side force S has,
    # seen from the steering command, the cornering stiffness C/(1 + C·c) (front, toe out of the turn)
    # or C/(1 − C·c) (rear, toe towards the force) — Pacejka 2012, sec. 1.3 (effective axle
    # characteristics); Gillespie 1992, ch. 6. C is the tyre's own, from the tyre-frame fit.
    from suvtwin.estimators.lateral_detection import wheel_loads
    from suvtwin.pipeline.lateral_detection import fit_bank

    steering = load_vehicle().steering
    loads = wheel_loads(0.0, two_track_vehicle())
    own, effective = fit_bank(slip="tyre"), fit_bank(slip="detector")
    assert isinstance(effective.nominal, tuple) and not isinstance(own.nominal, tuple)

    def stiffness(tire, fz):
        return (tire.k1 - fz / tire.k2) * fz * tire.k3

    front, rear = stiffness(own.nominal, loads[0]), stiffness(own.nominal, loads[2])
    predicted_front = front / (1.0 + front * steering.compliance_steer_front)
    predicted_rear = rear / (1.0 - rear * steering.compliance_steer_rear)
    # the front also has bump steer (roll understeer), which the per-force formula leaves out: ≤ 8 %
    assert stiffness(effective.nominal[0], loads[0]) == pytest.approx(predicted_front, rel=0.08)
    assert stiffness(effective.nominal[1], loads[2]) == pytest.approx(predicted_rear, rel=0.05)
    assert stiffness(effective.nominal[0], loads[0]) < 0.85 * front


def test_without_compliance_the_effective_axle_is_the_tyre():
    # With the wheels steering exactly as commanded (RIGID_STEERING), the per-axle characteristic
    # fitted from the steering command must be the tyre's own: C_eff = C/(1 + C·0).
    from suvtwin.estimators.lateral_detection import wheel_loads
    from suvtwin.pipeline.lateral_detection import RIGID_STEERING, fit_bank

    loads = wheel_loads(0.0, two_track_vehicle())
    own = fit_bank(slip="tyre", vehicle=RIGID_STEERING)
    effective = fit_bank(slip="detector", vehicle=RIGID_STEERING)
    sc = lane_change_scenario(speed_kmh=90.0, vehicle=RIGID_STEERING)
    assert sc.vehicle == RIGID_STEERING

    def stiffness(tire, fz):
        return (tire.k1 - fz / tire.k2) * fz * tire.k3

    for axle, wheel in ((0, 0), (1, 2)):
        assert stiffness(effective.nominal[axle], loads[wheel]) == pytest.approx(
            stiffness(own.nominal, loads[wheel]), rel=0.08
        )


@pytest.mark.parametrize(
    ("steering", "message"),
    [
        ({"mode": "circle", "radius_m": 80.0}, "steering.mode 'circle' needs road: flat"),
        ({"mode": "lane", "lane_y_m": 1.5}, "steering.lane_y_m must stay within ±0.93 m"),
        ({"mode": "iso3888"}, "steering.lane_y_m + path y must stay within ±0.93 m"),
    ],
)
def test_steering_that_leaves_a_rough_road_s_strip_is_refused(steering, message):
    # a road with segments is a straight heightfield strip 4 m wide; beyond it the "road" would be its
    # edge row extended (an 80 m circle on a class C road read the monitor's tyres 47-63 kPa low)
    road = {"segments": [{"length_m": 300.0, "road_class": "C"}]}
    with pytest.raises(InputError, match="steering") as info:
        parse_scenario({"duration_s": 5.0, "road": road, "steering": steering})
    assert message in str(info.value)
    parse_scenario({"duration_s": 5.0, "road": "flat", "steering": steering})  # fine on a flat road
    weave = {"mode": "path", "path": [[0.0, 0.0], [20.0, 0.7], [40.0, -0.7], [60.0, 0.0]]}
    parse_scenario({"duration_s": 5.0, "road": road, "steering": weave})  # within the strip
