"""The batched UKF against filterpy 2.0's UnscentedKalmanFilter, a reference loop, and repair."""

import numpy as np
import pytest
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

from suvtwin.estimators.quarter_car import (
    QuarterCar,
    accelerations,
    measurement_noise,
    process_euler,
    process_noise,
)
from suvtwin.estimators.ukf import merwe_weights, robust_cholesky, ukf_predict, ukf_update

DT = 1e-3
QC = QuarterCar(
    sprung_mass=466.7,
    unsprung_mass=61.14,
    spring_rate=32000.0,
    spring_cubic=1.3e6,
    damping=2200.0,
    damping_nonlinear=800.0,
)
Q = process_noise([1e2, 1e2, 1e4, 1e5, 1e16], DT)
R = measurement_noise(0.5, 0.5)
ALPHA, BETA, KAPPA = 0.5, 2.0, 0.0  # well-conditioned weights (alpha = 1e-3 gives W0 ~ -1e6)


def _road(k):
    return 0.01 * np.sin(2 * np.pi * 1.3 * k * DT) + 0.003 * np.sin(2 * np.pi * 9.0 * k * DT)


def _measurements(n_steps, seed):
    """Noisy accelerations of the non-linear QC itself, fine-stepped (truth kt = 200 kN/m)."""
    rng = np.random.default_rng(seed)
    x = np.array([0.0, 0.0, 0.0, 0.0, 2.0e5])
    out = []
    for k in range(n_steps):
        for j in range(10):
            x = process_euler(x, _road(k + j / 10), QC, DT / 10)
        out.append(np.array(accelerations(x, _road(k + 1), QC)) + rng.normal(0, 0.5, 2))
    return np.array(out)


def _initial(batch):
    rng = np.random.default_rng(1)
    x0 = np.zeros((batch, 5))
    x0[:, 4] = rng.uniform(1.5e5, 2.8e5, batch)
    P0 = np.tile(np.diag([1e-4, 1e-4, 1e-2, 1e-2, 4e9]), (batch, 1, 1))
    return x0, P0


def test_batched_ukf_equals_filterpy():
    n_steps, batch = 400, 3
    z = _measurements(n_steps, seed=2)
    x0, P0 = _initial(batch)
    w = merwe_weights(5, alpha=ALPHA, beta=BETA, kappa=KAPPA)
    refs = []
    for b in range(batch):
        points = MerweScaledSigmaPoints(5, alpha=ALPHA, beta=BETA, kappa=KAPPA)
        f = UnscentedKalmanFilter(dim_x=5, dim_z=2, dt=DT, fx=None, hx=None, points=points)
        f.x, f.P, f.Q, f.R = x0[b].copy(), P0[b].copy(), Q.copy(), R.copy()
        refs.append(f)
    x, P = x0.copy(), P0.copy()
    worst = 0.0
    for k in range(n_steps):
        road = _road(k)
        pred = ukf_predict(x, P, lambda s, r=road: process_euler(s, r, QC, DT), Q, w)
        post = ukf_update(pred, z[k], lambda s, r=_road(k + 1): np.stack(accelerations(s, r, QC), -1), R, w)
        x, P = post.x, post.P
        for b, f in enumerate(refs):
            f.predict(fx=lambda s, dt, r=road: process_euler(s, r, QC, dt))
            f.update(z[k], hx=lambda s, r=_road(k + 1): np.array(accelerations(s, r, QC)))
            scale_x = np.abs(f.x) + np.sqrt(np.diag(f.P))
            worst = max(worst, np.max(np.abs(x[b] - f.x) / scale_x))
            np.testing.assert_allclose(P[b], f.P, rtol=1e-8, atol=1e-8 * np.abs(f.P).max())
            assert post.log_likelihood[b] == pytest.approx(f.log_likelihood, rel=1e-8, abs=1e-8)
    assert worst < 1e-8


def test_batch_equals_single_filter_loop():
    n_steps, batch = 100, 4
    z = _measurements(n_steps, seed=4)
    x0, P0 = _initial(batch)
    w = merwe_weights(5, alpha=ALPHA, beta=BETA, kappa=KAPPA)

    def run(x, P):
        for k in range(n_steps):
            pred = ukf_predict(x, P, lambda s, r=_road(k): process_euler(s, r, QC, DT), Q, w)
            post = ukf_update(
                pred, z[k], lambda s, r=_road(k + 1): np.stack(accelerations(s, r, QC), -1), R, w
            )
            x, P = post.x, post.P
        return x, P

    xb, Pb = run(x0, P0)
    for b in range(batch):
        xs, Ps = run(x0[b], P0[b])
        np.testing.assert_allclose(xb[b], xs, rtol=1e-12)
        np.testing.assert_allclose(Pb[b], Ps, rtol=1e-10, atol=1e-10 * np.abs(Ps).max())


def test_broken_covariance_is_repaired_and_counted():
    good = np.diag([1.0, 2.0, 3.0])
    asymmetric = good + np.array([[0, 1e-3, 0], [0, 0, 0], [0, 0, 0]])
    indefinite = np.diag([1.0, -1e-9, 2.0])
    nan_free = np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # eigenvalue -1
    L, repaired = robust_cholesky(np.stack([good, asymmetric, indefinite, nan_free]))
    assert repaired.tolist() == [False, False, True, True]
    assert np.all(np.isfinite(L))
    np.testing.assert_allclose(L[0] @ L[0].T, good)
    # the repaired ones are positive definite and close to the input where it was nearly PD
    for m in L[2:] @ np.swapaxes(L[2:], -1, -2):
        assert np.all(np.linalg.eigvalsh(m) > 0)
    np.testing.assert_allclose(L[2] @ L[2].T, np.diag([1.0, 0.0, 2.0]), atol=1e-6)


def test_unscented_transform_is_exact_for_linear_models():
    # a linear model through the UT gives the Kalman filter's prior exactly (independent check)
    rng = np.random.default_rng(0)
    A = rng.normal(size=(4, 4))
    x = rng.normal(size=4)
    m = rng.normal(size=(4, 4))
    P = m @ m.T + np.eye(4)
    w = merwe_weights(4, alpha=0.5, beta=2.0, kappa=0.0)
    pred = ukf_predict(x, P, lambda s: s @ A.T, np.eye(4) * 0.1, w)
    np.testing.assert_allclose(pred.x, A @ x, rtol=1e-12)
    np.testing.assert_allclose(pred.P, A @ P @ A.T + np.eye(4) * 0.1, rtol=1e-10)
