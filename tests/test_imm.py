"""The batched IMM of UKFs against filterpy 2.0's IMMEstimator, and the paper's Markov matrix."""

import numpy as np
import pytest
from filterpy.kalman import IMMEstimator, MerweScaledSigmaPoints, UnscentedKalmanFilter

from suvtwin.estimators.imm import PAPER_TRANSITION, imm_combine, imm_mix, imm_probabilities
from suvtwin.estimators.quarter_car import (
    QuarterCar,
    accelerations,
    measurement_noise,
    process_euler,
    process_noise,
)
from suvtwin.estimators.ukf import merwe_weights, ukf_predict, ukf_update

DT = 1e-3
# Brancati & Tufano 2022, Table 3 (classes A-D): cs, csnl, ks, ksnl
TABLE_3 = np.array(
    [
        [6576, 4319, 113086, 130098],
        [4585, 6016, 173415, 151886],
        [14819, 5839, 94544, 62836],
        [14708, 4555, 118114, 121723],
    ],
    dtype=float,
)
MS, MUS = 466.7, 61.14


def _modes(shape):
    return QuarterCar(
        sprung_mass=MS,
        unsprung_mass=MUS,
        spring_rate=TABLE_3[:, 2].reshape(shape),
        spring_cubic=TABLE_3[:, 3].reshape(shape),
        damping=TABLE_3[:, 0].reshape(shape),
        damping_nonlinear=TABLE_3[:, 1].reshape(shape),
    )


def _single(i):
    cs, csnl, ks, ksnl = TABLE_3[i]
    return QuarterCar(MS, MUS, ks, ksnl, cs, csnl)


Q = process_noise([1e2, 1e2, 1e4, 1e5, 1e15], DT)
R = measurement_noise(0.5, 0.5)
ALPHA, BETA, KAPPA = 0.5, 2.0, 0.0


def _road(k):
    return 0.008 * np.sin(2 * np.pi * 1.1 * k * DT) + 0.002 * np.sin(2 * np.pi * 11.0 * k * DT)


def test_paper_markov_matrix():
    assert np.allclose(PAPER_TRANSITION.sum(axis=1), 1.0)
    assert np.allclose(np.diag(PAPER_TRANSITION), 0.97) and PAPER_TRANSITION[0, 1] == pytest.approx(0.01)


def test_batched_imm_equals_filterpy_imm_estimator():
    n_steps = 300
    rng = np.random.default_rng(3)
    truth_qc = _single(1)
    x_true = np.array([0, 0, 0, 0, 2.2e5])
    z = []
    for k in range(n_steps):
        x_true = process_euler(x_true, _road(k), truth_qc, DT)
        z.append(np.array(accelerations(x_true, _road(k + 1), truth_qc)) + rng.normal(0, 0.5, 2))
    z = np.array(z)
    x0 = np.array([0, 0, 0, 0, 2.6e5])
    P0 = np.diag([1e-4, 1e-4, 1e-2, 1e-2, 4e9])
    mu0 = np.full(4, 0.25)

    state = {"k": 0}  # filterpy's filters read the road of the current step from here
    filters = []
    for i in range(4):
        qc = _single(i)
        f = UnscentedKalmanFilter(
            dim_x=5, dim_z=2, dt=DT,
            fx=lambda s, dt, qc=qc: process_euler(s, _road(state["k"]), qc, dt),
            hx=lambda s, qc=qc: np.array(accelerations(s, _road(state["k"] + 1), qc)),
            points=MerweScaledSigmaPoints(5, alpha=ALPHA, beta=BETA, kappa=KAPPA),
        )  # fmt: skip
        f.x, f.P, f.Q, f.R = x0.copy(), P0.copy(), Q.copy(), R.copy()
        filters.append(f)
    ref = IMMEstimator(filters, mu0.copy(), PAPER_TRANSITION.copy())

    w = merwe_weights(5, alpha=ALPHA, beta=BETA, kappa=KAPPA)
    modes = _modes((4, 1))  # broadcast against (..., S, 2n+1)
    x = np.tile(x0, (2, 4, 1))  # a batch of two identical runs
    P = np.tile(P0, (2, 4, 1, 1))
    mu = np.tile(mu0, (2, 1))
    for k in range(n_steps):
        state["k"] = k
        ref.predict()
        ref.update(z[k])
        mixed = imm_mix(x, P, mu, PAPER_TRANSITION)
        pred = ukf_predict(mixed.x, mixed.P, lambda s, r=_road(k): process_euler(s, r, modes, DT), Q, w)
        post = ukf_update(
            pred,
            z[k][None, None, :],
            lambda s, r=_road(k + 1): np.stack(accelerations(s, r, modes), -1),
            R,
            w,
        )
        mu = imm_probabilities(mixed.cbar, post.log_likelihood)
        x, P = post.x, post.P
        x_hat, P_hat = imm_combine(x, P, mu)
        for b in range(2):
            np.testing.assert_allclose(mu[b], ref.mu, rtol=1e-6, atol=1e-9)
            np.testing.assert_allclose(x_hat[b], ref.x, rtol=1e-6, atol=1e-6 * np.sqrt(np.diag(ref.P)).max())
            np.testing.assert_allclose(P_hat[b], ref.P, rtol=1e-6, atol=1e-6 * np.abs(ref.P).max())


def test_probability_floor_keeps_modes_alive():
    cbar = np.array([0.25, 0.25, 0.25, 0.25])
    ll = np.array([0.0, -800.0, -2000.0, -5.0])
    mu = imm_probabilities(cbar, ll, floor=1e-4)
    assert mu.sum() == pytest.approx(1.0) and mu.min() >= 1e-4 * 0.999
    assert mu.argmax() == 0
    assert np.all(np.isfinite(imm_probabilities(cbar, np.array([-1e6, -1e6 - 1, -1e6 - 2, -1e6 - 3]))))
