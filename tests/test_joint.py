"""The road-level-free (joint Whittle) estimator on quarter-car truth, and the fixed-level bias law."""

import numpy as np
import pytest

from suvtwin.estimators.joint import (
    LinearQuarterCar,
    _spectrum,
    corner_response,
    envelope_power,
    estimate_joint,
    profile_loglik,
    profile_loglik_slope,
    signal_direction,
    whittle_loglik,
)
from suvtwin.estimators.quarter_car import simulate_quarter_car, stiffness_from_pressure
from suvtwin.pipeline.quarter_car_truth import SPEED_MPS, TEST_CORNER, TIMESTEP_S, quarter_car_runs
from suvtwin.roads.iso8608 import draw_level_in_class
from suvtwin.roads.profile import generate_road
from suvtwin.roads.spec import RoadSpec, SegmentSpec

DT, SPEED = TIMESTEP_S, SPEED_MPS
MS, MUS, KS, CS = (TEST_CORNER.sprung_mass, TEST_CORNER.unsprung_mass, TEST_CORNER.spring_rate,
                   TEST_CORNER.damping)  # fmt: skip

QC = LinearQuarterCar(MS, MUS, KS, CS)


def test_joint_estimator_is_unbiased_with_an_honest_sigma():
    # 20 runs, true pressure uniform 130-230 kPa, road level anywhere in classes A-D, 10 s at 60 km/h
    runs = quarter_car_runs(20, 10000, seed=2)
    pressure, acc = runs.pressure, runs.acc
    est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED)
    error = est.pressure_pa - pressure[:, None]
    at_10s = error[:, -1]
    # unbiased within 2 standard errors of the batch mean (std/sqrt(20) ~ 3 kPa): measured -4.1, +4.0,
    # +0.7, +0.9, +1.9 kPa on seeds 2, 11, 7, 3, 5 (bench/joint_accuracy.py), +0.7 kPa over the 100 runs
    assert abs(at_10s.mean()) <= 2 * at_10s.std() / np.sqrt(at_10s.size)
    # issue 4 asks for a std <= 10 kPa at 10 s; the Cramer-Rao bound of the Gaussian slope-2 road
    # model is ~14-15 kPa here, and this (whole-record Whittle) estimator reaches it: 12.3, 15.7, 16.7,
    # 14.8, 10.2 kPa on seeds 2, 11, 7, 3, 5 (2 s Bartlett segments gave 13.2, 14.8, 22.5, 17.2, 10.9);
    # with the road's waviness estimated too (the default, bench/joint_waviness.py): 13.3, 15.5, 17.5 on
    # seeds 2, 11, 7 (the w = 2 model: 12.3, 15.7, 16.7)
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
    _, acc = simulate_quarter_car(x0, roads, TEST_CORNER, DT, substeps=5)
    return acc + rng.normal(0.0, 0.5, acc.shape)


def test_fixed_level_bias_law_and_level_recovery():
    level = 2.5e-4
    acc = _one_level_runs(level)
    kt = {}
    for factor in (0.25, 1.0, 4.0):  # the law of the w = 2 model (a free slope absorbs part of a wrong level)
        est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED, fixed_level=factor * level,
                             waviness=2.0)  # fmt: skip
        kt[factor] = est.stiffness[:, -1]
    # k_t ~ Gd^-1/2 (docs/DESIGN.md, "Identifiability of tyre stiffness"): assuming the level x4
    # scales k_t by about x0.5; measured x0.57-0.60 on these runs
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
    u = np.stack(signal_direction(f, QC), axis=-1)
    power = np.real(np.einsum("fi,fij,fj->f", np.conj(u), S_hat, u))[None] / noise
    h1, h2 = corner_response(f[None], kt[:, None], QC)
    log_sv = np.full((1, 1), np.log(4 * np.pi**2 * 0.01 * SPEED * level))
    scalar, _, _ = profile_loglik(power, (np.abs(h1) ** 2 + np.abs(h2) ** 2) / noise,
                                  np.full((1, f.size), float(k)), log_sv_bounds=(log_sv, log_sv))  # fmt: skip
    np.testing.assert_allclose(scalar[0] - scalar[0, 0], full - full[0], rtol=1e-9, atol=1e-6)


def _mujoco_runs(n_per_class: int, seed: int, duration: float = 10.0):
    """Short MuJoCo runs of the SUV (front-left corner), classes A-D, pressure 130-230 kPa, 40-80 km/h."""
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    rng = np.random.default_rng(seed)
    acc_s, acc_u, pressure, speed = [], [], [], []
    for road_class in "ABCD":
        for _ in range(n_per_class):
            p, v = rng.uniform(130.0, 230.0), rng.uniform(40.0, 80.0)
            level = draw_level_in_class(road_class, rng)
            scenario = {"duration_s": duration, "speed_kmh": v, "seed": int(rng.integers(0, 2**31)),
                        "road": {"segments": [{"length_m": 50.0 + v / 3.6 * duration, "gd_n0": level}]},
                        "pressure_kpa": p}  # fmt: skip
            table = simulate(parse_scenario(scenario)).table
            acc_s.append(table.fl_accel_sprung_mps2.to_numpy())
            acc_u.append(table.fl_accel_unsprung_mps2.to_numpy())
            pressure.append(p)
            speed.append(table.speed_mps.mean())
    return np.array(acc_s), np.array(acc_u), np.array(pressure), np.array(speed)


def test_corner_model_removes_the_bias_on_mujoco_truth():
    # the plain quarter car overestimates the pressure on the MuJoCo SUV (anti-roll bar, digressive
    # damper); the roll-plane corner model with the damping marginalized does not
    from suvtwin.pipeline.estimation import linear_corner_model

    acc_s, acc_u, pressure, speed = _mujoco_runs(6, seed=11)
    after = linear_corner_model("fl", 466.7)
    before = LinearQuarterCar(after.sprung_mass, after.unsprung_mass, after.spring_rate, after.damping)
    errors = {}
    for name, qc in (("before", before), ("after", after)):
        est = estimate_joint(acc_s, acc_u, DT, qc=qc, speed_mps=speed, min_record_s=9.5, update_s=10.0)
        errors[name] = est.pressure_pa[:, -1] / 1e3 - pressure
    # 24 runs, 10 s: mean error (est - truth) on seeds 11, 1, 2, 3, 4: before +35.8, +34.2, +31.6, +32.9,
    # +35.2 kPa; after +7.7, +6.2, -0.1, +4.2, +5.6 kPa (std 12-16, standard error of the mean ~2.7)
    assert errors["before"].mean() > 20.0
    assert abs(errors["after"].mean()) < 12.0
    assert errors["after"].std() < 20.0


def test_slope_profile_finds_the_grid_maximum():
    # Fisher scoring in (log Sv, slope) reaches the maximum of the scalar Whittle likelihood on a fine grid
    rng = np.random.default_rng(3)
    f = np.linspace(1.0, 25.0, 200)
    log_n = np.log(f / (0.1 * SPEED))[None]
    h1, h2 = corner_response(f, stiffness_from_pressure(180e3), QC)
    gain = (np.abs(h1) ** 2 + np.abs(h2) ** 2)[None] / (2 * 0.25 * DT)
    true_r = np.exp(np.log(0.05) - 0.4 * log_n) * gain
    power = (1.0 + true_r) * rng.exponential(size=f.size)
    weight = np.ones_like(power)
    ll, lam, beta, _ = profile_loglik_slope(power, np.log(gain), weight, log_n,
                                            log_sv_bounds=(np.full((1, 1), -20.0), np.full((1, 1), 5.0)),
                                            slope_bounds=(-1.5, 1.0))  # fmt: skip
    lg, bg = np.meshgrid(np.linspace(-6, 0, 301), np.linspace(-1.5, 1.0, 251), indexing="ij")
    r = np.exp(lg[..., None] + bg[..., None] * log_n[0]) * gain[0]
    grid = -np.sum(np.log1p(r) + power[0] / (1 + r), axis=-1)
    assert ll[0, 0] >= grid.max() - 1e-9
    i, j = np.unravel_index(grid.argmax(), grid.shape)
    assert abs(lam[0, 0] - lg[i, j]) < 0.05 and abs(beta[0, 0] - bg[i, j]) < 0.02


def test_waviness_estimate_removes_the_non_iso_road_bias():
    # roads of waviness 1.6 and 2.8 (the w = 2 model assumes the ISO classes' slope wrongly), 8 runs each,
    # 10 s at 60 km/h. Mean pressure error at 10 s (kPa) on seeds 1-12: w = 1.6 before +47 to +67, after
    # +2 to +34 (seed 1: +2); w = 2.8 before -91 to -117, after -19 to +7 (seed 1: -19). A batch mean's
    # standard error is ~8 kPa; at w = 1.6 part of the bias stays (w is estimated 1.63-1.83 there)
    for w in (1.6, 2.8):
        runs = quarter_car_runs(8, 10000, seed=1, waviness=w)
        pressure, acc = runs.pressure, runs.acc
        errors = {}
        for name, kwargs in (("before", {"waviness": 2.0}), ("after", {})):
            est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED, **kwargs)
            errors[name] = (est.pressure_pa[:, -1] - pressure) / 1e3
        before, after = errors["before"].mean(), errors["after"].mean()
        assert (before > 40.0) if w < 2 else (before < -80.0)
        assert (after < 40.0 and after > -20.0) if w < 2 else abs(after) < 30.0
        assert abs(np.mean(est.info["waviness_hat_at_end"]) - w) < 0.3  # measured 1.63-1.83, 2.68-2.84


def test_envelope_power_is_the_cos2_mean_of_a_sinusoid():
    # independent: the cos²-weighted mean over ±l of a road cos(2πns), by quadrature, squared
    half = 0.12
    s = np.linspace(-half, half, 200001)
    w = np.cos(0.5 * np.pi * s / half) ** 2
    for n in (0.0, 0.5, 1.5, 1.0 / (2 * half), 6.0, 20.0):
        mean = np.trapezoid(w * np.cos(2 * np.pi * n * s), s) / np.trapezoid(w, s)
        assert envelope_power(n, half) == pytest.approx(mean**2, rel=1e-6, abs=1e-12)
    assert envelope_power(3.0, 0.0) == 1.0
