"""The compiled IMM-UKF loop (backend "numba") against the numpy reference path, and its robust Cholesky."""

import numpy as np
import pytest

from suvtwin.errors import InputError
from suvtwin.estimators.imm_ukf_kernel import robust_cholesky_batch
from suvtwin.estimators.quarter_car import QuarterCar, simulate_quarter_car, stiffness_from_pressure
from suvtwin.estimators.tire_pressure import EstimatorSettings, estimate_pressure, load_modes
from suvtwin.estimators.ukf import robust_cholesky

DT, MS, MUS = 1e-3, 466.7, 61.14
RTOL = 1e-8  # rounding only: BLAS/LAPACK and the loops sum in different orders; measured <= ~1e-8
MODES = load_modes("paper")


@pytest.fixture(scope="module")
def data():
    """3 runs x 300 steps of a class-B quarter car on a random-walk road, 0.5 m/s^2 sensor noise."""
    rng = np.random.default_rng(3)
    n_runs, n_steps = 3, 300
    road = np.cumsum(rng.normal(0, 2e-4, (n_runs, n_steps)), axis=1)
    x0 = np.zeros((n_runs, 5))
    x0[:, 0] = x0[:, 1] = road[:, 0]
    x0[:, 4] = stiffness_from_pressure(rng.uniform(150e3, 250e3, n_runs))
    qc = QuarterCar(MS, MUS, MODES.ks[1], MODES.ksnl[1], MODES.cs[1], MODES.csnl[1])
    _, acc = simulate_quarter_car(x0, road, qc, DT, substeps=2)
    acc = acc + rng.normal(0.0, 0.5, acc.shape)
    return acc[..., 0], acc[..., 1], road


def _both(data, modes, road_input, **settings):
    acc_s, acc_u, road = data
    return [
        estimate_pressure(acc_s, acc_u, DT, modes=modes, sprung_mass=MS, unsprung_mass=MUS,
                          road_input=road_input, speed_mps=[12.0, 15.0, 20.0], seed=[1, 2, 3], road=road,
                          settings=EstimatorSettings(backend=backend, **settings))
        for backend in ("numpy", "numba")
    ]  # fmt: skip


def _close(actual, desired):
    """Equal to RTOL relative to the array's scale (a diverging single UKF can pass k_t through 0)."""
    np.testing.assert_allclose(actual, desired, rtol=RTOL, atol=RTOL * np.max(np.abs(desired)))


def _assert_same(ref, fast):
    _close(fast.stiffness, ref.stiffness)
    _close(fast.stiffness_sigma, ref.stiffness_sigma)
    _close(fast.pressure_pa, ref.pressure_pa)
    _close(fast.mode_stiffness, ref.mode_stiffness)
    if ref.mode_probability is None:
        assert fast.mode_probability is None
    else:
        np.testing.assert_allclose(fast.mode_probability, ref.mode_probability, rtol=RTOL, atol=1e-10)
    np.testing.assert_array_equal(fast.repairs, ref.repairs)
    np.testing.assert_array_equal(fast.t_s, ref.t_s)
    assert fast.info == ref.info and fast.classes == ref.classes


@pytest.mark.parametrize("n_modes", [4, 1])
@pytest.mark.parametrize("discretization", ["semi-implicit", "euler"])
@pytest.mark.parametrize("road_input", ["synthetic", "augmented", "true"])
def test_numba_backend_equals_numpy_backend(data, road_input, discretization, n_modes):
    modes = MODES if n_modes == 4 else MODES.subset(("B",))
    ref, fast = _both(data, modes, road_input, discretization=discretization)
    assert ref.stiffness.shape == (3, 300) and np.all(np.isfinite(ref.stiffness))
    _assert_same(ref, fast)


@pytest.mark.parametrize("road_input", ["synthetic", "augmented", "true"])
def test_numba_backend_paper_damper_and_road_levels(data, road_input):
    ref, fast = _both(data, MODES, road_input, damper_law="paper")
    _assert_same(ref, fast)
    acc_s, acc_u, road = data
    est = [
        estimate_pressure(acc_s, acc_u, DT, modes=MODES, sprung_mass=MS, unsprung_mass=MUS,
                          road_input=road_input, speed_mps=15.0, seed=7, road=road,
                          road_levels=[2e-6, 8e-6, 32e-6, 128e-6], initial_stiffness=[2.2e5, 2.5e5, 2.8e5],
                          settings=EstimatorSettings(backend=backend))
        for backend in ("numpy", "numba")
    ]  # fmt: skip
    _assert_same(*est)


@pytest.mark.parametrize("n_modes", [4, 1])
@pytest.mark.parametrize("road_input", ["synthetic", "augmented", "true"])
def test_repairs_are_counted_like_numpy(data, road_input, n_modes):
    # z_s starts with zero variance: every mode's covariance is singular at the first step, the
    # Cholesky factorization fails and is repaired (once per run); later covariances are PD.
    modes = MODES if n_modes == 4 else MODES.subset(("B",))
    ref, fast = _both(data, modes, road_input, initial_state_sigma=(0.0, 5e-2, 1e-1, 3e-1))
    np.testing.assert_array_equal(ref.repairs, [1, 1, 1])
    _assert_same(ref, fast)


def _cases():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(6, 6))
    spd = a @ a.T + 0.1 * np.eye(6)
    v = rng.normal(size=6)
    scales = np.diag([1e-2, 1e-2, 1e-1, 1e-1, 1e5, 1e-3])
    return {
        "spd": spd,
        "spd_badly_scaled": scales @ spd @ scales,
        "asymmetric_spd": spd + np.triu(rng.normal(size=(6, 6)), 1) * 0.3,  # only the lower part is read
        "asymmetric_indefinite": spd + np.tril(rng.normal(size=(6, 6)) * 3.0, -1),
        "rank_one": np.outer(v, v),
        "singular_diagonal": np.diag([1.0, 0.0, 2.0, 3.0, 4.0, 5.0]),
        "indefinite": a + a.T,
        "slightly_indefinite": spd - (np.linalg.eigvalsh(spd)[0] + 1e-9) * np.eye(6),
        "negative_definite": -spd,
        "5x5_indefinite": (a + a.T)[:5, :5],
    }


@pytest.mark.parametrize("name", list(_cases()))
def test_robust_cholesky_kernel_matches_numpy(name):
    m = _cases()[name]
    L_ref, rep_ref = robust_cholesky(m[None])
    L, rep = robust_cholesky_batch(m[None])
    assert rep[0] == rep_ref[0]
    assert np.allclose(np.triu(L[0], 1), 0.0)
    scale = np.max(np.abs(L_ref[0] @ L_ref[0].T))
    np.testing.assert_allclose(L[0] @ L[0].T, L_ref[0] @ L_ref[0].T, atol=1e-9 * scale)
    np.testing.assert_allclose(L, L_ref, atol=1e-7 * np.sqrt(scale))


def test_robust_cholesky_kernel_on_a_batch():
    cases = list(_cases().values())
    batch = np.stack([c for c in cases if c.shape == (6, 6)])
    L_ref, rep_ref = robust_cholesky(batch)
    L, rep = robust_cholesky_batch(batch)
    np.testing.assert_array_equal(rep, rep_ref)
    assert rep.any() and not rep.all()


def test_unknown_backend_is_refused(data):
    acc_s, acc_u, _ = data
    settings = EstimatorSettings(backend="jax")
    with pytest.raises(InputError, match="backend"):
        estimate_pressure(acc_s, acc_u, DT, modes=MODES, sprung_mass=MS, unsprung_mass=MUS,
                          road_input="augmented", speed_mps=15.0, settings=settings)  # fmt: skip


def test_short_true_road_is_refused(data):
    acc_s, acc_u, road = data
    with pytest.raises(InputError, match="road"):
        estimate_pressure(acc_s, acc_u, DT, modes=MODES, sprung_mass=MS, unsprung_mass=MUS,
                          road_input="true", speed_mps=15.0, road=road[:, :100])  # fmt: skip
