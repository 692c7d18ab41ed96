r"""Online four-corner tyre-pressure monitor: streaming, bounded state, follows pressure changes.

Usual call::

    mon = TyreMonitor(corner_models, dt=1e-3)
    for chunk in stream:                       # any chunk length, in time order
        out = mon.update(chunk.t_s, chunk.speed_mps, chunk.acc_sprung, chunk.acc_unsprung)
        out.pressure_pa, out.pressure_sigma_pa, out.observable   # one row per update

What it estimates (the model is :mod:`suvtwin.estimators.joint`'s, made causal and recursive):
each tyre's vertical stiffness k_t and pressure (eq. 3–4 of Brancati & Tufano 2022 [3]_) with σ,
each corner's road level :math:`G_d(n_0)` and waviness w, and the road's, pooled over the corners.
Each corner is the linear roll-plane corner model
(:class:`~suvtwin.estimators.joint.LinearQuarterCar`) driven by an ISO 8608 road; the likelihood
is Whittle's [1]_, projected on the road-driven direction of the corner's two accelerations (see
the joint estimator). The corners are estimated independently: tying their level and slope
together lowers the ideal Cramér–Rao bound a little (``bench/monitor_bound.py``), but on the
MuJoCo SUV it turned each corner model's small gain error into a k_t error of the other corners
and made every tyre worse (README, "Online tyre-pressure monitor").

How it runs, every ``update_s`` seconds on the last ``segment_s`` of data (a sliding window,
rectangular, linear detrend; above ``merge_above_hz`` the periodogram is averaged in bands of
``merge_width_hz``):

1. **Checks.** Per corner, a window with a missing value, a saturated (flat-topped) or
   implausible accelerometer, or a spike is skipped; so is a window whose speed is not
   finite, negative or changes by more than ``max_speed_change`` within it, and one at a
   speed whose spectral band (``band_cycles_per_m`` times the speed) stops below
   ``hop_margin`` times the corner's wheel-hop frequency: there k_t barely changes the
   spectrum (the Cramér–Rao bound at 25 km/h is ~60 kPa after 10 s), so the window is not
   used for k_t. Each skip is counted, by reason, in the output; nothing is fatal.
2. **Sufficient statistics with forgetting.** Each used window's 2×2 cross-periodogram of
   (sprung, unsprung) acceleration, weighted by update_s/segment_s (each sample lies in that
   many windows), is added to accumulators binned by speed (bins ``speed_bin_ratio`` wide: the
   road-velocity PSD and the band scale with speed). Every accumulator decays as
   :math:`e^{-\Delta t/\tau}` in time: a weighted likelihood. The state is these accumulators
   and the last ``change_window_s`` of windows: its size is fixed by the frequency grid, the
   speed bins and the corners, so the cost per second of data is the same after 10 s and after
   10 h (``bench/monitor_cost.py``).
3. **Estimates per memory.** For each memory τ in ``memories_s`` and each corner, the log level,
   the waviness slope β = 2 − w and the pressure maximize the weighted Whittle likelihood by
   Fisher scoring, warm-started (all memories and corners in one compiled call); the corner
   damping (a digressive damper's equivalent linear damping) is marginalized over
   ``damping_points`` values of its range, and the waviness has the joint estimator's
   spike-and-slab prior (w = 2 with probability ``waviness_iso_weight``). σ comes from the
   inverse Fisher information of the corner's parameters together, corrected by the sandwich
   factor of a weighted likelihood, :math:`\sum w_k^2/\sum w_k`, which makes it the error std
   of the estimate under a constant pressure rather than the conservative
   :math:`(\sum w_k I)^{-1}`.
4. **Choosing the memory.** Before a window is added, each memory's estimate predicts the
   newest ``update_s`` of data: the score is its Whittle log-likelihood at that memory's
   parameters, less half the information it carries times the memory's variance (the expected
   log predictive density, Gaussian approximation). Per corner, the scores are summed with
   forgetting (``selection_s``) and the memories weighted by them (dynamic model averaging
   [2]_): a long memory wins while the pressure is steady, a short one while it changes; the
   output is their mixture (mean and variance).
5. **Change detection.** A generalized likelihood ratio test [4]_ looks for a step in each
   tyre's pressure within the last ``change_window_s``: the windows' scores and information in
   p at the longest memory's estimate, summed from each candidate start to now, give
   GLR = U²/(2I); above ``change_nats`` every memory of that tyre is rebuilt from the windows
   since the change's start, so after an abrupt change (or a change of road roughness, which
   the test also sees) the memory is cut, not left to fade.
6. **The suspension and the tyre, linearized at the measured travel.** A corner model with a
   suspension law (``LinearQuarterCar.suspension``: a progressive spring with stops, a
   digressive damper) is analysed at its statistically linearized rate
   (:func:`suvtwin.suspension_law.equivalent_spring_rate`): the travel's and its velocity's
   standard deviations come from each window's (and each memory's) spectrum of the relative
   acceleration a_s − a_us above ``travel_min_hz``, the mean travel from the corner's static
   travel and the damper's jacking; and its tyre's stiffness and damping are scaled by the share
   of time it touches the road, Φ(W/σ_F), with the dynamic wheel load −(m_s a_s + m_us a_us)
   taken as Gaussian. Gain tables are made per (corner, rate step ``rate_step``, contact step)
   when first needed and kept (at most ``table_slots``, least recently used replaced). Where the
   linearized travel is on a stop or the wheel off the ground more than ``max_nonlinear_share``
   of the time no linear model holds, and the window is skipped (``rough``).
7. **The front→rear preview** (``tracks``): each rear wheel runs over its front wheel's track a
   wheelbase/speed later, so the rear's unsprung acceleration is the front's through the ratio
   of the two wheels' responses (:mod:`suvtwin.estimators.preview`: 1 s segments on 20–40 Hz,
   the road cancels). Each track keeps that likelihood's statistics with the same memories; at
   each update, per memory, the rear's pressure given the front's estimate (Laplace along the
   likelihood's ridge, with a model-error floor) is fused with the rear's own
   (:func:`suvtwin.estimators.preview.fuse_track`); the front keeps its own. A memory whose front
   is not observable (σ above ``observable_sigma_kpa``) passes nothing on. A restart of either
   corner by the change test restarts the track's preview.
8. **Observability.** A corner whose σ exceeds ``observable_sigma_kpa`` (no usable data in
   memory: low speed, flat road, faulty sensor) is flagged not observable; its estimate
   then relaxes to the prior (``prior_pressure_kpa`` ± ``prior_sigma_kpa``) as the memory
   fades, instead of holding an old value with a small σ.

Everything uses data up to t only (the speed included): the estimate at t from a record cut
at t is the estimate at t from the whole record.

No MuJoCo here: the monitor consumes arrays.

References
----------
.. [1] P. Whittle, "Curve and periodogram smoothing", J. R. Stat. Soc. B 19(1), 1957.
.. [2] A. E. Raftery, M. Kárný, P. Ettler, "Online prediction under model uncertainty via
   dynamic model averaging: application to a cold rolling mill", Technometrics 52(1), 52–66,
   2010. doi:10.1198/TECH.2009.08104
.. [3] R. Brancati, F. Tufano, Machines 10(12), 1221, 2022, eq. 3–4 (k_t(p)).
.. [4] A. S. Willsky, H. L. Jones, "A generalized likelihood ratio approach to the detection and
   estimation of jumps in linear systems", IEEE Trans. Automatic Control 21(1), 108–112, 1976.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np
import numpy.typing as npt
from scipy.special import ndtr

from suvtwin.errors import InputError
from suvtwin.estimators.joint import N0, LinearQuarterCar, profile_loglik, signal_direction, signal_gain
from suvtwin.estimators.preview import PreviewConfig, PreviewTrack, fuse_track
from suvtwin.estimators.quarter_car import stiffness_from_pressure
from suvtwin.jit import cached_njit
from suvtwin.suspension_law import equivalent_spring_rate
from suvtwin.tire_stiffness import (
    TireStiffness,
    stiffness_at_pressure_array,
    stiffness_sigma_at_pressure_sigma,
    suv_tire_stiffness,
)

__all__ = ["SKIP_REASONS", "MonitorConfig", "MonitorUpdate", "TyreMonitor", "pressure_at"]

SKIP_REASONS = ("used", "gap", "clipped", "implausible", "spike", "speed", "low_speed", "rough")
"""Per corner and segment, why it was (not) used for k_t: index into this tuple.
``gap``: a missing (NaN) value; ``clipped``: three or more consecutive samples at the segment's
extreme or at the sensor's range; ``implausible``: a value beyond ``max_accel_mps2`` or a dead
(constant) channel; ``spike``: more than 0.2 % of an update's samples more than ``spike_z``
robust standard deviations from the median (fewer are replaced by the median and counted as
``despiked``, and the window is used); ``speed``: speed not finite, negative or changing
within the segment; ``low_speed``: the band does not reach past the wheel hop; ``rough``: the
suspension hits its stops or the wheel leaves the ground more than ``max_nonlinear_share`` of the
time (a corner model with a suspension law only): there no linear model holds."""

_USED, _GAP, _CLIPPED, _IMPLAUSIBLE, _SPIKE, _SPEED, _LOW_SPEED, _ROUGH = range(len(SKIP_REASONS))
_LEVEL_BOUNDS = (np.log(1e-8), np.log(1e-1))  # log Gd(n0), m³
_GRAVITY = 9.81  # m/s²


@dataclass(frozen=True)
class MonitorConfig:
    """Settings of :class:`TyreMonitor` (units in the names; defaults are the documented ones).

    Attributes
    ----------
    segment_s : float
        Length of the window each periodogram is taken over, s (its frequency resolution is
        1/segment_s; shorter windows bias k_t high on the MuJoCo SUV).
    update_s : float
        Interval between updates, s (the window slides by it; segment_s must be a multiple).
    memories_s : tuple of float
        Forgetting time constants τ of the memories, s, shortest first.
    selection_s : float
        Forgetting time constant of the memories' summed predictive scores, s.
    change_nats : float
        Threshold of the change test (generalized likelihood ratio of a pressure change within
        the last ``change_window_s``), nats.
    change_window_s : float
        How far back the change test looks for the change's start, s (the recent windows it
        keeps to rebuild a memory from the change on).
    band_cycles_per_m : (float, float)
        Spatial-frequency band used, cycles/m (times the speed: Hz).
    max_frequency_hz : float
        Upper limit of the band, Hz.
    merge_above_hz, merge_width_hz : float
        Above `merge_above_hz` the periodogram's neighbouring frequencies are averaged in bands
        about `merge_width_hz` wide (Whittle's likelihood of a band-averaged periodogram, each band
        weighted by the frequencies it holds): the spectra there are smooth on that scale, and
        the cost falls about threefold.
    sigma_accel : float
        Accelerometer noise std (each channel), m/s².
    pressure_range_kpa : (float, float)
        Range the pressures are kept in, kPa.
    prior_pressure_kpa, prior_sigma_kpa : float or None, float
        Gaussian prior on each pressure, kPa (None: the tyre's nominal pressure).
    waviness_range : (float, float)
        Range of the road waviness w.
    waviness_iso_weight : float
        Prior probability that w = 2 exactly (spike and slab).
    damping_points : int
        Damping values over the corner model's ``damping_range`` (marginalized).
    hop_margin : float
        A segment informs k_t only if its band reaches this times the wheel-hop frequency.
    speed_bin_ratio : float
        Ratio of neighbouring speed bins of the accumulators.
    max_speed_change : float
        Largest (max − min)/mean speed within a used segment.
    accel_range_mps2 : float or None
        The accelerometers' full scale, m/s²: samples at it count as clipped (None: only
        flat tops are detected).
    max_accel_mps2 : float
        Beyond this a sample is implausible, m/s².
    spike_z : float
        A sample this many robust σ (1.4826 MAD) from the median is a spike.
    observable_sigma_kpa : float
        Above this σ a corner is flagged not observable, kPa.
    travel_min_hz : float
        Lowest frequency of the suspension travel's spectrum the equivalent linearization
        integrates, Hz. Below about 1 Hz the rectangular window's leakage of sub-hertz content
        (speed control, the body's slow motions), amplified by 1/(2πf)⁴, dominates: from 0.5 Hz
        the travel's σ came out 10–80 % high on a MuJoCo class D run, from 1 Hz within 8 % of the
        simulated rate (``tests/test_monitor_linearization.py``).
    rate_step : float
        Relative step of the equivalent suspension rates the gain tables are made for (the
        rate is rounded to the nearest: error ≤ half a step).
    table_slots : int
        Most gain tables (corner and rate) kept at once; the least recently used is replaced.
    max_nonlinear_share : float
        A window whose travel (Gaussian, as linearized) reaches the bump or rebound stop, or whose
        wheel leaves the ground, more than this share of the time is not used for k_t (``rough``).
    """

    segment_s: float = 8.0
    update_s: float = 4.0
    memories_s: tuple[float, ...] = (4.0, 16.0, 64.0)
    selection_s: float = 10.0
    change_nats: float = 5.0
    change_window_s: float = 30.0
    band_cycles_per_m: tuple[float, float] = (0.05, 1.5)
    max_frequency_hz: float = 30.0
    merge_above_hz: float = 3.0
    merge_width_hz: float = 0.5
    sigma_accel: float = 0.5
    pressure_range_kpa: tuple[float, float] = (60.0, 400.0)
    prior_pressure_kpa: float | None = None
    prior_sigma_kpa: float = 100.0
    waviness_range: tuple[float, float] = (1.5, 3.0)
    waviness_iso_weight: float = 0.8
    damping_points: int = 3
    hop_margin: float = 1.25
    speed_bin_ratio: float = 1.05
    max_speed_change: float = 0.1
    accel_range_mps2: float | None = None
    max_accel_mps2: float = 1000.0
    spike_z: float = 8.0
    observable_sigma_kpa: float = 25.0
    travel_min_hz: float = 1.0
    rate_step: float = 0.02
    table_slots: int = 32
    max_nonlinear_share: float = 0.05

    def __post_init__(self) -> None:
        checks = [
            ("segment_s", 0.25 <= self.segment_s <= 60.0, "0.25–60 s"),
            (
                "update_s",
                0.25 <= self.update_s <= self.segment_s
                and abs(self.segment_s / self.update_s - round(self.segment_s / self.update_s)) < 1e-9,
                "0.25 s–segment_s, segment_s a multiple of it",
            ),
            (
                "memories_s",
                len(self.memories_s) >= 1
                and all(self.update_s <= m <= 1e6 for m in self.memories_s)
                and list(self.memories_s) == sorted(self.memories_s),
                "increasing values in [update_s, 1e6] s",
            ),
            ("selection_s", self.update_s <= self.selection_s <= 1e6, "update_s–1e6 s"),
            ("change_nats", self.change_nats > 0, "> 0"),
            ("change_window_s", self.update_s <= self.change_window_s <= 600.0, "update_s–600 s"),
            (
                "band_cycles_per_m",
                0 < self.band_cycles_per_m[0] < self.band_cycles_per_m[1],
                "0 < low < high",
            ),
            ("max_frequency_hz", self.max_frequency_hz > 0, "> 0"),
            ("merge_above_hz", self.merge_above_hz >= 0, "≥ 0"),
            ("merge_width_hz", 0 < self.merge_width_hz <= 5.0, "(0, 5] Hz"),
            ("sigma_accel", self.sigma_accel > 0, "> 0"),
            (
                "pressure_range_kpa",
                0 < self.pressure_range_kpa[0] < self.pressure_range_kpa[1],
                "0 < low < high",
            ),
            ("prior_sigma_kpa", self.prior_sigma_kpa > 0, "> 0"),
            ("waviness_range", self.waviness_range[0] <= self.waviness_range[1], "low ≤ high"),
            ("waviness_iso_weight", 0 <= self.waviness_iso_weight < 1, "[0, 1)"),
            ("damping_points", self.damping_points >= 1, "≥ 1"),
            ("hop_margin", self.hop_margin > 0, "> 0"),
            ("speed_bin_ratio", 1 < self.speed_bin_ratio <= 1.5, "(1, 1.5]"),
            ("max_speed_change", self.max_speed_change > 0, "> 0"),
            ("max_accel_mps2", self.max_accel_mps2 > 0, "> 0"),
            ("spike_z", self.spike_z > 3, "> 3"),
            ("observable_sigma_kpa", self.observable_sigma_kpa > 0, "> 0"),
            ("travel_min_hz", 0 < self.travel_min_hz < self.max_frequency_hz, "(0, max_frequency_hz) Hz"),
            ("rate_step", 0.001 <= self.rate_step <= 0.2, "0.001–0.2"),
            ("table_slots", self.table_slots >= 1, "≥ 1"),
            ("max_nonlinear_share", 0 < self.max_nonlinear_share <= 1, "(0, 1]"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"monitor setting {name} must be {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class MonitorUpdate:
    """The monitor's output for the segments finished by one :meth:`TyreMonitor.update` (K rows).

    `t_s` (K,): time of the segment's last sample, s (the estimate uses data up to it);
    `pressure_pa`, `pressure_sigma_pa`, `stiffness`, `stiffness_sigma` (K, C): per corner, Pa
    and N/m; `observable` (K, C): σ below the configured limit; `status` (K, C): index into
    :data:`SKIP_REASONS` of what became of the segment (0: used); `road_level` (K,): the
    shared Gd(n0), m³ (NaN before any data); `waviness` (K,); `speed_mps` (K,): the segment's
    mean speed; `memory_weights` (K, C, M); `restarts` (K, C): memories restarted by the change
    test at this segment; `spring_rate` (K, C): the suspension rate the segment's window was
    analysed with, N/m (the equivalent rate of a corner with a suspension law, else its model's;
    NaN where the window was not analysed); `tyre_contact` (K, C): the share of time the tyre
    was taken to touch the road (1 without a suspension law; NaN where not analysed).
    """

    t_s: np.ndarray
    pressure_pa: np.ndarray
    pressure_sigma_pa: np.ndarray
    stiffness: np.ndarray
    stiffness_sigma: np.ndarray
    observable: np.ndarray
    status: np.ndarray
    road_level: np.ndarray
    waviness: np.ndarray
    speed_mps: np.ndarray
    memory_weights: np.ndarray
    restarts: np.ndarray
    spring_rate: np.ndarray
    tyre_contact: np.ndarray

    @staticmethod
    def concatenate(parts: list[MonitorUpdate]) -> MonitorUpdate:
        """Rows of several updates, in order."""
        return MonitorUpdate(**{
            name: np.concatenate([getattr(p, name) for p in parts], axis=0)
            for name in MonitorUpdate.__dataclass_fields__
        })  # fmt: skip


@cached_njit
def _corner_terms(lam, beta, p_kpa, table, log_gain, dlog_gain, p_lo, p_step, proj, weight, x, log_cv):
    """Whittle log-likelihood, score and Fisher information per (corner, damping) in (λ_c, β, p).

    `lam`, `beta` (C,): each row's log level and slope; `table` (C, B): which gain table (slot) row c
    uses in bin b (rows may be memories × corners; a slot is a corner at a suspension rate).
    r = exp(λ_c + β_c x + log_cv + log g(p));
    ℓ = −Σ w [log(1 + r) + P/(1 + r)];
    ∂ℓ/∂θ = Σ w q (P/(1+r) − 1) ∂log r/∂θ, I = Σ w q² (∂log r)(∂log r)ᵀ, q = r/(1 + r).
    `log_gain` (S, D, P, F): log(|h|²/N) on the pressure grid p_lo + i·p_step (kPa), linearly
    interpolated; `dlog_gain` its derivative per kPa; `proj` (C, D, B, F); `weight` (C, B, F);
    `x`, (B, F) log(n/n0); `log_cv` (B,) log(4π² n0² v)."""
    n_c, n_d = p_kpa.shape
    n_b, n_f = x.shape
    n_p = log_gain.shape[2]
    ll = np.zeros((n_c, n_d))
    score = np.zeros((n_c, n_d, 3))
    info = np.zeros((n_c, n_d, 3, 3))
    for c in range(n_c):
        for d in range(n_d):
            pos = (p_kpa[c, d] - p_lo) / p_step
            i = min(max(int(np.floor(pos)), 0), n_p - 2)
            a = min(max(pos - i, 0.0), 1.0)
            s0 = s1 = s2 = 0.0
            i00 = i01 = i02 = i11 = i12 = i22 = 0.0
            acc = 0.0
            for b in range(n_b):
                g = table[c, b]
                for j in range(n_f):
                    wf = weight[c, b, j]
                    if wf == 0.0:
                        continue
                    lg = (1.0 - a) * log_gain[g, d, i, j] + a * log_gain[g, d, i + 1, j]
                    dl = (1.0 - a) * dlog_gain[g, d, i, j] + a * dlog_gain[g, d, i + 1, j]
                    xf = x[b, j]
                    r = np.exp(lam[c] + beta[c] * xf + log_cv[b] + lg)
                    inv = 1.0 / (1.0 + r)
                    q = r * inv
                    pw = proj[c, d, b, j]
                    acc -= wf * (np.log1p(r) + pw * inv)
                    e = wf * q * (pw * inv - 1.0)
                    s0 += e
                    s1 += e * xf
                    s2 += e * dl
                    wq = wf * q * q
                    i00 += wq
                    i01 += wq * xf
                    i02 += wq * dl
                    i11 += wq * xf * xf
                    i12 += wq * xf * dl
                    i22 += wq * dl * dl
            ll[c, d] = acc
            score[c, d, 0], score[c, d, 1], score[c, d, 2] = s0, s1, s2
            info[c, d, 0, 0], info[c, d, 0, 1], info[c, d, 0, 2] = i00, i01, i02
            info[c, d, 1, 0], info[c, d, 1, 1], info[c, d, 1, 2] = i01, i11, i12
            info[c, d, 2, 0], info[c, d, 2, 1], info[c, d, 2, 2] = i02, i12, i22
    return ll, score, info


@cached_njit
def _newton_kernel(
    variant,
    lam,
    beta,
    p,
    table,
    log_gain,
    dlog_gain,
    grid_lo,
    grid_step,
    proj,
    weight,
    x,
    log_cv,
    prior,
    prior_var,
    p_lo,
    p_hi,
    lam_lo,
    lam_hi,
    b_lo,
    b_hi,
    iterations,
):
    """Block Fisher scoring of one memory's likelihood, each corner on its own.

    Parameters per corner: log level λ_c and slope β_c (β_c only if `variant` is 1, else kept),
    and per (corner, damping) the pressure p with a Gaussian prior (`prior` (C,), `prior_var`,
    kPa). Each pressure takes its conditional step given (λ_c, β_c); then (λ_c, β_c) take the
    Newton step of their profile likelihood (the pressures' information Schur-complemented out,
    damping-weighted). Steps are clipped (30 kPa, 2 in λ, 0.5 in β) and kept in their ranges; at
    most `iterations` steps, fewer once below 1e-3 (0.1 kPa, 0.001 in λ and β). `lam`, `beta` (C,)
    and `p` (C, D) are updated in place. Returns the damping weights (C, D) (Laplace marginal over
    p), and ℓ (C, D), score (C, D, 3), information (C, D, 3, 3) at the last point, the pressure
    prior included."""
    n_c, n_d = p.shape
    wd = np.empty((n_c, n_d))
    it = 0
    while True:
        ll, score, info = _corner_terms(
            lam, beta, p, table, log_gain, dlog_gain, grid_lo, grid_step, proj, weight, x, log_cv
        )
        for c in range(n_c):
            top = -1e300
            for d in range(n_d):
                dev = p[c, d] - prior[c]
                score[c, d, 2] -= dev / prior_var
                info[c, d, 2, 2] += 1.0 / prior_var
                wd[c, d] = ll[c, d] - 0.5 * dev * dev / prior_var - 0.5 * np.log(info[c, d, 2, 2])
                top = max(top, wd[c, d])
            total = 0.0
            for d in range(n_d):
                wd[c, d] = np.exp(wd[c, d] - top)
                total += wd[c, d]
            for d in range(n_d):
                wd[c, d] /= total
        if it >= iterations:
            break
        moved = 0.0
        for c in range(n_c):
            a = b = e = g = h = 0.0
            for d in range(n_d):
                ipp = info[c, d, 2, 2]
                w = wd[c, d]
                sp = score[c, d, 2] / ipp
                a += w * (info[c, d, 0, 0] - info[c, d, 0, 2] ** 2 / ipp)
                b += w * (info[c, d, 0, 1] - info[c, d, 0, 2] * info[c, d, 1, 2] / ipp)
                e += w * (info[c, d, 1, 1] - info[c, d, 1, 2] ** 2 / ipp)
                g += w * (score[c, d, 0] - info[c, d, 0, 2] * sp)
                h += w * (score[c, d, 1] - info[c, d, 1, 2] * sp)
                new = min(max(p[c, d] + min(max(sp, -30.0), 30.0), p_lo), p_hi)
                moved = max(moved, abs(new - p[c, d]) * 1e-2)
                p[c, d] = new
            a += 1e-9
            e += 1e-9
            if variant == 1:
                det = a * e - b * b
                d_lam = (e * g - b * h) / det
                d_beta = (a * h - b * g) / det
                new_b = min(max(beta[c] + min(max(d_beta, -0.5), 0.5), b_lo), b_hi)
                moved = max(moved, abs(new_b - beta[c]))
                beta[c] = new_b
            else:
                d_lam = g / a
            new_l = min(max(lam[c] + min(max(d_lam, -2.0), 2.0), lam_lo), lam_hi)
            moved = max(moved, abs(new_l - lam[c]))
            lam[c] = new_l
        it += 1
        if moved < 1e-3:
            iterations = it  # evaluate once more at the converged point
    return wd, ll, score, info


def _logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = np.max(a, axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    return np.squeeze(m, axis=axis) + np.log(np.sum(np.exp(a - m), axis=axis))


@dataclass
class _Fit:
    """One memory's estimate. Variants: 0 the ISO slope w = 2, 1 the slope free (spike and slab)."""

    lam: np.ndarray  # (V, C) each corner's log level, log m³
    beta: np.ndarray  # (V, C) each corner's slope β = 2 − w
    p: np.ndarray  # (V, C, D) kPa
    wd: np.ndarray  # (V, C, D) damping weights
    variant_weight: np.ndarray  # (C, V)
    p_mean: np.ndarray  # (C,) kPa
    p_var: np.ndarray  # (C,) kPa²
    lam_mean: np.ndarray  # (C,)
    lam_var: np.ndarray  # (C,)
    beta_mean: np.ndarray  # (C,)
    beta_var: np.ndarray  # (C,)
    has_data: bool


@dataclass
class _State:
    """Everything the monitor remembers: bounded, fixed-size arrays."""

    spec: np.ndarray  # (M, C, NB, F, 3) complex: Σ w_k S_k of S11, S22, S12 (one-sided, per Hz) / scale
    weight: np.ndarray  # (M, C, NB): Σ w_k / scale
    weight2: np.ndarray  # (M, C, NB): Σ w_k² / scale²
    speed_sum: np.ndarray  # (M, C, NB): Σ w_k v_k / scale
    scale: np.ndarray  # (M,): the forgetting factor accumulated since the last renormalization
    score: np.ndarray  # (C, M): forgotten sum of predictive scores
    fits: list  # M × _Fit or None
    buffer_t: np.ndarray  # the last window's samples, then those not yet in a window
    buffer_v: np.ndarray
    buffer_s: np.ndarray
    buffer_u: np.ndarray
    blocks: np.ndarray  # (segment/update, C) status of the window's update blocks, newest last
    recent_spec: np.ndarray  # (K, C, F, 3) the last K windows' weighted cross-periodograms, newest last
    recent_weight: np.ndarray  # (K, C) their weights (0: not used)
    recent_speed: np.ndarray  # (K,) their speeds, m/s
    recent_t: np.ndarray  # (K,) their end times, s
    recent_u: np.ndarray  # (K, C) each window's score in p (1/kPa) at the longest memory's estimate then
    recent_i: np.ndarray  # (K, C) its information in p (1/kPa²)
    recent_p: np.ndarray  # (K, C) the pressure it was taken at, kPa
    in_window: int = 0  # samples at the buffer's start that belong to the last window
    last_t: float = math.nan  # time of the last sample received
    last_segment_t: float = math.nan  # time of the last finished segment
    counts: dict = field(default_factory=dict)


class TyreMonitor:
    """Streaming estimator of the four (or any number of) tyres' pressures; see the module docstring.

    Parameters
    ----------
    corner_models : sequence of LinearQuarterCar
        One linear corner model per monitored corner (C of them), in the column order of the
        accelerations given to :meth:`update`.
    dt : float
        Sampling interval of the stream, s.
    config : MonitorConfig, optional
    tire : TireStiffness or sequence of them, optional
        Each corner's k_t(p) law (eq. 3–4); default the SUV's tyre on every corner.
    names : sequence of str, optional
        Corner names for messages (default ``c0, c1, …``).
    tracks : sequence of (int, int), optional
        (front, rear) column pairs of corners on one track: the rear's estimate is fused with the
        front→rear preview (:mod:`suvtwin.estimators.preview`) of each memory. Needs `wheelbase_m`.
    wheelbase_m : float, optional
        Distance from the front to the rear axle, m.
    preview_config : PreviewConfig, optional
    """

    def __init__(
        self,
        corner_models: list[LinearQuarterCar] | tuple[LinearQuarterCar, ...],
        *,
        dt: float,
        config: MonitorConfig | None = None,
        tire: TireStiffness | list[TireStiffness] | tuple[TireStiffness, ...] | None = None,
        names: list[str] | tuple[str, ...] | None = None,
        tracks: tuple[tuple[int, int], ...] | list = (),
        wheelbase_m: float | None = None,
        preview_config: PreviewConfig | None = None,
    ) -> None:
        if not (np.isfinite(dt) and 1e-5 <= dt <= 0.05):
            raise InputError(f"sampling interval dt must be within 1e-5–0.05 s, got {dt!r}")
        self.config = cfg = config or MonitorConfig()
        self.models = tuple(corner_models)
        if not self.models:
            raise InputError("the monitor needs at least one corner model")
        n_c = len(self.models)
        self.names = tuple(names) if names is not None else tuple(f"c{i}" for i in range(n_c))
        tires = tire if isinstance(tire, (list, tuple)) else [tire or suv_tire_stiffness()] * n_c
        if len(tires) != n_c or len(self.names) != n_c:
            raise InputError("give one tyre law and one name per corner model")
        self.tires = tuple(tires)
        self.dt = float(dt)
        self.hop = int(round(cfg.update_s / dt))
        self.window = self.hop * int(round(cfg.segment_s / cfg.update_s))
        if self.hop < 32:
            raise InputError(f"update_s = {cfg.update_s} s holds fewer than 32 samples at dt = {dt} s")
        freq = np.fft.rfftfreq(self.window, dt)
        self._f_index = np.flatnonzero((freq > 0) & (freq <= cfg.max_frequency_hz * (1.0 + 1e-9)))
        fine = freq[self._f_index]
        # bands: single frequencies below merge_above_hz, groups of ~merge_width_hz above
        per_group = max(int(round(cfg.merge_width_hz * cfg.segment_s)), 1)
        group = np.where(fine <= cfg.merge_above_hz, np.arange(fine.size), 0)
        above = fine > cfg.merge_above_hz
        first_above = int(np.argmax(above)) if np.any(above) else fine.size
        n_single = first_above
        group[above] = n_single + (np.arange(fine.size - first_above) // per_group)
        self._group_start = np.flatnonzero(np.r_[True, np.diff(group) != 0])  # reduceat offsets
        self._group_size = np.diff(np.r_[self._group_start, fine.size]).astype(float)
        # an update block's own Fourier frequency nearest each window frequency
        self._block_index = np.rint(fine * self.hop * dt).astype(int)
        self.freq = np.add.reduceat(fine, self._group_start) / self._group_size
        if self.freq.size < 4:
            raise InputError("the frequency band holds fewer than 4 Fourier frequencies; lengthen segment_s")
        self.noise = 2.0 * cfg.sigma_accel**2 * dt  # one-sided white-noise PSD, (m/s²)²/Hz
        # speed bins: geometric from 1 m/s to 100 m/s
        self._v_lo = 1.0
        self._log_ratio = math.log(cfg.speed_bin_ratio)
        self.n_bins = int(math.ceil(math.log(100.0 / self._v_lo) / self._log_ratio)) + 1
        # pressure grid (kPa) for the gain tables; dampings per corner
        p_lo, p_hi = cfg.pressure_range_kpa
        self._p_step = 1.0
        self._p_grid = np.arange(p_lo, p_hi + 0.5, self._p_step)
        n_d = cfg.damping_points
        self._fine = fine
        self._hop_hz = np.empty(n_c)
        self.dampings = np.empty((n_c, n_d))
        for c, qc in enumerate(self.models):
            self.dampings[c] = (np.full(n_d, qc.damping) if qc.damping_range is None
                                else np.linspace(qc.damping_range[0], qc.damping_range[1], n_d))  # fmt: skip
            kt_nom = stiffness_from_pressure(self.tires[c].p0, **asdict(self.tires[c]))
            self._hop_hz[c] = math.sqrt((qc.spring_rate + kt_nom) / qc.unsprung_mass) / (2.0 * math.pi)
        # gain tables, one per (corner, suspension rate): slot c holds corner c at its model's rate;
        # equivalent rates (corners with a suspension law) get slots when first needed
        # Σ_f S(f) Δf / (2πf)² per band (Δf = 1/segment_s): velocity from acceleration; /(2πf)² again: travel
        omega2 = (2.0 * np.pi * self.freq) ** 2
        in_travel = self.freq >= cfg.travel_min_hz
        self._travel_weight = np.where(in_travel, self._group_size / (cfg.segment_s * omega2), 0.0)
        self._travel_x_weight = self._travel_weight / omega2  # /(2πf)² once more: travel
        self._band_df = self._travel_weight * omega2  # Σ S Δf over the same band
        self._slot_of: dict[tuple[int, int], int] = {}
        self._slot_used = np.zeros(0, dtype=np.int64)
        self._n_updates = 0
        shape = (n_c, n_d, self._p_grid.size, self.freq.size)
        self._log_gain, self._dlog_gain = np.empty(shape), np.empty(shape)
        self._u11 = np.empty((n_c, n_d, 1, self.freq.size))
        self._u22 = np.empty_like(self._u11)
        self._u12 = np.empty(self._u11.shape, dtype=complex)
        for c in range(n_c):
            self._slot(c, 0)
        self._nonlinear = any(qc.suspension is not None for qc in self.models)
        self.tracks = tuple((int(f), int(r)) for f, r in tracks)
        used = [c for pair in self.tracks for c in pair]
        if self.tracks and (wheelbase_m is None or any(not 0 <= c < n_c for c in used)
                            or len(set(used)) != len(used)):  # fmt: skip
            raise InputError(
                f"tracks must be (front, rear) pairs of distinct corner indices 0–{n_c - 1}, with wheelbase_m"
            )
        self._previews = [
            PreviewTrack(self.models[f], self.models[r], self.tires[f], self.tires[r], dt, float(wheelbase_m),
                         preview_config, memories=len(cfg.memories_s))
            for f, r in self.tracks
        ]  # fmt: skip
        self._laws = np.array([[t.kt0, t.p0, t.pfz1] for t in self.tires]).T  # (3, C): eq. 3–4 per corner
        self._prior = np.array(
            [t.p0 / 1e3 if cfg.prior_pressure_kpa is None else cfg.prior_pressure_kpa for t in self.tires]
        )
        self._prior_var = cfg.prior_sigma_kpa**2
        self._n_recent = int(math.ceil(cfg.change_window_s / cfg.update_s))
        w_lo, w_hi = cfg.waviness_range
        self._beta_bounds = (2.0 - w_hi, 2.0 - w_lo)
        self._slope_free = self._beta_bounds[1] > self._beta_bounds[0]
        self.reset()

    # ------------------------------------------------------------------ gain tables
    def _fill_slot(self, slot: int, c: int, step: int, lift: int) -> None:
        """Gain tables of corner c with its suspension rate times (1 + rate_step)^step and its tyre's
        stiffness and damping times the contact share (1 + rate_step)^−lift, in `slot`.

        log(|h|²/N) per damping, pressure and band (the band's mean gain), its derivative in p,
        and the signal direction's terms u^H S u = |u1|² S11 + |u2|² S22 + 2 Re(conj(u1) u2 S12)."""
        qc = self.models[c]
        rate = qc.spring_rate * (1.0 + self.config.rate_step) ** step
        contact = (1.0 + self.config.rate_step) ** -lift
        kt = contact * stiffness_from_pressure(self._p_grid * 1e3, **asdict(self.tires[c]))
        for d, cd in enumerate(self.dampings[c]):
            model = replace(qc, damping=float(cd), spring_rate=rate, tire_damping=contact * qc.tire_damping)
            g = signal_gain(self._fine[None, :], kt[:, None], model) / self.noise
            g = np.add.reduceat(g, self._group_start, axis=1) / self._group_size
            self._log_gain[slot, d] = np.log(np.maximum(g, 1e-300))
            u1, u2 = signal_direction(self.freq, model)
            self._u11[slot, d, 0] = np.abs(u1) ** 2 / self.noise
            self._u22[slot, d, 0] = np.abs(u2) ** 2 / self.noise
            self._u12[slot, d, 0] = 2.0 * np.conj(u1) * u2 / self.noise
        self._dlog_gain[slot] = np.gradient(self._log_gain[slot], self._p_step, axis=1)

    def _slot(self, c: int, step: int, lift: int = 0) -> int:
        """Index of the gain tables of corner c at rate step `step` and contact step `lift`, made (or
        recycled: the least recently used slot not used in this update) when missing."""
        key = (c, step, lift)
        slot = self._slot_of.get(key)
        if slot is None:
            n = self._slot_used.size
            idle = np.flatnonzero(self._slot_used[len(self.models):] < self._n_updates) + len(self.models)
            if n < self.config.table_slots or idle.size == 0:
                slot = n  # grow
                grow = lambda a: np.concatenate([a, np.empty((1,) + a.shape[1:], a.dtype)])  # noqa: E731
                if n >= self._log_gain.shape[0]:
                    self._log_gain, self._dlog_gain = grow(self._log_gain), grow(self._dlog_gain)
                    self._u11, self._u22, self._u12 = grow(self._u11), grow(self._u22), grow(self._u12)
                self._slot_used = np.append(self._slot_used, self._n_updates)
            else:
                slot = int(idle[np.argmin(self._slot_used[idle])])
                del self._slot_of[next(k for k, v in self._slot_of.items() if v == slot)]
            self._fill_slot(slot, c, step, lift)
            self._slot_of[key] = slot
        self._slot_used[slot] = self._n_updates
        return slot

    def _tables_for(self, corners: np.ndarray, spec: np.ndarray):
        """Gain-table slots for spectra `spec` (..., F, 3) of corners `corners` (same leading shape),
        the share of time the linearization's Gaussian travel spends on a stop or the wheel off
        the ground (0 for corners without a suspension law), the suspension rate (N/m) and the
        tyre's contact share: four arrays of that shape.

        A corner whose model has a suspension law gets the tables of its equivalent rate
        (:func:`suvtwin.suspension_law.equivalent_spring_rate`) at the travel's and travel
        velocity's standard deviations, integrated from the spectrum of the relative acceleration
        S11 + S22 − 2 Re S12 (less the two sensors' noise) above ``travel_min_hz``, and of its
        tyre's equivalent stiffness and damping: the tyre pushes only while in contact, so its
        statistically linearized rate is k_t·P(contact), with the dynamic wheel load
        −(m_s a_s + m_us a_us) Gaussian of the std its spectrum gives and the static load
        (m_s + m_us)·g: P(contact) = Φ(W/σ_F). The others get their model's tables."""
        corners = np.asarray(corners)
        out = corners.copy()
        share = np.zeros(corners.shape)
        rate = np.array([self.models[c].spring_rate for c in corners.ravel()]).reshape(corners.shape)
        touch = np.ones(corners.shape)
        if not self._nonlinear:
            return out, share, rate, touch
        rel = spec[..., 0].real + spec[..., 1].real - 2.0 * spec[..., 2].real  # S of a_s − a_u
        rel = np.maximum(rel - 2.0 * self.noise, 0.0)
        var_v = rel @ self._travel_weight
        var_x = rel @ self._travel_x_weight
        log_step = math.log1p(self.config.rate_step)
        for c in np.unique(corners):
            qc = self.models[c]
            if qc.suspension is None:
                continue
            here = corners == c
            sub = spec[here]
            ms, mu = qc.sprung_mass, qc.unsprung_mass
            load = ms**2 * sub[..., 0].real + mu**2 * sub[..., 1].real + 2.0 * ms * mu * sub[..., 2].real
            var_f = np.maximum(load - (ms**2 + mu**2) * self.noise, 0.0) @ self._band_df
            contact = ndtr((ms + mu) * _GRAVITY / np.sqrt(np.maximum(var_f, 1e-12)))
            lift = np.rint(-np.log(np.maximum(contact, 0.05)) / log_step).astype(int)
            sd = np.sqrt(var_x[here])
            mean, k_eq = equivalent_spring_rate(qc.suspension, qc.static_travel, sd, np.sqrt(var_v[here]))
            steps = np.rint(np.log(np.maximum(k_eq / qc.spring_rate, 1e-3)) / log_step).astype(int)
            out[here] = [self._slot(int(c), int(k), int(j)) for k, j in zip(steps, lift, strict=True)]
            law = qc.suspension
            stops = ndtr((mean - law.bump_clearance) / np.maximum(sd, 1e-9)) + ndtr(
                (-mean - law.rebound_clearance) / np.maximum(sd, 1e-9))  # fmt: skip
            share[here] = stops + (1.0 - contact)
            rate[here], touch[here] = k_eq, contact
        return out, share, rate, touch

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget everything (a new drive with unknown pressures)."""
        for track in getattr(self, "_previews", []):
            track.reset()
        n_m, n_c = len(self.config.memories_s), len(self.models)
        shape = (n_m, n_c, self.n_bins)
        self._state = _State(
            spec=np.zeros(shape + (self.freq.size, 3), dtype=complex),
            weight=np.zeros(shape),
            weight2=np.zeros(shape),
            speed_sum=np.zeros(shape),
            scale=np.ones(n_m),
            score=np.zeros((n_c, n_m)),
            fits=[None] * n_m,
            buffer_t=np.empty(0),
            buffer_v=np.empty(0),
            buffer_s=np.empty((0, n_c)),
            buffer_u=np.empty((0, n_c)),
            blocks=np.full((self.window // self.hop, n_c), _GAP, dtype=np.int8),
            recent_spec=np.zeros((self._n_recent, n_c, self.freq.size, 3), dtype=complex),
            recent_weight=np.zeros((self._n_recent, n_c)),
            recent_speed=np.full(self._n_recent, np.nan),
            recent_t=np.full(self._n_recent, np.nan),
            recent_u=np.zeros((self._n_recent, n_c)),
            recent_i=np.zeros((self._n_recent, n_c)),
            recent_p=np.zeros((self._n_recent, n_c)),
            counts={
                "segments": 0, **{r: np.zeros(n_c, dtype=int) for r in SKIP_REASONS},
                "restarts": np.zeros(n_c, dtype=int),
                "despiked": np.zeros(n_c, dtype=int),
            },
        )  # fmt: skip

    @property
    def state_nbytes(self) -> int:
        """Size of the state the monitor carries between updates, bytes (bounded)."""
        s = self._state
        arrays = [
            s.spec,
            s.weight,
            s.weight2,
            s.speed_sum,
            s.score,
            s.buffer_t,
            s.buffer_v,
            s.buffer_s,
            s.buffer_u,
            s.recent_spec,
            s.recent_weight,
            s.recent_speed,
            s.recent_t,
            s.recent_u,
            s.recent_i,
            s.recent_p,
        ]
        return int(sum(a.nbytes for a in arrays)) + sum(t.state_nbytes for t in self._previews)

    @property
    def counts(self) -> dict:
        """Segments seen, and per corner how many were used or skipped, by reason; restarts."""
        return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in self._state.counts.items()}

    # ------------------------------------------------------------------ streaming
    def update(
        self,
        t_s: npt.ArrayLike,
        speed_mps: npt.ArrayLike,
        acc_sprung: npt.ArrayLike,
        acc_unsprung: npt.ArrayLike,
    ) -> MonitorUpdate:
        """Consume samples (in time order, any number) and return one row per finished segment.

        `t_s` (n,), s, continuing the stream every `dt` (a jump in time drops the unfinished
        segment); `speed_mps` (n,); `acc_sprung`, `acc_unsprung` (n, C), m/s², NaN where a
        sample is missing.
        """
        t = np.asarray(t_s, dtype=float).reshape(-1)
        v = np.asarray(speed_mps, dtype=float).reshape(-1)
        n_c = len(self.models)
        a_s = np.asarray(acc_sprung, dtype=float).reshape(t.size, -1) if t.size else np.empty((0, n_c))
        a_u = np.asarray(acc_unsprung, dtype=float).reshape(t.size, -1) if t.size else np.empty((0, n_c))
        if v.shape != t.shape or a_s.shape != (t.size, n_c) or a_u.shape != (t.size, n_c):
            raise InputError(
                f"update needs t_s and speed_mps of shape (n,) and accelerations of shape (n, {n_c}); "
                f"got {t.shape}, {v.shape}, {a_s.shape}, {a_u.shape}"
            )
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InputError("t_s must be finite and strictly increasing")
        s = self._state
        if t.size and np.isfinite(s.last_t) and t[0] <= s.last_t:
            raise InputError(f"t_s must continue the stream: got {t[0]} s after {s.last_t} s")
        rows = []
        # a jump in time (a gap in the stream) drops the unfinished segment
        previous = np.concatenate([[s.last_t], t[:-1]])
        breaks = np.flatnonzero(np.isfinite(previous) & (np.abs(t - previous - self.dt) > 0.5 * self.dt))
        bounds = [0, *[int(i) for i in breaks if i > 0], t.size]
        for k in range(len(bounds) - 1):
            lo, hi = bounds[k], bounds[k + 1]
            if lo in breaks or (lo == 0 and 0 in breaks):
                if s.buffer_t.size:
                    s.counts["gap"] += 1
                self._clear_buffer()
            self._append(t[lo:hi], v[lo:hi], a_s[lo:hi], a_u[lo:hi], rows)
        if t.size:
            s.last_t = float(t[-1])
        if not rows:
            return self._empty()
        return MonitorUpdate.concatenate(rows)

    def _clear_buffer(self) -> None:
        for track in self._previews:
            track.break_stream()
        s = self._state
        n_c = len(self.models)
        s.buffer_t, s.buffer_v = np.empty(0), np.empty(0)
        s.buffer_s, s.buffer_u = np.empty((0, n_c)), np.empty((0, n_c))
        s.in_window = 0
        s.blocks[:] = _GAP

    def _append(self, t, v, a_s, a_u, rows) -> None:
        """Add samples; each time `update_s` of new ones are in, slide the window and update."""
        s = self._state
        s.buffer_t = np.concatenate([s.buffer_t, t])
        s.buffer_v = np.concatenate([s.buffer_v, v])
        s.buffer_s = np.concatenate([s.buffer_s, a_s])
        s.buffer_u = np.concatenate([s.buffer_u, a_u])
        while s.buffer_t.size - s.in_window >= self.hop:
            end = s.in_window + self.hop
            start = max(0, end - self.window)
            block = slice(s.in_window, end)
            window = slice(start, end)
            rows.append(self._update_window(
                (s.buffer_t[block], s.buffer_v[block], s.buffer_s[block], s.buffer_u[block]),
                (s.buffer_t[window], s.buffer_v[window], s.buffer_s[window], s.buffer_u[window]),
            ))  # fmt: skip
            keep = slice(start, None)
            s.buffer_t, s.buffer_v = s.buffer_t[keep], s.buffer_v[keep]
            s.buffer_s, s.buffer_u = s.buffer_s[keep], s.buffer_u[keep]
            s.in_window = end - start

    def _empty(self) -> MonitorUpdate:
        n_c, n_m = len(self.models), len(self.config.memories_s)
        z = np.empty((0, n_c))
        return MonitorUpdate(
            t_s=np.empty(0), pressure_pa=z, pressure_sigma_pa=z.copy(), stiffness=z.copy(),
            stiffness_sigma=z.copy(), observable=np.empty((0, n_c), dtype=bool),
            status=np.empty((0, n_c), dtype=np.int8), road_level=np.empty(0), waviness=np.empty(0),
            speed_mps=np.empty(0), memory_weights=np.empty((0, n_c, n_m)),
            restarts=np.empty((0, n_c), dtype=int), spring_rate=z.copy(), tyre_contact=z.copy(),
        )  # fmt: skip

    # ------------------------------------------------------------------ one segment
    def _check_block(self, v: np.ndarray, a_s: np.ndarray, a_u: np.ndarray) -> np.ndarray:
        """Status per corner (index into SKIP_REASONS) of one update block's accelerometer data."""
        cfg = self.config
        n_c = len(self.models)
        status = np.zeros(n_c, dtype=np.int8)
        x = np.concatenate([a_s.T, a_u.T])  # (2C, m): sprung rows, then unsprung rows
        top, bottom = x.max(axis=1), x.min(axis=1)  # NaN where a sample is missing
        finite = np.isfinite(top) & np.isfinite(bottom)
        xf = np.where(finite[:, None], x, 0.0) if not np.all(finite) else x
        top, bottom = np.where(finite, top, 0.0), np.where(finite, bottom, 0.0)
        implausible = (np.maximum(top, -bottom) > cfg.max_accel_mps2) | (top == bottom)
        clipped = _clipped(xf, top, bottom, cfg.accel_range_mps2)
        spiky, med, mad = _spiky(xf, top, bottom, cfg.spike_z)
        # isolated spikes (at most 0.2 % of the block) are replaced by the block's median, in the
        # stream's buffer itself (a_s, a_u are views of it), so the windows see clean data
        limit = max(1, int(0.002 * x.shape[1]))
        for r in np.flatnonzero(spiky & finite):
            where = np.flatnonzero(np.abs(xf[r] - med[r]) > cfg.spike_z * max(mad[r], 1e-12))
            if where.size <= limit:
                (a_s if r < n_c else a_u)[where, r % n_c] = med[r]
                self._state.counts["despiked"][r % n_c] += where.size
                spiky[r] = False
        for c in range(n_c):
            rows = [c, n_c + c]
            if not np.all(finite[rows]):
                status[c] = _GAP
            elif np.any(implausible[rows]):
                status[c] = _IMPLAUSIBLE
            elif np.any(clipped[rows]):
                status[c] = _CLIPPED
            elif np.any(spiky[rows]):
                status[c] = _SPIKE
        if not np.all(np.isfinite(v)) or np.min(v) < 0.0:
            status[:] = _SPEED
        return status

    def _update_window(self, block, window) -> MonitorUpdate:
        """One update: check the new block, then use the window (the last `segment_s`) if it is sound."""
        cfg = self.config
        s = self._state
        n_c, n_m = len(self.models), len(cfg.memories_s)
        t, v, a_s, a_u = window
        s.blocks = np.roll(s.blocks, -1, axis=0)
        s.blocks[-1] = self._check_block(block[1], block[2], block[3])
        n_blocks = t.size // self.hop
        status = np.zeros(n_c, dtype=np.int8)
        for row in s.blocks[-n_blocks:]:  # the first problem of each corner's window, oldest first
            status = np.where(status == _USED, row, status)
        # a window whose only problem is a gap keeps its data after the gap (at least a quarter window)
        tail = np.full(n_c, t.size)
        gap_only = np.all(np.isin(s.blocks[-n_blocks:], (_USED, _GAP)), axis=0) & (status == _GAP)
        for c in np.flatnonzero(gap_only):
            bad = np.flatnonzero(~(np.isfinite(a_s[:, c]) & np.isfinite(a_u[:, c])))
            after = t.size - 1 - bad[-1]
            if after >= self.window // 4:
                tail[c], status[c] = after, _USED
        speed = float(np.mean(v))
        if np.any(status == _SPEED) or not (np.isfinite(speed) and speed > 0.0) or (
            np.ptp(v) > cfg.max_speed_change * speed
        ):  # fmt: skip
            status[:] = _SPEED
            speed = math.nan
        else:
            top = min(cfg.band_cycles_per_m[1] * speed, cfg.max_frequency_hz)
            status = np.where((status == _USED) & (top < cfg.hop_margin * self._hop_hz), _LOW_SPEED, status)
        s.counts["segments"] += 1
        for c in range(n_c):
            s.counts[SKIP_REASONS[status[c]]][c] += 1
        used = status == _USED
        t_end = float(t[-1])
        elapsed = cfg.update_s if not np.isfinite(s.last_segment_t) else t_end - s.last_segment_t
        s.last_segment_t = t_end
        self._feed_previews(block, s.blocks[-1], elapsed)
        restarts = np.zeros(n_c, dtype=int)
        analysed_rate, analysed_touch = np.full(n_c, np.nan), np.full(n_c, np.nan)
        if np.any(used):
            share = self.hop / self.window  # each sample is in window/hop windows
            # weights: a window of fewer samples (while the first fills, or the part after a gap) is
            # zero-padded and counts for the share of a window it holds
            w_c = share * np.minimum(tail, t.size) / self.window
            whole = used & (tail == t.size)
            spec = np.empty((int(used.sum()), self.freq.size, 3), dtype=complex)
            if np.any(whole):
                spec[whole[used]] = self._cross_spectra(a_s[:, whole], a_u[:, whole])
            for i, c in enumerate(np.flatnonzero(used)):
                if not whole[c]:
                    spec[i] = self._cross_spectra(a_s[-tail[c] :, c : c + 1], a_u[-tail[c] :, c : c + 1])[0]
            b = self._speed_bin(speed)
            table = np.arange(n_c)[:, None]  # each corner's gain tables at this window's travel
            table[used, 0], rough, rate_c, touch_c = self._tables_for(np.flatnonzero(used), spec)
            analysed_rate[used], analysed_touch[used] = rate_c, touch_c
            rough_c = np.zeros(n_c, dtype=bool)
            rough_c[used] = rough > cfg.max_nonlinear_share
            if np.any(rough_c):  # no linear model holds: the window is not used for k_t
                status[rough_c] = _ROUGH
                s.counts["used"][rough_c] -= 1
                s.counts["rough"][rough_c] += 1
                spec = spec[~rough_c[used]]
                used = used & ~rough_c
                whole = whole & used
                table[~used, 0] = np.arange(n_c)[~used]
            # 1. predictive scores of the memories for the new block (before it is added; whole
            # windows only: a block with a gap predicts nothing)
            scores = np.zeros((n_c, n_m))
            if np.any(whole):
                newest = self._cross_spectra(block[2][:, whole], block[3][:, whole], own_grid=True)
                scores = self._predictive_scores(newest, whole, speed, share, table)  # (C, M), 0 where unused
            decay = math.exp(-elapsed / cfg.selection_s)
            s.score = decay * s.score + scores
            # 2. forget (lazily: the stored sums are divided by the accumulated factor) and add
            self._forget(elapsed)
            w = w_c[used]
            for m in range(n_m):
                k = s.scale[m]
                s.spec[m][used, b] += w[:, None, None] * spec / k
                s.weight[m][used, b] += w / k
                s.weight2[m][used, b] += w * w / share / k**2  # overlapping windows: blocks of weight w/share
                s.speed_sum[m][used, b] += w * speed / k
            # 3. change test: keep the window, look for a pressure change within the recent ones
            s.recent_spec = np.roll(s.recent_spec, -1, axis=0)
            s.recent_weight = np.roll(s.recent_weight, -1, axis=0)
            s.recent_speed, s.recent_t = np.roll(s.recent_speed, -1), np.roll(s.recent_t, -1)
            s.recent_u, s.recent_i = np.roll(s.recent_u, -1, axis=0), np.roll(s.recent_i, -1, axis=0)
            s.recent_p = np.roll(s.recent_p, -1, axis=0)
            s.recent_spec[-1] = 0.0
            s.recent_spec[-1, used] = w[:, None, None] * spec
            s.recent_weight[-1] = np.where(used, w_c, 0.0)
            s.recent_speed[-1], s.recent_t[-1] = speed, t_end
            s.recent_u[-1], s.recent_i[-1], s.recent_p[-1] = self._window_score(spec, used, speed, w_c, table)
            start = self._change_test(used)
            for c in np.flatnonzero(start >= 0):
                self._rebuild(c, int(start[c]), t_end)
                restarts[c] += 1
            s.counts["restarts"] += restarts
            for track, (f, r) in zip(self._previews, self.tracks, strict=True):
                if restarts[f] or restarts[r]:
                    track.reset()  # its ratio changed: start it afresh
        else:
            self._forget(elapsed)  # time passes: memories fade
        s.fits = self._fit_all(s.fits)
        self._n_updates += 1
        return self._output(t_end, speed, status, restarts, analysed_rate, analysed_touch)

    def _feed_previews(self, block, status: np.ndarray, elapsed: float) -> None:
        """Forget and add the new block to each track's preview (a corner's faulty block as NaN)."""
        if not self._previews:
            return
        _, v, a_s, a_u = block
        decay = np.exp(-elapsed / np.asarray(self.config.memories_s, dtype=float))
        for track, (f, r) in zip(self._previews, self.tracks, strict=True):
            track.decay(decay)
            ok = status[f] == _USED and status[r] == _USED
            pick = (lambda x, c: x[:, c]) if ok else (lambda x, c: np.full(x.shape[0], np.nan))  # noqa: E731
            track.add(pick(a_u, f), pick(a_u, r), v, acc_s_front=pick(a_s, f), acc_s_rear=pick(a_s, r))

    def _speed_bin(self, speed: float) -> int:
        """Index of the accumulators' speed bin nearest `speed` (m/s), geometric bins."""
        b = math.floor(math.log(speed / self._v_lo) / self._log_ratio + 0.5)
        return int(np.clip(b, 0, self.n_bins - 1))

    def _change_test(self, used: np.ndarray) -> np.ndarray:
        """Per corner, the index into the recent windows where a pressure change starts, or −1.

        Generalized likelihood ratio of a step in p [4]_: for each start j among the recent
        windows, the score U_j and information I_j in p of the windows from j on, at the longest
        memory's estimate, give GLR_j = U_j²/(2 I_j); a change is declared where max_j GLR_j
        exceeds ``change_nats`` (with at least two windows from j on). The road's level is held at
        the memory's, not profiled: profiled, it would absorb most of a pressure step (the
        level–k_t ridge); held, the test also fires when the road's roughness changes, which
        makes the old windows as misleading as a pressure change does."""
        s = self._state
        n_c = len(self.models)
        out = np.full(n_c, -1)
        fit = s.fits[-1]
        if fit is None or not fit.has_data or not np.any(used):
            return out
        pick = np.arange(n_c)
        # each window's score moved to the memory's present estimate (the score is linear in p near it)
        p_now = fit.p_mean[None, :]
        u = np.where(s.recent_i > 0, s.recent_u - s.recent_i * (p_now - s.recent_p), 0.0)
        info = s.recent_i
        total_u = np.cumsum(u[::-1], axis=0)[::-1]  # from window j to the newest
        total_i = np.cumsum(info[::-1], axis=0)[::-1]
        n_after = np.cumsum(info[::-1] > 0, axis=0)[::-1]
        glr = np.where((total_i > 0) & (n_after >= 2), total_u**2 / (2.0 * np.maximum(total_i, 1e-300)), 0.0)
        best = np.argmax(glr, axis=0)
        hit = (glr[best, pick] > self.config.change_nats) & used
        out[hit] = best[hit]
        return out

    def _terms_at(self, fit: _Fit, table, proj, weight, x, log_cv):
        """:func:`_corner_terms` at a memory's estimate, each corner with its likelier slope model;
        also that model's damping weights (C, D)."""
        n_c = len(self.models)
        v = np.argmax(fit.variant_weight, axis=1)
        pick = np.arange(n_c)
        lam = np.ascontiguousarray(fit.lam[v, pick])
        lam = np.where(np.isfinite(lam), lam, math.log(1e-5))
        ll, score, info = _corner_terms(
            lam, np.ascontiguousarray(fit.beta[v, pick]), np.ascontiguousarray(fit.p[v, pick]), table,
            self._log_gain, self._dlog_gain, float(self._p_grid[0]), self._p_step, proj, weight, x, log_cv,
        )  # fmt: skip
        return ll, score, info, fit.wd[v, pick]

    def _window_score(self, spec: np.ndarray, used: np.ndarray, speed: float, w: np.ndarray, table):
        """Score and information in p of one window (its corners `used`, weights `w` (C,), gain-table
        slots `table` (C, 1)) at the longest memory's estimate, and that estimate: three (C,) arrays
        (zero for corners not used)."""
        s = self._state
        n_c = len(self.models)
        zeros = np.zeros(n_c)
        fit = s.fits[-1]
        if fit is None or not fit.has_data:
            return zeros, zeros, zeros
        full = np.zeros((n_c, 1, self.freq.size, 3), dtype=complex)
        full[used, 0] = spec
        weight, x, log_cv = self._band(np.array([speed]))
        weight = (w * used)[:, None, None] * weight[None]
        _, score, info, wd = self._terms_at(fit, table, self._project(full, table), weight, x, log_cv)
        u = np.einsum("cd,cd->c", wd, score[..., 2])
        i = np.einsum("cd,cd->c", wd, info[..., 2, 2])
        return u, i, np.where(used, fit.p_mean, 0.0)

    def _rebuild(self, c: int, start: int, t_end: float) -> None:
        """Corner c's memories from recent window `start` on only (each memory cut at the change);
        the windows before it leave the change test's record."""
        s = self._state
        share = self.hop / self.window
        for m, tau in enumerate(self.config.memories_s):
            k = s.scale[m]
            s.spec[m, c] = 0.0
            s.weight[m, c] = 0.0
            s.weight2[m, c] = 0.0
            s.speed_sum[m, c] = 0.0
            for j in range(start, s.recent_t.size):
                w = s.recent_weight[j, c]
                if w <= 0:
                    continue
                b = self._speed_bin(s.recent_speed[j])
                rho = math.exp(-(t_end - s.recent_t[j]) / tau)
                s.spec[m, c, b] += rho * s.recent_spec[j, c] / k
                s.weight[m, c, b] += rho * w / k
                s.weight2[m, c, b] += rho * rho * w * w / share / k**2
                s.speed_sum[m, c, b] += rho * w * s.recent_speed[j] / k
        s.recent_weight[:start, c] = 0.0
        s.recent_spec[:start, c] = 0.0
        s.recent_u[:, c] = s.recent_i[:, c] = 0.0  # the change test starts afresh for this corner
        s.score[c] = 0.0  # the memories hold the same data now: equal weights

    def _forget(self, elapsed: float) -> None:
        """Decay every memory by exp(−elapsed/τ) (renormalizing the stored sums when the factor is tiny)."""
        s = self._state
        for m, tau in enumerate(self.config.memories_s):
            s.scale[m] *= math.exp(-elapsed / tau)
            if s.scale[m] < 1e-100:
                k = s.scale[m]
                s.spec[m] *= k
                s.weight[m] *= k
                s.weight2[m] *= k * k
                s.speed_sum[m] *= k
                s.scale[m] = 1.0

    def _cross_spectra(self, a_s: np.ndarray, a_u: np.ndarray, *, own_grid: bool = False) -> np.ndarray:
        """One-sided cross-periodogram per Hz of (sprung, unsprung) on the window's frequencies, (C, F, 3):
        S11, S22, S12. Linear detrend, rectangular window; fewer samples than a window are
        zero-padded to it (the periodogram of the data there, sampled on the window's grid), or with
        `own_grid` (one update's block) taken on their own grid and each window frequency given
        the value of the nearest one (half the cost; used for the memories' predictive scores)."""
        x = _detrend(np.stack([a_s.T, a_u.T]))  # (2, C, n)
        if own_grid and x.shape[-1] == self.hop:
            X = np.fft.rfft(x, axis=-1)[..., self._block_index]
        else:
            X = np.fft.rfft(x, n=self.window, axis=-1)[..., self._f_index]
        k = 2.0 * self.dt / x.shape[-1]
        fine = np.empty(X.shape[1:] + (3,), dtype=complex)
        fine[..., 0] = np.abs(X[0]) ** 2 * k
        fine[..., 1] = np.abs(X[1]) ** 2 * k
        fine[..., 2] = X[0] * np.conj(X[1]) * k
        return np.add.reduceat(fine, self._group_start, axis=1) / self._group_size[:, None]

    def _project(self, spec: np.ndarray, table: np.ndarray) -> np.ndarray:
        """u^H S u / N for each damping: spec (R, B, F, 3) → (R, D, B, F), row r and bin b with the
        signal direction of gain-table slot `table[r, b]`."""
        u11 = self._u11[table][..., 0, :].transpose(0, 2, 1, 3)  # (R, D, B, F)
        u22 = self._u22[table][..., 0, :].transpose(0, 2, 1, 3)
        u12 = self._u12[table][..., 0, :].transpose(0, 2, 1, 3)
        sp = spec[:, None]
        return u11 * sp[..., 0].real + u22 * sp[..., 1].real + (u12 * sp[..., 2]).real

    def _band(self, speeds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Band weights (B, F: the number of Fourier frequencies averaged, 0 outside the band), log(n/n0)
        (B, F) and log(4π² n0² v) (B,) at the bins' speeds."""
        cfg = self.config
        f = self.freq[None, :]
        v = speeds[:, None]
        mask = (f >= cfg.band_cycles_per_m[0] * v) & (
            f <= np.minimum(cfg.band_cycles_per_m[1] * v, cfg.max_frequency_hz)
        )
        weight = mask * self._group_size[None, :]  # a band counts for the frequencies it averages
        return weight, np.log(f / (N0 * v)), np.log(4.0 * np.pi**2 * N0**2 * speeds)

    def _predictive_scores(
        self, spec: np.ndarray, used: np.ndarray, speed: float, share: float, table: np.ndarray
    ) -> np.ndarray:
        """Expected log predictive density of the newest block under each memory, (C, M), with the
        window's gain-table slots `table` (C, 1).

        `spec`: the block's periodogram zero-padded to the window, whose bins are correlated over
        window/block neighbours: its Whittle log-likelihood is weighted by `share` = block/window."""
        s = self._state
        n_c, n_m = len(self.models), len(self.config.memories_s)
        out = np.zeros((n_c, n_m))
        corners = np.flatnonzero(used)
        full = np.zeros((n_c, 1, self.freq.size, 3), dtype=complex)
        full[corners, 0] = spec
        proj = self._project(full, table)  # (C, D, 1, F)
        mask, x, log_cv = self._band(np.array([speed]))
        weight = share * used[:, None, None] * mask[None]  # (C, 1, F): the unused corners weigh nothing
        for m, fit in enumerate(s.fits):
            if fit is None or not fit.has_data:
                continue
            ll, _, info, wd = self._terms_at(fit, table, proj, weight, x, log_cv)
            plug_in = _logsumexp(ll + np.log(np.maximum(wd, 1e-300)), axis=1)
            i_pp = np.einsum("cd,cd->c", wd, info[:, :, 2, 2])
            i_ll = np.einsum("cd,cd->c", wd, info[:, :, 0, 0])
            out[corners, m] = (plug_in - 0.5 * (i_pp * fit.p_var + i_ll * fit.lam_var))[corners]
        return out

    # ------------------------------------------------------------------ estimation
    def _empty_fit(self) -> _Fit:
        """A memory with no data: the prior."""
        n_c, n_d = len(self.models), self.config.damping_points
        n_v = 2 if self._slope_free else 1
        nan = np.full(n_c, np.nan)
        return _Fit(
            lam=np.full((n_v, n_c), np.nan), beta=np.zeros((n_v, n_c)),
            p=np.broadcast_to(self._prior[:, None], (n_v, n_c, n_d)).copy(),
            wd=np.full((n_v, n_c, n_d), 1.0 / n_d),
            variant_weight=np.tile(np.eye(n_v)[0], (n_c, 1)), p_mean=self._prior.copy(),
            p_var=np.full(n_c, self._prior_var), lam_mean=nan, lam_var=np.full(n_c, np.inf),
            beta_mean=np.zeros(n_c), beta_var=np.full(n_c, np.inf), has_data=False,
        )  # fmt: skip

    def _fit_all(self, previous: list) -> list:
        """Fisher scoring of every memory's weighted likelihood, warm-started from `previous`.

        The memories' corners are independent rows of one kernel call per slope model (memory m,
        corner c → row m·C + c), so the cost of Python is paid once per update, not per memory."""
        cfg = self.config
        s = self._state
        n_m, n_c, n_d = len(cfg.memories_s), len(self.models), cfg.damping_points
        n_v = 2 if self._slope_free else 1
        W = s.weight * s.scale[:, None, None]  # (M, C, NB) Σ w_k
        has_data = W.sum(axis=(1, 2)) > 1e-9
        bins = np.flatnonzero(W.sum(axis=(0, 1)) > 1e-9)
        if bins.size == 0:
            return [self._empty_fit() for _ in range(n_m)]
        rows = n_m * n_c
        Wb = W[:, :, bins]  # (M, C, B)
        speeds = (s.speed_sum[:, :, bins] * s.scale[:, None, None]).sum(axis=(0, 1)) / Wb.sum(axis=(0, 1))
        band, x, log_cv = self._band(speeds)
        stored = s.weight[:, :, bins]
        mean_spec = s.spec[:, :, bins] / np.maximum(stored, 1e-300)[..., None, None]
        mean_spec = mean_spec.reshape(rows, bins.size, self.freq.size, 3)
        row_corner = np.tile(np.arange(n_c), n_m)
        table = self._tables_for(np.repeat(row_corner[:, None], bins.size, axis=1), mean_spec)[0]
        proj = self._project(mean_spec, table)  # (rows, D, B, F)
        weight = Wb.reshape(rows, bins.size)[:, :, None] * band[None]  # (rows, B, F)
        total = W.sum(axis=2).reshape(rows)
        eff = (s.weight2.sum(axis=2) * s.scale[:, None] ** 2).reshape(rows) / np.maximum(total, 1e-300)
        eff = np.where(total > 1e-9, np.minimum(eff, 1.0), 1.0)  # sandwich factor per row
        prior_rows = np.tile(self._prior, n_m)
        prior = np.repeat(prior_rows[:, None], n_d, axis=1)
        lam0 = np.empty((n_v, rows))
        beta0 = np.zeros((n_v, rows))
        p0 = np.empty((n_v, rows, n_d))
        cold = [m for m in range(n_m) if previous[m] is None or not previous[m].has_data]
        if cold:
            rows_cold = np.concatenate([np.arange(m * n_c, (m + 1) * n_c) for m in cold])
            lam_c, p_c = self._cold_start(proj[rows_cold], weight[rows_cold], log_cv, table[rows_cold],
                                          np.tile(np.arange(n_c), n_m)[rows_cold])  # fmt: skip
            lam0[:, rows_cold], p0[:, rows_cold] = lam_c, p_c
        for m in range(n_m):
            if m in cold:
                continue
            sl = slice(m * n_c, (m + 1) * n_c)
            lam = previous[m].lam.copy()
            finite = np.isfinite(lam)
            lam[~finite] = np.mean(lam[finite]) if np.any(finite) else math.log(1e-5)
            lam0[:, sl], beta0[:, sl], p0[:, sl] = lam, previous[m].beta, previous[m].p
        iterations = 30 if cold else 6
        fits = []
        for v in range(n_v):
            lam, beta, p = (np.ascontiguousarray(a[v], dtype=float).copy() for a in (lam0, beta0, p0))
            wd, ll, _, info = _newton_kernel(
                v, lam, beta, p, table, self._log_gain, self._dlog_gain, float(self._p_grid[0]), self._p_step,
                proj, weight, x, log_cv, prior_rows, self._prior_var, *cfg.pressure_range_kpa, *_LEVEL_BOUNDS,
                *self._beta_bounds, iterations,
            )  # fmt: skip
            # per row, the covariance of (λ_c, [β_c], p_c) from the damping-weighted information
            keep = [0, 1, 2] if v == 1 else [0, 2]
            J = np.einsum("cd,cdij->cij", wd, info)[:, keep][:, :, keep] + np.eye(len(keep)) * 1e-9
            cov = np.linalg.inv(J)
            p_bar = np.einsum("cd,cd->c", wd, p)
            p_var = cov[:, -1, -1] * eff + np.einsum("cd,cd->c", wd, (p - p_bar[:, None]) ** 2)
            _, logdet = np.linalg.slogdet(J / (2.0 * np.pi))
            ev = _logsumexp(ll - 0.5 * (p - prior) ** 2 / self._prior_var - math.log(n_d), axis=1)
            ev -= 0.5 * logdet
            if v == 1:
                width = self._beta_bounds[1] - self._beta_bounds[0]
                ev += math.log1p(-cfg.waviness_iso_weight) - math.log(width)
            elif n_v == 2:
                ev += math.log(cfg.waviness_iso_weight)
            beta_var = cov[:, 1, 1] if v == 1 else np.zeros(rows)
            fits.append((lam, beta, p, wd, ev, p_bar, p_var, cov[:, 0, 0], beta_var))
        logev = np.array([f[4] for f in fits]).T  # (rows, V)
        vw = np.exp(logev - logev.max(axis=1, keepdims=True))
        vw /= vw.sum(axis=1, keepdims=True)

        def mix(i_mean: int, i_var: int) -> tuple[np.ndarray, np.ndarray]:
            means = np.array([f[i_mean] for f in fits]).T  # (rows, V)
            mean = np.sum(vw * means, axis=1)
            var = np.sum(vw * (np.array([f[i_var] for f in fits]).T + (means - mean[:, None]) ** 2), axis=1)
            return mean, var

        p_mean, p_var = mix(5, 6)
        lam_mean, lam_var = mix(0, 7)
        beta_mean, beta_var = mix(1, 8)
        out = []
        for m in range(n_m):
            if not has_data[m]:
                out.append(self._empty_fit())
                continue
            sl = slice(m * n_c, (m + 1) * n_c)
            out.append(_Fit(
                lam=np.array([f[0][sl] for f in fits]), beta=np.array([f[1][sl] for f in fits]),
                p=np.array([f[2][sl] for f in fits]), wd=np.array([f[3][sl] for f in fits]),
                variant_weight=vw[sl], p_mean=p_mean[sl], p_var=p_var[sl], lam_mean=lam_mean[sl],
                lam_var=lam_var[sl], beta_mean=beta_mean[sl], beta_var=beta_var[sl], has_data=True,
            ))  # fmt: skip
        return out

    def _cold_start(self, proj, weight, log_cv, table, corner) -> tuple[np.ndarray, np.ndarray]:
        """First guess per row: the joint estimator's 5 kPa grid with the level profiled, w = 2.

        `table` (rows, B): each row's gain-table slot per bin; `corner` (rows,): its corner. Returns
        each row's log level (rows,) and pressure (rows, D), kPa."""
        n_r, n_d = proj.shape[:2]
        d = n_d // 2
        grid = np.arange(0, self._p_grid.size, 5)
        p0 = np.empty((n_r, n_d))
        lam = np.full(n_r, math.log(1e-5))
        bounds = (np.full((1, 1), _LEVEL_BOUNDS[0]), np.full((1, 1), _LEVEL_BOUNDS[1]))
        for r in range(n_r):
            w = weight[r].reshape(1, -1)
            c = int(corner[r])
            if not np.any(w > 0):
                p0[r] = self._prior[c]
                continue
            log_gain = self._log_gain[table[r], d][:, grid].transpose(1, 0, 2)  # (P, B, F)
            gain = np.exp(log_gain + log_cv[None, :, None])
            gain = gain.reshape(grid.size, -1)
            ll, lam_r, fisher = profile_loglik(proj[r, d].reshape(1, -1), gain, w, log_sv_bounds=bounds)
            best = int(np.argmax(ll[0] - 0.5 * np.log(np.maximum(fisher[0], 1e-300))))
            p0[r] = self._p_grid[grid][best]
            lam[r] = lam_r[0, best]
        return lam, p0

    def _fuse_previews(self, means: np.ndarray, vars_: np.ndarray, pi: np.ndarray):
        """Each rear's per-memory estimate fused with its track's preview given the front's
        (:func:`suvtwin.estimators.preview.fuse_track`; the front keeps its own): (C, M) kPa, kPa²."""
        if not self._previews:
            return means, vars_
        means, vars_ = means.copy(), vars_.copy()
        lo, hi = self._previews[0].config.pressure_range_kpa
        limit = self.config.observable_sigma_kpa**2
        for track, (f, r) in zip(self._previews, self.tracks, strict=True):
            for m in range(means.shape[1]):
                # a front without information of its own (not observable: at its prior) has none to pass on
                if pi[r, m] < 1e-3 or not np.isfinite(means[f, m]) or vars_[f, m] > limit:
                    continue
                p_f = float(np.clip(means[f, m], lo, hi))
                cond = track.conditional(p_f, math.sqrt(vars_[f, m]), memory=m)
                if not cond.informative:
                    continue
                mean, cov = fuse_track(p_f, math.sqrt(vars_[f, m]), means[r, m], math.sqrt(vars_[r, m]), cond)
                means[r, m], vars_[r, m] = mean[1], cov[1, 1]
        return means, vars_

    # ------------------------------------------------------------------ output
    def _output(self, t_end, speed, status, restarts, spring_rate, tyre_contact) -> MonitorUpdate:
        cfg = self.config
        s = self._state
        score = s.score - s.score.max(axis=1, keepdims=True)
        pi = np.exp(score)
        pi /= pi.sum(axis=1, keepdims=True)  # (C, M)
        means = np.array([f.p_mean for f in s.fits]).T  # (C, M)
        vars_ = np.array([f.p_var for f in s.fits]).T
        means, vars_ = self._fuse_previews(means, vars_, pi)
        p = np.sum(pi * means, axis=1)
        var = np.sum(pi * (vars_ + (means - p[:, None]) ** 2), axis=1)
        sigma = np.sqrt(var)
        # the road's level and waviness: the corners' estimates pooled (inverse-variance weights)
        best = s.fits[int(np.argmax(pi.mean(axis=0)))]
        level = waviness = math.nan
        ok = np.isfinite(best.lam_mean) & np.isfinite(best.lam_var) & (best.lam_var > 0)
        if best.has_data and np.any(ok):
            level = math.exp(np.average(best.lam_mean[ok], weights=1.0 / best.lam_var[ok]))
            spread = np.where(best.beta_var[ok] > 0, best.beta_var[ok], np.inf)
            pooled = np.any(np.isfinite(spread))
            waviness = 2.0 - (np.average(best.beta_mean[ok], weights=1.0 / spread) if pooled
                              else float(np.mean(best.beta_mean[ok])))  # fmt: skip
        kt = stiffness_at_pressure_array(p * 1e3, *self._laws)
        kt_sig = np.abs(stiffness_sigma_at_pressure_sigma(sigma * 1e3, *self._laws))
        return MonitorUpdate(
            t_s=np.array([t_end]),
            pressure_pa=p[None] * 1e3,
            pressure_sigma_pa=sigma[None] * 1e3,
            stiffness=kt[None],
            stiffness_sigma=kt_sig[None],
            observable=(sigma <= cfg.observable_sigma_kpa)[None],
            status=status[None].astype(np.int8),
            road_level=np.array([level]),
            waviness=np.array([waviness]),
            speed_mps=np.array([speed]),
            memory_weights=pi[None],
            restarts=restarts[None],
            spring_rate=spring_rate[None],
            tyre_contact=tyre_contact[None],
        )


def _detrend(x: np.ndarray) -> np.ndarray:
    """x less its least-squares line along the last axis."""
    n = np.arange(x.shape[-1], dtype=float)
    n -= n.mean()
    centred = x - x.mean(axis=-1, keepdims=True)
    return centred - (centred @ n / (n @ n))[..., None] * n


def _clipped(x: np.ndarray, top: np.ndarray, bottom: np.ndarray, full_scale: float | None) -> np.ndarray:
    """Per row: three or more consecutive samples at the row's extreme `top` or `bottom` (or at the
    full scale)."""
    out = np.zeros(x.shape[0], dtype=bool)
    if full_scale is not None:
        out |= np.maximum(top, -bottom) >= 0.999 * full_scale
    for extreme in (top, bottom):
        at = x == extreme[:, None]
        maybe = np.flatnonzero(np.count_nonzero(at, axis=1) >= 3)  # rare: look closer only there
        for r in maybe:
            out[r] |= bool(np.any(at[r, :-2] & at[r, 1:-1] & at[r, 2:]))
    return out


def _spiky(x: np.ndarray, top: np.ndarray, bottom: np.ndarray, z: float):
    """Per row: a sample more than z robust σ (1.4826 × median absolute deviation) from the median;
    and the rows' medians and robust σ.

    The median and MAD are those of every 16th sample (a robust scale at a 16th of the cost);
    only the row's extremes `top` and `bottom` need comparing with them."""
    sub = x[:, ::16]
    med = np.median(sub, axis=1)
    mad = 1.4826 * np.median(np.abs(sub - med[:, None]), axis=1)
    return np.maximum(top - med, med - bottom) > z * np.maximum(mad, 1e-12), med, mad


def pressure_at(update: MonitorUpdate, t_s: np.ndarray, prior_pa: np.ndarray, prior_sigma_pa: float):
    """The monitor's estimate on another time axis (step-hold: each row holds until the next).

    Before the first row: `prior_pa` (C,) ± `prior_sigma_pa`. Returns pressure and σ, (T, C), Pa.
    """
    idx = np.searchsorted(update.t_s, np.asarray(t_s, dtype=float), side="right") - 1
    n_c = update.pressure_pa.shape[1] if update.pressure_pa.ndim == 2 else len(prior_pa)
    p = np.empty((idx.size, n_c))
    sig = np.empty((idx.size, n_c))
    before = idx < 0
    p[before], sig[before] = prior_pa, prior_sigma_pa
    p[~before] = update.pressure_pa[idx[~before]]
    sig[~before] = update.pressure_sigma_pa[idx[~before]]
    return p, sig
