r"""Scores of a pressure (or stiffness) estimate against the truth.

Usual call: ``idx = monte_carlo_indexes(truth, estimate, sigma)`` for N runs, or
``m = run_metrics(t, truth, estimate, sigma, tolerance=12.5e3)`` for one run.

Monte Carlo indexes of Brancati & Tufano 2022, §5.3, per time step over N runs
(arrays shaped (N, T)):

- eq. 23, mean error: :math:`\overline{Err}_\tau = \frac1N\sum_j (k_{\tau,j} - \hat k_{\tau,j})`
  (truth minus estimate, as in the paper);
- eq. 24, error standard deviation (N − 1 in the denominator);
- eq. 25, mean σ-bound: :math:`\frac1N\sum_j\sqrt{P_{\tau,j}}`.

Per-run metrics: fraction of samples inside ±σ and ±2σ, RMSE and mean error after
convergence, and the time to converge: the first time after which the error stays
within `tolerance` (5 % of p0 = 12.5 kPa for pressure) until the end.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ["PRESSURE_TOLERANCE_KPA", "MonteCarloIndexes", "RunMetrics", "monte_carlo_indexes", "run_metrics"]

PRESSURE_TOLERANCE_KPA = 12.5
"""Convergence band of a pressure estimate: 5 % of p0 = 250 kPa."""


@dataclass(frozen=True)
class MonteCarloIndexes:
    """Per-time-step indexes over N runs, each of shape (T,), in the units of the inputs."""

    mean_error: np.ndarray
    error_std: np.ndarray
    sigma_bound: np.ndarray


def monte_carlo_indexes(
    truth: npt.ArrayLike, estimate: npt.ArrayLike, sigma: npt.ArrayLike
) -> MonteCarloIndexes:
    """Paper 000 eq. 23–25 over runs (axis 0) of (N, T) arrays; `sigma` is each run's filter std."""
    truth, estimate, sigma = (np.atleast_2d(np.asarray(a, dtype=float)) for a in (truth, estimate, sigma))
    error = truth - estimate  # eq. 23 sign: k - k_hat
    n = error.shape[0]
    std = error.std(axis=0, ddof=1) if n > 1 else np.full(error.shape[1], np.nan)
    return MonteCarloIndexes(mean_error=error.mean(axis=0), error_std=std, sigma_bound=sigma.mean(axis=0))


@dataclass(frozen=True)
class RunMetrics:
    """Scores of one run (units of the inputs; time in s).

    Attributes
    ----------
    time_to_converge_s : first time after which |error| ≤ tolerance to the end (NaN if never)
    mean_error, rmse : estimate − truth after convergence (or after `settle_s`)
    inside_1sigma, inside_2sigma : fraction of those samples with |error| ≤ σ, ≤ 2σ
    """

    time_to_converge_s: float
    mean_error: float
    rmse: float
    inside_1sigma: float
    inside_2sigma: float


def run_metrics(
    t: npt.ArrayLike,
    truth: npt.ArrayLike,
    estimate: npt.ArrayLike,
    sigma: npt.ArrayLike,
    *,
    tolerance: float,
    settle_s: float | None = None,
) -> RunMetrics:
    """Metrics of one run; samples from `settle_s` on (default: from convergence) are scored.

    If the run never converges and no `settle_s` is given, the statistics use the
    last half of the run.
    """
    t, truth, estimate, sigma = (np.asarray(a, dtype=float) for a in (t, truth, estimate, sigma))
    error = estimate - truth
    outside = ~(np.abs(error) <= tolerance)  # a NaN estimate is never within the tolerance
    if not outside.any():
        converge = float(t[0])
    elif outside[-1]:
        converge = float("nan")
    else:
        converge = float(t[np.flatnonzero(outside)[-1] + 1])
    start = settle_s if settle_s is not None else (converge if np.isfinite(converge) else t[t.size // 2])
    keep = t >= start
    e, s = error[keep], sigma[keep]
    finite = np.isfinite(e)  # the mean and RMSE of the samples with an estimate (NaN if none)
    return RunMetrics(
        time_to_converge_s=converge,
        mean_error=float(e[finite].mean()) if finite.any() else float("nan"),
        rmse=float(np.sqrt(np.mean(e[finite] ** 2))) if finite.any() else float("nan"),
        inside_1sigma=float(np.mean(np.abs(e) <= s)),
        inside_2sigma=float(np.mean(np.abs(e) <= 2 * s)),
    )
