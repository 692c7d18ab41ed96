"""Road-profile estimation (Wang et al. 2017, KF and MME&KF) against independent references.

Discretization against scipy's ZOH and a quadrature; A against the force equations; the road
model's PSD against ISO 8608's level (analytic) and against a Welch estimate of its own
output; the quarter-car truth against solve_ivp; the Kalman filter against the discrete
algebraic Riccati equation; MME against a known constant model error; batch against
one-by-one runs; bad input.
"""

import numpy as np
import pytest
from scipy.integrate import quad_vec, solve_ivp
from scipy.linalg import expm, solve_discrete_are
from scipy.signal import cont2discrete, welch

from suvtwin.errors import InputError
from suvtwin.estimators.road_estimation import (
    PAPER_QUARTER_CAR,
    QuarterCar,
    continuous_matrices,
    covariance_constraint_weight,
    discretize,
    error_input_matrix,
    error_std_percent,
    iso_road_model,
    kalman_filter,
    mme_kalman_filter,
    road_model_psd,
    simulate_quarter_car,
)
from suvtwin.roads.iso8608 import class_level, displacement_psd
from suvtwin.roads.profile import superposition_profile

CAR = PAPER_QUARTER_CAR
SPEED = 40.0 / 3.6
DT = 1e-3
ROAD_C = iso_road_model(class_level("C"), speed=SPEED)


def _forces_rhs(car, x, xr, xr_dot=0.0, road_acc=0.0):
    """Eq. 1 written from the spring, damper and tyre forces (not from eq. 4's matrix)."""
    xb, vb, xw, vw = x[:4]
    f_susp = car.suspension_stiffness * (xw - xb) + car.damping * (vw - vb)  # on the body, up
    f_tyre = car.tire_stiffness * (xr - xw)  # on the wheel, up
    return np.array([vb, f_susp / car.sprung_mass, vw, (f_tyre - f_susp) / car.unsprung_mass])


# --- model and discretization ---------------------------------------------------------------


def test_state_matrix_is_the_force_equations_with_the_sign_corrected():
    A, C = continuous_matrices(CAR, ROAD_C)
    eps = 1e-6
    jac = np.zeros((4, 6))
    for i, e in enumerate(np.eye(6)):
        xp, xm = eps * e, -eps * e
        jac[:, i] = (_forces_rhs(CAR, xp, xp[4]) - _forces_rhs(CAR, xm, xm[4])) / (2 * eps)
    np.testing.assert_allclose(A[:4], jac, rtol=1e-9, atol=1e-9)
    assert A[1, 0] == -CAR.suspension_stiffness / CAR.sprung_mass  # eq. 4 prints +ks/mb
    np.testing.assert_array_equal(C, A[[1, 3]])
    np.testing.assert_array_equal(A[5, 4:], [-ROAD_C.a1, -ROAD_C.a2])  # eq. 3


def test_discretization_matches_scipy_zoh_and_van_loan_quadrature():
    A, C = continuous_matrices(CAR, ROAD_C)
    exact = discretize(CAR, ROAD_C, dt=DT, method="exact", acceleration_noise=0.3)
    Phi_ref, *_ = cont2discrete((A, np.zeros((6, 1)), C, np.zeros((2, 1))), DT, method="zoh")
    np.testing.assert_allclose(exact.Phi, Phi_ref, rtol=1e-12, atol=1e-14)
    Qc = np.diag([0.0, 0.3, 0.0, 0.3, 0.0, ROAD_C.intensity])
    Q_ref, _ = quad_vec(lambda s: expm(A * s) @ Qc @ expm(A * s).T, 0.0, DT, epsabs=1e-18, epsrel=1e-11)
    # both exact; the quadrature is good to ~1e-10 relative
    np.testing.assert_allclose(exact.Q, Q_ref, rtol=1e-8, atol=1e-14 * np.abs(Q_ref).max())
    euler = discretize(CAR, ROAD_C, dt=DT, method="euler")  # eq. 7, literally
    np.testing.assert_array_equal(euler.Phi, np.eye(6) + A * DT)
    G = error_input_matrix("accelerations")
    np.testing.assert_array_equal(euler.error_transition(G), DT * G)
    gam_ref, _ = quad_vec(lambda s: expm(A * s) @ G, 0.0, DT, epsabs=1e-16, epsrel=1e-12)
    np.testing.assert_allclose(exact.error_transition(G), gam_ref, rtol=1e-8, atol=1e-16)


# --- the road model --------------------------------------------------------------------------


@pytest.mark.parametrize("road_class", ["B", "C", "D"])
def test_road_model_psd_follows_the_iso_level_between_its_poles(road_class):
    gd = class_level(road_class)
    road = iso_road_model(gd, speed=SPEED)
    f1, f2 = 0.011 * SPEED, 2.83 * SPEED  # Hz: the poles
    f = np.geomspace(10 * f1, f2 / 10, 30)
    iso = displacement_psd(f / SPEED, gd_n0=gd) / SPEED  # G(f) = Gd(n)/v, n = f/v
    # off the poles by a decade each side: (1 + (f1/f)^2)(1 + (f/f2)^2) <= 1.02
    np.testing.assert_allclose(road_model_psd(road, f), iso, rtol=0.021)
    # and it is the level: at n0 = 0.1 cycle/m, within the same 2 %
    g0 = road_model_psd(road, 0.1 * SPEED)
    assert abs(g0 * SPEED / gd - 1.0) < 0.021
    # below the low pole flat, above the high pole falling as f^-4
    assert road_model_psd(road, f1 / 100) / road_model_psd(road, f1 / 10) == pytest.approx(1.0, rel=0.02)
    hi = road_model_psd(road, np.array([20 * f2, 40 * f2]))
    assert hi[0] / hi[1] == pytest.approx(16.0, rel=0.02)


def test_road_model_output_has_the_analytic_psd():
    """The exact discrete model driven by its own noise: Welch against road_model_psd."""
    model = discretize(CAR, ROAD_C, dt=DT, method="exact")
    rng = np.random.default_rng(3)
    Lq = np.linalg.cholesky(model.Q[4:, 4:])
    Phi = model.Phi[4:, 4:]
    n, runs = 2**17, 4
    x = np.zeros((runs, 2))
    out = np.empty((runs, n))
    for k in range(n):
        x = x @ Phi.T + rng.standard_normal((runs, 2)) @ Lq.T
        out[:, k] = x[:, 0]
    f, p = welch(out[:, 1000:], fs=1 / DT, nperseg=2**14)
    band = (f > 0.5) & (f < 20.0)
    ratio = p.mean(axis=0)[band] / road_model_psd(ROAD_C, f[band])
    # 4 runs x ~15 segments: each bin ~±13 %; the band's mean within 5 %
    assert abs(ratio.mean() - 1.0) < 0.05
    assert np.all(np.abs(ratio - 1.0) < 0.5)


# --- the truth --------------------------------------------------------------------------------


def test_quarter_car_simulation_matches_solve_ivp():
    car = CAR.with_sprung_mass(590.0)
    n = 1501
    z = superposition_profile(n, SPEED * DT, gd_n0=class_level("D"), rng=np.random.default_rng(1),
                              n_min=0.011, n_max=2.83)
    t = np.arange(n) * DT
    resp = simulate_quarter_car(car, z, dt=DT)

    def rhs(tt, x):
        return _forces_rhs(car, x, np.interp(tt, t, z[0]))  # the road linear between samples

    x0 = [z[0, 0], 0.0, z[0, 0], 0.0]
    sol = solve_ivp(rhs, (0.0, t[-1]), x0, t_eval=t, rtol=1e-10, atol=1e-13, method="DOP853",
                    max_step=DT / 2)
    assert sol.success
    scale = np.abs(sol.y.T).max(axis=0)
    # both integrate the same piecewise-linear road; 1e-6 of each state's range is loose
    np.testing.assert_allclose(resp.states[0] / scale, sol.y.T / scale, atol=1e-6)
    acc = np.array([_forces_rhs(car, x, zr)[[1, 3]] for x, zr in zip(sol.y.T, z[0], strict=True)])
    np.testing.assert_allclose(resp.accelerations[0], acc, atol=1e-6 * np.abs(acc).max())


# --- the filters ------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["euler", "exact"])
def test_kalman_gain_reaches_the_steady_state_riccati_solution(method):
    model = discretize(CAR, ROAD_C, dt=DT, method=method, acceleration_noise=1e-2)
    sigma = np.array([0.02, 0.05])
    R = np.diag(sigma**2)
    P_prior = solve_discrete_are(model.Phi.T, model.C.T, model.Q, R)
    K_ref = P_prior @ model.C.T @ np.linalg.inv(model.C @ P_prior @ model.C.T + R)
    est = kalman_filter(np.zeros((20001, 2)), model, measurement_std=sigma, state_covariance0=1e-4)
    # geometric convergence; after 20 s the gain agrees with the DARE to its own precision
    np.testing.assert_allclose(est.gain[-1], K_ref, rtol=1e-5, atol=1e-7 * np.abs(K_ref).max())


def _model_truth(model, n, *, rng, d0=None, G=None, x0=None):
    """States of the filter's own model from a known start (optionally + a constant error);
    ``rng=None``: without the road's process noise."""
    x = np.zeros((n, 6))
    if x0 is not None:
        x[0] = x0
    vals, vecs = np.linalg.eigh(model.Q[4:, 4:])  # Euler's Q is rank one (noise on the road's rate)
    L = vecs * np.sqrt(np.clip(vals, 0.0, None))
    for k in range(n - 1):
        x[k + 1] = model.Phi @ x[k]
        if rng is not None:
            x[k + 1, 4:] += L @ rng.standard_normal(2)
        if d0 is not None:
            x[k + 1] += model.error_transition(G) @ d0
    return x


def test_mme_recovers_a_known_constant_model_error_without_noise():
    """A constant body-acceleration error (a mass error's direct effect): d_k = d0 at every step."""
    model = discretize(CAR, ROAD_C, dt=DT)
    G = error_input_matrix("body")
    d0 = np.array([0.4])  # m/s^2
    # a deterministic road (the model's free response from a bump 5 mm high, rising at 0.2 m/s)
    x = _model_truth(model, 2001, rng=None, d0=d0, G=G, x0=[0.0, 0.0, 0.0, 0.0, 0.005, 0.2])
    y = x @ model.C.T  # noise-free
    P0 = np.diag([1e-14] * 5 + [1e-6])
    sigma = 1e-3  # the filters' assumed noise; the data have none
    mme = mme_kalman_filter(y, model, measurement_std=sigma, weight=1e-9, error_input="body",
                            feedthrough=False, state_covariance0=P0, state0=x[0])  # y = h(x), eq. 6
    # no noise anywhere: the one-step fit sees only d0 (W = 1e-9 against D^T R^-1 D ~ 24)
    np.testing.assert_allclose(mme.model_errors[1:, 0], d0[0], rtol=1e-5)
    np.testing.assert_allclose(mme.road, x[:, 4], atol=1e-9)
    # the plain KF, blind to the error, drifts (the test can fail)
    kf = kalman_filter(y, model, measurement_std=sigma, state_covariance0=P0, state0=x[0])
    assert np.abs(kf.road - x[:, 4]).max() > 1e-3


def test_mme_with_infinite_weight_is_the_kalman_filter():
    model = discretize(CAR, ROAD_C, dt=DT)
    rng = np.random.default_rng(5)
    y = _model_truth(model, 500, rng=rng) @ model.C.T + 0.02 * rng.standard_normal((500, 2))
    kf = kalman_filter(y, model, measurement_std=0.02)
    mme = mme_kalman_filter(y, model, measurement_std=0.02, weight=1e30, error_input="all")
    np.testing.assert_allclose(mme.states, kf.states, rtol=1e-9, atol=1e-15)


def test_covariance_constraint_weight_meets_eq_20():
    model = discretize(CAR, ROAD_C, dt=DT)
    rng = np.random.default_rng(6)
    sigma = 0.02
    y = _model_truth(model, 1500, rng=rng) @ model.C.T + sigma * rng.standard_normal((1500, 2))
    opts = {"error_input": "all", "feedthrough": False}  # eq. 16-21 as printed, eq. 20 against R
    w = covariance_constraint_weight(y, model, measurement_std=sigma, target="R", bounds=(1e-6, 1e8), **opts)
    r = mme_kalman_filter(y, model, measurement_std=sigma, weight=w, **opts).residuals[1:]
    assert np.mean(np.sum(r**2, axis=-1)) / sigma**2 == pytest.approx(2.0, rel=1e-3)


@pytest.mark.parametrize("mme", [False, True])
def test_batched_equals_one_by_one(mme):
    model = discretize(CAR, ROAD_C, dt=DT)
    rng = np.random.default_rng(4)
    y = np.stack([_model_truth(model, 400, rng=rng) @ model.C.T for _ in range(3)])
    y += 0.02 * rng.standard_normal(y.shape)

    def run(data):
        if mme:
            return mme_kalman_filter(data, model, measurement_std=0.02, weight=10.0,
                                     error_input="accelerations")
        return kalman_filter(data, model, measurement_std=0.02)

    batch = run(y)
    for r in range(3):
        one = run(y[r])
        # the same arithmetic on (3, .) and (1, .) arrays: equal to rounding
        np.testing.assert_allclose(batch.states[r], one.states, rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(batch.model_errors[r], one.model_errors, rtol=1e-10, atol=1e-12)


def test_error_std_percent_on_known_signals():
    t = np.linspace(0.0, 1.0, 1001)
    z = np.sin(2 * np.pi * 3 * t)
    np.testing.assert_allclose(error_std_percent(z, 0.9 * z), 10.0, rtol=1e-12)
    np.testing.assert_allclose(error_std_percent(z, z + 0.05), 0.0, atol=1e-12)  # an offset is not counted
    batch = error_std_percent(np.stack([z, z]), np.stack([z, 1.5 * z]))
    np.testing.assert_allclose(batch, [0.0, 50.0], atol=1e-12)


# --- bad input --------------------------------------------------------------------------------


def test_bad_input_raises_input_error_naming_the_field():
    model = discretize(CAR, ROAD_C, dt=DT)
    y = np.zeros((2, 10, 2))
    y[1, 4, 1] = np.nan
    with pytest.raises(InputError, match=r"measurements must be finite.*run 1, step 4"):
        kalman_filter(y, model, measurement_std=0.02)
    with pytest.raises(InputError, match="measurements must have shape"):
        kalman_filter(np.zeros((10, 3)), model, measurement_std=0.02)
    with pytest.raises(InputError, match=r"measurement_std must be > 0"):
        kalman_filter(np.zeros((10, 2)), model, measurement_std=-0.02)
    with pytest.raises(InputError, match=r"weight must be a positive definite 2x2"):
        mme_kalman_filter(np.zeros((10, 2)), model, measurement_std=0.02, weight=0.0,
                          error_input="accelerations")
    with pytest.raises(InputError, match=r"error_input must be one of"):
        mme_kalman_filter(np.zeros((10, 2)), model, measurement_std=0.02, weight=1.0, error_input="wheel")
    with pytest.raises(InputError, match="state_covariance0 must be"):
        kalman_filter(np.zeros((10, 2)), model, measurement_std=0.02, state_covariance0=np.ones((3, 3)))
    with pytest.raises(InputError, match=r"QuarterCar.sprung_mass must be .*> 0 kg"):
        QuarterCar(-410.0, 39.0, 2e4, 1.83e5, 2e3)
    with pytest.raises(InputError, match=r"dt must be .*> 0 s"):
        discretize(CAR, ROAD_C, dt=0.0)
    with pytest.raises(InputError, match="method must be 'euler' or 'exact'"):
        discretize(CAR, ROAD_C, dt=DT, method="rk4")
    with pytest.raises(InputError, match=r"speed must be .*> 0 m/s"):
        iso_road_model(class_level("C"), speed=-1.0)
    with pytest.raises(InputError, match=r"n_low must be < n_high"):
        iso_road_model(class_level("C"), speed=SPEED, n_low=3.0, n_high=2.0)
    with pytest.raises(InputError, match=r"road_height must be a finite"):
        simulate_quarter_car(CAR, [0.0, np.inf, 0.0], dt=DT)
