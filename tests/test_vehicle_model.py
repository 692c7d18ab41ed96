"""The MuJoCo SUV against statics, the 2-DOF quarter car and MuJoCo's own geometry queries."""

from importlib import resources
from pathlib import Path

import mujoco
import numpy as np
import pytest
import scipy.signal
import scipy.stats

from suvtwin.estimators.full_car import wheel_responses
from suvtwin.mjcf.builder import build_model, flat_road_xml
from suvtwin.mjcf.kernel import H_NCOL, H_NROW, road_height
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import CORNERS, GRAVITY, load_vehicle, parameter_table
from suvtwin.pipeline.estimation import full_car_model
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import read_run, simulate, write_run
from suvtwin.roads.profile import generate_road
from suvtwin.roads.spec import RoadSpec, SegmentSpec

SUV_DIR = Path(str(resources.files("suvtwin.mjcf") / "suv"))
VEHICLE = load_vehicle()
TIRE = load_tire(VEHICLE.tire_file)
QUIET = {"accel_sprung_mps2": 0.0, "accel_unsprung_mps2": 0.0}


def _kt(pressure_pa):
    # Brancati & Tufano 2022 eq. 3-4, written out here (not the model's function)
    return 264700.0 * (1 + 0.7097 * (pressure_pa - 250e3) / 250e3)


def test_model_folder_is_complete_and_every_number_documented():
    for name in ("README.md", "LICENSE", "CHANGELOG.md", "parameters.toml", "suv.xml", "scene.xml"):
        assert (SUV_DIR / name).is_file(), name
    for section, entries in parameter_table().items():
        for name, entry in entries.items():
            assert {"value", "unit", "source"} <= set(entry), f"{section}.{name}"
            if "bounds" in entry:
                low, high = entry["bounds"]
                assert low <= entry["value"] <= high, f"{section}.{name} outside its bounds"
    # suv.xml is the builder's output for the current parameters
    assert (SUV_DIR / "suv.xml").read_text() == flat_road_xml()
    mujoco.MjModel.from_xml_path(str(SUV_DIR / "scene.xml"))


def test_masses_and_yaw_inertia_match_paper_table_1():
    road = generate_road(RoadSpec(segments=[SegmentSpec(length_m=60, road_class="A")]), seed=0)
    model = build_model(VEHICLE, road).model
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    # total mass = chassis + four wheel masses of Table 1, nothing else
    assert mujoco.mj_getTotalmass(model) == pytest.approx(1788 + 2 * 61.14 + 2 * 52.75, abs=1e-6)
    # whole-vehicle yaw inertia about the vertical through the chassis CoG (parallel-axis sum of
    # MuJoCo's world-frame body inertias) = Table 1 Jz
    chassis = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "chassis")
    origin = data.xipos[chassis]
    izz = 0.0
    for b in range(1, model.nbody):
        rot = data.ximat[b].reshape(3, 3)
        inertia_world = rot @ np.diag(model.body_inertia[b]) @ rot.T
        r = data.xipos[b] - origin
        izz += inertia_world[2, 2] + model.body_mass[b] * (r[0] ** 2 + r[1] ** 2)
    assert izz == pytest.approx(3230.0, rel=1e-6)


def test_heightfield_reader_agrees_with_mujoco_ray_casts():
    road = generate_road(RoadSpec(segments=[SegmentSpec(length_m=80, road_class="D")]), seed=3)
    vm = build_model(VEHICLE, road)
    data = mujoco.MjData(vm.model)
    mujoco.mj_forward(vm.model, data)
    hdata = vm.model.hfield_data.reshape(int(vm.hfield[H_NROW]), int(vm.hfield[H_NCOL]))
    rng = np.random.default_rng(0)
    geomid = np.zeros(1, np.int32)
    track = 0.25 * (VEHICLE.chassis.track_front + VEHICLE.chassis.track_rear)
    for _ in range(200):
        x = rng.uniform(1, 79)
        y = rng.choice([-1, 1]) * (track + rng.uniform(-0.2, 0.2))  # on a track plateau
        road_only = np.array([1, 0, 0, 0, 0, 0], np.uint8)  # the road is geom group 0, the car 1 and 3
        hit = mujoco.mj_ray(
            vm.model, data, np.array([x, y, 5.0]), np.array([0, 0, -1.0]), road_only, 1, -1, geomid
        )
        assert road_height(x, y, vm.hfield, hdata) == pytest.approx(5.0 - hit, abs=2e-6)
        # and the heightfield holds the road: the track's profile at x
        assert 5.0 - hit == pytest.approx(road.height(x, 0 if y > 0 else 1), abs=2e-6)


def test_smoke_steps_without_warnings():
    # Menagerie-style: step the model with deterministic quasi-random controls inside their range
    road = generate_road(RoadSpec(segments=[SegmentSpec(length_m=60, road_class="B")]), seed=1)
    vm = build_model(VEHICLE, road)
    data = mujoco.MjData(vm.model)
    data.qpos[2] = VEHICLE.chassis.cog_height + 0.1
    sampler = scipy.stats.qmc.Halton(d=vm.model.nu, seed=0)
    for _ in range(50):
        data.ctrl[:] = (sampler.random(1)[0] - 0.5) * [0.2, 0.2, 100, 100, 100, 100]
        mujoco.mj_step(vm.model, data, nstep=10)
    assert np.all(data.warning.number == 0)
    assert np.all(np.isfinite(data.qpos))


def _static_run(pressure_kpa):
    scenario = parse_scenario(
        {"duration_s": 3.0, "speed_kmh": 0.0, "road": "flat", "pressure_kpa": pressure_kpa, "noise": QUIET}
    )
    return simulate(scenario).table.iloc[-200:].mean()


@pytest.mark.parametrize("pressure_kpa", [130, 180, 230, 250])
def test_static_loads_and_deflections(pressure_kpa):
    row = _static_run(pressure_kpa)
    fz = np.array([row[f"{c}_tire_fz_n"] for c in CORNERS])
    weight = (1788 + 2 * 61.14 + 2 * 52.75) * GRAVITY
    assert fz.sum() == pytest.approx(weight, rel=0.005)
    # front axle load from moment balance about the rear axle: chassis by a2/l, wheels on their axle
    front = 1788 * GRAVITY * 1.471 / (1.347 + 1.471) + 2 * 61.14 * GRAVITY
    assert fz[:2].sum() == pytest.approx(front, rel=0.02)
    assert fz[2:].sum() == pytest.approx(weight - front, rel=0.02)
    # static deflection from geometry (unloaded radius minus centre height over the road) against
    # the statically predicted corner load over kt(p)
    predicted_load = np.array([front / 2] * 2 + [(weight - front) / 2] * 2)
    deflection = np.array(
        [TIRE.unloaded_radius - (row[f"{c}_z_unsprung_m"] - row[f"{c}_road_z_m"]) for c in CORNERS]
    )
    np.testing.assert_allclose(deflection, predicted_load / _kt(pressure_kpa * 1e3), rtol=0.02)


def _two_dof_acceleration_gain(f, ms, mus, ks, kt, cs, ct):
    """|sprung|², |unsprung|² acceleration per unit road elevation of the linear quarter car.

    ms zs'' = -ks(zs-zu) - cs(zs'-zu');  mus zu'' = ks(zs-zu) + cs(zs'-zu') - kt(zu-zr) - ct(zu'-zr').
    """
    s = 2j * np.pi * f
    a00, a01 = ms * s**2 + cs * s + ks, -(cs * s + ks)
    a11 = mus * s**2 + (cs + ct) * s + ks + kt
    det = a00 * a11 - a01 * a01
    road = kt + ct * s
    return np.abs(s**2 * (-a01 * road) / det) ** 2, np.abs(s**2 * (a00 * road) / det) ** 2


def _peak(f, psd, band):
    """Peak frequency of a broad PSD hump: vertex of a parabola fitted to the (9-bin smoothed) log
    PSD where it lies within a factor 2 of its maximum. Applied alike to measured and predicted
    spectra, so both peaks are located the same way."""
    sel = (f >= band[0]) & (f <= band[1])
    f, smooth = f[sel], np.convolve(np.log(psd[sel]), np.ones(9) / 9, mode="same")
    j = int(np.argmax(smooth[4:-4])) + 4
    lo, hi = j, j
    while lo > 0 and smooth[lo - 1] > smooth[j] - np.log(2):
        lo -= 1
    while hi < smooth.size - 1 and smooth[hi + 1] > smooth[j] - np.log(2):
        hi += 1
    a, b, _ = np.polyfit(f[lo : hi + 1], smooth[lo : hi + 1], 2)
    return -b / (2 * a)


def _welch(x):
    return scipy.signal.welch(np.asarray(x), fs=1000.0, nperseg=20000)


@pytest.fixture(scope="module")
def low_road_runs():
    """120 s at 60 km/h on a road a quarter of class A's level (near-linear suspension)."""
    runs = {}
    for tracks, pressure in (("identical", 250), ("identical", 130), ("independent", 250)):
        scenario = parse_scenario(
            {
                "duration_s": 120.0,
                "speed_kmh": 60.0,
                "seed": 5,
                "road": {"segments": [{"length_m": 2060, "gd_n0": 4e-6}], "tracks": tracks},
                "pressure_kpa": pressure,
                "noise": QUIET,
            }
        )
        runs[tracks, pressure] = simulate(scenario).table
    return runs


def _peaks(table, corner, pressure_kpa):
    """Measured and 2-DOF-predicted (body, hop) peaks at one corner; the prediction is driven by
    the road the tire really saw (its road_z column)."""
    i = CORNERS.index(corner)
    s = VEHICLE.suspension
    c_lin = 0.5 * (s.damper_compression_low + s.damper_rebound_low)  # mean of bump and rebound slopes
    f, road = _welch(table[f"{corner}_road_z_m"])
    gain_s, gain_u = _two_dof_acceleration_gain(
        f, VEHICLE.sprung_mass_corner[i], VEHICLE.unsprung_mass[i], VEHICLE.spring_rate[i],
        _kt(pressure_kpa * 1e3), c_lin, TIRE.vertical_damping,
    )  # fmt: skip
    _, sprung = _welch(table[f"{corner}_accel_sprung_true_mps2"])
    _, unsprung = _welch(table[f"{corner}_accel_unsprung_true_mps2"])
    body, hop = (0.6, 3.0), (5.0, 20.0)
    return (_peak(f, sprung, body), _peak(f, unsprung, hop)), (
        _peak(f, gain_s * road, body),
        _peak(f, gain_u * road, hop),
    )


@pytest.mark.parametrize("corner", ["fl", "rl"])
def test_body_bounce_and_wheel_hop_match_the_two_dof_prediction(low_road_runs, corner):
    # identical tracks: heave and pitch only, the motions a corner quarter car describes
    (body, hop), (body_qc, hop_qc) = _peaks(low_road_runs["identical", 250], corner, 250)
    assert body == pytest.approx(body_qc, rel=0.05)
    assert hop == pytest.approx(hop_qc, rel=0.05)


def test_roll_makes_the_body_stiffer_than_a_quarter_car(low_road_runs):
    # independent tracks also excite roll, where the anti-roll bar adds to the corner's rate: the
    # full vehicle's corner bounce peak sits above the quarter car's (a limit of the QC premise)
    (body, _), (body_qc, _) = _peaks(low_road_runs["independent", 250], "fl", 250)
    assert body > 1.05 * body_qc


@pytest.mark.parametrize("corner", ["fl", "rl"])
def test_wheel_hop_falls_with_pressure_as_predicted(low_road_runs, corner):
    i = CORNERS.index(corner)
    ks, mus = VEHICLE.spring_rate[i], VEHICLE.unsprung_mass[i]
    (_, hop_250), _ = _peaks(low_road_runs["identical", 250], corner, 250)
    (_, hop_130), (_, hop_130_qc) = _peaks(low_road_runs["identical", 130], corner, 130)
    predicted_ratio = np.sqrt((ks + _kt(130e3)) / mus) / np.sqrt((ks + _kt(250e3)) / mus)
    assert hop_130 / hop_250 == pytest.approx(predicted_ratio, rel=0.05)
    assert hop_130 == pytest.approx(hop_130_qc, rel=0.05)


def test_straight_run_holds_speed_and_lane():
    scenario = parse_scenario(
        {
            "duration_s": 10.0,
            "speed_kmh": 60.0,
            "seed": 2,
            "road": {"segments": [{"length_m": 200, "road_class": "C"}]},
        }
    )
    table = simulate(scenario).table
    assert np.all(np.abs(table.speed_mps / (60 / 3.6) - 1) < 0.01)
    assert np.abs(table.y_m).max() < 0.3


def test_brakes_hold_a_stopped_car_instead_of_reversing_it():
    """Braked to rest from 60 km/h and held at 0: brakes are friction, so the car stops and stays
    (before, the speed controller's signed brake torque rolled it back 1.5 m at up to 0.64 m/s);
    at rest on a level road the tyres' longitudinal forces cancel."""
    scenario = parse_scenario(
        {"duration_s": 16.0, "speed_kmh": [[0.0, 60.0], [4.0, 60.0], [9.0, 0.0], [16.0, 0.0]], "seed": 5,
         "road": "flat", "noise": QUIET}
    )  # fmt: skip
    table = simulate(scenario).table
    t, v, x = table.t_s.to_numpy(), table.speed_mps.to_numpy(), table.x_m.to_numpy()
    assert v[t < 8.0].min() > 1.0  # still braking
    assert v.min() > -0.05
    held = t >= 11.0
    assert np.ptp(x[held]) < 0.02
    assert np.abs(table.loc[held, [f"{c}_wheel_speed_radps" for c in CORNERS]].to_numpy()).max() < 0.2
    fx = table.loc[held, [f"{c}_tire_fx_n" for c in CORNERS]].to_numpy().sum(axis=1)
    assert np.abs(fx).max() < 50.0  # N, against 20 kN of weight


def test_same_scenario_same_bytes(tmp_path):
    scenario = parse_scenario(
        {
            "duration_s": 1.0,
            "speed_kmh": 50.0,
            "seed": 4,
            "road": {"segments": [{"length_m": 40, "road_class": "B"}]},
        }
    )
    write_run(simulate(scenario), tmp_path / "a.parquet")
    write_run(simulate(scenario), tmp_path / "b.parquet")
    assert (tmp_path / "a.parquet").read_bytes() == (tmp_path / "b.parquet").read_bytes()
    table, meta = read_run(tmp_path / "a.parquet")
    assert meta["scenario"]["seed"] == 4 and len(table) == 1000
    other = parse_scenario({**scenario.model_dump(), "seed": 5})
    assert not np.allclose(simulate(other).table.fl_road_z_m, table.fl_road_z_m)


def _circle(pressure_kpa, steering):
    scenario = parse_scenario(
        {"duration_s": 24.0, "speed_kmh": 60.0, "road": "flat", "steering": steering,
         "pressure_kpa": pressure_kpa, "noise": QUIET}
    )  # fmt: skip
    table = simulate(scenario).table
    return table[table.t_s > 14.0]


def test_steady_circle_lateral_acceleration_and_pressure_effect():
    from suvtwin.mjcf.tire import tire_forces

    v, radius = 60 / 3.6, 50.0
    closed = _circle(250.0, {"mode": "circle", "radius_m": radius, "direction": "left"})
    # lateral acceleration of a steady circle: v^2 / R (within 5 %)
    assert closed.lat_accel_mps2.mean() == pytest.approx(v**2 / radius, rel=0.05)
    assert closed.speed_mps.mean() == pytest.approx(v, rel=0.01)
    # now hold that steering angle fixed and lower the outer front tire (right, in a left turn)
    steer = float(closed.steer_rad.mean())
    series = {"mode": "series", "series": [[0.0, steer]]}
    base = _circle(250.0, series)
    low = _circle({"fl": 250.0, "fr": 150.0, "rl": 250.0, "rr": 250.0}, series)
    # the tire model's prediction at the baseline operating point of that tire: more (or less)
    # lateral force at the same load and slip angle means more (or less) yaw
    fz, alpha = float(base.fr_tire_fz_n.mean()), float(base.fr_tire_slip_angle_rad.mean())
    tp = TIRE.to_array()
    fy_nominal = tire_forces(fz, 0.0, alpha, 250e3, tp)[1]
    fy_low = tire_forces(fz, 0.0, alpha, 150e3, tp)[1]
    predicted = np.sign(abs(fy_low) - abs(fy_nominal))
    change = low.yaw_rate_radps.mean() - base.yaw_rate_radps.mean()
    assert predicted != 0 and np.sign(change) == predicted
    assert abs(change) > 1e-4  # a measurable change, not numerical noise


def test_envelope_contact_against_mujoco_native_contact():
    # class A road, 40 km/h, 0.25 ms steps. MuJoCo's sphere has no contact-patch enveloping, so it
    # is compared with the envelope reader at (nearly) point contact; the default +-0.12 m
    # enveloping must then lower the hub acceleration (it filters the shortest wavelengths).
    def run(contact, half_length):
        scenario = parse_scenario(
            {"duration_s": 8.0, "timestep_s": 2.5e-4, "speed_kmh": 40.0, "seed": 3,
             "road": {"segments": [{"length_m": 120, "road_class": "A"}]}, "contact": contact,
             "vehicle": {"tire": {"envelope_half_length": half_length}}, "noise": QUIET}
        )  # fmt: skip
        table = simulate(scenario).table
        keep = table.t_s > 1.0
        rms = {
            f: np.sqrt(np.mean(table[f][keep] ** 2)) for f in table.columns if "accel" in f and "true" in f
        }
        return rms

    native = run("native", 0.12)
    point = run("envelope", 0.01)
    default = run("envelope", 0.12)
    for c in CORNERS:
        assert point[f"{c}_accel_sprung_true_mps2"] == pytest.approx(
            native[f"{c}_accel_sprung_true_mps2"], rel=0.05
        )
        assert point[f"{c}_accel_unsprung_true_mps2"] == pytest.approx(
            native[f"{c}_accel_unsprung_true_mps2"], rel=0.10
        )
        assert default[f"{c}_accel_unsprung_true_mps2"] < point[f"{c}_accel_unsprung_true_mps2"]


@pytest.mark.parametrize("corner", ["fl", "rl"])
def test_full_car_model_predicts_the_corner_spectra_on_independent_tracks(low_road_runs, corner):
    # the linear full car (suvtwin.estimators.full_car) with the tyres' lateral slip, driven by the
    # four roads the tyres saw, predicts each corner's body and wheel acceleration power band by band
    # within 20 %, where the quarter car misses the body's peak (roll, the rear wheels re-running the
    # front road). Without the lateral slip the body's 2–3 Hz band is over-predicted: the car's roll
    # about its centre of gravity slides the wheel centres sideways, and the tyres' side forces damp
    # it (MuJoCo 0.56–0.72 of the vertical model's power there at 60 km/h; 0.35–0.62 at 36 km/h)
    table = low_road_runs["independent", 250]
    i = CORNERS.index(corner)
    roads = np.stack([np.asarray(table[f"{c}_road_z_m"]) for c in CORNERS])  # (4, T)
    f = np.fft.rfftfreq(roads.shape[1], 1e-3)
    z = np.fft.rfft(roads - roads.mean(axis=1, keepdims=True), axis=1)  # (4, F)
    speed = float(np.mean(table["speed_mps"]))
    sel_f = (f > 0.0) & (f < 100.0)

    def predict(car, speed_mps):
        h = np.zeros((f.size, 2, 4), dtype=complex)
        h[sel_f] = wheel_responses(f[sel_f], car, i, [car.tire_stiffness[i]], speed_mps=speed_mps)[0]
        return np.fft.irfft(np.einsum("fkw,wf->kf", h, 2j * np.pi * f * z), n=roads.shape[1], axis=1)

    predicted = predict(full_car_model(VEHICLE, lateral=True), speed)
    vertical = predict(full_car_model(VEHICLE), None)
    bands = {"sprung": [(0.6, 1.0), (1.0, 2.0), (2.0, 2.5), (2.5, 3.0), (3.0, 5.0), (5.0, 8.0), (8.0, 12.0)],
             "unsprung": [(0.6, 2.0), (2.0, 5.0), (5.0, 8.0), (8.0, 12.0), (12.0, 16.0)]}  # fmt: skip
    for k, what in enumerate(("sprung", "unsprung")):
        fw, psd_measured = _welch(table[f"{corner}_accel_{what}_true_mps2"])
        _, psd_predicted = _welch(predicted[k])
        _, psd_vertical = _welch(vertical[k])
        for lo, hi in bands[what]:
            sel = (fw >= lo) & (fw < hi)
            ratio = psd_measured[sel].mean() / psd_predicted[sel].mean()
            assert 0.8 < ratio < 1.2, (what, lo, hi, ratio)
            if what == "sprung" and lo >= 2.0 and hi <= 3.0:
                assert psd_measured[sel].mean() / psd_vertical[sel].mean() < 0.8, (lo, hi)
