"""Half-car input estimation (Lin et al. 2021, CIE and AWIE) against independent references.

Discretization against scipy's ZOH and a quadrature; the exact inputs against the car driven
by the road itself (solve_ivp); the Kalman filter against the discrete algebraic Riccati
equation; the recursive least squares against the batch weighted least-squares solution it
claims to compute; the batch against one-by-one runs.
"""

import numpy as np
import pytest
from scipy.integrate import quad_vec, solve_ivp
from scipy.linalg import expm, solve_discrete_are
from scipy.signal import cont2discrete

from suvtwin.errors import InputError
from suvtwin.estimators.input_estimation import (
    PAPER_HALF_CAR,
    HalfCar,
    cleat_inputs,
    continuous_matrices,
    discretize,
    estimate_inputs,
    norm_difference_error,
    normalized_error,
    road_inputs,
    simulate_measurements,
    sine_bump_inputs,
)

CAR = PAPER_HALF_CAR
DT = 1e-3


def _road_driven_rhs(road):
    """Eq. 1–2 written from the spring and damper forces (not from eq. 3–4's matrices).

    ``road(t) -> (z_front, zdot_front, z_rear, zdot_rear)``. Signs: front axle at +L_F,
    a compressed spring pushes the body up; pitch positive nose up.
    """
    c = CAR

    def rhs(t, x):
        z, zd, th, thd = x
        zf, vf, zr, vr = road(t)
        f_front = c.front_stiffness * (z + c.front_length * th - zf) + c.front_damping * (
            zd + c.front_length * thd - vf
        )
        f_rear = c.rear_stiffness * (z - c.rear_length * th - zr) + c.rear_damping * (
            zd - c.rear_length * thd - vr
        )
        zdd = -(f_front + f_rear) / c.mass
        thdd = (f_rear * c.rear_length - f_front * c.front_length) / c.pitch_inertia
        return [zd, zdd, thd, thdd]

    return rhs


def _input_driven_rhs(inputs_of_t):
    F, G, _ = continuous_matrices(CAR)
    return lambda t, x: F @ x + G @ inputs_of_t(t)


def _solve(rhs, t_end, t_eval, breaks=()):
    """Integrate from rest, restarting at the forcing's discontinuities `breaks` (s)."""
    edges = np.unique(np.concatenate([[0.0], [b for b in breaks if 0.0 < b < t_end], [t_end]]))
    x0, out = np.zeros(4), np.empty((len(t_eval), 4))
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        # the forcing is evaluated strictly inside the segment (its one-sided limits at the ends)
        seg = solve_ivp(lambda t, x, a=a, b=b: rhs(np.clip(t, a + 1e-12, b - 1e-12), x),
                        (a, b), x0, rtol=1e-11, atol=1e-14, method="DOP853", dense_output=True)
        assert seg.success
        inside = (t_eval >= a) & (t_eval <= b)
        if inside.any():
            out[inside] = seg.sol(t_eval[inside]).T
        x0 = seg.y[:, -1]
    return out


# --- model and discretization -------------------------------------------------------------


def test_discretization_matches_scipy_zoh_and_quadrature():
    F, G, H = continuous_matrices(CAR)
    sys_ = discretize(CAR, dt=DT)
    Phi_ref, Gamma_ref, *_ = cont2discrete((F, G, H, np.zeros((2, 2))), DT, method="zoh")
    gamma_quad, _ = quad_vec(lambda s: expm(F * s) @ G, 0.0, DT, epsabs=1e-16, epsrel=1e-12)
    # both are exact up to rounding; Gamma's entries are ~1e-10 (m/N per step)
    np.testing.assert_allclose(sys_.Phi, Phi_ref, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sys_.Gamma, Gamma_ref, rtol=1e-10, atol=1e-20)
    np.testing.assert_allclose(sys_.Gamma, gamma_quad, rtol=1e-8, atol=1e-20)


def test_state_matrices_are_the_force_equations():
    """F and G (eq. 4) against finite differences of eq. 1–2 written from the forces."""
    F, G, _ = continuous_matrices(CAR)
    still = (0.0, 0.0, 0.0, 0.0)
    rhs = _road_driven_rhs(lambda t: still)
    eps = 1e-6
    columns = [(np.array(rhs(0, eps * e)) - np.array(rhs(0, -eps * e))) / (2 * eps) for e in np.eye(4)]
    jac = np.column_stack(columns)
    np.testing.assert_allclose(F, jac, rtol=1e-9, atol=1e-9)
    # a road under the axles acts as G @ road_inputs (eq. 3's right-hand side)
    road = (0.01, 0.2, -0.02, 0.1)
    acc = np.array(_road_driven_rhs(lambda t: road)(0.0, np.zeros(4)))
    np.testing.assert_allclose(acc, G @ road_inputs(CAR, *road), rtol=1e-12, atol=1e-12)


# --- exact inputs (eq. 25–28) against the car driven by the road ---------------------------


@pytest.mark.parametrize("speed_kmh", [30.0, 90.0])
def test_sine_bump_inputs_drive_the_car_as_the_road_does(speed_kmh):
    v, h0, D = speed_kmh / 3.6, 0.1, 1.0
    w, L = np.pi * v / D, CAR.wheelbase

    def bump(s):  # elevation and its rate at distance s past the bump's start
        on = (s >= 0) & (s <= D)
        height = np.where(on, h0 * np.sin(np.pi * s / D), 0.0)
        return height, np.where(on, h0 * w * np.cos(np.pi * s / D), 0.0)

    def road(t):
        zf, vf = bump(v * t)
        zr, vr = bump(v * t - L)
        return zf, vf, zr, vr

    t_eval = np.linspace(0.0, 1.2, 601)
    breaks = (D / v, L / v, (L + D) / v)
    x_road = _solve(_road_driven_rhs(road), 1.2, t_eval, breaks)
    x_eq25 = _solve(_input_driven_rhs(lambda t: sine_bump_inputs(CAR, t, speed=v, height=h0, length=D)),
                    1.2, t_eval, breaks)
    scale = np.abs(x_road).max(axis=0)
    # both integrate the same piecewise-smooth forcing at rtol 1e-11; 1e-6 of the peak is loose
    np.testing.assert_allclose(x_eq25 / scale, x_road / scale, atol=1e-6)
    # the rear wheel acts (the printed window U_tL - U_tp1 would remove it)
    u = sine_bump_inputs(CAR, t_eval, speed=v, height=h0, length=D)
    rear = (t_eval > L / v) & (t_eval < (L + D) / v)
    assert np.abs(u[rear]).max() > 0.5 * CAR.rear_stiffness * h0


def test_cleat_inputs_omit_the_damper_impulses():
    """A car on a (steep) cleat = eq. 27–28 + an impulse C·h0 at the front edge."""
    v, h0, D, ramp = 30.0 / 3.6, 0.1, 1.0, 1e-3  # cleat edges rise over 1 mm (0.12 ms)

    def cleat(s):
        x = np.clip(s / ramp, 0.0, 1.0)
        smooth = x * x * (3 - 2 * x)  # smoothstep up at s = 0
        rate = np.where((s > 0) & (s < ramp), 6 * x * (1 - x) / ramp * v, 0.0)
        return h0 * smooth, h0 * rate

    def road(t):
        zf, vf = cleat(v * t)
        return zf, vf, 0.0, 0.0

    t_end = 0.1  # before the front wheel leaves the cleat (0.12 s)
    t_eval = np.array([t_end])
    x_road = _solve(_road_driven_rhs(road), t_end, t_eval, (ramp / v,))[0]
    x_eq27 = _solve(_input_driven_rhs(lambda t: cleat_inputs(CAR, t, speed=v, height=h0, length=D)),
                    t_end, t_eval)[0]
    F, G, _ = continuous_matrices(CAR)
    impulse = np.array([CAR.front_damping * h0, CAR.front_damping * h0 * CAR.front_length])  # N s, N m s
    x_impulse = expm(F * t_end) @ G @ impulse
    scale = np.abs(x_road)
    # the ramp spreads the impulse over 0.12 ms: an O(ramp/v) error, ~1e-3 of the response
    np.testing.assert_allclose(x_eq27 + x_impulse, x_road, rtol=0, atol=2e-3 * scale.max())
    # and the omission is not small: the impulse is a large part of the response
    assert np.abs(x_impulse[1]) > 0.3 * np.abs(x_road[1])


def test_random_road_literal_inputs_are_collinear():
    """Eq. 29–30: both wheels on the same elevation, no dampers -> T/F is one constant."""
    z = np.random.default_rng(3).normal(0.0, 0.01, 200)
    u = road_inputs(CAR, z, 0.0, z, 0.0)
    ratio = (CAR.front_stiffness * CAR.front_length - CAR.rear_stiffness * CAR.rear_length) / (
        CAR.front_stiffness + CAR.rear_stiffness
    )
    np.testing.assert_allclose(u[:, 1], ratio * u[:, 0], rtol=1e-12)
    np.testing.assert_allclose(u[:, 0], 10000.0 * z, rtol=1e-12)  # (K_F + K_R) z, eq. 29


# --- the Kalman filter and the recursive least squares ------------------------------------


def test_kalman_gain_reaches_the_steady_state_riccati_solution():
    sys_ = discretize(CAR, dt=DT)
    q, sigma = 1e4, 1e-4
    R = np.eye(2) * sigma**2
    GQG = sys_.Gamma @ (q * np.eye(2)) @ sys_.Gamma.T
    P_prior = solve_discrete_are(sys_.Phi.T, sys_.H.T, GQG, R)
    S_ref = sys_.H @ P_prior @ sys_.H.T + R
    K_ref = P_prior @ sys_.H.T @ np.linalg.inv(S_ref)
    est = estimate_inputs(np.zeros((3000, 2)), sys_, input_noise=q, measurement_std=sigma, fading=0.5,
                          state_covariance0=1.0)
    # the recursion converges geometrically; after 3 s it agrees to the DARE's own precision
    np.testing.assert_allclose(est.kalman_gain[-1], K_ref, rtol=1e-6, atol=1e-9 * np.abs(K_ref).max())
    np.testing.assert_allclose(est.innovation_covariance[-1], S_ref, rtol=1e-6)


def _weighted_least_squares(est, weights, k, u0, Pb0):
    """The minimizer of sum_j w_j |Zbar(j) - B(j) u|^2_{S(j)^-1} + w_0 |u - u0|^2_{Pb0^-1}."""
    A = weights[0] * np.linalg.inv(Pb0)
    b = A @ u0
    for j in range(1, k + 1):
        B, Si = est.sensitivity[j], np.linalg.inv(est.innovation_covariance[j])
        A = A + weights[j] * B.T @ Si @ B
        b = b + weights[j] * B.T @ Si @ est.innovations[j]
    return np.linalg.solve(A, b)


@pytest.mark.parametrize("fading", [1.0, 0.9, "adaptive"])
def test_rls_is_the_exponentially_weighted_least_squares_solution(fading):
    """Eq. 17–22 claim to minimize the faded sum of squared innovation residuals; check the sum."""
    sys_ = discretize(CAR, dt=DT)
    t = np.arange(301) * DT
    u = sine_bump_inputs(CAR, t, speed=60 / 3.6, height=0.1, length=1.0)
    sigma = 1e-7
    _, z = simulate_measurements(sys_, u, measurement_std=sigma, rng=np.random.default_rng(5))
    Pb0 = np.diag([1e6, 1e5])
    est = estimate_inputs(z[0], sys_, input_noise=1e2, measurement_std=sigma, fading=fading,
                          input_covariance0=Pb0)
    for k in (40, 150, 300):
        gam = est.fading[: k + 1].copy()
        gam[0] = 1.0
        # weight of step j at time k: product of the fading factors applied after it
        weights = np.array([np.prod(gam[j + 1 : k + 1]) for j in range(k + 1)])
        ref = _weighted_least_squares(est, weights, k, np.zeros(2), Pb0)
        np.testing.assert_allclose(est.inputs[k], ref, rtol=1e-6, atol=1e-6 * np.abs(ref).max())


def test_rls_recovers_a_constant_and_a_step_input():
    sys_ = discretize(CAR, dt=DT)
    n = 600
    u = np.tile([800.0, -300.0], (n, 1))
    u[300:] = [-200.0, 500.0]
    _, z = simulate_measurements(sys_, u, measurement_std=1e-8, rng=np.random.default_rng(11), n_runs=2)
    plain = estimate_inputs(z, sys_, input_noise=1e2, measurement_std=1e-8, fading=1.0)
    # without fading, least squares over the 300 steps before the step: well inside 1 %
    np.testing.assert_allclose(plain.inputs[:, 300], np.broadcast_to([800.0, -300.0], (2, 2)), rtol=1e-2)
    for fading in (0.5, "adaptive"):
        est = estimate_inputs(z, sys_, input_noise=1e2, measurement_std=1e-8, fading=fading)
        np.testing.assert_allclose(est.inputs[:, 299], np.broadcast_to([800.0, -300.0], (2, 2)), rtol=0.05)
        # 50 steps after the step the faded estimator has followed it
        np.testing.assert_allclose(est.inputs[:, 350:].mean(axis=1), np.broadcast_to([-200.0, 500.0], (2, 2)),
                                   rtol=0.05)
    # plain least squares cannot follow the step (it averages the whole record)
    assert abs(plain.inputs[0, -1, 0] - (-200.0)) > 100.0


def test_awie_fading_is_in_range_and_follows_eq_20():
    sys_ = discretize(CAR, dt=DT)
    t = np.arange(1201) * DT
    u = cleat_inputs(CAR, t, speed=30 / 3.6, height=0.1, length=1.0)
    sigma = 1e-8
    _, z = simulate_measurements(sys_, u, measurement_std=sigma, rng=np.random.default_rng(2), n_runs=3)
    est = estimate_inputs(z, sys_, input_noise=1e2, measurement_std=sigma, fading="adaptive")
    g = est.fading[:, 1:]
    assert np.all(g > 0.0) and np.all(g <= 1.0)
    norm = np.linalg.norm(est.innovations[:, 1:], axis=-1)
    np.testing.assert_allclose(g, np.where(norm <= sigma, 1.0, sigma / norm), rtol=1e-12)
    # both branches occur on this record
    assert (g == 1.0).any() and (g < 0.1).any()


@pytest.mark.parametrize("fading", [0.1, "adaptive"])
def test_batched_equals_one_by_one(fading):
    sys_ = discretize(CAR, dt=DT)
    t = np.arange(400) * DT
    u = sine_bump_inputs(CAR, t, speed=90 / 3.6, height=0.1, length=1.0)
    _, z = simulate_measurements(sys_, u, measurement_std=1e-7, rng=np.random.default_rng(4), n_runs=3)
    batch = estimate_inputs(z, sys_, input_noise=1e2, measurement_std=1e-7, fading=fading)
    for r in range(3):
        one = estimate_inputs(z[r], sys_, input_noise=1e2, measurement_std=1e-7, fading=fading)
        # the same arithmetic on a (3, .) or (1, .) array: equal to rounding
        np.testing.assert_allclose(batch.inputs[r], one.inputs, rtol=1e-10, atol=1e-8)
        np.testing.assert_allclose(batch.states[r], one.states, rtol=1e-10, atol=1e-18)
        np.testing.assert_allclose(batch.fading[r], one.fading, rtol=1e-10)


def test_paper_sine_bump_end_to_end():
    """60 km/h, sigma = 1e-8, CIE f_tr = 0.1: the norm reading is small, the standard one is not."""
    sys_ = discretize(CAR, dt=DT)
    t = np.arange(1201) * DT
    u = sine_bump_inputs(CAR, t, speed=60 / 3.6, height=0.1, length=1.0)
    _, z = simulate_measurements(sys_, u, measurement_std=1e-8, rng=np.random.default_rng(0), n_runs=4)
    est = estimate_inputs(z, sys_, input_noise=1e2, measurement_std=1e-8, fading=0.1)
    aligned = normalized_error(u[:-1], est.inputs[:, 1:])  # u_hat(k) estimates u(k-1)
    norms = np.abs(norm_difference_error(u, est.inputs))
    assert np.all(norms < 3.0)  # the paper's Table 3 cell: 0.74 % / 0.30 %
    assert np.all(aligned > 10.0) and np.all(aligned < 40.0)


def test_error_metrics_on_known_signals():
    u = np.array([[1.0, 2.0], [1.0, 2.0], [1.0, 2.0], [1.0, 2.0]])
    uh = u.copy()
    uh[3] = 0.0
    np.testing.assert_allclose(normalized_error(u, uh), [50.0, 50.0])
    # a signal and its one-sample delay: same norm, wrong timing
    alternating = u * np.array([[1.0], [-1.0], [1.0], [-1.0]])
    delayed = np.roll(alternating, 1, axis=0)
    np.testing.assert_allclose(norm_difference_error(alternating, delayed), [0.0, 0.0])
    np.testing.assert_allclose(normalized_error(alternating, delayed), [200.0, 200.0])
    # eq. 32 as printed has units 1/N: the channel twice as large in N gets half the value
    printed = norm_difference_error(u, uh, printed=True)
    np.testing.assert_allclose(printed, 100 * (2 - np.sqrt(3)) / 4 / np.array([1.0, 2.0]))


# --- bad input -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"fading": 0.0}, "fading"),
        ({"fading": 1.5}, "fading"),
        ({"fading": "fast"}, "fading"),
        ({"measurement_std": -1e-8}, "measurement_std"),
        ({"measurement_std": [1e-8, np.nan]}, "measurement_std"),
        ({"input_noise": -1.0}, "input_noise"),
        ({"state_covariance0": np.ones((3, 3))}, "state_covariance0"),
    ],
)
def test_bad_settings_raise_input_error(kwargs, field):
    sys_ = discretize(CAR, dt=DT)
    settings = {"input_noise": 1e2, "measurement_std": 1e-8, "fading": 0.1} | kwargs
    with pytest.raises(InputError, match=field):
        estimate_inputs(np.zeros((10, 2)), sys_, **settings)


def test_bad_data_and_parameters_raise_input_error():
    sys_ = discretize(CAR, dt=DT)
    z = np.zeros((2, 10, 2))
    z[1, 4, 0] = np.nan
    with pytest.raises(InputError, match=r"measurements must be finite.*run 1, step 4"):
        estimate_inputs(z, sys_, input_noise=1e2, measurement_std=1e-8, fading=0.1)
    with pytest.raises(InputError, match="measurements must have shape"):
        estimate_inputs(np.zeros((10, 3)), sys_, input_noise=1e2, measurement_std=1e-8, fading=0.1)
    with pytest.raises(InputError, match=r"dt must be .*> 0"):
        discretize(CAR, dt=0.0)
    with pytest.raises(InputError, match=r"HalfCar.mass must be .*> 0 kg"):
        HalfCar(-1.0, 600, 5000, 5000, 500, 500, 0.8, 1.2)
    with pytest.raises(InputError, match=r"speed must be .*> 0 m/s"):
        sine_bump_inputs(CAR, [0.0], speed=-8.0, height=0.1, length=1.0)
    with pytest.raises(InputError, match=r"obstacle length must be"):
        cleat_inputs(CAR, [0.0], speed=8.0, height=0.1, length=0.0)
