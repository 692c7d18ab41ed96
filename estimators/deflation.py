r"""Deflation warning per tyre on top of the online monitor's pressure estimates.

Usual call: ``w = deflation_warnings(t, p_kpa, sigma_kpa, observable, speed, placard_kpa=230)``.

What the regulations ask of an indirect TPMS:

- UN Regulation No. 141 (Annex 5): a tyre 20 % below its reference (the pressure the system
  learned after the driver's reset) is detected within 10 minutes of cumulative driving at
  40–100 km/h; all four tyres deflated together within 60 minutes.
- US FMVSS No. 138 (S4.2): warn within 20 minutes once any number of tyres, up to all four,
  are 25 % or more below the vehicle's placard pressure.

The rule here: the reference :math:`p_{ref}` is the placard pressure if given, else the
monitor's estimate once it has been observable for ``learn_s`` seconds after the reset with
σ ≤ ``learn_sigma_kpa`` (its σ is kept). A tyre is warned when the probability that it is
more than ``detect_fraction`` below its reference,

.. math::
    P = \Phi\!\left(\frac{(1 - f_d)\,p_{ref} - \hat p}
    {\sqrt{\sigma^2 + (1-f_d)^2\sigma_{ref}^2}}\right),

reaches ``probability`` on ``confirm_updates`` consecutive observable updates. σ there is the
spread of the estimate's upper tail when the monitor gives its 95 % quantile
(:math:`(p_{95} - \hat p)/1.645`, ``upper_kpa``), else its standard deviation: the monitor's
posterior is not Gaussian (its changing regime, the range's bounds, early on a lean towards the
prior), and with the quantile the probability reaches 0.95 exactly when the posterior's own 95 %
quantile reaches the threshold (placard reference). On the MuJoCo ``warning`` runs (the
monitor's windows ``rough`` above 10 %, its limit then) this is a wash in detection (runs warned
within 60 s 81 % against 79 % with σ, low tyres warned 81.9 % against 83.1 %, median time 28 s
against 24 s; ``nominal_long`` still without a false warning, the highest two-update probability
of an inflated tyre 0.896 against 0.902 in that day's replay; the bench's ``max_held_probability``,
on observable updates only as the rule counts them, gave 0.82 on 2026-12-02); it is kept
because it is the posterior's own probability at the decision. With
:math:`f_d` = 12.5 %, halfway between a tyre at its reference and FMVSS 138's 25 % and
7.5 points below UN R141's 20 %: a tyre at the regulations' loss is warned once its σ is below
about 7.5 % of the reference / 1.645, and one at its reference would need an error of more than
12.5 % plus the probability's margin. Measured on the MuJoCo SUV (``bench/monitor_mujoco.py``,
the monitor's estimates replayed through other rules): 15 % warned 33 % of the ``warning`` runs
within 60 s, 12.5 % 64 %, 10 % 78 % but with 2 false warnings in the 501 simulated minutes of
``nominal_long`` (none at 12.5 % and 15 %). The warning latches (stays on) until the next reset, and
carries the time, the probability and the estimate that set it.

Every value at a row uses only that row and earlier ones (causal), so it can run alongside
the monitor. No MuJoCo here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.special

from suvtwin.errors import InputError

__all__ = ["DeflationRule", "DeflationWarnings", "deflation_warnings"]


@dataclass(frozen=True)
class DeflationRule:
    """Settings of the warning (see the module docstring).

    Attributes
    ----------
    detect_fraction : float
        Loss below the reference the probability is computed for, − (0.125).
    probability : float
        Probability that triggers a warning (0.95).
    confirm_updates : int
        Consecutive observable updates at or above it (2).
    learn_s : float
        Observable driving after a reset before the reference is taken, s (60).
    learn_sigma_kpa : float
        Largest σ of the learned reference, kPa (8).
    """

    detect_fraction: float = 0.125
    probability: float = 0.95
    confirm_updates: int = 2
    learn_s: float = 60.0
    learn_sigma_kpa: float = 8.0

    def __post_init__(self) -> None:
        checks = [
            ("detect_fraction", 0.0 < self.detect_fraction < 1.0, "(0, 1)"),
            ("probability", 0.5 <= self.probability < 1.0, "[0.5, 1)"),
            ("confirm_updates", self.confirm_updates >= 1, "≥ 1"),
            ("learn_s", 0.0 <= self.learn_s <= 3600.0, "0–3600 s"),
            ("learn_sigma_kpa", self.learn_sigma_kpa > 0.0, "> 0"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"warning setting {name} must be {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class DeflationWarnings:
    """Per update and tyre: reference (kPa, NaN until known), probability of a loss beyond the
    detection fraction, latched warning; per tyre: the warning's time (s, NaN: none), and the
    probability, estimate and reference (kPa) that set it."""

    reference_kpa: np.ndarray
    probability: np.ndarray
    warning: np.ndarray
    warning_time_s: np.ndarray
    warning_probability: np.ndarray
    warning_pressure_kpa: np.ndarray
    warning_reference_kpa: np.ndarray


def deflation_warnings(
    t_s: np.ndarray,
    pressure_kpa: np.ndarray,
    sigma_kpa: np.ndarray,
    observable: np.ndarray,
    speed_mps: np.ndarray | None = None,
    *,
    placard_kpa: float | None = None,
    reset_at_s: float = 0.0,
    rule: DeflationRule | None = None,
    upper_kpa: np.ndarray | None = None,
    upper_level: float = 0.95,
) -> DeflationWarnings:
    r"""Warnings from the monitor's rows: `t_s` (K,), `pressure_kpa`, `sigma_kpa`, `observable` (K, C).

    `placard_kpa`: the reference of every tyre (None: learned after the reset at `reset_at_s`).
    `speed_mps` is accepted for the record and not used: the warning holds at any speed at
    which the monitor is observable. `upper_kpa` (K, C): the pressure's quantile at `upper_level`
    (the monitor's ``pressure_upper_pa``); given, the probability's spread of the estimate is its
    upper tail's, :math:`(p_{upper} - \hat p)/\Phi^{-1}(\text{upper\_level})`, instead of σ — with a
    placard reference the probability then reaches `upper_level` exactly when the quantile reaches
    the detection threshold, whatever the posterior's shape.
    """
    rule = rule or DeflationRule()
    t = np.asarray(t_s, dtype=float)
    p = np.asarray(pressure_kpa, dtype=float)
    sig = np.asarray(sigma_kpa, dtype=float)
    spread_p = sig  # the estimate's spread in the probability (the reference is learned on σ)
    if upper_kpa is not None:
        if not 0.5 < upper_level < 1.0:
            raise InputError(f"upper_level must be in (0.5, 1), got {upper_level!r}")
        z = math.sqrt(2.0) * float(scipy.special.erfinv(2.0 * upper_level - 1.0))
        tail = (np.asarray(upper_kpa, dtype=float) - p) / z
        spread_p = np.where(np.isfinite(tail) & (tail > 0.0), tail, sig)  # a degenerate tail keeps σ
    obs = np.asarray(observable, dtype=bool)
    n_k, n_c = p.shape
    ref = np.full((n_k, n_c), np.nan)
    prob = np.full((n_k, n_c), np.nan)
    warning = np.zeros((n_k, n_c), dtype=bool)
    w_time = np.full(n_c, np.nan)
    w_prob, w_p, w_ref = np.full(n_c, np.nan), np.full(n_c, np.nan), np.full(n_c, np.nan)
    ref_now = np.full(n_c, np.nan if placard_kpa is None else float(placard_kpa))
    ref_sig = np.zeros(n_c)
    learned = np.zeros(n_c)  # observable time since the reset, s
    streak = np.zeros(n_c, dtype=int)
    keep = 1.0 - rule.detect_fraction
    for k in range(n_k):
        step = t[k] - t[k - 1] if k > 0 else 0.0
        after_reset = t[k] >= reset_at_s
        for c in range(n_c):
            if not after_reset:
                continue
            if np.isnan(ref_now[c]):
                if obs[k, c]:
                    learned[c] += step
                if learned[c] >= rule.learn_s and obs[k, c] and sig[k, c] <= rule.learn_sigma_kpa:
                    ref_now[c], ref_sig[c] = p[k, c], sig[k, c]
                continue
            ref[k, c] = ref_now[c]
            spread = math.sqrt(spread_p[k, c] ** 2 + (keep * ref_sig[c]) ** 2)
            prob[k, c] = 0.5 * scipy.special.erfc(-(keep * ref_now[c] - p[k, c]) / (spread * math.sqrt(2.0)))
            streak[c] = streak[c] + 1 if (obs[k, c] and prob[k, c] >= rule.probability) else 0
            if np.isnan(w_time[c]) and streak[c] >= rule.confirm_updates:
                w_time[c], w_prob[c], w_p[c], w_ref[c] = t[k], prob[k, c], p[k, c], ref_now[c]
            warning[k, c] = not np.isnan(w_time[c])
    return DeflationWarnings(
        reference_kpa=ref, probability=prob, warning=warning, warning_time_s=w_time,
        warning_probability=w_prob, warning_pressure_kpa=w_p, warning_reference_kpa=w_ref,
    )  # fmt: skip
