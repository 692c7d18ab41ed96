"""Half-car input estimation on the MuJoCo SUV (suvtwin.pipeline.input_estimation).

References independent of the code under test: the parameter file's numbers, the analytic
bump shape, the static weight shares, a linear half car integrated by scipy's solve_ivp,
and Newton's law on the simulated body.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from scipy.integrate import solve_ivp

from suvtwin.errors import InputError
from suvtwin.estimators.input_estimation import continuous_matrices
from suvtwin.mjcf.vehicle import CORNERS, GRAVITY, load_vehicle
from suvtwin.pipeline.input_estimation import (
    closure_error,
    estimate_run,
    half_car_from_vehicle,
    model_input,
    obstacle_scenario,
    scores,
    stiffness_damping,
    suspension_loads,
)
from suvtwin.roads.profile import generate_road

VEHICLE = load_vehicle()
CAR = half_car_from_vehicle(VEHICLE)


def test_half_car_takes_the_suv_parameters():
    assert CAR.mass == 1788.0
    assert CAR.pitch_inertia == 3200.0
    assert (CAR.front_length, CAR.rear_length) == (1.347, 1.471)
    assert (CAR.front_stiffness, CAR.rear_stiffness) == (2 * 32000.0, 2 * 38000.0)
    assert CAR.front_damping == CAR.rear_damping == 2 * (1100.0 + 3300.0) / 2


def test_mass_stiffness_damping_reproduce_the_state_matrix():
    M, K, C = stiffness_damping(CAR)
    F, _, _ = continuous_matrices(CAR)
    Minv = np.linalg.inv(M)
    assert -Minv @ K == pytest.approx(F[[1, 3]][:, [0, 2]])
    assert -Minv @ C == pytest.approx(F[[1, 3]][:, [1, 3]])
    assert K == pytest.approx(K.T) and C == pytest.approx(C.T)


@pytest.mark.parametrize("kind", ["sine_bump", "cleat"])
def test_obstacle_scenario_puts_the_paper_obstacle_on_both_tracks(kind):
    speed_kmh, lead = 60.0, 0.3
    scenario = obstacle_scenario(kind, speed_kmh=speed_kmh, lead_s=lead)
    road = generate_road(scenario.road, seed=scenario.road_seed())
    start = 10.0 + VEHICLE.chassis.a2 + VEHICLE.chassis.a1 + speed_kmh / 3.6 * lead  # front axle at t = lead
    s = road.x - start
    inside = (s > 1e-9) & (s < 1.0 - 1e-9)
    expected = 0.1 * np.sin(np.pi * s[inside]) if kind == "sine_bump" else np.full(inside.sum(), 0.1)
    for track in (0, 1):
        assert road.z[track, inside] == pytest.approx(expected, abs=1e-5)  # base road: micrometres
        assert np.abs(road.z[track, (s < -0.01) | (s > 1.01)]).max() < 1e-5


def test_at_rest_each_corner_carries_its_static_weight_share():
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    table = simulate(parse_scenario({"duration_s": 1.0, "speed_kmh": 0.0, "road": "flat"})).table
    a1, a2 = VEHICLE.chassis.a1, VEHICLE.chassis.a2
    share = 0.5 * VEHICLE.chassis.mass * GRAVITY * np.array([a2, a2, a1, a1]) / VEHICLE.wheelbase
    for i, c in enumerate(CORNERS):
        assert table[f"{c}_susp_force_n"].iloc[-1] == pytest.approx(share[i], rel=5e-3)
    loads = suspension_loads(table, VEHICLE)
    weight = VEHICLE.chassis.mass * GRAVITY
    assert np.abs(loads[:, 0]).max() < 5e-3 * weight  # N
    assert np.abs(loads[:, 1]).max() < 5e-3 * weight * VEHICLE.wheelbase  # N m


def _linear_run(u_fn, duration=1.2, dt=1e-3):
    """A fake run file: the linear half car driven by u_fn(t), integrated by solve_ivp.

    The corner forces are those that put [F_s, T_s] = u − Kx − Cẋ (plus the weight) on the body.
    """
    F, G, _ = continuous_matrices(CAR)
    t = np.arange(int(round(duration / dt)) + 1) * dt
    rhs = lambda s, X: F @ X + G @ u_fn(s)  # noqa: E731
    sol = solve_ivp(rhs, (0, t[-1]), np.zeros(4), t_eval=t, rtol=1e-10, atol=1e-13)
    X = sol.y.T
    _, K, C = stiffness_damping(CAR)
    u = np.array([u_fn(s) for s in t])
    loads = u - X[:, [0, 2]] @ K.T - X[:, [1, 3]] @ C.T
    a1, a2, lw = CAR.front_length, CAR.rear_length, CAR.wheelbase
    mg = CAR.mass * GRAVITY
    front = 0.5 * (a2 * mg + a2 * loads[:, 0] + loads[:, 1]) / lw
    rear = 0.5 * (a1 * mg + a1 * loads[:, 0] - loads[:, 1]) / lw
    table = pd.DataFrame({"t_s": t, "heave_m": X[:, 0], "pitch_rad": -X[:, 2]})
    for c, f in zip(CORNERS, (front, front, rear, rear), strict=True):
        table[f"{c}_susp_force_n"] = f
    return table, u, loads


def _u(s):
    return np.array([3000.0 * np.sin(2 * np.pi * 2.0 * s) + 1000.0, 2000.0 * np.cos(2 * np.pi * 1.5 * s)])


def test_truths_of_a_linear_half_car():
    table, u, loads = _linear_run(_u)
    assert suspension_loads(table, VEHICLE) == pytest.approx(loads, abs=1e-6)
    assert scores(u, model_input(table, CAR, VEHICLE))["same_index"].max() < 0.5  # central differences


@pytest.mark.parametrize("method", ["CIE f=0.1", "AWIE"])
def test_estimator_recovers_the_input_of_a_linear_half_car(method):
    table, u, loads = _linear_run(_u)
    r = estimate_run(table, method=method, measurement_std=1e-8, seed=3, runs=2, vehicle=VEHICLE)
    assert r.estimate.shape == (2, len(table), 2)
    assert scores(r.truth_input, r.estimate)["aligned"].max() < 8.0  # with the start-up transient
    late = slice(200, None)  # after 0.2 s
    assert scores(r.truth_input[late], r.estimate[:, late])["aligned"].max() < 2.0
    assert scores(r.truth_suspension[late], r.estimate_suspension[:, late])["aligned"].max() < 2.0
    assert r.truth_suspension == pytest.approx(loads, abs=1e-6)


def test_on_the_suv_the_body_obeys_the_suspension_loads_and_awie_tracks_them():
    from suvtwin.pipeline.simulator import simulate

    table = simulate(obstacle_scenario("sine_bump", speed_kmh=60, duration_s=1.0)).table
    closure = closure_error(table, CAR, VEHICLE)
    assert closure[0] < 2.0  # heave: Newton on the body, the slide axes tilt by the pitch
    assert closure[1] < 12.0  # pitch: the tyres' longitudinal forces reach the body through the joints
    r = estimate_run(table, method="AWIE", measurement_std=1e-8, seed=0, vehicle=VEHICLE)
    s = scores(r.truth_input, r.estimate[0])
    assert s["aligned"][0] < 15.0 and s["aligned"][1] < 25.0
    assert np.abs(s["eq32"]).max() < 2.0
    # the truth is real: the bump raises the vertical force by tens of kN
    assert np.abs(r.truth_suspension[:, 0]).max() > 1e4


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda t: estimate_run(t, method="KF"), "method"),
        (lambda t: estimate_run(t, measurement_std=-1.0), "measurement_std"),
        (lambda t: estimate_run(t, measurement_std=0.0), "filter_std"),
        (lambda t: estimate_run(t, input_noise=0.0), "input_noise"),
        (lambda t: estimate_run(t.drop(columns="heave_m")), "heave_m"),
        (lambda t: obstacle_scenario("speed_bump", speed_kmh=30), "road"),
        (lambda t: obstacle_scenario("cleat", speed_kmh=500), "speed_kmh"),
    ],
)
def test_bad_input_names_the_field(call, field):
    table, _, _ = _linear_run(_u, duration=0.05)
    with pytest.raises(InputError, match=field):
        call(table)


def test_nan_in_a_run_is_input_error():
    table, _, _ = _linear_run(_u, duration=0.05)
    table.loc[3, "pitch_rad"] = np.nan
    with pytest.raises(InputError, match="pitch_rad"):
        estimate_run(table)
