"""Scoring: the paper's eq. 23-25 and the per-run metrics, on cases computed by hand."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from suvtwin.pipeline.scoring import monte_carlo_indexes, run_metrics


def test_monte_carlo_indexes_by_hand():
    truth = np.array([[10.0, 10.0], [10.0, 10.0], [10.0, 10.0]])
    estimate = np.array([[9.0, 12.0], [11.0, 12.0], [13.0, 9.0]])
    sigma = np.array([[1.0, 4.0], [2.0, 4.0], [3.0, 1.0]])
    idx = monte_carlo_indexes(truth, estimate, sigma)
    # eq. 23: mean of (truth - estimate): (1 - 1 - 3)/3, (-2 - 2 + 1)/3
    np.testing.assert_allclose(idx.mean_error, [-1.0, -1.0])
    # eq. 24 with N - 1: errors (1, -1, -3) -> deviations (2, 0, -2) -> sqrt(8/2) = 2
    np.testing.assert_allclose(idx.error_std, [2.0, np.sqrt(((-1) ** 2 + (-1) ** 2 + 2**2) / 2)])
    np.testing.assert_allclose(idx.sigma_bound, [2.0, 3.0])  # eq. 25


@settings(max_examples=30, deadline=None)
@given(st.integers(2, 30), st.integers(1, 50), st.integers(0, 2**32 - 1))
def test_indexes_match_numpy_statistics(n, t, seed):
    rng = np.random.default_rng(seed)
    truth, est, sig = rng.normal(size=(n, t)), rng.normal(size=(n, t)), rng.uniform(0.1, 2, (n, t))
    idx = monte_carlo_indexes(truth, est, sig)
    np.testing.assert_allclose(idx.error_std, np.std(truth - est, axis=0, ddof=1), rtol=1e-12)
    np.testing.assert_allclose(idx.mean_error, np.mean(truth - est, axis=0), rtol=1e-10, atol=1e-12)


def test_run_metrics_convergence_and_coverage():
    t = np.arange(10) * 1.0
    truth = np.full(10, 200.0)
    estimate = np.array([150, 170, 190, 205, 180, 195, 198, 202, 201, 199.0])
    sigma = np.full(10, 1.5)
    m = run_metrics(t, truth, estimate, sigma, tolerance=12.5)
    # |error| > 12.5 last at t = 4 (error -20): converged from t = 5
    assert m.time_to_converge_s == 5.0
    errors = estimate[5:] - 200.0  # -5, -2, 2, 1, -1
    assert m.mean_error == pytest.approx(errors.mean())
    assert m.rmse == pytest.approx(np.sqrt(np.mean(errors**2)))
    # |error| <= 1.5: (1, -1); <= 3: (-2, 2, 1, -1)
    assert m.inside_1sigma == pytest.approx(2 / 5) and m.inside_2sigma == pytest.approx(4 / 5)
    never = run_metrics(t, truth, truth + np.r_[np.zeros(9), 50.0], sigma, tolerance=12.5)
    assert np.isnan(never.time_to_converge_s)
    assert run_metrics(t, truth, truth, sigma, tolerance=1.0, settle_s=3.0).time_to_converge_s == 0.0
