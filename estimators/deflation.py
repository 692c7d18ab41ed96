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
:math:`f_d` = 10 %, halfway between a tyre at its reference and UN R141's 20 % loss: the rule warns
once the posterior puts 95 % on the tyre being nearer a 20 % loss than its reference (the boundary
between the two with equal weight); a tyre at the regulations' loss is warned once its σ is below
about 10 % of the reference / 1.645, and one at its reference would need an error of more than
10 % plus the probability's margin. Chosen on 2026-12-04 (the monitor's estimates of that day
replayed through the rule, MuJoCo runs with the radii; warned within 60 s on the ``warning``
runs 0–99 and 5000–5099 / 200–299, ``warning_multi`` 0–99, ``reset_leak`` 0–39 within 60 s of the
leak; the highest probability an inflated tyre held on two counted updates in the ``warning`` runs
/ in the 1012 ``nominal_long`` minutes): 12.5 % (the rule before) 95.0 / 96 %, 81 %, 87.5 %; 0.865
/ 0.840, 0.646; 10 % 99.0 / 99 %, 93 %, 92.5 %; 0.915 / 0.938, 0.825, no warning on an inflated tyre
or at nominal pressure with either. Before the monitor's σ became honest it was the other way (10 %
gave 2 false warnings in 501 ``nominal_long`` minutes on 2026-12-02, and an inflated tyre held
0.948 on 2026-12-03; 12.5 % none). The margin left is in the ``warning`` runs' inflated tyres
(0.938 on a class D run where both fronts read 24–33 kPa low together at a fused σ of 10 kPa):
a warning on the wrong tyre of a car that has a low one is the likelier error now, not a warning
on a car that has none. The warning latches (stays on) until the next reset, and
carries the time, the probability and the estimate that set it.

**The car's common loss.** Tyres often lose pressure together (diffusion through the rubber, a
colder day, months without a check), and FMVSS 138 asks for all four at once. Each tyre's
estimate alone then needs its σ below about 6 % of the reference to be warned at a 20 % loss;
their mean needs less of each. At every update where all the tyres with a reference are
observable (three or more), their relative pressures :math:`u_i = \hat p_i / p_{ref,i}` are
fitted with one common value r by generalized least squares (:func:`_common_loss`; A. C. Aitken,
"On least squares and linear combination of observations", Proc. R. Soc. Edinburgh 55, 42–48, 1935),
their errors correlated by ``track_correlation`` on a track (front and rear on one side read the
same road) and ``cross_correlation`` otherwise; if the fit's χ² passes at level
``common_alpha`` (one value explains them all), the probability that r is more than
``detect_fraction`` below 1 (``common_probability``) counts for each of them beside its own: a tyre
is warned when either reaches ``probability`` on ``confirm_updates`` consecutive updates
(``warning_common`` tells which set it). A single low tyre makes the fit fail, and the others
keep their own evidence only; a tyre at its reference is warned through the others only where
one common value explains it within its σ beside them (wide σ, very low others). On the MuJoCo
``warning`` runs (60 s): all four low warned in 17 of 20 runs (13 with each tyre alone), one low
tyre unchanged (71 of 80), no warning on an inflated tyre; on ``nominal_long`` (506 simulated
minutes at placard) no warning, the common loss's highest probability held on two updates 0.45
(the tyres' own 0.82); with the common fit taken from two
observable tyres on, a class D run's front tyre at its placard, read 26 % low at σ 17 kPa
beside the low one, was warned: hence all of them, three or more. Where the radii are fused
(below) and a tyre is not observable, the fit takes every tyre's fused estimate, with the
fusion's covariance, where three are observable (:func:`_common_fit`): a tyre whose windows were
refused (rough) is tied to the others by its radius, to within the tyres' spread, and the χ² then
also tests the radii's contrasts. Where all are observable the fit stays the vibration estimates'
(the spread of their upper tails, as each tyre's own probability): with the fused estimates there
too (their symmetric σ), the ``reset_leak`` runs' all four warned in 3 of 8 instead of 4. But the
fused estimates' χ² must pass too where they are known (:func:`_radii_refute_common`, in
:func:`_common_fit`): the vibration's errors are correlated 0.75 along a track, so two tyres low
on one side (or an axle with a track's error beside it) fit one common loss by the vibration
alone, and on MuJoCo runs with two or three tyres low it warned inflated ones (the
``warning_multi`` bench set, 100 runs: 4 warnings on inflated tyres before, none after; the low
tyres warned in 81 % of the runs either way); the radii's contrasts refute it. With one tyre
model slope for all, a common r moves no excess, so the fit's r is the vibration
estimates' own least-squares mean, the refused tyre's at its wide σ: the radii add the tie and
the test, not a level. A tyre neither observable nor fused has only the monitor's prior, the
same for every tyre, whose error no correlation here describes: it is never fitted. On the
MuJoCo ``warning`` runs (2026-12-03) all four low warned
in 19 of 20 (17 with every tyre observable required; class D runs with a rear's windows refused),
no warning on an inflated tyre; ``nominal_long``: no warning, the common loss's highest
probability held on two updates 0.45 (as before; over the 182 updates of 80 runs fitted over the
fused estimates at most 0.48, held 0.35); ``reset_leak``: the same 90 %.

**The wheels' rolling radii.** Given the radius analysis (:class:`RadiusEvidence`, from
:class:`suvtwin.estimators.rolling_radius.RollingRadius`), every row's estimates are fused with it
against the tyre model within the tyres' spread ``radius_spread_permille``
(:func:`suvtwin.estimators.radius_fusion.fuse_with_radii`; the vibration estimates' variance grown
by how far they may lag a change the radii saw, ``RadiusEvidence.lag_kpa``), and with a placard
reference the tyre's probability is that fused estimate's. With learned references, once every
tyre has one, the excess is compared against its own value when they were learned (the
calibration at that moment, which cancels the tyres' own radius offsets; :func:`_fuse_radius`:
generalized least squares of the four losses p − reference, the vibration estimates and learned
references correlated as in the common fit, rank three), and the probability is that estimate's.
With learned references the radii are also calibrated ``radius_learn_s`` after the reset, and a
tyre that has since lost ``detect_fraction`` more than the others' mean warns on its own
(:func:`_relative_loss`, ``relative_probability``, ``warning_relative``): before the vibration has
learned any reference, as production wheel-speed systems do after their reset. A row counts for
the confirmation where the tyre is observable, fused within the monitor's observability limit
(``informed_sigma_kpa``) or compared. On the MuJoCo ``warning`` runs
(placard, spread 1 ‰, 2026-12-03): warned within 60 s 96 % (one tyre 77 of 80, all four 19 of 20;
88 % without the radii), no warning on an inflated tyre; ``nominal_long`` (506 min): no false
warning, the highest probability held 0.55;
``reset_leak`` (learned references, a 20 % leak after 150–180 s): one tyre warned within 60 s of
the leak's end in 31 of 32 runs, none before it.

Every value at a row uses only that row and earlier ones (causal), so it can run alongside
the monitor. No MuJoCo here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.special

from suvtwin.errors import InputError
from suvtwin.estimators.radius_fusion import (
    RadiusModel,
    excess_cov,
    excess_operator,
    fuse_with_radii,
    gls_step,
    wheel_sd,
)

__all__ = ["DeflationRule", "DeflationWarnings", "RadiusEvidence", "deflation_warnings"]


@dataclass(frozen=True)
class DeflationRule:
    """Settings of the warning (see the module docstring).

    Attributes
    ----------
    detect_fraction : float
        Loss below the reference the probability is computed for, − (0.10: halfway to UN R141's 20 %).
    probability : float
        Probability that triggers a warning (0.95).
    confirm_updates : int
        Consecutive observable updates at or above it (2).
    learn_s : float
        Observable driving after a reset before the reference is taken, s (60).
    learn_sigma_kpa : float
        Largest σ of the learned reference, kPa (8).
    common_alpha : float or None
        Level of the test that the observable tyres share one relative pressure (χ² of the
        common fit); the common loss's probability counts only where the test passes (0.05; None:
        no common test, each tyre on its own).
    track_correlation, cross_correlation : float
        Correlation of the pressure errors of two tyres on one track (front and rear on a side),
        and of two others, in the common fit. On the MuJoCo ``constant`` runs: front–rear 0.76,
        0.56 and 0.32 at 10, 30 and 40 s, the two fronts −0.2 to 0.15; the largest are taken
        (0.75, 0.15): the common loss's σ is then not smaller than the data's. Without the tracks
        given, every pair gets `track_correlation`. Where the monitor reads the left and right
        tracks' road coherence γ (``track_coherence`` of :func:`deflation_warnings`), two tyres on
        different tracks get at least `track_correlation`·γ²: their errors come from the
        periodograms' fluctuations, and two jointly Gaussian Fourier coefficients of correlation γ
        have periodograms correlated by γ² (cov(|X|², |Y|²) = |E[X Ȳ]|²). On the first 32
        ``constant`` scenarios with identical tracks (γ read 0.90–0.95) the two sides' errors
        correlated 0.62–0.91 at 10–30 s (fronts, rears; the preview's output), against −0.2 to
        0.5 with independent tracks (``bench/monitor_tracks.py``'s runs).
    radius_spread_permille : float
        The spread (σ) of the tyres' effective rolling radii about the tyre model's at the same
        pressure and load, ‰ (manufacturing, wear): the fusion with the radii compares the tyres
        against the model within it (1 ‰ = 0.37 mm on the SUV's tyre; an assumption for a real
        car, where a reset calibrates it away; the simulator's tyres are identical, 0), with a
        placard reference and, with learned ones, until every tyre has its reference (then the
        radii are compared against their values at that moment and this is not used).
    radius_learn_s : float
        With a learned reference, the time after the reset at which the radii are calibrated for the
        relative route (each tyre against the others since then; 20 s: five blocks of the radius
        analysis), s.
    informed_sigma_kpa : float
        A row where the tyre is not observable but its estimate is fused with the radii counts
        toward the confirmation only where the fused σ is at most this, kPa: the monitor's own
        observability limit (``MonitorConfig.observable_sigma_kpa``, 25 kPa; the pipeline passes
        the monitor's). Counted at any σ, the first update (half a window, fused σ 27 kPa) confirmed
        the second, whose window holds its data: on the MuJoCo ``warning`` runs 200–299 a class A
        run at 105 km/h, every tyre read 50–75 kPa low over its first 8 s (the road's realization),
        warned an inflated tyre at 8 s.
    """

    detect_fraction: float = 0.10
    probability: float = 0.95
    confirm_updates: int = 2
    learn_s: float = 60.0
    learn_sigma_kpa: float = 8.0
    common_alpha: float | None = 0.05
    track_correlation: float = 0.75
    cross_correlation: float = 0.15
    radius_spread_permille: float = 1.0
    radius_learn_s: float = 20.0
    informed_sigma_kpa: float = 25.0

    def __post_init__(self) -> None:
        checks = [
            ("detect_fraction", 0.0 < self.detect_fraction < 1.0, "(0, 1)"),
            ("probability", 0.5 <= self.probability < 1.0, "[0.5, 1)"),
            ("confirm_updates", self.confirm_updates >= 1, "≥ 1"),
            ("learn_s", 0.0 <= self.learn_s <= 3600.0, "0–3600 s"),
            ("learn_sigma_kpa", self.learn_sigma_kpa > 0.0, "> 0"),
            ("common_alpha", self.common_alpha is None or 0.0 < self.common_alpha < 1.0, "(0, 1) or None"),
            ("track_correlation", 0.0 <= self.track_correlation < 1.0, "[0, 1)"),
            ("cross_correlation", 0.0 <= self.cross_correlation <= self.track_correlation,
             "0–track_correlation"),
            ("radius_spread_permille", 0.0 <= self.radius_spread_permille <= 20.0, "0–20 ‰"),
            ("radius_learn_s", 0.0 <= self.radius_learn_s <= 3600.0, "0–3600 s"),
            ("informed_sigma_kpa", self.informed_sigma_kpa > 0.0, "> 0 kPa"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"warning setting {name} must be {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class DeflationWarnings:
    """Per update and tyre: reference (kPa, NaN until known), probability of a loss beyond the
    detection fraction, latched warning; per update: the probability that the tyres' common
    relative pressure is that low (`common_probability`, NaN where fewer than three are observable,
    where a tyre with a reference is neither observable nor fused with the radii, or where the test
    that they share it fails); per
    tyre: the warning's time (s, NaN: none), and the probability, estimate and reference (kPa)
    that set it, and whether the common loss set it (`warning_common`)."""

    reference_kpa: np.ndarray
    probability: np.ndarray
    warning: np.ndarray
    warning_time_s: np.ndarray
    warning_probability: np.ndarray
    warning_pressure_kpa: np.ndarray
    warning_reference_kpa: np.ndarray
    common_probability: np.ndarray
    warning_common: np.ndarray
    fused_kpa: np.ndarray
    fused_sigma_kpa: np.ndarray
    relative_probability: np.ndarray
    warning_relative: np.ndarray


@dataclass(frozen=True)
class RadiusEvidence:
    r"""The radius analysis (:class:`suvtwin.estimators.rolling_radius.RollingRadius`) at the warning's rows.

    `excess`, `sigma` (K, C): each tyre's log effective rolling radius over the other tyres' mean
    and its σ (dimensionless) at each row (NaN: none yet); `gain_per_kpa` (C,): the change of the
    tyre's log radius per kPa of its pressure, > 0 (the tyre model's secant from the reference to the
    detection threshold: exact where the warning decides), for the learned references' route;
    `model` or None: each tyre's log radius against its pressure at its load
    (:class:`~suvtwin.estimators.radius_fusion.RadiusModel`): given, every row's estimates are fused
    with the radii against it (:func:`~suvtwin.estimators.radius_fusion.fuse_with_radii`, within the
    tyres' spread), and a placard reference decides on that; `lag_kpa` (K, C) or None: how far the
    vibration estimate may lag a change the radii saw
    (:func:`~suvtwin.estimators.radius_fusion.vibration_lag_kpa`), added to its variance in the fusion.

    With learned references, linearized, :math:`e - e_0 = A\,G\,(p - p_{ref}) + \varepsilon` with A the
    excess operator (:func:`suvtwin.estimators.rolling_radius.excess_of`), G = diag(gain), e_0 the
    excess when the references were learned: rank C − 1, since a loss shared by all tyres leaves
    every excess unchanged.
    """

    excess: np.ndarray
    sigma: np.ndarray
    gain_per_kpa: np.ndarray
    model: RadiusModel | None = None
    lag_kpa: np.ndarray | None = None

    def check(self, n_k: int, n_c: int) -> None:
        """One clear message for arrays of the wrong shape or a gain that is not positive."""
        if np.shape(self.excess) != (n_k, n_c) or np.shape(self.sigma) != (n_k, n_c):
            raise InputError(f"radius excess and sigma must be ({n_k}, {n_c}), got {np.shape(self.excess)}")
        gain = np.asarray(self.gain_per_kpa, dtype=float)
        if gain.shape != (n_c,) or not np.all(np.isfinite(gain) & (gain > 0)):
            raise InputError(f"radius gain_per_kpa must be ({n_c},) positive values, got {gain!r}")
        if self.lag_kpa is not None and np.shape(self.lag_kpa) != (n_k, n_c):
            raise InputError(f"radius lag_kpa must be ({n_k}, {n_c}), got {np.shape(self.lag_kpa)}")
        if self.model is not None and self.model.n_tyres != n_c:
            raise InputError(f"radius model must be for {n_c} tyres, got {self.model.n_tyres}")


def _fuse_radius(p, sd, rho, ref, radius: RadiusEvidence, k: int, calibration, ref_sd):
    r"""With learned references: the Gaussian fusion of the vibration estimates `p` ± `sd` (C,), kPa,
    correlated by `rho`, with the radius analysis at row `k` against its `calibration` (e0, its
    covariance: the excess at the moment the references were learned), for the loss L = p − `ref`
    (the references, ± `ref_sd` correlated as the estimates: learned from them):
    :math:`\Lambda = \Sigma^{-1} + H^T R^{-1} H`, :math:`\hat L = \Lambda^{-1}(\Sigma^{-1}
    (\hat p - p_{ref}) + H^T R^{-1} y)`, Σ = Σ_v + Σ_ref, y = e − e0, H = A G, R = A diag(σ_δ²) Aᵀ +
    cov(e0) (:func:`suvtwin.estimators.radius_fusion.gls_step`, one step: linear in L). Returns
    `ref` + L̂ (C,) and Λ⁻¹ (C, C), kPa and kPa²: the radii compare the tyres against their own state
    at the reset, so the reference's error cancels from the contrasts they pin."""
    n_c = p.size
    e0, cov0, read = calibration
    first = np.flatnonzero(read)[:-1]  # any m − 1 of the m wheels' excesses hold all their information
    h = excess_operator(n_c, read) * np.asarray(radius.gain_per_kpa, dtype=float)[None, :]
    y = radius.excess[k] - e0  # NaN for a wheel not read: not among `first`
    r = excess_cov(wheel_sd(radius.sigma[k], int(read.sum())), read) + cov0
    h, y, r = h[first], y[first], r[np.ix_(first, first)]
    info_v = np.linalg.inv(rho * (np.outer(sd, sd) + np.outer(ref_sd, ref_sd)))
    loss0 = p - ref
    loss, cov = gls_step(loss0, loss0, info_v, h, y - h @ loss0, r)
    return ref + loss, cov


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
    tracks: tuple[tuple[int, int], ...] | list = (),
    radius: RadiusEvidence | None = None,
    track_coherence: np.ndarray | None = None,
) -> DeflationWarnings:
    r"""Warnings from the monitor's rows: `t_s` (K,), `pressure_kpa`, `sigma_kpa`, `observable` (K, C).

    `placard_kpa`: the reference of every tyre (None: learned after the reset at `reset_at_s`).
    `speed_mps` is accepted for the record and not used: the warning holds at any speed at
    which the monitor is observable. `upper_kpa` (K, C): the pressure's quantile at `upper_level`
    (the monitor's ``pressure_upper_pa``); given, the probability's spread of the estimate is its
    upper tail's, :math:`(p_{upper} - \hat p)/\Phi^{-1}(\text{upper\_level})`, instead of σ — with a
    placard reference the probability then reaches `upper_level` exactly when the quantile reaches
    the detection threshold, whatever the posterior's shape. `tracks`: (front, rear) column pairs
    on one track, for the common fit's error correlation (:class:`DeflationRule`). `radius`: the
    radius analysis at each row (:class:`RadiusEvidence`), fused with the estimates where every tyre
    has a reference (``fused_kpa``, ``fused_sigma_kpa``; NaN elsewhere) and the tyre's probability
    then taken from the fused estimate. `track_coherence` (K,): the left and right tracks' road
    coherence the monitor read at each row (its ``track_coherence``; NaN: none), which raises the
    correlation of tyres on different tracks (:class:`DeflationRule`'s ``cross_correlation``).
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
    same_track = np.ones((n_c, n_c), dtype=bool)
    if tracks:
        same_track = np.eye(n_c, dtype=bool)
        for f, r in tracks:
            if not (0 <= f < n_c and 0 <= r < n_c and f != r):
                raise InputError(f"tracks must be pairs of distinct columns 0–{n_c - 1}, got {tracks!r}")
            same_track[f, r] = same_track[r, f] = True
    # the errors' correlation per row: tyres on different tracks share the tracks' coherent part
    cross = np.full(n_k, rule.cross_correlation)
    if track_coherence is not None:
        gamma = np.asarray(track_coherence, dtype=float)
        if gamma.shape != (n_k,):
            raise InputError(f"track_coherence must have shape ({n_k},), got {gamma.shape}")
        coherent = rule.track_correlation * np.clip(np.nan_to_num(gamma), 0.0, 1.0) ** 2
        cross = np.maximum(cross, coherent)
    rho = np.where(same_track[None], rule.track_correlation, cross[:, None, None])  # (K, C, C)
    rho[:, np.arange(n_c), np.arange(n_c)] = 1.0
    common = np.full(n_k, np.nan)
    ref = np.full((n_k, n_c), np.nan)
    prob = np.full((n_k, n_c), np.nan)
    warning = np.zeros((n_k, n_c), dtype=bool)
    w_time = np.full(n_c, np.nan)
    w_prob, w_p, w_ref = np.full(n_c, np.nan), np.full(n_c, np.nan), np.full(n_c, np.nan)
    ref_now = np.full(n_c, np.nan if placard_kpa is None else float(placard_kpa))
    ref_sig = np.zeros(n_c)
    learned = np.zeros(n_c)  # observable time since the reset, s
    streak = np.zeros(n_c, dtype=int)
    w_common = np.zeros(n_c, dtype=bool)
    keep = 1.0 - rule.detect_fraction
    fused, fused_sd = np.full((n_k, n_c), np.nan), np.full((n_k, n_c), np.nan)
    fused_cov = np.full((n_k, n_c, n_c), np.nan)  # the fused estimates' covariance, kPa²
    model_fused = None
    if radius is not None:
        radius.check(n_k, n_c)
        if radius.model is not None:
            model_fused = fuse_with_radii(p, sig, rho, radius.excess, radius.sigma, radius.model,
                                          spread_permille=rule.radius_spread_permille,
                                          lag_kpa=radius.lag_kpa)  # fmt: skip
    calibration = None  # radius excess the references go with, and its variance
    relative = np.full((n_k, n_c), np.nan)
    w_relative = np.zeros(n_c, dtype=bool)
    early = None  # learned mode: the radii at radius_learn_s after the reset, their σ, the pressures
    for k in range(n_k):
        step = t[k] - t[k - 1] if k > 0 else 0.0
        if t[k] < reset_at_s:
            continue
        rel, rel_sd = np.full(n_c, np.nan), np.full(n_c, np.nan)  # pressure / reference and its spread
        for c in range(n_c):
            if np.isnan(ref_now[c]):
                if obs[k, c]:
                    learned[c] += step
                if learned[c] >= rule.learn_s and obs[k, c] and sig[k, c] <= rule.learn_sigma_kpa:
                    ref_now[c], ref_sig[c] = p[k, c], sig[k, c]
                continue
            ref[k, c] = ref_now[c]
            spread = math.sqrt(spread_p[k, c] ** 2 + (keep * ref_sig[c]) ** 2)
            prob[k, c] = _below(keep * ref_now[c], p[k, c], spread)
            rel[c], rel_sd[c] = p[k, c] / ref_now[c], spread / ref_now[c]
        informed = np.zeros(n_c, dtype=bool)
        # the wheels the radii's excesses are over at this row (all, or all but a dead sensor's): a
        # calibration holds while they are the same wheels (an excess over others is another quantity)
        read = np.isfinite(radius.excess[k]) if radius is not None else np.zeros(n_c, dtype=bool)
        radii_here = read.sum() >= 2
        if radius is not None and placard_kpa is None and radii_here:
            if early is None and t[k] - reset_at_s >= rule.radius_learn_s:
                early = (radius.excess[k].copy(), radius.sigma[k].copy(), p[k].copy())
            if early is not None and np.array_equal(read, np.isfinite(early[0])):
                relative[k] = _relative_loss(radius, k, early, rule.detect_fraction)
        if model_fused is not None and np.isfinite(model_fused.pressure_kpa[k]).all():
            # against the tyre model within the tyres' spread: a placard reference decides on it
            fused[k], fused_sd[k] = model_fused.pressure_kpa[k], model_fused.sigma_kpa[k]
            fused_cov[k] = model_fused.cov_kpa2[k]
            if placard_kpa is not None:
                for c in range(n_c):
                    prob[k, c] = _below(keep * ref_now[c], fused[k, c], fused_sd[k, c])
                informed[:] = True
        learned_all = placard_kpa is None and not np.isnan(ref_now).any()
        if calibration is None and radius is not None and learned_all and radii_here:
            # the radii as they were when the references were learned, and over which wheels
            calibration = (radius.excess[k].copy(),
                           excess_cov(wheel_sd(radius.sigma[k], int(read.sum())), read), read)  # fmt: skip
        if calibration is not None and learned_all and np.array_equal(read, calibration[2]):
            sd_k = sig[k] if radius.lag_kpa is None else np.hypot(sig[k], radius.lag_kpa[k])
            fused[k], cov = _fuse_radius(p[k], sd_k, rho[k], ref_now, radius, k, calibration, ref_sig)
            fused_sd[k], fused_cov[k] = np.sqrt(np.diag(cov)), cov
            for c in range(n_c):  # cov is the loss's, p − reference: the reference's σ is in it
                prob[k, c] = _below(keep * ref_now[c], fused[k, c], fused_sd[k, c])
            informed[:] = True
        # the common loss is the whole car's: three or more tyres observable, and every tyre with a
        # reference either observable or, fused with the radii, tied to the others (_common_fit)
        inside = obs[k] & np.isfinite(rel)
        if rule.common_alpha is not None:
            scale = np.outer(ref_now, ref_now)
            fit = _common_fit(inside, rel, rel_sd, rho[k], fused[k] / ref_now, fused_cov[k] / scale,
                              rule.common_alpha)  # fmt: skip
            if fit is not None:
                inside, u, cov_u = fit
                common[k] = _common_loss(u, cov_u, keep, rule.common_alpha)
        for c in range(n_c):
            apart = relative[k, c] >= rule.probability  # NaN: no
            if np.isnan(ref_now[c]) and np.isnan(relative[k, c]):
                continue
            own = prob[k, c] >= rule.probability  # NaN before the reference: no
            shared = bool(inside[c]) and common[k] >= rule.probability
            # a row counts where the tyre is observable, or fused with the radii at a σ within the
            # monitor's observability limit, or compared with the others by its radius
            fused_ok = informed[c] and fused_sd[k, c] <= rule.informed_sigma_kpa
            counted = obs[k, c] or fused_ok or not np.isnan(relative[k, c])
            streak[c] = streak[c] + 1 if (counted and (own or shared or apart)) else 0
            if np.isnan(w_time[c]) and streak[c] >= rule.confirm_updates:
                w_time[c], w_ref[c] = t[k], ref_now[c]
                w_p[c] = fused[k, c] if np.isfinite(fused[k, c]) else p[k, c]
                w_common[c] = shared and not own
                w_relative[c] = apart and not own and not shared
                w_prob[c] = prob[k, c] if own else common[k] if shared else relative[k, c]
            warning[k, c] = not np.isnan(w_time[c])
    return DeflationWarnings(
        reference_kpa=ref, probability=prob, warning=warning, warning_time_s=w_time,
        warning_probability=w_prob, warning_pressure_kpa=w_p, warning_reference_kpa=w_ref,
        common_probability=common, warning_common=w_common, fused_kpa=fused, fused_sigma_kpa=fused_sd,
        relative_probability=relative, warning_relative=w_relative,
    )  # fmt: skip


def _relative_loss(radius: RadiusEvidence, k: int, early, fraction: float) -> np.ndarray:
    r"""Per tyre, the probability that it has lost `fraction` of its pressure more than the others'
    mean since the radii's calibration `early` (their excess, its σ and the pressures then, kPa):
    a tyre that alone loses ΔL kPa drops its excess by g ΔL, so with the deficit
    :math:`d_i = e_{0,i} - e_i` (σ from both), :math:`P = \Phi((d_i - g_i f p_{0,i})/\sigma_i)`. Losses the
    others share lower it (all four alike: 0): it can only under-state a single tyre's loss."""
    e0, sd0, p0 = early
    gain = np.asarray(radius.gain_per_kpa, dtype=float)
    deficit = e0 - radius.excess[k]
    spread = np.sqrt(sd0**2 + radius.sigma[k] ** 2)
    return scipy.special.ndtr((deficit - gain * fraction * p0) / spread)


def _common_fit(inside, rel, rel_sd, rho, fused_rel, fused_cov, alpha):
    r"""Which tyres the common loss is fitted over at a row, and with what: None (no fit), or the
    tyres (C,) bool, their relative pressures and its covariance; three or more observable
    (`inside`) in any case. Where every tyre with a reference (`rel` finite) is observable: those,
    each vibration estimate `rel` ± `rel_sd` (the spread of its upper tail, as the tyre's own
    probability) correlated by `rho` — unless the estimates fused with the radii refute one common
    value at level `alpha` (:func:`_radii_refute_common`): then None. Else, where every tyre's
    estimate fused with the radii is known (`fused_rel` (C,): over its reference, `fused_cov` (C, C)
    its covariance, relative): all of them, fused — the radii tie a tyre whose windows were refused
    to the others (its contrast to them, to within the tyres' spread), and the fusion's covariance
    carries that tie. A tyre that is neither observable nor fused has only the monitor's prior, the
    same for every tyre: its error is not one `rho` describes, so it is never fitted."""
    known = np.isfinite(rel)
    if np.count_nonzero(inside) < 3:
        return None
    if np.all(inside[known]):
        if _radii_refute_common(fused_rel, fused_cov, alpha):
            return None  # the radii's contrasts say the tyres differ
        return inside, rel[inside], rho[np.ix_(inside, inside)] * np.outer(rel_sd[inside], rel_sd[inside])
    if np.all(known) and np.all(np.isfinite(fused_rel)) and np.all(np.isfinite(fused_cov)):
        return known, fused_rel, fused_cov
    return None


def _radii_refute_common(fused_rel: np.ndarray, fused_cov: np.ndarray, alpha: float) -> bool:
    r"""Whether the estimates fused with the radii (`fused_rel` (C,): over their references, `fused_cov`
    (C, C) their covariance, relative) reject at level `alpha` that one relative pressure explains
    every tyre (the χ² of :func:`_common_gls`). False where they are not all known or their
    covariance is degenerate.

    Where every tyre is observable the common fit is the vibration estimates', whose errors are
    correlated 0.75 along a track: two tyres low on one side look to it like that track's shared
    error beside a common loss. The radii pin the tyres' contrasts (to within the tyres' spread), so
    their test tells a one- or two-sided loss from the car's common one (MuJoCo, left front and rear
    20 % low, class A at 116 km/h: the vibration's fit passed and warned the two inflated tyres)."""
    if not (np.all(np.isfinite(fused_rel)) and np.all(np.isfinite(fused_cov))):
        return False
    fit = _common_gls(fused_rel, fused_cov)
    return fit is not None and fit[2] < alpha


def _common_gls(rel: np.ndarray, cov: np.ndarray) -> tuple[float, float, float] | None:
    r"""One relative pressure r fitted to every tyre's: its estimate, σ and the fit's χ² p-value, or
    None where the covariance is degenerate.

    `rel` (n,): each tyre's estimate over its reference; `cov` (n, n): their errors' covariance
    Σ (relative). Generalized least squares:
    :math:`\hat r = 1^T\Sigma^{-1}u / 1^T\Sigma^{-1}1`, :math:`\mathrm{var}\,\hat r = 1/1^T\Sigma^{-1}1`;
    the fit's :math:`\chi^2 = (u - \hat r)^T\Sigma^{-1}(u - \hat r)` with n − 1 degrees of freedom
    tests that one r explains them all (Aitken 1935)."""
    try:
        inv_one, inv_rel = np.linalg.solve(cov, np.column_stack([np.ones(rel.size), rel])).T
    except np.linalg.LinAlgError:
        return None
    info = float(inv_one.sum())
    if not (np.isfinite(info) and info > 0.0):
        return None
    r_hat = float(inv_one @ rel) / info
    chi2 = float(inv_rel @ rel) - r_hat**2 * info  # (u − r̂)ᵀΣ⁻¹(u − r̂)
    return r_hat, 1.0 / math.sqrt(info), float(scipy.special.chdtrc(rel.size - 1, max(chi2, 0.0)))


def _common_loss(rel: np.ndarray, cov: np.ndarray, keep: float, alpha: float) -> float:
    """Probability that tyres sharing one relative pressure r (:func:`_common_gls` of `rel`, `cov`)
    have it below `keep`, or NaN where the test that they share it fails at level `alpha` (or the
    covariance is degenerate)."""
    fit = _common_gls(rel, cov)
    if fit is None or fit[2] < alpha:
        return math.nan
    return _below(keep, fit[0], fit[1])


def _below(threshold: float, mean: float, spread: float) -> float:
    """Φ((threshold − mean)/spread): the probability that a Gaussian estimate lies below `threshold`."""
    return float(0.5 * scipy.special.erfc(-(threshold - mean) / (spread * math.sqrt(2.0))))
