"""Solmaz's 16-model lateral deflation detector against independent references.

The arctan tyre's linear range against its analytic cornering stiffness; the two-track
model's steady state against the linear bicycle model; the load transfer against the
static force and moment balance; mirror symmetry of left and right turns; eq. 10 against
the simulated sideslip; the model numbering round trip; the batch against one-by-one runs;
the detector on noise-free data; bad input.
"""

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.lateral_detection import (
    DEFLATED_TIRE,
    GRAVITY,
    NOMINAL_MODEL,
    NOMINAL_TIRE,
    PAPER_VEHICLE,
    ArctanTire,
    TwoTrackVehicle,
    bank_tires,
    cornering_stiffness,
    deflated_wheels,
    detect_deflation,
    lateral_tire_force,
    model_number,
    sideslip_from_measurements,
    simulate_two_track,
    steering_angles,
    wheel_loads,
)

CAR = PAPER_VEHICLE
DT = 0.01  # s
SPEED = 120 / 3.6  # m/s, Sec. IV


def _lane_change(t, amplitude=np.deg2rad(0.5), t0=1.0):
    """Two one-period sines of 2 s, 1 s apart (the bench's manoeuvre, shorter lead-in)."""
    d = np.zeros_like(t)
    for start, sign in ((t0, 1.0), (t0 + 3.0, -1.0)):
        m = (t >= start) & (t < start + 2.0)
        d[m] = sign * amplitude * np.sin(np.pi * (t[m] - start))
    return d


def _analytic_stiffness(tire, load):
    """dS/dα at α = 0 of eq. 3, by hand: (k1 − F_Z/k2)·F_Z·k3."""
    return (tire.k1 - load / tire.k2) * load * tire.k3


@pytest.mark.parametrize("tire", [NOMINAL_TIRE, DEFLATED_TIRE])
@pytest.mark.parametrize("load", [2000.0, 3316.0, 4000.0])
def test_arctan_tire_linear_range_matches_cornering_stiffness(tire, load):
    k = tire.as_array()
    slip = 1e-4  # rad; arctan(x) = x − x³/3: relative error (k3·α)²/3 < 1e-6
    slope = (lateral_tire_force(slip, load, k) - lateral_tire_force(-slip, load, k)) / (2 * slip)
    np.testing.assert_allclose(slope, _analytic_stiffness(tire, load), rtol=1e-6)
    # eq. 15's secant stiffness: the same limit at zero slip, and S/α elsewhere
    np.testing.assert_allclose(cornering_stiffness(0.0, load, k), _analytic_stiffness(tire, load), rtol=1e-14)
    big = 0.05
    np.testing.assert_allclose(
        cornering_stiffness(big, load, k), lateral_tire_force(big, load, k) / big, rtol=1e-14
    )


def test_load_transfer_obeys_static_balance():
    ay = np.array([-3.0, 0.0, 1.5, 4.0])  # m/s²
    fz = wheel_loads(ay, CAR)
    m, g, h, T = CAR.mass, GRAVITY, CAR.cog_height, CAR.track
    # vertical force balance
    np.testing.assert_allclose(fz.sum(axis=-1), m * g, rtol=1e-13)
    # roll moment about the contact line's midpoint: (right − left)·T/2 = m·h·a_y
    right_minus_left = fz[:, 1] + fz[:, 3] - fz[:, 0] - fz[:, 2]
    np.testing.assert_allclose(right_minus_left * T / 2, m * h * ay, rtol=1e-13, atol=1e-9)
    # pitch moment about the centre of gravity (no longitudinal acceleration)
    front, rear = fz[:, 0] + fz[:, 1], fz[:, 2] + fz[:, 3]
    np.testing.assert_allclose(front * CAR.front_length, rear * CAR.rear_length, rtol=1e-13)


def _steady_state(tires, steer, speed=20.0, seconds=20.0):
    t = np.arange(0.0, seconds, DT)
    sim = simulate_two_track(np.full_like(t, steer), speed, tires, CAR, dt=DT)
    return sim.yaw_rate[0, -1], sim.lateral_acceleration[0, -1]


@pytest.mark.parametrize("front_deflated", [False, True])
def test_steady_state_cornering_matches_linear_bicycle_model(front_deflated):
    number = 12 if front_deflated else NOMINAL_MODEL  # 12: both front tyres deflated
    tires = bank_tires(number)
    loads = wheel_loads(0.0, CAR)
    front_tire = DEFLATED_TIRE if front_deflated else NOMINAL_TIRE
    c_front = 2 * _analytic_stiffness(front_tire, loads[0])
    c_rear = 2 * _analytic_stiffness(NOMINAL_TIRE, loads[2])
    L, m, lv, lh = CAR.wheelbase, CAR.mass, CAR.front_length, CAR.rear_length
    understeer = m / L * (lh / c_front - lv / c_rear)  # rad per m/s², linear bicycle model
    speed, steer = 20.0, 2e-3
    yaw_rate, ay = _steady_state(tires, steer, speed=speed)
    gain = speed / (L + understeer * speed**2)
    # small steer (a_y ≈ 0.5 m/s²): the load-transfer and arctan terms are second and third order
    np.testing.assert_allclose(yaw_rate / steer, gain, rtol=2e-3)
    np.testing.assert_allclose(ay, speed * yaw_rate, rtol=1e-9)  # steady state: β̇ = 0
    measured_understeer = (steer - L * yaw_rate / speed) / ay
    np.testing.assert_allclose(measured_understeer, understeer, rtol=2e-2)


def test_left_and_right_turns_mirror():
    """Eq. 2 and eq. 9 as printed break this symmetry; the implemented model keeps it."""
    t = np.arange(0.0, 8.0, DT)
    steer = _lane_change(t, amplitude=np.deg2rad(2.0))
    tires = bank_tires(16)
    left = simulate_two_track(steer, SPEED, tires, CAR, dt=DT)
    right = simulate_two_track(-steer, SPEED, tires, CAR, dt=DT)
    np.testing.assert_allclose(right.yaw_rate, -left.yaw_rate, rtol=0, atol=1e-13)
    np.testing.assert_allclose(right.wheel_loads, left.wheel_loads[..., [1, 0, 3, 2]], rtol=1e-13)
    ang = steering_angles(np.array([0.1, -0.1]), CAR)
    assert ang[0, 0] > ang[0, 1]  # left turn: the left (inner) wheel steers more
    assert abs(ang[1, 1]) > abs(ang[1, 0])  # right turn: the right (inner) wheel steers more


def test_sideslip_integration_recovers_the_simulated_sideslip():
    t = np.arange(0.0, 8.0, DT)
    sim = simulate_two_track(_lane_change(t), SPEED, bank_tires(8), CAR, dt=DT)
    beta = sideslip_from_measurements(sim.lateral_acceleration, sim.yaw_rate, SPEED, dt=DT)
    # trapezoid on the sampled derivative vs RK4: O(dt²) of a ~1e-3 rad signal
    np.testing.assert_allclose(beta, sim.sideslip, rtol=0, atol=2e-5 * np.abs(sim.sideslip).max() / 1e-3)


def test_model_numbering_round_trip():
    seen = set()
    for n in range(1, 17):
        flags = deflated_wheels(n)
        assert model_number(flags) == n
        seen.add(flags)
        np.testing.assert_array_equal(
            bank_tires(n)[:, 1], [DEFLATED_TIRE.k2 if f else NOMINAL_TIRE.k2 for f in flags]
        )
    assert len(seen) == 16
    assert deflated_wheels(8) == (True, False, False, False)  # the paper's model 8: front left
    assert deflated_wheels(16) == (False, False, False, False)
    assert deflated_wheels(15) == (True, True, True, True)


def _detect(steer, sim):
    return detect_deflation(
        steer, SPEED, sim.lateral_acceleration, sim.yaw_rate, CAR, dt=DT,
        instant_weight=0.5, integral_weight=1.0, forgetting_rate=0.2,
    )


@pytest.mark.filterwarnings("ignore:a wheel load reached k1")  # deflated front models, rear-failure runs
def test_batched_equals_one_by_one():
    t = np.arange(0.0, 6.0, DT)
    steer = np.stack([_lane_change(t), 0.5 * _lane_change(t), -_lane_change(t)])
    tires = bank_tires()[[7, 15, 2]]
    batch = simulate_two_track(steer, SPEED, tires, CAR, dt=DT)
    det = _detect(steer, batch)
    for k in range(3):
        one = simulate_two_track(steer[k], SPEED, tires[k], CAR, dt=DT)
        np.testing.assert_array_equal(one.yaw_rate[0], batch.yaw_rate[k])
        np.testing.assert_array_equal(one.lateral_acceleration[0], batch.lateral_acceleration[k])
        d1 = _detect(steer[k], one)
        np.testing.assert_array_equal(d1.selected[0], det.selected[k])
        np.testing.assert_array_equal(d1.cost[0], det.cost[k])


@pytest.mark.filterwarnings("ignore:a wheel load reached k1")
def test_detector_picks_the_truth_model_on_noise_free_data():
    t = np.arange(0.0, 6.0, DT)
    steer = np.tile(_lane_change(t), (16, 1))
    sim = simulate_two_track(steer, SPEED, bank_tires(), CAR, dt=DT)
    det = _detect(steer, sim)
    np.testing.assert_array_equal(det.selected[:, -1], np.arange(1, 17))
    # before the steering starts every model fits: the tie goes to the nominal model
    assert np.all(det.selected[:, t < 1.0] == NOMINAL_MODEL)
    # eq. 15 on the front-left failure: the selected model's secant stiffnesses are the truth's
    truth_c = cornering_stiffness(sim.slip_angles[7], sim.wheel_loads[7], bank_tires(8))
    late = t > 2.0
    np.testing.assert_allclose(det.cornering_stiffness[7, late], truth_c[late], rtol=2e-2)
    assert np.all(det.cornering_stiffness[7, late, 0] < 0.7 * det.cornering_stiffness[7, late, 1])


def _zero_detect(**override):
    args = dict(steer=np.zeros(5), speed=SPEED, lateral_acceleration=np.zeros(5), yaw_rate=np.zeros(5),
                vehicle=CAR, dt=DT, instant_weight=0.0, integral_weight=1.0, forgetting_rate=0.0)
    args.update(override)
    return detect_deflation(**args)


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: TwoTrackVehicle(-1300.0, 1200.0, 1.2, 1.3, 0.7, 1.5), "mass"),
        (lambda: ArctanTire(1.0, 0.0, 15.0), "k2"),
        (lambda: wheel_loads(12.0, CAR), "lateral_acceleration"),
        (lambda: deflated_wheels(17), "model number"),
        (lambda: model_number([1, 0, 0]), "deflated"),
        (lambda: simulate_two_track(np.zeros(5), 0.0, bank_tires(16), CAR, dt=DT), "speed"),
        (lambda: simulate_two_track(np.zeros(5), SPEED, np.ones((4, 2)), CAR, dt=DT), "tires"),
        (lambda: _zero_detect(lateral_acceleration=[0, 0, np.nan, 0, 0]), "lateral_acceleration"),
        (lambda: _zero_detect(forgetting_rate=-1.0), "forgetting_rate"),
        (lambda: _zero_detect(yaw_rate=np.zeros(4)), "broadcast"),
        (lambda: _zero_detect(dt=0.0), "dt"),
        (lambda: _zero_detect(instant_weight=0.0, integral_weight=0.0), "integral_weight"),
        (lambda: _zero_detect(error_scale=(1.0, 0.0)), "error_scale"),
    ],
)
def test_bad_input_raises_input_error_naming_the_field(call, field):
    with pytest.raises(InputError, match=field):
        call()


def test_given_sideslip_replaces_eq10():
    """``sideslip=`` with eq. 10's own output changes nothing; with noise, the true β keeps model 8."""
    t = np.arange(0.0, 8.0, DT)
    steer = _lane_change(t)
    sim = simulate_two_track(steer, SPEED, bank_tires(8), CAR, dt=DT)
    rng = np.random.default_rng(0)
    shape = sim.yaw_rate.shape
    ay = sim.lateral_acceleration + 0.05 * rng.standard_normal(shape)  # m/s², the bench's ESC-grade noise
    r = sim.yaw_rate + np.deg2rad(0.2) * rng.standard_normal(shape)  # rad/s
    cost = dict(instant_weight=0.0, integral_weight=1.0, forgetting_rate=0.0)
    own = detect_deflation(steer, SPEED, ay, r, CAR, dt=DT, **cost)
    again = detect_deflation(steer, SPEED, ay, r, CAR, dt=DT, sideslip=own.measured_sideslip, **cost)
    np.testing.assert_array_equal(again.cost, own.cost)
    ideal = detect_deflation(steer, SPEED, ay, r, CAR, dt=DT, sideslip=sim.sideslip, **cost)
    assert ideal.selected[0, -1] == 8
    with pytest.raises(InputError, match="sideslip"):
        detect_deflation(steer, SPEED, ay, r, CAR, dt=DT, sideslip=np.zeros(3), **cost)


def test_a_per_axle_bank_puts_each_axles_tyre_on_its_wheels():
    front_nom, rear_nom = ArctanTire(1.0, 6000.0, 10.0), ArctanTire(1.2, 9000.0, 16.0)
    front_def, rear_def = ArctanTire(1.1, 5000.0, 8.0), ArctanTire(1.3, 8000.0, 13.0)
    bank = bank_tires(nominal=(front_nom, rear_nom), deflated=(front_def, rear_def))
    expected = {  # model number: the tyres of FL, FR, RL, RR written out by hand
        8: (front_def, front_nom, rear_nom, rear_nom),
        4: (front_nom, front_def, rear_nom, rear_nom),
        3: (front_nom, front_nom, rear_def, rear_def),
        9: (front_def, front_nom, rear_nom, rear_def),
        16: (front_nom, front_nom, rear_nom, rear_nom),
        15: (front_def, front_def, rear_def, rear_def),
    }
    for number, tyres in expected.items():
        np.testing.assert_array_equal(bank[number - 1], [[t.k1, t.k2, t.k3] for t in tyres])
    with pytest.raises(InputError, match="front, rear"):
        bank_tires(nominal=(front_nom,), deflated=front_def)


def test_given_wheel_loads_replace_eq7():
    t = np.arange(0.0, 6.0, DT)
    steer = _lane_change(t)
    sim = simulate_two_track(steer, SPEED, bank_tires(8), CAR, dt=DT)
    kwargs = dict(dt=DT, instant_weight=0.0, integral_weight=1.0, forgetting_rate=0.0)
    plain = detect_deflation(steer, SPEED, sim.lateral_acceleration, sim.yaw_rate, CAR, **kwargs)
    eq7 = wheel_loads(sim.lateral_acceleration, CAR)  # the loads eq. 7 gives: the same detection
    given = detect_deflation(steer, SPEED, sim.lateral_acceleration, sim.yaw_rate, CAR,
                             wheel_load=eq7, **kwargs)  # fmt: skip
    np.testing.assert_array_equal(given.selected, plain.selected)
    np.testing.assert_allclose(given.cost, plain.cost, rtol=1e-12)
    heavier = detect_deflation(steer, SPEED, sim.lateral_acceleration, sim.yaw_rate, CAR,
                               wheel_load=eq7 * 1.1, **kwargs)  # fmt: skip
    assert not np.allclose(heavier.cost, plain.cost)  # the loads do enter
    with pytest.raises(InputError, match="wheel_load"):
        detect_deflation(steer, SPEED, sim.lateral_acceleration, sim.yaw_rate, CAR,
                         wheel_load=np.ones(3), **kwargs)  # fmt: skip
