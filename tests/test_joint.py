"""The road-level-free (joint Whittle) estimator on quarter-car truth, and the fixed-level bias law."""

import numpy as np
import pytest

from estimators.joint import (
    LinearQuarterCar,
    _direction,
    _response,
    _spectrum,
    estimate_joint,
    profile_loglik,
    whittle_loglik,
)
from estimators.quarter_car import QuarterCar, simulate_quarter_car, stiffness_from_pressure
from pipeline.road_spec import RoadSpec, SegmentSpec
from pipeline.roads import generate_road
from tests.test_tire_pressure import CS, DT, KS, MS, MUS, SPEED, _truth

QC = LinearQuarterCar(MS, MUS, KS, CS)


def test_joint_estimator_is_unbiased_with_an_honest_sigma():
    # 20 runs, true pressure uniform 130-230 kPa, road level anywhere in classes A-D, 10 s at 60 km/h
    pressure, _, acc = _truth(20, 10000, seed=2)
    est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED)
    error = est.pressure_pa - pressure[:, None]
    at_10s = error[:, -1]
    # unbiased within 2 standard errors of the batch mean (std/sqrt(20) ~ 3 kPa): measured -4.1, +4.0,
    # +0.7, +0.9, +1.9 kPa on seeds 2, 11, 7, 3, 5 (bench/joint_accuracy.py), +0.7 kPa over the 100 runs
    assert abs(at_10s.mean()) <= 2 * at_10s.std() / np.sqrt(at_10s.size)
    # issue 4 asks for a std <= 10 kPa at 10 s; the Cramer-Rao bound of the Gaussian slope-2 road
    # model is ~14-15 kPa here, and this (whole-record Whittle) estimator reaches it: 12.3, 15.7, 16.7,
    # 14.8, 10.2 kPa on seeds 2, 11, 7, 3, 5 (2 s Bartlett segments gave 13.2, 14.8, 22.5, 17.2, 10.9)
    assert at_10s.std() <= 18e3
    after = est.t_s >= 4.0
    assert np.mean(np.abs(error[:, after]) <= 2 * est.pressure_sigma_pa[:, after]) >= 0.9


def _one_level_runs(level, n_runs=4, seed=5):
    rng = np.random.default_rng(seed)
    n = 10000
    roads = np.array(
        [
            generate_road(
                RoadSpec(
                    segments=[SegmentSpec(length_m=SPEED * n * DT + 5, gd_n0=level)],
                    spacing_m=SPEED * DT / 1.0001,
                ),
                seed=b,
            ).z[0][:n]
            for b in range(n_runs)
        ]
    )
    x0 = np.zeros((n_runs, 5))
    x0[:, 0] = x0[:, 1] = roads[:, 0]
    x0[:, 4] = stiffness_from_pressure(180e3)
    _, acc = simulate_quarter_car(x0, roads, QuarterCar(MS, MUS, KS, 0.0, CS, 0.0), DT, substeps=5)
    return acc + rng.normal(0.0, 0.5, acc.shape)


def test_fixed_level_bias_law_and_level_recovery():
    level = 2.5e-4
    acc = _one_level_runs(level)
    kt = {}
    for factor in (0.25, 1.0, 4.0):
        est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED, fixed_level=factor * level)
        kt[factor] = est.stiffness[:, -1]
    # DESIGN.md: assuming the level x4 scales k_t by about x0.5 (k_t ~ Gd^-1/2); measured x0.57-0.60
    assert np.all((kt[4.0] / kt[1.0] > 0.45) & (kt[4.0] / kt[1.0] < 0.65))
    assert np.all((kt[0.25] / kt[1.0] > 1.4) & (kt[0.25] / kt[1.0] < 2.2))
    free = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED)
    assert np.all(np.abs(free.road_level[:, -1] / level - 1) < 0.5)
    assert np.abs(free.stiffness[:, -1] / stiffness_from_pressure(180e3) - 1).max() < 0.12
    assert free.road_level[:, 0] == pytest.approx(np.full(4, np.nan), nan_ok=True)  # nothing before 2 s


def test_projected_likelihood_equals_the_2x2_whittle_likelihood():
    # the signal direction h/|h| does not depend on k_t, so the 2x2 Whittle likelihood is the scalar
    # one of the projected periodogram plus a constant: same differences over the k_t grid
    x = np.random.default_rng(0).normal(size=(2, 3000)) * np.array([[1.0], [5.0]])
    f, S_hat, k = _spectrum(x, DT, 1000)
    f, S_hat = f[1:200], S_hat[1:200]
    kt = stiffness_from_pressure(np.linspace(100e3, 300e3, 21))
    level, sigma = 2.5e-4, 0.5
    full = whittle_loglik(f, S_hat, k, stiffness=kt, level=np.array([level]), qc=QC, speed=SPEED,
                          sigma=sigma, dt=DT)[:, 0]  # fmt: skip
    noise = 2 * sigma**2 * DT
    u = np.stack(_direction(f, QC), axis=-1)
    power = np.real(np.einsum("fi,fij,fj->f", np.conj(u), S_hat, u))[None] / noise
    h1, h2 = _response(f[None], kt[:, None], QC)
    log_sv = np.full((1, 1), np.log(4 * np.pi**2 * 0.01 * SPEED * level))
    scalar, _, _ = profile_loglik(power, (np.abs(h1) ** 2 + np.abs(h2) ** 2) / noise,
                                  np.full((1, f.size), float(k)), log_sv_bounds=(log_sv, log_sv))  # fmt: skip
    np.testing.assert_allclose(scalar[0] - scalar[0, 0], full - full[0], rtol=1e-9, atol=1e-6)
