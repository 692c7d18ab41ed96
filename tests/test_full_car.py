"""The linear full car (estimators/full_car.py) against closed forms, a 2-DOF quarter car and MuJoCo."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.full_car import (
    FullCar,
    blend_gain_at_delay,
    corner_spectrum,
    gain_at_delay,
    projected_terms,
    suspension_force_responses,
    track_responses,
    wheel_responses,
)
from suvtwin.estimators.joint import LinearQuarterCar, corner_response, signal_direction
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.estimation import full_car_model

VEHICLE = load_vehicle()
CAR = full_car_model(VEHICLE)


def _displacement(f, car, corner, **kw):
    """Corner's (body, wheel) displacement per unit road elevation under each wheel, (F, 2, 4)."""
    s = 2j * np.pi * np.asarray(f)
    return wheel_responses(f, car, corner, [car.tire_stiffness[corner]], **kw)[0] / s[:, None, None]


@pytest.mark.parametrize("corner", range(4))
def test_slow_rigid_ground_motions_are_followed(corner):
    # at 1 mHz the car rides a ground that rises, pitches or rolls as one rigid body: every point follows it
    xy = np.asarray(CAR.corner_xy)
    h = _displacement([1e-3], CAR, corner)[0]  # (2, 4)
    for ground in (np.ones(4), xy[:, 0], xy[:, 1]):  # heave, pitch, roll of the road plane
        assert h @ ground == pytest.approx(np.full(2, ground[corner]), abs=1e-6)


def test_roll_resonance_on_rigid_tyres_is_the_suspensions_roll_stiffness():
    # tyres 1000× stiffer and light damping: the body's roll mode alone, at √(K_roll / I_roll), with
    # K_roll = Σ_axles (k_s + 2 k_arb)·2·(track/2)² (both axles carry the body's roll)
    stiff = replace(CAR, tire_stiffness=tuple(1e3 * k for k in CAR.tire_stiffness), damping=(50.0,) * 4,
                    tire_damping=(0.0,) * 4)  # fmt: skip
    xy = np.asarray(stiff.corner_xy)
    k_roll = sum((stiff.spring_rate[i] + 2 * stiff.anti_roll[axle]) * 2 * xy[i, 1] ** 2
                 for axle, i in ((0, 0), (1, 2)))  # fmt: skip
    f_roll = np.sqrt(k_roll / stiff.inertia_roll) / (2 * np.pi)
    f = np.linspace(0.5 * f_roll, 2.0 * f_roll, 3001)
    h = _displacement(f, stiff, 0)  # corner fl
    roll_input = h[:, 0] @ xy[:, 1]  # ground rolled by one radian, body point above fl
    assert f[np.argmax(np.abs(roll_input))] == pytest.approx(f_roll, rel=2e-3)


def test_front_axle_is_a_quarter_car_when_the_body_decouples():
    # pitch inertia m·a1·a2 (dynamic index 1), no bars, road under the front wheels only and alike
    # left and right: the front corner is the 2-DOF quarter car with sprung mass m·a2/(2L)
    xy = np.asarray(CAR.corner_xy)
    a1, a2 = xy[0, 0], -xy[2, 0]
    car = replace(CAR, inertia_pitch=CAR.sprung_mass * a1 * a2, anti_roll=(0.0, 0.0))
    f = np.linspace(0.3, 30.0, 200)
    h = wheel_responses(f, car, 0, [car.tire_stiffness[0]])[0]  # (F, 2, 4) per road velocity
    front_pair = h[:, :, 0] + h[:, :, 1]
    qc = LinearQuarterCar(sprung_mass=car.sprung_mass * a2 / (2 * (a1 + a2)),
                          unsprung_mass=car.unsprung_mass[0], spring_rate=car.spring_rate[0],
                          damping=car.damping[0], tire_damping=car.tire_damping[0])  # fmt: skip
    hs, hu = corner_response(f, car.tire_stiffness[0], qc)
    np.testing.assert_allclose(front_pair[:, 0], hs, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(front_pair[:, 1], hu, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("corner", range(4))
def test_a_suspension_force_pair_meets_the_mass_line_and_the_static_limit(corner):
    # far above every mode the masses alone answer: the body point by the rigid body's
    # 1/m + x²/I_pitch + y²/I_roll, the wheel by −1/m_us; far below, the static deflection's
    # acceleration −ω² x_static, x_static from the stiffness alone (tyres as springs)
    x, y = CAR.corner_xy[corner]
    rigid = 1 / CAR.sprung_mass + x**2 / CAR.inertia_pitch + y**2 / CAR.inertia_roll
    high = suspension_force_responses([5e4], CAR, corner)[0]
    assert high[0].real == pytest.approx(rigid, rel=1e-3)
    assert high[1].real == pytest.approx(-1 / CAR.unsprung_mass[corner], rel=1e-3)
    stiff_only = replace(CAR, damping=(0.0,) * 4, tire_damping=(0.0,) * 4)
    f = 1e-3
    low = suspension_force_responses([f], stiff_only, corner)[0] / -(2 * np.pi * f) ** 2  # static, m/N
    # static: the pair compresses this corner's suspension by 1/(its wheel rate and bar, against
    # the tyre and the rest of the car in series); the body point rises and the wheel sinks
    assert low[0].real > 0 > low[1].real
    assert low[0].real - low[1].real < 1 / CAR.spring_rate[corner]
    # the wheel sinks into its tyre by the force over k_t, less what the body's rise loads back
    assert -low[1].real < 1 / CAR.tire_stiffness[corner]
    # with the lateral slip, the vertical limits stay
    lateral = full_car_model(VEHICLE, lateral=True)
    high_lat = suspension_force_responses([5e4], lateral, corner, speed_mps=20.0)[0]
    assert high_lat[1].real == pytest.approx(high[1].real, rel=1e-3)


def test_the_tyre_grid_by_rank_one_updates_equals_a_direct_solve():
    f = np.linspace(0.2, 30.0, 37)
    kt = np.linspace(1.2e5, 3.6e5, 5)
    got = wheel_responses(f, CAR, 2, kt, spring_rate=5.0e4, damping=2500.0, tire_scale=0.8)
    for p, k in enumerate(kt):
        car = replace(CAR, tire_stiffness=tuple(k if i == 2 else CAR.tire_stiffness[i] for i in range(4)),
                      spring_rate=tuple(5.0e4 if i == 2 else CAR.spring_rate[i] for i in range(4)),
                      damping=tuple(2500.0 if i == 2 else CAR.damping[i] for i in range(4)))  # fmt: skip
        direct = wheel_responses(f, car, 2, [k], tire_scale=0.8)[0]
        np.testing.assert_allclose(got[p], direct, rtol=1e-9, atol=1e-12)


def test_several_dampings_by_rank_one_updates_equal_one_call_each():
    # a damping is a rank-one change of the dynamic stiffness (s δc e eᵀ): one inversion for all of them
    f = np.linspace(0.2, 30.0, 37)
    kt = np.linspace(1.2e5, 3.6e5, 5)
    dampings = np.array([1800.0, 3100.0, 5200.0])
    got = wheel_responses(f, CAR, 1, kt, spring_rate=6.0e4, damping=dampings, tire_scale=0.9)
    assert got.shape == (3, 5, 37, 2, 4)
    for d, c in enumerate(dampings):
        one = wheel_responses(f, CAR, 1, kt, spring_rate=6.0e4, damping=float(c), tire_scale=0.9)
        np.testing.assert_allclose(got[d], one, rtol=1e-9, atol=1e-12 * np.abs(one).max())


def test_projected_gain_at_a_delay_is_the_spectrum_along_the_direction():
    f = np.linspace(0.5, 25.0, 50)
    qc = LinearQuarterCar(sprung_mass=450.0, unsprung_mass=52.75, spring_rate=45e3, damping=3000.0)
    u1, u2 = signal_direction(f, qc)
    speed = 17.0
    a_sq, cross = projected_terms(wheel_responses(f, CAR, 3, [CAR.tire_stiffness[3]]), u1, u2)
    gain = gain_at_delay(a_sq, cross, f, CAR.wheelbase / speed)[0]
    spec = corner_spectrum(f, speed, CAR, 3)
    u = np.stack([u1, u2], axis=1)
    along = np.einsum("fi,fij,fj->f", np.conj(u), spec, u).real
    np.testing.assert_allclose(gain, along, rtol=1e-10)


@pytest.mark.parametrize("speed", [8.0, 27.0])
def test_track_responses_give_each_corners_spectrum(speed):
    # one 7×7 solve per frequency for all eight channels against the corner-by-corner rank-one grid
    # (a second implementation): each corner's 2×2 block of Σ_tracks g g^H is corner_spectrum's
    car = replace(CAR, tire_stiffness=(2.1e5, 2.6e5, 1.8e5, 2.3e5))
    f = np.linspace(0.2, 30.0, 61)
    g = track_responses(f, car, car.wheelbase / speed)
    assert g.shape == (f.size, 8, 2)
    spec = np.einsum("fit,fjt->fij", g, np.conj(g))
    for c in range(4):
        block = spec[:, 2 * c : 2 * c + 2, 2 * c : 2 * c + 2]
        np.testing.assert_allclose(block, corner_spectrum(f, speed, car, c), rtol=1e-9, atol=1e-12)


def test_track_responses_follow_a_slow_road():
    # at 0.1 mHz the car follows its road: both tracks together lift every point alike, and on a car
    # with equal front and rear tracks one track's road is a rigid plane (the left up, the right
    # still), so acceleration per road velocity is s = i2πf on its side and 0 on the other
    f = np.array([1e-4])
    s = 2j * np.pi * f[0]
    g = track_responses(f, CAR, CAR.wheelbase / 15.0)[0] / s  # (8, 2)
    np.testing.assert_allclose(g.sum(axis=1), np.ones(8), atol=1e-3)
    xy = np.asarray(CAR.corner_xy)
    equal = replace(CAR, corner_xy=tuple((float(x), float(np.sign(y)) * xy[0, 1]) for x, y in xy))
    g = track_responses(f, equal, equal.wheelbase / 15.0)[0] / s
    left = np.repeat([1.0, 0.0, 1.0, 0.0], 2)  # fl body, fl wheel, fr body, ..., rr wheel
    np.testing.assert_allclose(g, np.stack([left, 1.0 - left], axis=1), atol=1e-3)


def test_rear_wheels_rerunning_the_front_road_shape_the_body_spectrum():
    # the body's response to one track's road differs with speed (the wheelbase filter), the wheel's
    # well above the body modes hardly at all
    f = np.array([1.2, 15.0])
    slow, fast = corner_spectrum(f, 10.0, CAR, 0), corner_spectrum(f, 30.0, CAR, 0)
    assert abs(slow[0, 0, 0].real / fast[0, 0, 0].real - 1.0) > 0.2
    assert abs(slow[1, 1, 1].real / fast[1, 1, 1].real - 1.0) < 0.05


LATERAL = full_car_model(VEHICLE, lateral=True)


def test_lateral_block_is_the_single_track_model_of_rajamani():
    # without roll and relaxation, the (lateral velocity, yaw rate) rows are the linear bicycle
    # model: their determinant vanishes at the eigenvalues of Rajamani's state matrix (2012, eq.
    # 2.31), written here from the textbook with each axle's two tyres (C_f, C_r per tyre, l_f, l_r)
    from suvtwin.estimators.full_car import _body_matrices, _dynamic_stiffness

    car = replace(LATERAL, relaxation_length=0.0)
    v = 20.0
    m = car.sprung_mass + sum(car.unsprung_mass)
    iz = car.inertia_yaw
    cf, cr = car.cornering_stiffness[0], car.cornering_stiffness[2]
    lf, lr = car.corner_xy[0][0], -car.corner_xy[2][0]
    a = np.array([
        [-(2 * cf + 2 * cr) / (m * v), -v - (2 * cf * lf - 2 * cr * lr) / (m * v)],
        [-(2 * lf * cf - 2 * lr * cr) / (iz * v), -(2 * lf**2 * cf + 2 * lr**2 * cr) / (iz * v)],
    ])  # fmt: skip
    _, stiff, damp, mass = _body_matrices(car, np.asarray(car.spring_rate), np.asarray(car.damping))
    for lam in np.linalg.eigvals(a):
        block = _dynamic_stiffness(car, np.array([lam]), stiff, damp, mass, v)[0, 7:9, 7:9] / lam
        scale = abs(block[0, 0] * block[1, 1]) + abs(block[0, 1] * block[1, 0])
        assert abs(np.linalg.det(block)) < 1e-9 * scale


def test_lateral_slip_damps_the_roll_and_vanishes_at_high_speed():
    f = np.linspace(0.3, 20.0, 80)
    base = track_responses(f, LATERAL, LATERAL.wheelbase / 17.0)
    # the cornering stiffnesses act as C/V: at a speed where that is nil the model is the vertical one
    fast = track_responses(f, LATERAL, LATERAL.wheelbase / 17.0, speed_mps=1e9)
    np.testing.assert_allclose(fast, base, rtol=1e-6, atol=1e-9)
    # at road speed the body's roll peak (2–3 Hz) is damped, the wheel hop is not touched
    slow = track_responses(f, LATERAL, LATERAL.wheelbase / 17.0, speed_mps=17.0)
    roll = (f >= 2.0) & (f <= 3.0)
    hop = (f >= 9.0) & (f <= 15.0)
    body = lambda g: np.sum(np.abs(g[:, 0, :]) ** 2, axis=-1)  # noqa: E731 - fl's body, both tracks
    wheel = lambda g: np.sum(np.abs(g[:, 1, :]) ** 2, axis=-1)  # noqa: E731
    assert np.mean(body(slow)[roll]) < 0.8 * np.mean(body(base)[roll])
    np.testing.assert_allclose(wheel(slow)[hop], wheel(base)[hop], rtol=0.03)
    # a car without cornering stiffness ignores the speed; bad lateral parameters are refused
    np.testing.assert_array_equal(track_responses(f, CAR, 0.2, speed_mps=17.0), track_responses(f, CAR, 0.2))
    with pytest.raises(InputError, match="wheel_centre_height"):
        replace(LATERAL, wheel_centre_height=1.0)
    with pytest.raises(InputError, match="cornering_stiffness"):
        replace(LATERAL, cornering_stiffness=(1.0, 1.0, 1.0))
    with pytest.raises(InputError, match="speed"):
        track_responses(f, LATERAL, 0.2, speed_mps=0.0)


def test_lateral_parameters_come_from_the_tyre_and_the_loads():
    # cornering stiffness: the MF slope at the static load (fronts heavier, less by their compliance
    # steer); a load up and behind raises the centre of gravity and adds yaw inertia
    c = LATERAL.cornering_stiffness
    assert c[0] == c[1] and c[2] == c[3]
    from suvtwin.mjcf.tire import load_tire, tire_forces_array

    tire = load_tire(VEHICLE.tire_file)
    fz_front = VEHICLE.chassis.mass * 9.81 * VEHICLE.chassis.a2 / VEHICLE.wheelbase / 2 + 61.14 * 9.81
    _, fy = tire_forces_array(fz_front, 0.0, 1e-3, tire.nominal_pressure, tire)
    raw = abs(float(fy)) / 1e-3
    assert c[0] == pytest.approx(raw / (1 + raw * VEHICLE.steering.compliance_steer_front), rel=2e-3)
    assert 40e3 < c[0] < 80e3 and 40e3 < c[2] < 80e3
    loaded = full_car_model(VEHICLE, ((250.0, (-1.0, 0.0, 0.3)),), lateral=True)
    assert loaded.cog_height > LATERAL.cog_height and loaded.inertia_yaw > LATERAL.inertia_yaw
    assert loaded.cornering_stiffness[2] > c[2]
    assert 0.3 < LATERAL.wheel_centre_height < 0.37 < LATERAL.cog_height


def test_bad_car_and_speed_are_refused():
    with pytest.raises(InputError, match="one entry per corner"):
        replace(CAR, spring_rate=(1.0, 2.0))
    with pytest.raises(InputError, match="> 0"):
        replace(CAR, sprung_mass=-1.0)
    with pytest.raises(InputError, match="speed"):
        corner_spectrum([1.0], 0.0, CAR, 0)
    assert isinstance(CAR, FullCar)


def test_loads_move_the_centre_of_gravity_and_add_inertia():
    loaded = full_car_model(VEHICLE, ((300.0, (-1.0, 0.4, 0.2)),))
    assert loaded.sprung_mass == pytest.approx(CAR.sprung_mass + 300.0)
    shift = 300.0 * np.array([-1.0, 0.4]) / loaded.sprung_mass
    np.testing.assert_allclose(np.asarray(loaded.corner_xy), np.asarray(CAR.corner_xy) - shift, atol=1e-12)
    assert loaded.inertia_pitch > CAR.inertia_pitch + 300.0 * 0.8**2
    assert loaded.inertia_roll > CAR.inertia_roll


def _full_car_record(car, pressures_kpa, speed, seconds, gd, seed, sigma=0.5, dt=1e-3):
    """Accelerations (T, 4) body and wheel of the linear full car on two independent ISO tracks of
    level gd (waviness 2: white road velocity), rears delayed by wheelbase/speed, plus noise; drawn
    in the frequency domain (circular record)."""
    from suvtwin.estimators.quarter_car import stiffness_from_pressure

    rng = np.random.default_rng(seed)
    n = int(round(seconds / dt))
    f = np.fft.rfftfreq(n, dt)
    truth = replace(car, tire_stiffness=tuple(float(stiffness_from_pressure(p * 1e3)) for p in pressures_kpa))
    s_v = 4 * np.pi**2 * gd * 0.1**2 * speed  # one-sided road-velocity PSD per track
    amp = np.sqrt(s_v * n / (4 * dt))  # rfft coefficients' std for that one-sided PSD
    lag = np.exp(-2j * np.pi * f * car.wheelbase / speed)
    roads = []
    for _ in range(2):
        r = amp * (rng.normal(size=f.size) + 1j * rng.normal(size=f.size))
        r[0] = 0.0
        roads.append(r)
    wheel_road = np.stack([roads[0], roads[1], roads[0] * lag, roads[1] * lag])  # fl, fr, rl, rr
    acc_s, acc_u = np.empty((n, 4)), np.empty((n, 4))
    for c in range(4):
        h = wheel_responses(f, truth, c, [truth.tire_stiffness[c]])[0]  # (F, 2, 4)
        y = np.einsum("fkw,wf->kf", h, wheel_road)
        acc_s[:, c] = np.fft.irfft(y[0], n=n) + sigma * rng.normal(size=n)
        acc_u[:, c] = np.fft.irfft(y[1], n=n) + sigma * rng.normal(size=n)
    return acc_s, acc_u


def test_monitor_reads_four_tyres_of_a_full_car_record():
    # the monitor with full-car corner models on 64 s the linear full car made at 80 km/h, class C (its
    # tables' neighbour tyres at nominal, the record's not: a small model error): tables, delay and band
    # averaging together. Measured on seeds 11, 12 at 40 and 80 km/h: errors within 1σ, σ 9–21 kPa
    from suvtwin.estimators.monitor import TyreMonitor
    from suvtwin.pipeline.estimation import corner_sprung_mass, linear_corner_model

    pressures = (180.0, 230.0, 150.0, 210.0)
    speed = 80 / 3.6
    acc_s, acc_u = _full_car_record(CAR, pressures, speed, 64.0, 256e-6, seed=11)
    models = [replace(linear_corner_model(c, corner_sprung_mass(c, vehicle=VEHICLE), vehicle=VEHICLE,
                                          full_car=CAR), suspension=None, envelope_half_length=0.0)
              for c in ("fl", "fr", "rl", "rr")]  # fmt: skip
    monitor = TyreMonitor(models, dt=1e-3)
    n = acc_s.shape[0]
    out = monitor.update(np.arange(n) * 1e-3, np.full(n, speed), acc_s, acc_u)
    error = out.pressure_pa[-1] / 1e3 - np.array(pressures)
    sigma = out.pressure_sigma_pa[-1] / 1e3
    assert np.all(np.abs(error) <= 2.5 * sigma), (error, sigma)
    assert np.all(out.observable[-1]) and np.all(sigma < 20.0)


def test_gain_at_delay_averaged_over_bands_and_picked_rows_is_the_mean_of_its_frequencies():
    # banding and row picking (used by the monitor on its gain tables, without copying them) against
    # numpy's reduceat of the per-frequency gain; the per-frequency gain is checked against the
    # spectrum above
    rng = np.random.default_rng(5)
    f = np.linspace(0.5, 20.0, 40)
    a_sq = rng.random((3, 5, f.size))
    cross = rng.standard_normal((3, 5, f.size)) + 1j * rng.standard_normal((3, 5, f.size))
    start = np.array([0, 1, 2, 6, 10, 25, 39])
    per_f = gain_at_delay(a_sq, cross, f, 0.17)
    assert per_f.shape == (3, 5, f.size)
    sizes = np.diff(np.r_[start, f.size])
    banded = np.add.reduceat(per_f, start, axis=-1) / sizes
    np.testing.assert_allclose(gain_at_delay(a_sq, cross, f, 0.17, band_start=start), banded, rtol=1e-13)
    rows = np.array([14, 0, 7])
    got = gain_at_delay(a_sq, cross, f, 0.17, band_start=start, rows=rows)
    np.testing.assert_allclose(got, banded.reshape(15, -1)[rows], rtol=1e-13)
    with pytest.raises(InputError, match="band_start"):
        gain_at_delay(a_sq, cross, f, 0.17, band_start=np.array([1, 5]))


def test_blend_gain_at_delay_adds_the_blended_band_gains_bit_for_bit():
    # the monitor's blend of gain tables at the window's delay: the same sums as gain_at_delay's
    # band means, weighted and added in order of the weights, skipping zero weights
    rng = np.random.default_rng(6)
    f = np.linspace(0.5, 20.0, 40)
    a_sq = rng.random((4, 3, 5, f.size))
    cross = rng.standard_normal(a_sq.shape) + 1j * rng.standard_normal(a_sq.shape)
    start = np.array([0, 1, 2, 6, 10, 25, 39])
    banded = gain_at_delay(a_sq, cross, f, 0.17, band_start=start)  # (4, 3, 5, K)
    targets = np.array([2, 0])
    tables = np.array([[3, 1, 0], [2, 2, 1]])
    weights = np.array([[0.25, 0.0, 0.75], [0.5, 0.5, 0.0]])
    out = rng.random((3, 3, 5, start.size))
    want = out.copy()
    for i, c in enumerate(targets):
        for k in range(tables.shape[1]):
            if weights[i, k] > 0.0:
                want[c] += weights[i, k] * banded[tables[i, k]]
    blend_gain_at_delay(a_sq, cross, f, 0.17, start.astype(np.int64), targets, tables, weights, out)
    np.testing.assert_array_equal(out, want)
