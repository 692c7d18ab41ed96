r"""Online four-corner tyre-pressure monitor: streaming, bounded state, follows pressure changes.

Usual call::

    mon = TyreMonitor(corner_models, dt=1e-3)
    for chunk in stream:                       # any chunk length, in time order
        out = mon.update(chunk.t_s, chunk.speed_mps, chunk.acc_sprung, chunk.acc_unsprung)
        out.pressure_pa, out.pressure_sigma_pa, out.observable   # one row per update

What it estimates (the model is :mod:`suvtwin.estimators.joint`'s, made causal and recursive):
each tyre's vertical stiffness k_t and pressure (eq. 3–4 of Brancati & Tufano 2022 [3]_) with σ,
each corner's road level :math:`G_d(n_0)` and waviness w, and the road's, pooled over the corners.
Each corner is modelled as its place in a linear full car (:mod:`suvtwin.estimators.full_car`:
body heave, pitch and roll on four corners with anti-roll bars, two independent ISO 8608 tracks,
each rear wheel re-running its front wheel's road a wheelbase/speed later) when its
:class:`~suvtwin.estimators.joint.LinearQuarterCar` carries ``full_car``, else as the roll-plane
corner model (half a heave and half a roll quarter car). The roll-plane model puts the whole
roll inertia on one axle with that axle's roll stiffness alone and misses the rear wheels
re-exciting the body, which biases k_t by speed-dependent amounts (29 kPa low at 120 km/h on the
full car's expected spectrum, ``bench/monitor_model_bias.py``); on the MuJoCo ``constant`` runs
(observable tyres, 30 s, point contact, band to 30 Hz) it read +4.0 ± 12.7 kPa, the full car
−1.1 ± 9.0 kPa (``python bench/monitor_mujoco.py --set constant --runs 100 [--corner-model
roll_plane]``). The full car's gain depends on the speed only through the front→rear delay, so its
speed-free parts are tabulated and the delay applied per window
(:func:`~suvtwin.estimators.full_car.gain_at_delay`). The road's PSD is multiplied by the power
gain of the tyre's enveloping (the corner model's ``envelope_half_length``,
:func:`~suvtwin.estimators.joint.envelope_power`): the tyre reads the road as a mean over its
contact patch, which at low speed cuts the road's power around the wheel hop; left out, it read
the fronts 5.6 kPa low at 40–55 km/h on those runs and gave false warnings at 36–42 km/h. The
likelihood is Whittle's [1]_, projected on the road-driven direction of the corner's two
accelerations (the heave quarter car's; see the joint estimator). The corners are estimated
independently: tying their level and slope
together lowers the ideal Cramér–Rao bound a little (``bench/monitor_bound.py``), but on the
MuJoCo SUV it turned each corner model's small gain error into a k_t error of the other corners
and made every tyre worse (docs/monitor.md).

How it runs, every ``update_s`` seconds (every ``change_update_s`` while a tyre's pressure may be
changing: its changing regime, item 3, at ``change_update_probability`` or more) on the last
``segment_s`` of data (a sliding window, rectangular, linear detrend; above ``merge_above_hz`` the
periodogram is averaged in bands of ``merge_width_hz``):

1. **Checks.** Per corner, a window with a missing value, a saturated (flat-topped) or
   implausible accelerometer, or a spike is skipped; so is a window whose speed is not
   finite, negative or changes by more than ``max_speed_change`` within it, and one at a
   speed whose spectral band (``band_cycles_per_m`` times the speed) stops below
   ``hop_margin`` times the corner's wheel-hop frequency: there k_t barely changes the
   spectrum and the model's errors near the resonance set the estimate, so the window is not
   used for k_t. So is a window where one of the corner's two accelerometers reads only its
   noise while the other reads the road (``silent``: a disconnected sensor), one with no road
   signal above the noise (``smooth``) and one where no linear model holds (``rough``; item 6).
   Each skip is counted, by reason, in the output; nothing is fatal.
2. **Each window's likelihood on a grid.** Each used window's 2×2 cross-periodogram of
   (sprung, unsprung) acceleration gives its Whittle log-likelihood on a fixed grid of the
   corner's unknowns: ``damping_points`` dampings over the model's ``damping_range`` (a
   digressive damper's equivalent linear damping), the waviness w at ``waviness_points`` values
   over ``waviness_range`` and at w = 2, and the pressure every ``grid_step_kpa`` over
   ``pressure_range_kpa`` (spline-interpolated to 1 kPa). The window's own road level is
   integrated out (Laplace, its maximum found by warm-started Fisher scoring, all corners in one
   compiled call, :func:`_window_loglik`): each window may sit on a rougher or smoother stretch
   of road, so a change of roughness is not taken for one of pressure. Windows overlapping by
   half (4 s updates) have periodograms correlated by 1/4 (Welch 1967 [5]_, rectangular window),
   so the windows' summed score has 1.5 times the variance of independent ones: each window's
   log-likelihood is weighted by 2/3 (1 where they do not overlap, 8 s updates; :func:`_overlap_weight`),
   which makes the posterior's width the information the data
   hold (on the MuJoCo ``warning`` runs the error divided by σ had a std of 1.06 at 10 s and 0.93
   at 30 s; with weight 1/2, each sample counted once, 0.90 and 0.81).
3. **A Bayesian filter on the grid.** Each corner's state is its posterior on regime ×
   damping × waviness × pressure (1 kPa): a hidden Markov model [4]_, filtered exactly (predict,
   then Bayes' rule with each window; :meth:`TyreMonitor._predict`, :meth:`TyreMonitor._correct`).
   Between updates the pressure follows a random walk whose rate depends on a two-state regime,
   *steady* (``steady_drift_kpa`` per √s: temperature, diffusion) or *changing*
   (``change_drift_kpa`` per √s: a leak, a drop), the regime a Markov chain (a change starts
   every ``change_every_s`` on average and lasts ``change_lasts_s``) — the interacting
   multiple-model idea [2]_, exact on the grid instead of Gaussian; a pressure is redrawn from its
   prior every ``redraw_every_s`` (a refill the stream does not show) and each corner's damping
   and waviness from theirs every ``road_change_s`` (the road's character changes). So the memory
   is not a tuning knob but follows from what the filter must allow: while the data agree with a
   steady pressure its σ shrinks to what the windows hold; when they contradict it the changing
   regime takes over, σ widens and the estimate moves; with no data (low speed, faults) σ grows
   and the estimate relaxes to the prior. The output is the posterior's mean and σ of the
   pressure, the probability of the changing regime (``change_probability``), and the waviness's
   mean. The state is this grid (about 0.4 MB for four corners) and the last window's samples:
   fixed in size, so the cost per second of data is the same after 10 s and after 10 h
   (``bench/monitor_cost.py``). The filter is the Kalman filter where that is exact (a Gaussian
   likelihood, one regime: ``tests/test_monitor.py``).
4. **Why not forgetting and model averaging.** The version before this one kept memories with
   exponential forgetting (τ = 4, 16, 64 s), weighted them by their predictive scores (dynamic
   model averaging) and cut them with a likelihood-ratio change test. On the MuJoCo SUV one 4 s
   block's predictive density differed by a few hundredths of a nat between memories, so their
   weights stayed near equal and the output mixed a 4 s memory's noise into a 64 s memory's
   estimate: at 60 s σ was about 1.5 times the error (the deflation warning, 15 % rule, preview
   on, then fired in 33 % of the ``warning`` runs, against 52 % for this filter).
5. **Change probability.** A change is not declared by a threshold: the changing regime's
   posterior probability is reported per update (``change_probability``; ``counts["changes"]``
   counts its rises through 0.5).
6. **The suspension and the tyre, linearized at the measured travel.** A corner model with a
   suspension law (``LinearQuarterCar.suspension``: a progressive spring with stops, a
   digressive damper) is analysed at its statistically linearized rate
   (:func:`suvtwin.suspension_law.equivalent_spring_rate`): the travel's and its velocity's
   standard deviations come from each window's spectrum of the relative
   acceleration a_s − a_us above ``travel_min_hz``, the mean travel from the corner's static
   travel and the damper's jacking; and its tyre's stiffness and damping are scaled by the share
   of time it touches the road, Φ(W/σ_F), with the dynamic wheel load −(m_s a_s + m_us a_us)
   taken as Gaussian. Gain tables are made per (corner, rate step ``rate_step``, contact step)
   when first needed and kept (at most ``table_slots``, least recently used replaced); a window
   is analysed with the (up to) four around its rate and contact share blended (bilinear in the
   steps), so its likelihood is continuous in them. Where the
   linearized travel is on a stop or the wheel off the ground more than ``max_nonlinear_share``
   of the time no linear model holds, and the window is skipped (``rough``); from
   ``nonlinear_taper_from`` to that limit its weight falls linearly to 0. What the
   linearization drops, the asymmetric damper's even part, is added as known extra power beside
   the noise (``damper_distortion``, :meth:`TyreMonitor._damper_distortion`): its force spectrum
   is that of the rectified suspension velocity (:func:`suvtwin.suspension_law.rectified_psd`),
   carried to the accelerations by the corner's quarter car at each grid pressure.
7. **The front→rear preview** (``tracks``, off unless given): each rear wheel runs over its front
   wheel's track a wheelbase/speed later, so the rear's unsprung acceleration is the front's
   through the ratio of the two wheels' responses (:mod:`suvtwin.estimators.preview`: 1 s segments
   on 20–40 Hz, the road cancels). Each track keeps that likelihood's statistics, forgotten with
   ``preview_memory_s`` and restarted while either corner's change probability exceeds 0.5; at each
   update the rear's pressure given the front's estimate (Laplace along the likelihood's ridge, with
   a model-error floor) is fused with the rear's own (:func:`suvtwin.estimators.preview.fuse_track`)
   if the two agree within ``preview_gate`` combined σ (an innovation gate; rejections counted);
   the front moves with it (the two estimates' errors taken as correlated by
   ``preview_correlation``: the wheels read the same road) if the rear is observable. A front that
   is not observable passes nothing on. A track is fed only
   the blocks where both its corners' windows are used (not ``rough``, not ``low_speed``), and its
   preview is used only while the two wheels are coherent (``PreviewConfig.min_coherence``):
   where the rear wheel does not follow the front's road the ratio is attenuated and pulls the
   rear low (before these gates: 3–4 false warnings in 506 simulated minutes at nominal
   pressure, docs/monitor.md).
8. **Observability.** A corner whose σ exceeds ``observable_sigma_kpa`` (no usable data for a
   while: low speed, flat road, faulty sensor) is flagged not observable; its estimate
   then relaxes toward the prior (``prior_pressure_kpa`` ± ``prior_sigma_kpa``) as the filter's
   random walk and redraws spread it, instead of holding an old value with a small σ.
9. **Tails.** The posterior is not Gaussian: the changing regime spreads a share of the mass at
   every prediction (a skirt beside a sharp likelihood, a broadening beside the MuJoCo SUV's
   windows), the range's bounds cut it, and early on it leans towards the prior. Each pressure's
   5 % and 95 % quantiles are reported beside the mean and σ (``TAIL_LEVELS``; through the
   preview's fusion by the affine map that takes the filter's mean and σ to the fused ones [6]_),
   and the deflation warning reads the upper one (:mod:`suvtwin.estimators.deflation`). On the
   100 ``constant`` runs (observable updates after 2 s) the truth lay above the 95 % quantile in
   3.3 % and below the 5 % one in 3.1 % of them (mean ± 1.645 σ: 3.1 % and 2.2 %).

10. **The force closure** (``force_closure``, where the monitor has both tracks and every corner its
   suspension law): each track's rear wheel meets its front wheel's road a wheelbase later, and
   under each wheel the road is the wheel's height plus its tyre's dynamic force over the tyre's
   stiffness, so the two tyres' stiffnesses close a relation that holds no road spectrum
   (:mod:`suvtwin.estimators.force_closure`). Its windows, clear of the suspension's stops and of
   lift-off, enter each tyre's posterior as a likelihood (:meth:`TyreMonitor._correct_closure`);
   tempered by ``closure_tempering`` (each update's windows share an error their number does not
   shrink), and the output adds its model-error floor (``closure_floor_kpa``). On the 100
   ``constant`` runs (with the radii) it took the error from ± 15.0 / 10.1 kPa at 10 / 30 s to
   ± 10.8 / 6.2 with 4 s windows, to ± 6.4 / 3.3 with 0.5 s windows, to ± 6.4 / 3.0 tempered; class
   D's wheels reach the stops often, so fewer of its windows are clear: a track whose 0.5 s windows
   mostly are not is read in 0.25 s windows, each kind weighed by its own residual level (since
   2026-12-05; ± 6.5 / 3.3 → ± 4.2 / 2.6 kPa, class D ± 10.0 / 4.6 → ± 5.0 / 2.6;
   docs/monitor.md).

Everything uses data up to t only (the speed included): the estimate at t from a record cut
at t is the estimate at t from the whole record.

No MuJoCo here: the monitor consumes arrays.

References
----------
.. [1] P. Whittle, "Curve and periodogram smoothing", J. R. Stat. Soc. B 19(1), 1957.
.. [2] H. A. P. Blom, Y. Bar-Shalom, "The interacting multiple model algorithm for systems with
   Markovian switching coefficients", IEEE Trans. Automatic Control 33(8), 780–783, 1988.
.. [3] R. Brancati, F. Tufano, Machines 10(12), 1221, 2022, eq. 3–4 (k_t(p)).
.. [4] L. R. Rabiner, "A tutorial on hidden Markov models and selected applications in speech
   recognition", Proc. IEEE 77(2), 257–286, 1989 (the forward recursion filtered here).
.. [5] P. D. Welch, "The use of fast Fourier transform for the estimation of power spectra: a
   method based on time averaging over short, modified periodograms", IEEE Trans. Audio
   Electroacoustics 15(2), 70–73, 1967.
.. [6] J. L. Anderson, "An ensemble adjustment Kalman filter for data assimilation", Monthly
   Weather Review 129(12), 2884–2903, 2001.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np
import numpy.typing as npt
from scipy.interpolate import CubicSpline
from scipy.special import logsumexp, ndtr

from suvtwin.errors import InputError
from suvtwin.estimators.force_closure import (
    ClosureConfig,
    ClosureStream,
    CornerParts,
    objective_on_grid,
    pair_messages,
)
from suvtwin.estimators.full_car import (
    axle_coherence_parts,
    blend_gain_at_delay,
    projected_gains,
    wheel_responses,
)
from suvtwin.estimators.joint import N0, LinearQuarterCar, envelope_power, signal_direction, signal_gain
from suvtwin.estimators.preview import PreviewConfig, PreviewTrack, fuse_track
from suvtwin.estimators.quarter_car import stiffness_from_pressure
from suvtwin.jit import cached_njit
from suvtwin.suspension_law import damper_even_slope, equivalent_spring_rate, rectified_psd
from suvtwin.tire_stiffness import (
    TireStiffness,
    stiffness_at_pressure_array,
    stiffness_sigma_at_pressure_sigma,
    suv_tire_stiffness,
)

__all__ = ["SKIP_REASONS", "TAIL_LEVELS", "MonitorConfig", "MonitorUpdate", "TyreMonitor", "pressure_at"]

TAIL_LEVELS = (0.05, 0.95)
"""Quantile levels of each pressure's reported tails (``pressure_lower_pa``, ``pressure_upper_pa``):
a 90 % credible interval; the upper one is what the deflation warning's 95 % decision needs."""

SKIP_REASONS = ("used", "gap", "clipped", "implausible", "spike", "speed", "low_speed", "rough", "smooth",
                "silent")
"""Per corner and segment, why it was (not) used for k_t: index into this tuple.
``gap``: a missing (NaN) value; ``clipped``: three or more consecutive samples at the segment's
extreme or at the sensor's range; ``implausible``: a value beyond ``max_accel_mps2`` or a dead
(constant) channel; ``spike``: more than 0.2 % of an update's samples more than ``spike_z``
robust standard deviations from the median (fewer are replaced by the median and counted as
``despiked``, and the window is used); ``speed``: speed not finite, negative or changing
within the segment; ``low_speed``: the band does not reach past the wheel hop; ``rough``: the
suspension hits its stops or the wheel leaves the ground more than ``max_nonlinear_share`` of the
time (a corner model with a suspension law only): there no linear model holds; ``smooth``: no road
signal to read k_t from: the unsprung power over the band stands less than ``min_signal_z``
standard errors above the sensors' noise, or the window's likeliest road is at the level's lower
bound (10⁻⁸ m³, where the model's road still rises well above the noise at the wheel hop; a MuJoCo
run on a road with no roughness at all read every tyre 80–87 kPa and warned all four before this
check); ``silent``: one of the corner's two accelerometers reads only the sensors' noise in the body's
band while the other reads the road there (a disconnected or loose sensor, ``silent_other_z``;
before this check a body accelerometer reading noise alone read its tyre 9.9 kPa low on 12 bench
runs, −20 on one, and through the preview its track's front 7.0 kPa low, −19 on that run)."""

(_USED, _GAP, _CLIPPED, _IMPLAUSIBLE, _SPIKE, _SPEED, _LOW_SPEED, _ROUGH, _SMOOTH,
 _SILENT) = range(len(SKIP_REASONS))
_LEVEL_BOUNDS = (np.log(1e-8), np.log(1e-1))  # log Gd(n0), m³
_FREQ_TOL = 1e-9  # relative tolerance of a Fourier frequency at a threshold (TyreMonitor.__init__)
_GRAVITY = 9.81  # m/s²
_COHERENCE_POOL_OCTAVES = 0.5  # each band's track coherence pooled from the bands within this (TyreMonitor)
_COHERENCE_PRIOR = 0.1  # the coherence's prior: this share of a window at full signal that read γ = 0


def _at_level_floor(ll: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """Per corner (C,), whether a window's likeliest grid point (the maximum of `ll` (C, D, B, G)
    over damping, slope and pressure) has its road level `lam` (log Gd(n0), same shape) at the lower
    bound of :data:`_LEVEL_BOUNDS`: the data want less road than the model allows."""
    flat_ll, flat_lam = ll.reshape(ll.shape[0], -1), lam.reshape(lam.shape[0], -1)
    best = flat_lam[np.arange(ll.shape[0]), np.argmax(flat_ll, axis=1)]
    return best <= _LEVEL_BOUNDS[0] + 1e-6


@dataclass(frozen=True)
class MonitorConfig:
    """Settings of :class:`TyreMonitor` (units in the names; defaults are the documented ones).

    Attributes
    ----------
    segment_s : float
        Length of the window each periodogram is taken over, s (its frequency resolution is
        1/segment_s; shorter windows bias k_t high on the MuJoCo SUV).
    update_s : float
        Interval between updates, s (the window slides by it; segment_s must be a multiple). 8 s: the
        windows do not overlap, and an update's cost is mostly fixed (its window's likelihood on the
        grid, the closure's J and messages, the previews, the prediction), so the cost per second of
        data is 1.35–1.5 times lower than with 4 s (``bench/monitor_cost.py``: a varied hour of four
        corners at 528–594× real time on one core with 8 s updates; on the looped 60 s run the bench
        used before, 545–586× against 357–359×); the estimate is 8 s old at most, 4 s while a
        pressure may be changing (``change_update_s``).
        On the ``bench/monitor_mujoco.py`` sets with the radii (4 s in parentheses): ``constant``
        ± 6.54 / 3.36 kPa at 10 / 30 s (± 6.40 / 3.03; the 30 s score reads the 24 s update, not
        the 28 s one), ±2σ 99.5 % (99.5 %); ``drop`` 19 of 20 settled within 15 s, ±2σ 100 %
        (19, 88.8 %); ``warning`` 97 %, median 16 s (98 %, 8 s); ``nominal_long`` no false
        warning, highest held 0.48 (0.61); the monitor's own output during a leak ±2σ 61 % (78 %).
    change_update_s : float or None
        Interval between updates while a tyre's pressure may be changing (its changing regime's
        probability at the last update at least ``change_update_probability``), s; None, or not below
        ``update_s``: always ``update_s``. With 8 s updates a change that ends just after an update
        leaves the monitor 8 s of data before 15 s have passed (the next update but one comes 16 s
        after): on 20 ``drop`` runs with the drop at 6.8–8.3 s instead of 10–11.5 s, with the radii,
        17 of 20 dropped tyres within 12.5 kPa by 15 s; updating every 4 s while the changing regime
        holds, 18 of 20 (the class D one whose own estimate was +14 kPa at σ 6 kPa at 16 s settled at
        20 s; the two left, class D at 104 and 112 km/h, where the vibration is too uncertain for
        the changing regime to take over). No cost on steady driving, the bench sets' scores the
        same or better.
    change_update_probability : float
        The changing regime's probability (any tyre) from which updates come every
        ``change_update_s``.
    min_signal_z : float
        A window is used for k_t only where its unsprung power over the band stands at least this
        many standard errors above the sensors' noise (:meth:`TyreMonitor._road_signal_z`), else it
        is ``smooth``: with noise alone z is about standard normal, so 5 almost never takes noise
        for a road; on quarter-car roads of classes A–D at 60 km/h z was at least 13 900.
    silent_band_hz : float
        Upper end of the body's band, Hz, where a corner's two accelerometers are compared
        (:meth:`TyreMonitor._silent`): up to about twice the body's frequency the body follows the
        road, so the body (sprung) and wheel (unsprung) accelerations carry power of the same order.
    silent_other_z : float
        A window is ``silent`` where one of the corner's accelerometers stands less than
        ``min_signal_z`` standard errors above the sensors' noise over the band up to
        ``silent_band_hz`` (the energy detector of ``min_signal_z`` on that band) while the other
        stands at least this many above it: one sensor reads noise while the road moves the
        other. On the MuJoCo bench runs (10 134 windows of ``constant``, ``low_speed``, ``warning``
        and ``nominal_long``, 20–130 km/h, classes A–D) the body's z over the wheel's was 0.07–15.8
        on this band, and neither was below 14: 100 leaves a factor above 1.4 to the clean windows'
        extremes, and where both are small (a road smoother than class A) nothing is concluded.
    steady_drift_kpa : float
        Random walk of a tyre's pressure while it is steady, kPa per √s (temperature, diffusion
        through the rubber; 0.15 kPa/√s is 9 kPa in an hour).
    change_drift_kpa : float
        Random walk while it is changing, kPa per √s (a 20 % leak over 30 s moves 1.5 kPa/s;
        4 kPa/√s spreads 8 kPa per 4 s update).
    change_every_s : float
        Mean time a steady tyre stays steady before a change starts, s (the prior hazard of a
        change; short enough that the filter keeps doubting, which bounds its memory).
    change_lasts_s : float
        Mean duration of a change, s.
    redraw_every_s : float
        Mean time between redraws of a pressure from its prior (a tyre refilled or changed
        during a stop the stream does not show), s.
    road_change_s : float
        Mean time between changes of the road's character: the damping and waviness of each
        corner are redrawn from their prior at this rate, s.
    preview_memory_s : float
        Forgetting time constant of the front→rear preview's statistics, s.
    preview_gate : float
        A rear's preview is fused only if it lies within this many combined σ of the rear's own
        estimate (an innovation gate).
    preview_correlation : float
        Correlation of a track's front and rear own estimates' errors assumed when the preview fuses
        them (:func:`suvtwin.estimators.preview.fuse_track`): the two wheels read the same road, so
        their estimates share its departures from the model. Measured on the 100 ``constant`` runs
        (each tyre on its own, observable): 0.76 at 10 s, 0.56 at 30 s, 0.32 at 40 s (the two
        tracks' fronts −0.2 to 0.15). With 0.5 the tyres' error over σ had a std of 0.91–1.05 from
        8 to 20 s and 0.74–0.76 at 40 s; with 0 (independent) 1.04–1.23 and 0.84: ±2σ then held
        88–94 % of the tyres before 20 s, and the slow leak's coverage fell to 83 %.
    track_coherence : float or None
        The left and right tracks' road coherence γ in the full car's expected spectrum
        (:mod:`suvtwin.estimators.full_car`): None (the default) estimates it per band from the two
        axles' wheels (:meth:`TyreMonitor._update_coherence`), a number in [−1, 1] fixes it (0:
        independent tracks, the monitor before 2026-12-04). On roads whose tracks are correlated
        taken as 0 read every tyre low: on the first 32 ``constant`` scenarios with their tracks
        correlated by 0.5 (the simulator's ``tracks: correlated``) −21.0 ± 17.1 kPa at 10 s (with
        the radii) and a would-be false warning on 31 of 128 tyres, with identical tracks
        −44.6 ± 24.1 and 124 of 128; estimated, −4.7 ± 15.3 and none, −5.7 ± 19.9 and 1 (held 0.951)
        (``python bench/monitor_tracks.py --runs 32``).
    coherence_memory_s : float
        Time constant of the coherence estimate's exponential memory, s (its sums decay by
        exp(−elapsed/τ) per update).
    band_cycles_per_m : (float, float)
        Spatial-frequency band used, cycles/m (times the speed: Hz). Up to 3 cycles/m (ISO 8608's
        classes span 0.011–2.83 cycles/m; the simulator's roads reach 10): the band then reaches
        ``max_frequency_hz`` from 24 km/h on, past the wheel hop where k_t shapes the spectrum. With
        1.5 cycles/m it stopped at the hop below about 40 km/h: on the ``low_speed`` runs
        (20–35 km/h) every update was flagged not observable, and on ``nominal_long`` the first
        windows above the margin (36 km/h, band to 1.35 times the hop) read a front tyre 60 kPa
        low: a false warning. With 3 cycles/m: ``low_speed`` 70 % of the updates observable,
        +3.3 ± 18.2 kPa at 10 s, 2 of 560 updates beyond 3σ; ``constant`` and ``nominal_long``
        unchanged (no false warning in 506 min).
    max_frequency_hz : float
        Upper limit of the band, Hz. 20 Hz: above it the MuJoCo SUV's wheel acceleration exceeds
        the linear full car's by 7–17 % (20–25 Hz, twice the wheel hop; 3–7 % below 20 Hz) on
        a smooth road; a symmetric damper takes the 20–25 Hz excess to 5 %, and the damper's even
        part (``damper_distortion``) accounts for about half of it; read as road-driven power the
        rest makes the tyre look stiff. On the 100 ``constant`` runs, without the even part, the
        observable tyres' error at 30 s was +4.5 ± 9.0 kPa with 30 Hz, +1.9 ± 9.6 kPa with 20 Hz.
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
        Gaussian prior on each pressure, kPa (None: the tyre's nominal pressure), cut to
        ``pressure_range_kpa``. The default σ, 1000 kPa, makes it flat over the range (its density
        varies there by under 6 %): the monitor does not presume a tyre inflated. A prior about the
        nominal pressure pulls every early estimate of a low tyre up, against the warnings the
        monitor is for: N(nominal, 100 kPa), the default until 2026-12-03, read the 100
        ``constant`` bench runs (130–230 kPa) +3.0 kPa high at 10 s, the flat one +0.2 (docs/monitor.md).
    waviness_range : (float, float)
        Range of the road waviness w.
    waviness_iso_weight : float
        Prior probability that w = 2 exactly (spike and slab).
    waviness_points : int
        Values of w over ``waviness_range`` in the slab (marginalized, with w = 2 beside them).
    damping_points : int
        Damping values over the corner model's ``damping_range`` (marginalized).
    grid_step_kpa : float
        Step of the pressure grid each window's likelihood is evaluated on, kPa (interpolated to
        1 kPa by a cubic spline for the posteriors: the log-likelihood is smooth on that scale).
    hop_margin : float
        A segment informs k_t only if its band reaches this times the corner's nominal wheel-hop
        frequency. With the band ending barely past the resonance, the roll-off above it that pins
        k_t is missing and what the model leaves out there (the damper's even part, the
        suspension's non-linearity) sets the estimate: with the band to 1.5 cycles/m and a margin
        of 1.25, a front tyre read 30–50 kPa low at 33.5 km/h with σ 12–16 kPa (beyond 3σ); with
        3 cycles/m and 1.35, the error over σ had a std of 1.25 at 19–25 km/h (band to 1.4–1.6
        times the hop), 1.04 at 25–30 and 0.83 at 30–36 km/h. 1.6: the SUV's fronts are used from
        21 km/h, its rears from 23 km/h.
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
        Relative step of the lattice of equivalent suspension rates (and tyre contact shares) the
        gain tables are made for; a window's tables are its four neighbours' blended. 4 %: on a
        varied hour (bench ``monitor_cost.py``, the rates 1–9 times the design's) 216 lattice points
        against 320 at 2 % (the default until 2026-12-05), 466 tables made against 687 (32 kept), the
        100 ``constant`` runs' errors and the ``drop``, ``slow_leak`` and ``low_speed`` scores
        unchanged (with the radii ±6.50 / 3.34 kPa at 10 / 30 s against ±6.54 / 3.36), the 100
        ``warning`` runs 98 % warned against 97 %; at 10 % ±7.02 / 3.45.
    table_slots : int
        Most gain tables (corner, rate and contact step) kept at once, 1.1 MB each with the full car;
        the least recently used is replaced. On a varied hour (bench ``monitor_cost.py``: 215 lattice
        points met) 32 kept made 490 tables and 96 262 (2.8 ms each), the cache then at most 110 MB
        (:attr:`TyreMonitor.gain_tables_nbytes`); outputs do not depend on it (identical on that hour).
    damper_distortion : bool
        Add the asymmetric damper's even part (a force b(|v| − E|v|) between body and wheel, at
        sums of the suspension velocity's frequencies, which no linear model holds) to each
        window's model spectrum as known extra power (:meth:`TyreMonitor._damper_distortion`;
        corners with a suspension law). On the 100 ``constant`` runs it took the observable
        tyres' error at 30 s from +1.9 ± 9.6 to +0.0 ± 9.6 kPa (class A +3.9 → 0.0).
    force_closure : bool
        Each track's two tyres also from the force closure (:meth:`TyreMonitor._correct_closure`,
        :mod:`suvtwin.estimators.force_closure`) where the monitor has two tracks and every corner
        its suspension law (the closure's settings: the monitor's ``closure_config``).
    closure_floor_kpa : float
        σ of the closure's model error per tyre, kPa: an offset its windows share, which their
        number does not shrink (:meth:`TyreMonitor._closure_floor_var`). On the first 30
        ``constant`` runs (classes A–C, the closure alone) the tyres' errors kept a std of
        2.2–3 kPa after 30–40 s while the closure's own σ fell to 1–1.5 kPa; without the floor the
        monitor's ±2σ held the truth in 80 % of those runs' updates (measured with the closure summed
        over the other tyre's posterior, :meth:`TyreMonitor._correct_closure`), with 3 kPa 96–98 %.
    closure_memory_s : float
        Forgetting time constant of the closure's information counted toward that floor, s (it
        starts afresh when the tyre's pressure is changing).
    closure_tempering : float
        κ ≥ 1: each update's closure log-likelihood is divided by it (a tempered, or power,
        likelihood: its variance κ times the quasi-likelihood's). The windows of one update share
        errors the quasi-likelihood counts as independent: one span of integration, and 2–4 s of
        one road. Their scores scatter as the curvature of J says (a sandwich estimate from the
        windows' scores, lag one included, moved the RMS of the z-scores by 10 % at most), yet one
        update's closure estimate alone, from a flat prior, missed the truth by 1.42 σ RMS at the
        first update of the first 40 ``constant`` runs, and by 1.69 σ on the 20 ``low_speed`` runs:
        κ = 2. With it, on the 100 ``constant`` runs the monitor's own output read ± 10.35 / 5.66 kPa
        at 10 / 30 s and ±2σ held 99.1 % (κ = 1: ± 10.26 / 6.02, 97.6 %; κ = 3: ± 10.48 / 5.69,
        99.6 %), 3 of 4000 updates beyond 3σ (16 with κ = 1); ``low_speed`` with the radii none of
        560 beyond 3σ (2 with κ = 1).
    max_nonlinear_share : float
        A window whose travel (Gaussian, as linearized) reaches the bump or rebound stop, or whose
        wheel leaves the ground, more than this share of the time is not used for k_t (``rough``).
        20 %, with the weight tapered from ``nonlinear_taper_from``: the taper carries the
        linearized model's growing error, so the limit only marks where no linear model is
        tried. On the 100 ``constant`` runs, class D (32 runs, all tyres, 30 s): limit 10 %
        +9.5 ± 24.2 kPa, 26 % of the tyres not observable, ±2σ 99.6 % of the updates; 20 %
        +2.5 ± 17.0, 10 %, 97.6 %; 25 % +1.3 ± 15.6, 6 %, 96.3 %. All classes at 30 s
        (all tyres): +3.3 ± 16.2 kPa (10 %), +1.0 ± 12.1 (20 %), +0.6 ± 11.5 (25 %); ±2σ 98.7 %,
        98.0 %, 97.6 %. ``warning`` detected within 60 s 81 %, 84 %, 84 % (class D 62 %, 73 %,
        73 %); ``slow_leak`` coverage 90 %, 88.5 %, 84.6 %; ``drop`` 73 %, 68 %, 67.5 % (the class D
        tyres it now reads are no longer covered by a σ of 80 kPa); ``nominal_long`` no false
        warning with any. Without the taper (hard limits, class D, 30 s, observable tyres only):
        5 % left 43 % of the tyres not observable (−0.5 ± 9.6 kPa, 0.8 % beyond 2σ), 10 % 24 %
        (−1.7 ± 11.6, 2.3 %), 15 % 9 % (−1.4 ± 13.7, 5.5 %), 20 % 6 % (−0.7 ± 15.0, 8.6 %).
    nonlinear_taper_from : float
        From this share of time on a stop or off the ground up to ``max_nonlinear_share`` a
        window's log-likelihood weight falls linearly to 0 (a tempered likelihood: the linearized
        model's error grows toward the limit, and one periodogram's share is itself noisy). With a
        hard limit alone, a class D ``drop`` run (112 km/h) used one window at 9.8 % among
        neighbours at 10–23 %, read the rear 72 kPa high at σ 22 kPa and kept it. On the 100
        ``constant`` runs with the limit at 10 % (against the hard limit): observable tyres
        +1.6 ± 16.6 kPa at 10 s (+2.1 ± 17.1), −0.2 ± 9.1 at 30 s (−0.3 ± 9.5), class D ±2σ 99.6 %
        (98.1 %), 26 % of D's tyres not observable at 30 s (23 %); ``drop`` coverage 73 % (67.5 %),
        ``slow_leak`` 90 % (88.9 %); ``warning`` 79 % (81 %: two class D runs less).
    """

    segment_s: float = 8.0
    update_s: float = 8.0
    min_signal_z: float = 5.0
    silent_band_hz: float = 3.0
    silent_other_z: float = 100.0
    steady_drift_kpa: float = 0.15
    change_drift_kpa: float = 15.0
    change_every_s: float = 60.0
    change_lasts_s: float = 8.0
    redraw_every_s: float = 3600.0
    road_change_s: float = 60.0
    preview_memory_s: float = 32.0
    preview_gate: float = 3.0
    preview_correlation: float = 0.5
    track_coherence: float | None = None
    coherence_memory_s: float = 32.0
    band_cycles_per_m: tuple[float, float] = (0.05, 3.0)
    max_frequency_hz: float = 20.0
    merge_above_hz: float = 3.0
    merge_width_hz: float = 0.5
    sigma_accel: float = 0.5
    pressure_range_kpa: tuple[float, float] = (60.0, 400.0)
    prior_pressure_kpa: float | None = None
    prior_sigma_kpa: float = 1000.0
    waviness_range: tuple[float, float] = (1.5, 3.0)
    waviness_iso_weight: float = 0.8
    waviness_points: int = 5
    damping_points: int = 3
    grid_step_kpa: float = 8.0
    hop_margin: float = 1.6
    max_speed_change: float = 0.1
    accel_range_mps2: float | None = None
    max_accel_mps2: float = 1000.0
    spike_z: float = 8.0
    observable_sigma_kpa: float = 25.0
    travel_min_hz: float = 1.0
    rate_step: float = 0.04
    table_slots: int = 96
    max_nonlinear_share: float = 0.20
    nonlinear_taper_from: float = 0.05
    damper_distortion: bool = True
    force_closure: bool = True
    closure_floor_kpa: float = 3.0
    closure_memory_s: float = 60.0
    closure_tempering: float = 2.0
    change_update_s: float | None = 4.0
    change_update_probability: float = 0.5

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
                "change_update_s",
                self.change_update_s is None
                or (0.25 <= self.change_update_s <= 60.0
                    and (self.change_update_s >= self.update_s
                         or abs((k := self.update_s / self.change_update_s) - round(k)) < 1e-9)),
                "None or 0.25–60 s, below update_s a divisor of it",
            ),  # fmt: skip
            ("change_update_probability", 0.0 < self.change_update_probability <= 1.0, "(0, 1]"),
            ("min_signal_z", 0.0 <= self.min_signal_z <= 1e3, "0–1000"),
            ("silent_band_hz", 0.0 < self.silent_band_hz <= 1e3, "0–1000 Hz, above 0"),
            ("silent_other_z", self.min_signal_z <= self.silent_other_z <= 1e9, "min_signal_z–1e9"),
            ("steady_drift_kpa", 0.0 <= self.steady_drift_kpa <= 10.0, "0–10 kPa/√s"),
            ("change_drift_kpa", self.steady_drift_kpa < self.change_drift_kpa <= 50.0,
             "steady_drift_kpa–50 kPa/√s"),
            ("change_every_s", self.update_s <= self.change_every_s <= 1e7, "update_s–1e7 s"),
            ("change_lasts_s", self.update_s <= self.change_lasts_s <= 1e5, "update_s–1e5 s"),
            ("redraw_every_s", self.update_s <= self.redraw_every_s <= 1e9, "update_s–1e9 s"),
            ("road_change_s", self.update_s <= self.road_change_s <= 1e9, "update_s–1e9 s"),
            ("preview_memory_s", self.update_s <= self.preview_memory_s <= 1e6, "update_s–1e6 s"),
            ("preview_gate", 0.0 < self.preview_gate <= 1e3, "(0, 1000]"),
            ("preview_correlation", 0.0 <= self.preview_correlation < 1.0, "[0, 1)"),
            ("track_coherence", self.track_coherence is None or -1.0 <= self.track_coherence <= 1.0,
             "[-1, 1] or None (estimated)"),
            ("coherence_memory_s", self.update_s <= self.coherence_memory_s <= 1e6, "update_s–1e6 s"),
            (
                "band_cycles_per_m",
                0 < self.band_cycles_per_m[0] < self.band_cycles_per_m[1],
                "0 < low < high",
            ),
            ("max_frequency_hz", self.max_frequency_hz > 0, "> 0"),
            ("merge_above_hz", self.merge_above_hz >= 0, "≥ 0"),
            ("merge_width_hz", 0 < self.merge_width_hz <= 5.0, "(0, 5] Hz"),
            ("sigma_accel", 0 < self.sigma_accel <= 100.0, "(0, 100] m/s²"),
            (
                "pressure_range_kpa",
                0 < self.pressure_range_kpa[0] < self.pressure_range_kpa[1],
                "0 < low < high",
            ),
            ("prior_sigma_kpa", self.prior_sigma_kpa > 0, "> 0"),
            ("waviness_range", self.waviness_range[0] <= self.waviness_range[1], "low ≤ high"),
            ("waviness_iso_weight", 0 <= self.waviness_iso_weight < 1, "[0, 1)"),
            ("waviness_points", 1 <= self.waviness_points <= 50, "1–50"),
            ("damping_points", 1 <= self.damping_points <= 50, "1–50"),
            ("grid_step_kpa", 1.0 <= self.grid_step_kpa <= 25.0, "1–25 kPa"),
            ("hop_margin", self.hop_margin > 0, "> 0"),
            ("max_speed_change", self.max_speed_change > 0, "> 0"),
            ("max_accel_mps2", self.max_accel_mps2 > 0, "> 0"),
            ("spike_z", self.spike_z > 3, "> 3"),
            ("observable_sigma_kpa", self.observable_sigma_kpa > 0, "> 0"),
            ("travel_min_hz", 0 < self.travel_min_hz < self.max_frequency_hz, "(0, max_frequency_hz) Hz"),
            ("rate_step", 0.001 <= self.rate_step <= 0.2, "0.001–0.2"),
            ("table_slots", self.table_slots >= 1, "≥ 1"),
            ("max_nonlinear_share", 0 < self.max_nonlinear_share <= 1, "(0, 1]"),
            ("nonlinear_taper_from", 0 <= self.nonlinear_taper_from <= self.max_nonlinear_share,
             "0–max_nonlinear_share"),
            ("closure_floor_kpa", 0 <= self.closure_floor_kpa <= 100.0, "0–100 kPa"),
            ("closure_memory_s", self.update_s <= self.closure_memory_s <= 1e6, "update_s–1e6 s"),
            ("closure_tempering", 1.0 <= self.closure_tempering <= 100.0, "1–100"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"monitor setting {name} must be {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class MonitorUpdate:
    """The monitor's output for the segments finished by one :meth:`TyreMonitor.update` (K rows).

    `t_s` (K,): time of the segment's last sample, s (the estimate uses data up to it);
    `pressure_pa`, `pressure_sigma_pa`, `stiffness`, `stiffness_sigma` (K, C): per corner, Pa
    and N/m; `pressure_lower_pa`, `pressure_upper_pa` (K, C): the pressure's 5 % and 95 % quantiles
    (:data:`TAIL_LEVELS`), Pa: the posterior is not Gaussian (the changing regime's skirt, the
    grid's bounds), and a one-sided decision such as the deflation warning needs its tail;
    `observable` (K, C): σ below the configured limit; `status` (K, C): index into
    :data:`SKIP_REASONS` of what became of the segment (0: used); `road_level` (K,): the
    shared Gd(n0), m³ (NaN before any data); `waviness` (K,); `speed_mps` (K,): the segment's
    mean speed; `change_probability` (K, C): the filter's probability that the tyre's pressure
    is changing (a leak, a drop); `spring_rate` (K, C): the suspension rate the segment's window was
    analysed with, N/m (the equivalent rate of a corner with a suspension law, else its model's;
    NaN where the window was not analysed); `tyre_contact` (K, C): the share of time the tyre
    was taken to touch the road (1 without a suspension law; NaN where not analysed);
    `track_coherence` (K,): the left and right tracks' road coherence in use, averaged over the
    segment's band (the fixed ``track_coherence`` where it is not estimated; NaN before the
    estimate has a window, without a speed, or with no corner in a full car).
    """

    t_s: np.ndarray
    pressure_pa: np.ndarray
    pressure_sigma_pa: np.ndarray
    pressure_lower_pa: np.ndarray
    pressure_upper_pa: np.ndarray
    stiffness: np.ndarray
    stiffness_sigma: np.ndarray
    observable: np.ndarray
    status: np.ndarray
    road_level: np.ndarray
    waviness: np.ndarray
    speed_mps: np.ndarray
    change_probability: np.ndarray
    spring_rate: np.ndarray
    tyre_contact: np.ndarray
    track_coherence: np.ndarray

    @staticmethod
    def concatenate(parts: list[MonitorUpdate]) -> MonitorUpdate:
        """Rows of several updates, in order."""
        return MonitorUpdate(**{
            name: np.concatenate([getattr(p, name) for p in parts], axis=0)
            for name in MonitorUpdate.__dataclass_fields__
        })  # fmt: skip


@cached_njit(fastmath={"reassoc", "contract", "arcp"})
def _window_loglik(proj, noise, weight, lo, hi, base, gain, slot, lam_lo, lam_hi, out_ll, out_lam):
    r"""One window's Whittle log-likelihood with its road level integrated out, on the parameter grid.

    For each corner c (gain-table slot ``slot[c]``, skipped where −1), damping d, slope b and
    pressure g, in units of the sensors' white noise N: the road's signal along the signal direction
    s_f = e^λ base[b, f] gain[slot, d, g, f], the noise beside it n_f = noise[c, d, g, f] (1 + the
    damper's even part; 1 where `noise` is empty), :math:`\ell(\lambda) = -\sum_f w_f[\log(n_f + s_f)
    + P_f/(n_f + s_f)]`, maximized over the window's log level λ = log Gd(n0) within
    [lam_lo, lam_hi] by Fisher scoring (r = s/n, q = r/(1 + r): score U = :math:`\sum w q (P/(n + s) -
    1)`, information :math:`I = \sum w q^2`); out_ll = ℓ(λ̂) − ½ log I(λ̂) (Laplace's integral over λ
    with a flat prior, up to a constant common to the whole grid), out_lam = λ̂. Each pressure
    starts from its neighbours' λ̂ extrapolated along the grid; once a step δ is below 0.02 it is
    the last: ℓ, taken in the same pass as the score where that step starts, and log I are carried
    to its end to second order (ℓ + Uδ − Iδ²/2; dlog I/dλ = 2Σwq²(1 − q)/I): one pass over the band
    per grid point where the start is good (1.07 on average on a class C run). The sums run in
    units of the noise beside the signal: per corner, damping and pressure, gain/n and P/n and
    Σ_f w_f log n_f are taken once and shared by the slopes and iterations. Σ_f w_f log(1 + r_f) is
    taken as the logarithm of the product of the (1 + r_f)^{w_f} (w_f a count; a logarithm per band
    otherwise), flushed before it could overflow: 2.5 times faster than a logarithm per band, the
    same ℓ within 1e-12.

    `proj` (C, D, F): u^H S u / N of the window (dimensionless); `noise` (C, D, G, F) or empty;
    `weight` (F,): Fourier frequencies per band, nonzero only within [lo, hi); `base` (B, F):
    exp(β_b log(n/n0) + log(4π² n0² v)); `gain` (S, D, G, F): |h|²/N on the pressure grid; outputs
    (C, D, B, G). The same sums as :func:`suvtwin.estimators.joint.profile_loglik` (tested against
    it), compiled and warm-started for the grid."""
    n_c, n_d = proj.shape[0], proj.shape[1]
    n_b, n_g = base.shape[0], gain.shape[2]
    n_f = hi - lo
    white = noise.shape[0] == 0
    gn = np.empty((n_g, n_f))  # signal gain over the noise beside it, per pressure and band
    pn = np.empty((n_g, n_f))  # the window's power over that noise
    log_n = np.zeros(n_g)  # Σ_f w_f log n_f
    wi = np.empty(n_f, dtype=np.int64)  # the band weights as counts (0: not a count)
    for j in range(n_f):
        wf = weight[lo + j]
        wi[j] = int(wf) if (int(wf) == wf and 1.0 <= wf <= 16.0) else 0
    for c in range(n_c):
        s = slot[c]
        if s < 0:
            continue
        for d in range(n_d):
            for g in range(n_g):
                prod = 1.0
                logs = 0.0
                for j in range(n_f):
                    f = lo + j
                    n = 1.0 if white else noise[c, d, g, f]
                    gn[g, j] = gain[s, d, g, f] / n
                    pn[g, j] = proj[c, d, f] / n
                    if not white:
                        k = wi[j]
                        if k == 0 or n > 1e16:
                            logs += weight[f] * math.log(n)
                        else:
                            for _ in range(k):
                                prod *= n
                            if prod > 1e200:
                                logs += math.log(prod)
                                prod = 1.0
                log_n[g] = logs + math.log(prod)
            for b in range(n_b):
                lam1 = lam2 = 0.0
                for g in range(n_g):
                    if g >= 2:
                        lam = 2.0 * lam1 - lam2
                    elif g == 1:
                        lam = lam1
                    else:  # method of moments
                        total = excess = 0.0
                        for j in range(n_f):
                            wf = weight[lo + j]
                            total += wf * base[b, lo + j] * gn[g, j]
                            excess += wf * max(pn[g, j] - 1.0, 0.0)
                        lam = math.log(max(excess, 1e-12) / max(total, 1e-300))
                    lam = min(max(lam, lam_lo), lam_hi)
                    level = info = slope = score = step = quad = logs = 0.0
                    prod = 1.0
                    for _ in range(50):
                        # the score, information and ℓ at λ in one pass (ℓ is needed where the last step
                        # starts; a separate pass for it cost as much as the scoring)
                        level = math.exp(lam)
                        score = info = slope = quad = logs = 0.0
                        prod = 1.0
                        for j in range(n_f):
                            r = level * base[b, lo + j] * gn[g, j]
                            one_r = 1.0 + r
                            inv = 1.0 / one_r
                            q = r * inv
                            wf = weight[lo + j]
                            pi = pn[g, j] * inv
                            score += wf * q * (pi - 1.0)
                            wq2 = wf * q * q
                            info += wq2
                            slope += wq2 * (1.0 - q)
                            quad += wf * pi
                            k = wi[j]
                            if k == 0 or one_r > 1e16:
                                logs += wf * math.log(one_r)
                            else:
                                x = one_r
                                for _ in range(k - 1):
                                    x *= one_r
                                prod *= x
                                if prod > 1e200:
                                    logs += math.log(prod)
                                    prod = 1.0
                        info = max(info, 1e-300)
                        new = min(max(lam + min(max(score / info, -2.0), 2.0), lam_lo), lam_hi)
                        step = new - lam
                        lam = new
                        if abs(step) < 0.02:
                            break
                    ll = -(log_n[g] + logs + math.log(prod)) - quad
                    if abs(step) < 0.02:
                        ll += score * step - 0.5 * info * step * step
                        info *= math.exp(2.0 * step * slope / info)
                    out_ll[c, d, b, g] = ll - 0.5 * math.log(max(info, 1e-300))
                    out_lam[c, d, b, g] = lam
                    lam2, lam1 = lam1, lam


@cached_njit
def _blend_rows(table, slots, weights, out):
    """out[r] = Σ_k weights[r, k] table[slots[r, k]] for tables flattened to (S, M) and rows (R, M)
    (:meth:`TyreMonitor._blend`): the first term times its weight, then each later one with a
    positive weight added in turn; where no row has a second term the first is copied unscaled (its
    weight is 1). The same operations, in the same order, as the numpy indexing it replaced, without
    its temporary arrays (five blends an update, each 30–200 µs in numpy)."""
    n_r, n_k = slots.shape
    scale = False
    for r in range(n_r):
        for k in range(1, n_k):
            if weights[r, k] != 0.0:
                scale = True
    for r in range(n_r):
        first = slots[r, 0]
        w0 = weights[r, 0]
        for m in range(out.shape[1]):
            out[r, m] = table[first, m] * w0 if scale else table[first, m]
        if not scale:
            continue
        for k in range(1, n_k):
            w = weights[r, k]
            if w > 0.0:
                s = slots[r, k]
                for m in range(out.shape[1]):
                    out[r, m] += w * table[s, m]


@cached_njit
def _mix_walk_banded(post, w_steady, w_changing, start, band, moved, to):
    """moved[:, to] = the regimes' mixture w_steady post[:, 0] + w_changing post[:, 1] walked along
    pressure by a banded walk (:class:`_BandedWalk`: row i's entries `band[i]` at columns start[i] …),
    in one pass over `post` (C, R, D, B, P) (:meth:`TyreMonitor._predict`). Each row's terms are added
    in column order, a column at a time over all rows (a loop the compiler vectorizes: twice as fast
    as a sparse row's indexed columns, the same sums)."""
    n_c, _, n_d, n_b, n_p = post.shape
    mixed = np.empty(n_p)
    acc = np.empty(n_p)
    for c in range(n_c):
        for d in range(n_d):
            for b in range(n_b):
                for p in range(n_p):
                    mixed[p] = w_steady * post[c, 0, d, b, p] + w_changing * post[c, 1, d, b, p]
                    acc[p] = 0.0
                for k in range(band.shape[1]):
                    for i in range(n_p):
                        acc[i] += band[i, k] * mixed[start[i] + k]
                for i in range(n_p):
                    moved[c, to, d, b, i] = acc[i]


@dataclass(frozen=True)
class _BandedWalk:
    """A walk's matrix (P, P) (row: to, column: from) that is zero beyond a band about its diagonal,
    stored by rows: row i's entries at columns start[i] … start[i] + W − 1 are band[i] (W,), the
    matrix's zeros within them included (:meth:`TyreMonitor._kernel`)."""

    start: np.ndarray  # (P,) int64
    band: np.ndarray  # (P, W)

    @classmethod
    def of(cls, matrix: np.ndarray) -> _BandedWalk:
        """The banded storage of a square `matrix` with at least one nonzero per row."""
        n_p = matrix.shape[0]
        nonzero = matrix != 0.0
        first = np.argmax(nonzero, axis=1)
        last = n_p - 1 - np.argmax(nonzero[:, ::-1], axis=1)
        width = int(np.max(last - first)) + 1
        start = np.clip(first, 0, n_p - width).astype(np.int64)
        return cls(start, matrix[np.arange(n_p)[:, None], start[:, None] + np.arange(width)])

    def toarray(self) -> np.ndarray:
        """The dense matrix (P, P)."""
        n_p = self.start.size
        out = np.zeros((n_p, n_p))
        out[np.arange(n_p)[:, None], self.start[:, None] + np.arange(self.band.shape[1])] = self.band
        return out


@cached_njit
def _redraw(moved, redraw, road, prior_db, prior_full):
    """The prediction's redraws, in place on the walked posterior `moved` (C, R, D, B, P), then each
    corner normalized: a share `road` of each regime's mass at each pressure takes the road's prior
    (damping, slope) `prior_db` (D, B), and a share `redraw` of each regime's mass the whole prior
    `prior_full` (C, D, B, P) (:meth:`TyreMonitor._predict`)."""
    n_c, n_r, n_d, n_b, n_p = moved.shape
    keep = (1.0 - road) * (1.0 - redraw)
    road_w = (1.0 - redraw) * road
    total_p = np.empty(n_p)
    for c in range(n_c):
        norm = 0.0
        for r in range(n_r):
            total_p[:] = 0.0
            for d in range(n_d):
                for b in range(n_b):
                    for p in range(n_p):
                        total_p[p] += moved[c, r, d, b, p]
            mass = 0.0
            for p in range(n_p):
                mass += total_p[p]
            for d in range(n_d):
                for b in range(n_b):
                    w_db = road_w * prior_db[d, b]
                    for p in range(n_p):
                        x = (moved[c, r, d, b, p] * keep + w_db * total_p[p]
                             + redraw * mass * prior_full[c, d, b, p])
                        moved[c, r, d, b, p] = x
                        norm += x
        inv = 1.0 / norm
        for r in range(n_r):
            for d in range(n_d):
                for b in range(n_b):
                    for p in range(n_p):
                        moved[c, r, d, b, p] *= inv


_EXP_ZERO = -746.0
"""Below this, math.exp gives exactly 0.0 (the smallest subnormal is e^−744.4): not taken."""


@cached_njit
def _bayes(post, rows, fine):
    """Bayes' rule in place: corner rows[u]'s posterior `post` (C, R, D, B, P) times exp(fine[u]) (U, D, B, P)
    (the window's weighted log-likelihood on the 1 kPa grid, shifted by its maximum), normalized; a
    corner whose product has no finite positive mass keeps its posterior (:meth:`TyreMonitor._correct`).
    `fine` may be (U, 1, 1, P): the same likelihood for every (damping, slope), each exponential taken
    once (the force closure's, :meth:`TyreMonitor._correct_closure`)."""
    n_r, n_d, n_b, n_p = post.shape[1:]
    f_d, f_b = fine.shape[1], fine.shape[2]
    like = np.empty((f_d, f_b, n_p))
    for u in range(rows.size):
        c = rows[u]
        top = -np.inf
        for d in range(f_d):
            for b in range(f_b):
                for p in range(n_p):
                    top = max(top, fine[u, d, b, p])
        for d in range(f_d):
            for b in range(f_b):
                for p in range(n_p):
                    x = fine[u, d, b, p] - top
                    like[d, b, p] = math.exp(x) if x > _EXP_ZERO else 0.0
        total = 0.0
        for d in range(n_d):
            for b in range(n_b):
                for p in range(n_p):
                    x = like[d % f_d, b % f_b, p]
                    for r in range(n_r):
                        total += post[c, r, d, b, p] * x
        if not (total > 0.0 and math.isfinite(total)):
            continue
        inv = 1.0 / total
        for r in range(n_r):
            for d in range(n_d):
                for b in range(n_b):
                    for p in range(n_p):
                        post[c, r, d, b, p] = post[c, r, d, b, p] * like[d % f_d, b % f_b, p] * inv


@dataclass
class _Fit:
    """The filter's posterior moments per corner (C of them), from :meth:`TyreMonitor._moments`."""

    p_mean: np.ndarray  # (C,) kPa
    p_var: np.ndarray  # (C,) kPa²
    p_tails: np.ndarray  # (C, 2) kPa: the pressure's TAIL_LEVELS quantiles
    p_marg: np.ndarray  # (C, P) the pressure's marginal on the 1 kPa grid (summing to 1 up to rounding)
    w_mean: np.ndarray  # (C,) waviness
    w_var: np.ndarray  # (C,)
    changing: np.ndarray  # (C,) probability of the changing regime
    mode: np.ndarray  # (C, 2) int: the likeliest (damping, slope)


def _overlap_weight(hop: int, window: int) -> float:
    """Weight of a window's log-likelihood among windows of `window` samples sliding by `hop`: Welch
    (1967), rectangular windows overlapping by a share r_j = 1 − j·hop/window have periodograms
    correlated by r_j², so the windows' summed score has the variance of 1 + 2 Σ_j r_j² independent
    ones per window; the inverse makes the posterior's curvature the information the data hold (2/3
    for windows overlapping by half, 1 for windows that do not overlap)."""
    overlap = 1.0 - np.arange(1, window // hop) * hop / window
    return 1.0 / (1.0 + 2.0 * float(np.sum(overlap**2)))


@dataclass
class _State:
    """Everything the monitor remembers: bounded, fixed-size arrays."""

    post: np.ndarray  # (C, R, D, B, P): the filter's posterior on regime × damping × slope × 1 kPa grid
    fit: _Fit | None
    buffer_t: np.ndarray  # the last window's samples, then those not yet in a window
    buffer_v: np.ndarray
    buffer_s: np.ndarray
    buffer_u: np.ndarray
    blocks: np.ndarray  # (segment/shortest update, C) status of the window's update blocks, newest last
    block_len: np.ndarray  # (segment/shortest update,) their samples (0: none yet)
    in_window: int = 0  # samples at the buffer's start that belong to the last window
    changing: bool = False  # a tyre's pressure may be changing: the next update after change_update_s
    last_t: float = math.nan  # time of the last sample received
    last_segment_t: float = math.nan  # time of the last finished segment
    level: float = math.nan  # the newest window's road level, m³
    counts: dict = field(default_factory=dict)
    coh_ab: np.ndarray | None = None  # (F,) the coherence's estimating equation: Σ a b, decaying
    coh_bb: np.ndarray | None = None  # (F,) Σ b², decaying
    coherence: np.ndarray | None = None  # (F,) the tracks' coherence per band in use
    coh_prior: np.ndarray | None = None  # (F,) the prior's weight in Σb² at the last window's speed
    closure_info: np.ndarray | None = None  # (C,) the force closure's precision taken in, 1/kPa², decaying


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
        (front, rear) column pairs of corners on one track: the two estimates are fused through the
        front→rear preview (:mod:`suvtwin.estimators.preview`). Needs `wheelbase_m`.
    wheelbase_m : float, optional
        Distance from the front to the rear axle, m.
    preview_config : PreviewConfig, optional
        Settings of each track's preview (default: the preview's defaults with this monitor's
        ``sigma_accel``: one noise figure for the accelerometers).
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
        closure_config: ClosureConfig | None = None,
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
        # while a pressure may be changing: updates every change_update_s (update_s without one)
        fast = self.hop if cfg.change_update_s is None else int(round(cfg.change_update_s / dt))
        self.hop_change = min(fast, self.hop)
        if self.hop_change < 32:
            raise InputError(
                f"change_update_s = {cfg.change_update_s} s holds fewer than 32 samples at dt = {dt} s")
        freq = np.fft.rfftfreq(self.window, dt)
        # thresholds on Fourier frequencies taken with a relative tolerance _FREQ_TOL: a frequency at a
        # threshold (1 Hz is the 8th of an 8 s window) must not fall either side of it by a change of
        # dt in the 12th digit (it did: the estimates moved by up to 7 kPa)
        self._f_index = np.flatnonzero((freq > 0) & (freq <= cfg.max_frequency_hz * (1.0 + _FREQ_TOL)))
        fine = freq[self._f_index]
        # a whole window's ramp n − n̄ and its transform at the kept frequencies (_cross_spectra)
        self._ramp = np.arange(self.window, dtype=float) - 0.5 * (self.window - 1)
        self._ramp_norm = float(self._ramp @ self._ramp)
        self._ramp_dft = self.window / (np.exp(-2j * np.pi * self._f_index / self.window) - 1.0)
        # bands: single frequencies below merge_above_hz, groups of ~merge_width_hz above
        per_group = max(int(round(cfg.merge_width_hz * cfg.segment_s)), 1)
        above = fine > cfg.merge_above_hz * (1.0 + _FREQ_TOL)
        group = np.where(~above, np.arange(fine.size), 0)
        first_above = int(np.argmax(above)) if np.any(above) else fine.size
        n_single = first_above
        group[above] = n_single + (np.arange(fine.size - first_above) // per_group)
        # reduceat offsets, int64 as the compiled gains take them
        self._group_start = np.flatnonzero(np.r_[True, np.diff(group) != 0]).astype(np.int64)
        self._group_size = np.diff(np.r_[self._group_start, fine.size]).astype(float)
        self.freq = np.add.reduceat(fine, self._group_start) / self._group_size
        self._silent_bins = self.freq <= cfg.silent_band_hz * (1.0 + _FREQ_TOL)  # the body's band (_silent)
        if self.freq.size < 4:
            raise InputError("the frequency band holds fewer than 4 Fourier frequencies; lengthen segment_s")
        self.noise = 2.0 * cfg.sigma_accel**2 * dt  # one-sided white-noise PSD, (m/s²)²/Hz
        # each window's log-likelihood weighted for its overlap with the others (Welch 1967; 1/2
        # would count each sample once), at either interval between updates
        self._window_weight = {hop: _overlap_weight(hop, self.window) for hop in (self.hop, self.hop_change)}
        # the pressure grids (kPa): coarse for the windows' likelihoods, 1 kPa for the posteriors
        p_lo, p_hi = cfg.pressure_range_kpa
        n_coarse = max(int(math.ceil((p_hi - p_lo) / cfg.grid_step_kpa - 1e-9)) + 1, 4)
        self._p_coarse = np.linspace(p_lo, p_hi, n_coarse)
        self._p_grid = np.linspace(p_lo, p_hi, int(round(p_hi - p_lo)) + 1)
        self._p_edges = np.r_[self._p_grid[0] - 0.5, self._p_grid + 0.5]  # the 1 kPa cells' edges (_moments)
        # a cubic spline through the coarse grid, as a matrix (fine, coarse): linear in the values
        self._to_fine = CubicSpline(self._p_coarse, np.eye(n_coarse))(self._p_grid)
        # waviness grid: w = 2 (the spike) and the slab's points, with their prior log weights
        w_lo, w_hi = cfg.waviness_range
        slab = np.linspace(w_lo, w_hi, cfg.waviness_points) if w_hi > w_lo else np.empty(0)
        iso = cfg.waviness_iso_weight if slab.size else 1.0
        self.waviness_grid = np.concatenate([[2.0], slab]) if iso > 0 else slab
        slab_weight = math.log1p(-iso) - math.log(slab.size) if slab.size else 0.0
        spike = [math.log(iso)] if iso > 0 else []
        self._w_logprior = np.concatenate([spike, np.full(slab.size, slab_weight)])
        # the prior on p on the fine grid: Gaussian (by default flat), cut to the range
        self._prior = np.array(
            [t.p0 / 1e3 if cfg.prior_pressure_kpa is None else cfg.prior_pressure_kpa for t in self.tires]
        )
        self._prior_var = cfg.prior_sigma_kpa**2
        log_prior = -0.5 * (self._p_grid[None, :] - self._prior[:, None]) ** 2 / self._prior_var
        self._log_prior = log_prior - logsumexp(log_prior, axis=1)[:, None]  # (C, P)
        n_d = cfg.damping_points
        self._fine = fine
        # each corner's tyre stiffness on the coarse pressure grid (eq. 3–4), N/m
        self._kt_coarse = np.array([stiffness_from_pressure(self._p_coarse * 1e3, **asdict(t))
                                    for t in self.tires])  # fmt: skip
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
        in_travel = self.freq >= cfg.travel_min_hz * (1.0 - _FREQ_TOL)
        self._travel_weight = np.where(in_travel, self._group_size / (cfg.segment_s * omega2), 0.0)
        self._travel_x_weight = self._travel_weight / omega2  # /(2πf)² once more: travel
        self._band_df = self._travel_weight * omega2  # Σ S Δf over the same band
        self._slot_of: dict[tuple[int, int], int] = {}
        self._slot_used = np.zeros(0, dtype=np.int64)
        self._n_updates = 0
        self._gain = np.empty((n_c, n_d, self._p_coarse.size, self.freq.size))
        self._u11 = np.empty((n_c, n_d, 1, self.freq.size))
        self._u22 = np.empty_like(self._u11)
        self._u12 = np.empty(self._u11.shape, dtype=complex)
        self._distortion = cfg.damper_distortion and any(
            qc.suspension is not None and qc.suspension.compression_low != qc.suspension.rebound_low
            for qc in self.models
        )
        # per slot, the damper's even part's transfer to the signal direction (_damper_distortion)
        self._along = np.zeros(self._gain.shape)
        self._per_window_gain = self._distortion or any(
            qc.full_car is not None or qc.envelope_half_length > 0 for qc in self.models
        )
        # corners placed in a full car: the gain's speed-free parts on the fine frequencies
        self._car_a = self._car_b = None
        self._car_a1 = self._car_b1 = None
        if any(qc.full_car is not None for qc in self.models):
            self._car_a = np.zeros((n_c, n_d, self._p_coarse.size, fine.size))
            self._car_b = np.zeros(self._car_a.shape, dtype=complex)
            # the tracks' cross term per unit coherence (full_car.projected_cross_terms)
            self._car_a1 = np.zeros(self._car_a.shape)
            self._car_b1 = np.zeros(self._car_a.shape, dtype=complex)
        for c in range(n_c):
            self._slot(c, 0)
        self._nonlinear = any(qc.suspension is not None for qc in self.models)
        # per corner, what _tables_for reads of its model every update: the spring rate (N/m), whether it
        # has a suspension law, the masses (kg), the tyre's static load (N: the car's weight shared by
        # its centre of gravity, else (m_s + m_us) g) and the stops' clearances (m; inf without a law)
        self._corner_rate = np.array([qc.spring_rate for qc in self.models], dtype=float)
        self._corner_has_law = np.array([qc.suspension is not None for qc in self.models], dtype=bool)
        self._corner_sprung = np.array([qc.sprung_mass for qc in self.models], dtype=float)
        self._corner_unsprung = np.array([qc.unsprung_mass for qc in self.models], dtype=float)
        self._corner_static_load = np.array(
            [(qc.sprung_mass + qc.unsprung_mass) * _GRAVITY if qc.static_load is None else qc.static_load
             for qc in self.models], dtype=float)  # fmt: skip
        self._corner_bump = np.array([qc.suspension.bump_clearance if qc.suspension else np.inf
                                      for qc in self.models], dtype=float)  # fmt: skip
        self._corner_rebound = np.array([qc.suspension.rebound_clearance if qc.suspension else np.inf
                                         for qc in self.models], dtype=float)  # fmt: skip
        self.tracks = tuple((int(f), int(r)) for f, r in tracks)
        used = [c for pair in self.tracks for c in pair]
        if self.tracks and (wheelbase_m is None or any(not 0 <= c < n_c for c in used)
                            or len(set(used)) != len(used)):  # fmt: skip
            raise InputError(
                f"tracks must be (front, rear) pairs of distinct corner indices 0–{n_c - 1}, with wheelbase_m"
            )
        self._previews = [
            PreviewTrack(self.models[f], self.models[r], self.tires[f], self.tires[r], dt, float(wheelbase_m),
                         preview_config or PreviewConfig(sigma_accel=cfg.sigma_accel))
            for f, r in self.tracks
        ]  # fmt: skip
        self._laws = np.array([[t.kt0, t.p0, t.pfz1] for t in self.tires]).T  # (3, C): eq. 3–4 per corner
        self._closure, self._closure_weights = self._new_closure(wheelbase_m, closure_config)
        # the prior of (damping, slope): uniform × spike and slab, normalized (D, B)
        prior_db = np.exp(self._w_logprior)[None, :] * np.ones((n_d, 1))
        self._prior_db = prior_db / prior_db.sum()
        # the prior of (damping, slope, pressure), the redraws' target (C, D, B, P)
        self._prior_full = np.exp(self._log_prior)[:, None, None, :] * self._prior_db[None, :, :, None]
        # the tracks' coherence: estimated from the two axles' wheels where one full car holds all four
        # corners (_update_coherence), else fixed (track_coherence; None there: 0)
        self._coherence_car = self._axles = None
        cars = {id(qc.full_car): qc.full_car for qc in self.models if qc.full_car is not None}
        if len(cars) == 1:
            car = next(iter(cars.values()))
            column = {qc.corner: c for c, qc in enumerate(self.models) if qc.full_car is car}
            if set(column) == {0, 1, 2, 3}:
                self._coherence_car = car
                self._axles = np.array([column[0], column[1], column[2], column[3]])  # fl, fr, rl, rr
                # full_car.axle_coherence_terms' speed-free parts on the bands' frequencies
                self._coherence_x, self._coherence_y = axle_coherence_parts(self.freq, car)
        self._coherence_fixed = 0.0 if cfg.track_coherence is None else float(cfg.track_coherence)
        self._estimate_coherence = cfg.track_coherence is None and self._coherence_car is not None
        # each band's coherence pooled from the bands within _COHERENCE_POOL_OCTAVES of it, by their bins
        octaves = np.abs(np.log2(self.freq[:, None] / self.freq[None, :]))
        self._coherence_pool = np.where(octaves <= _COHERENCE_POOL_OCTAVES, self._group_size[None, :], 0.0)
        self._kernels: dict[float, tuple] = {}
        self.reset()

    # ------------------------------------------------------------------ gain tables
    def _fill_slot(self, slot: int, c: int, step: int, lift: int) -> None:
        """Gain tables of corner c with its suspension rate times (1 + rate_step)^step and its tyre's
        stiffness and damping times the contact share (1 + rate_step)^−lift, in `slot`.

        |h|²/N per damping, coarse-grid pressure and band (the band's mean gain), and the signal
        direction's terms u^H S u = |u1|² S11 + |u2|² S22 + 2 Re(conj(u1) u2 S12)."""
        qc = self.models[c]
        rate = qc.spring_rate * (1.0 + self.config.rate_step) ** step
        contact = (1.0 + self.config.rate_step) ** -lift
        kt_inflated = self._kt_coarse[c]
        kt = contact * kt_inflated
        if qc.full_car is not None:  # every damping's responses at once (one inversion)
            responses = wheel_responses(self._fine, qc.full_car, qc.corner, kt_inflated, spring_rate=rate,
                                        damping=np.asarray(self.dampings[c], dtype=float),
                                        tire_scale=contact)  # fmt: skip
        for d, cd in enumerate(self.dampings[c]):
            model = replace(qc, damping=float(cd), spring_rate=rate, tire_damping=contact * qc.tire_damping)
            if qc.full_car is None:
                g = signal_gain(self._fine[None, :], kt[:, None], model) / self.noise
                self._gain[slot, d] = np.add.reduceat(g, self._group_start, axis=1) / self._group_size
            else:  # the full car: the speed-free parts, the speed added per window (_window_grid)
                u = signal_direction(self._fine, model)
                a_sq, cross, a1, b1 = projected_gains(responses[d], *u)
                self._car_a[slot, d], self._car_b[slot, d] = a_sq / self.noise, cross / self.noise
                self._car_a1[slot, d], self._car_b1[slot, d] = a1 / self.noise, b1 / self.noise
            u1, u2 = signal_direction(self.freq, model)
            self._u11[slot, d, 0] = np.abs(u1) ** 2 / self.noise
            self._u22[slot, d, 0] = np.abs(u2) ** 2 / self.noise
            self._u12[slot, d, 0] = 2.0 * np.conj(u1) * u2 / self.noise
            if self._distortion and qc.suspension is not None:
                # the damper's even part: a unit force pair (up on the body, down on the wheel)
                # carried to the two accelerations by the heave quarter car at each grid pressure,
                # projected on the signal direction, over the noise (_damper_distortion)
                s = 2j * np.pi * self.freq
                susp = rate + cd * s
                a11 = qc.sprung_mass * s**2 + susp
                a22 = qc.unsprung_mass * s**2 + susp + kt[:, None] + contact * qc.tire_damping * s  # (G, F)
                det = a11 * a22 - susp**2
                h_s, h_u = s**2 * (a22 - susp) / det, s**2 * (susp - a11) / det
                self._along[slot, d] = np.abs(np.conj(u1) * h_s + np.conj(u2) * h_u) ** 2 / self.noise

    def _slot(self, c: int, step: int, lift: int = 0) -> int:
        """Index of the gain tables of corner c at rate step `step` and contact step `lift`, made (or
        recycled: the least recently used slot not used in this update) when missing."""
        key = (c, step, lift)
        slot = self._slot_of.get(key)
        if slot is None:
            n = self._slot_used.size
            idle = np.flatnonzero(self._slot_used[len(self.models):] < self._n_updates) + len(self.models)
            if n < self.config.table_slots or idle.size == 0:
                slot = n  # grow, doubling (each growth copies the tables made: 1.1 MB each with the full car)
                grow = lambda a: np.concatenate([a, np.empty((max(8, a.shape[0]),) + a.shape[1:], a.dtype)])  # noqa: E731
                if n >= self._gain.shape[0]:
                    self._gain = grow(self._gain)
                    self._u11, self._u22, self._u12 = grow(self._u11), grow(self._u22), grow(self._u12)
                    self._along = grow(self._along)
                    if self._car_a is not None:
                        self._car_a, self._car_b = grow(self._car_a), grow(self._car_b)
                        self._car_a1, self._car_b1 = grow(self._car_a1), grow(self._car_b1)
                self._slot_used = np.append(self._slot_used, self._n_updates)
            else:
                slot = int(idle[np.argmin(self._slot_used[idle])])
                del self._slot_of[next(k for k, v in self._slot_of.items() if v == slot)]
            self._fill_slot(slot, c, step, lift)
            self._slot_of[key] = slot
        self._slot_used[slot] = self._n_updates
        return slot

    def _tables_for(self, corners: np.ndarray, spec: np.ndarray):
        """Gain-table slots and their blend weights for spectra `spec` (U, F, 3) of corners `corners`
        (U,): two (U, 4) arrays (:meth:`_blend`), then the share of time the linearization's Gaussian
        travel spends on a stop or the wheel off the ground (0 for corners without a suspension
        law), the suspension rate (N/m) and the tyre's contact share: three (U,) arrays.

        A corner whose model has a suspension law is analysed at its equivalent rate
        (:func:`suvtwin.suspension_law.equivalent_spring_rate`) at the travel's and travel
        velocity's standard deviations, integrated from the spectrum of the relative acceleration
        S11 + S22 − 2 Re S12 (less the two sensors' noise) above ``travel_min_hz``, and at its
        tyre's equivalent stiffness and damping: the tyre pushes only while in contact, so its
        statistically linearized rate is k_t·P(contact), with the dynamic wheel load
        −(m_s a_s + m_us a_us) Gaussian of the std its spectrum gives and the tyre's static load W
        (the model's ``static_load``: the car's weight shared by its centre of gravity, loads
        included; (m_s + m_us)·g where not given): P(contact) = Φ(W/σ_F). Tables are kept on a
        lattice of rate steps and contact steps (``rate_step``, the steps in log rate and log
        contact); the window's tables are the (up to) four lattice points around its (rate,
        contact) blended bilinearly (:func:`_lattice`: within a quarter step of a point, the point
        alone), so the likelihood is continuous in the linearization (rounded to the nearest
        point, it jumped where the rate crossed a step's edge: by 6 % of its change from one grid
        pressure to the next in the test). The others get their model's tables (weight 1 on the
        first)."""
        corners = np.asarray(corners)
        slots = np.repeat(corners[:, None], 4, axis=1)
        weights = np.zeros(slots.shape)
        weights[:, 0] = 1.0
        share = np.zeros(corners.shape)
        rate = self._corner_rate[corners]
        touch = np.ones(corners.shape)
        if not self._nonlinear:
            return slots, weights, share, rate, touch
        has_law = self._corner_has_law[corners]
        if not has_law.any():
            return slots, weights, share, rate, touch
        rel = spec[..., 0].real + spec[..., 1].real - 2.0 * spec[..., 2].real  # S of a_s − a_u
        rel = np.maximum(rel - 2.0 * self.noise, 0.0)
        var_v = rel @ self._travel_weight
        var_x = rel @ self._travel_x_weight
        log_step = math.log1p(self.config.rate_step)
        # every corner at once (the corners' masses, travels and clearances as arrays), one
        # equivalent-rate call per suspension law
        at = [self.models[c] for c in corners]
        ms, mu = self._corner_sprung[corners][:, None], self._corner_unsprung[corners][:, None]
        load = ms**2 * spec[..., 0].real + mu**2 * spec[..., 1].real + 2.0 * ms * mu * spec[..., 2].real
        var_f = np.maximum(load - (ms**2 + mu**2) * self.noise, 0.0) @ self._band_df
        weight = self._corner_static_load[corners]
        contact = ndtr(weight / np.sqrt(np.maximum(var_f, 1e-12)))
        sd = np.sqrt(var_x)
        mean, k_eq = np.zeros(corners.size), rate.copy()
        for law in {qc.suspension for qc in at if qc.suspension is not None}:
            same = [i for i, qc in enumerate(at) if qc.suspension == law]
            static = np.array([at[i].static_travel for i in same])
            mean[same], k_eq[same] = equivalent_spring_rate(law, static, sd[same], np.sqrt(var_v[same]))
        steps, step_w = _lattice(np.log(np.maximum(k_eq / rate, 1e-3)) / log_step)
        lifts, lift_w = _lattice(-np.log(np.maximum(contact, 0.05)) / log_step)
        bump, rebound = self._corner_bump[corners], self._corner_rebound[corners]
        stops = ndtr((mean - bump) / np.maximum(sd, 1e-9)) + ndtr((-mean - rebound) / np.maximum(sd, 1e-9))
        for i in np.flatnonzero(has_law):
            for k, (a, b) in enumerate(((0, 0), (1, 0), (0, 1), (1, 1))):
                w = step_w[i, a] * lift_w[i, b]
                weights[i, k] = w
                if w > 0.0:
                    slots[i, k] = self._slot(int(corners[i]), int(steps[i, a]), int(lifts[i, b]))
            slots[i, weights[i] == 0.0] = slots[i, np.argmax(weights[i])]
        share = np.where(has_law, stops + (1.0 - contact), share)
        rate = np.where(has_law, k_eq, rate)
        touch = np.where(has_law, contact, touch)
        return slots, weights, share, rate, touch

    def _blend(self, table: np.ndarray, slots: np.ndarray, weights: np.ndarray) -> np.ndarray:
        """Σ_k weights[:, k] table[slots[:, k]]: the rows' tables blended, (R, …) from slots and
        weights (R, K) (zero weights skipped)."""
        out = np.empty((slots.shape[0],) + table.shape[1:], dtype=table.dtype)
        _blend_rows(table.reshape(table.shape[0], -1), np.ascontiguousarray(slots, dtype=np.int64),
                    np.ascontiguousarray(weights, dtype=float), out.reshape(slots.shape[0], -1))  # fmt: skip
        return out

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Forget everything (a new drive with unknown pressures)."""
        for track in getattr(self, "_previews", []):
            track.reset()
        if getattr(self, "_closure", None) is not None:
            self._closure.reset()
        n_c = len(self.models)
        # the prior: steady, (damping, slope) and p independent
        prior_p = np.exp(self._log_prior)  # (C, P)
        post = np.zeros((n_c, 2) + self._prior_db.shape + (self._p_grid.size,))
        post[:, 0] = self._prior_db[None, :, :, None] * prior_p[:, None, None, :]
        self._state = _State(
            post=post,
            fit=None,
            buffer_t=np.empty(0),
            buffer_v=np.empty(0),
            buffer_s=np.empty((0, n_c)),
            buffer_u=np.empty((0, n_c)),
            blocks=np.full((self.window // self.hop_change, n_c), _GAP, dtype=np.int8),
            block_len=np.zeros(self.window // self.hop_change, dtype=np.int64),
            counts={
                "segments": 0, **{r: np.zeros(n_c, dtype=int) for r in SKIP_REASONS},
                "changes": np.zeros(n_c, dtype=int),
                "preview_rejected": np.zeros(n_c, dtype=int),
                "despiked": np.zeros(n_c, dtype=int),
                "closure_windows": np.zeros(n_c, dtype=int),
                "closure_skipped": np.zeros(n_c, dtype=int),
                "closure_short_windows": np.zeros(n_c, dtype=int),
            },
            coh_ab=np.zeros(self.freq.size),
            coh_bb=np.zeros(self.freq.size),
            coherence=np.full(self.freq.size, self._coherence_fixed),
            coh_prior=np.zeros(self.freq.size),
            closure_info=np.zeros(n_c),
        )  # fmt: skip
        self._state.fit = self._moments()

    @property
    def closure_config(self) -> ClosureConfig | None:
        """The force closure's settings where it runs (:meth:`_correct_closure`), else None."""
        return None if self._closure is None else self._closure.config

    @property
    def state_nbytes(self) -> int:
        """Size of the state the monitor carries between updates, bytes (bounded: the posterior grid,
        the last window's samples and the previews' statistics)."""
        s = self._state
        arrays = [s.post, s.buffer_t, s.buffer_v, s.buffer_s, s.buffer_u, s.blocks, s.block_len, s.coh_ab,
                  s.coh_bb, s.coherence, s.coh_prior]  # fmt: skip
        return int(sum(a.nbytes for a in arrays)) + sum(t.state_nbytes for t in self._previews)

    @property
    def gain_tables_nbytes(self) -> int:
        """Size of the gain tables made so far, bytes: a cache beside the state (at most ``table_slots``
        tables besides each corner's own, 1.1 MB each with the full car; remade when dropped)."""
        arrays = [self._gain, self._u11, self._u22, self._u12, self._along, self._car_a, self._car_b,
                  self._car_a1, self._car_b1]  # fmt: skip
        made = self._slot_used.size  # the arrays grow by doubling: room beyond the slots made not counted
        return int(sum(a[:made].nbytes for a in arrays if a is not None))

    @property
    def prior_pa(self) -> np.ndarray:
        """Each corner's prior mean pressure on the monitor's grid (the Gaussian cut to its range), Pa."""
        w = np.exp(self._log_prior)
        return 1e3 * (w @ self._p_grid)

    @property
    def prior_sigma_pa(self) -> np.ndarray:
        """Each corner's prior σ of the pressure on the monitor's grid, Pa (C,)."""
        w = np.exp(self._log_prior)
        mean = w @ self._p_grid
        return 1e3 * np.sqrt(np.maximum(w @ self._p_grid**2 - mean**2, 0.0))

    @property
    def counts(self) -> dict:
        """Segments seen, and per corner how many were used or skipped, by reason; changes (updates at
        which the probability of a changing pressure rose through 0.5) and despiked samples."""
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
        """Add samples; each time `update_s` of new ones are in (`change_update_s` while a pressure
        may be changing), slide the window and update."""
        s = self._state
        s.buffer_t = np.concatenate([s.buffer_t, t])
        s.buffer_v = np.concatenate([s.buffer_v, v])
        s.buffer_s = np.concatenate([s.buffer_s, a_s])
        s.buffer_u = np.concatenate([s.buffer_u, a_u])
        while s.buffer_t.size - s.in_window >= (hop := self.hop_change if s.changing else self.hop):
            end = s.in_window + hop
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
        n_c = len(self.models)
        z = np.empty((0, n_c))
        return MonitorUpdate(
            t_s=np.empty(0), pressure_pa=z, pressure_sigma_pa=z.copy(), pressure_lower_pa=z.copy(),
            pressure_upper_pa=z.copy(), stiffness=z.copy(),
            stiffness_sigma=z.copy(), observable=np.empty((0, n_c), dtype=bool),
            status=np.empty((0, n_c), dtype=np.int8), road_level=np.empty(0), waviness=np.empty(0),
            speed_mps=np.empty(0), change_probability=z.copy(), spring_rate=z.copy(), tyre_contact=z.copy(),
            track_coherence=np.empty(0),
        )  # fmt: skip

    # ------------------------------------------------------------------ one segment
    def _check_block(self, v: np.ndarray, a_s: np.ndarray, a_u: np.ndarray) -> np.ndarray:
        """Status per corner (index into SKIP_REASONS) of one update block's accelerometer data."""
        cfg = self.config
        n_c = len(self.models)
        status = np.zeros(n_c, dtype=np.int8)
        # per row (sprung rows, then unsprung rows): extremes, missing values, runs at an extreme
        top, bottom, finite, clipped = _block_extremes(a_s, a_u)
        implausible = (np.maximum(top, -bottom) > cfg.max_accel_mps2) | (top == bottom)
        if cfg.accel_range_mps2 is not None:
            clipped |= np.maximum(top, -bottom) >= 0.999 * cfg.accel_range_mps2
        spiky, med, mad = _spiky(np.concatenate([a_s[::16].T, a_u[::16].T]), top, bottom, cfg.spike_z)
        spiky &= finite
        # isolated spikes (at most 0.2 % of the block) are replaced by the block's median, in the
        # stream's buffer itself (a_s, a_u are views of it), so the windows see clean data
        limit = max(1, int(0.002 * a_s.shape[0]))
        for r in np.flatnonzero(spiky):
            row = (a_s if r < n_c else a_u)[:, r % n_c]
            where = np.flatnonzero(np.abs(row - med[r]) > cfg.spike_z * max(mad[r], 1e-12))
            if where.size <= limit:
                row[where] = med[r]
                self._state.counts["despiked"][r % n_c] += where.size
                spiky[r] = False
        # each corner's first problem over its two rows (sprung c, unsprung n_c + c), in this order
        problems = [~(finite[:n_c] & finite[n_c:]), implausible[:n_c] | implausible[n_c:],
                    clipped[:n_c] | clipped[n_c:], spiky[:n_c] | spiky[n_c:]]  # fmt: skip
        status[:] = np.select(problems, [_GAP, _IMPLAUSIBLE, _CLIPPED, _SPIKE], _USED)
        if not np.all(np.isfinite(v)) or np.min(v) < 0.0:
            status[:] = _SPEED
        return status

    def _update_window(self, block, window) -> MonitorUpdate:
        """One update: check the new block, then use the window (the last `segment_s`) if it is sound."""
        cfg = self.config
        s = self._state
        n_c = len(self.models)
        t, v, a_s, a_u = window
        hop = block[0].size
        s.blocks = np.roll(s.blocks, -1, axis=0)
        s.blocks[-1] = self._check_block(block[1], block[2], block[3])
        s.block_len = np.roll(s.block_len, -1)
        s.block_len[-1] = hop
        # the newest blocks that together cover the window (an 8 s window after a 4 s update: the
        # 4 s block and the 8 s block before it, whose status holds for its half in the window)
        covered = np.cumsum(s.block_len[::-1])
        n_blocks = min(int(np.searchsorted(covered, t.size)) + 1, s.block_len.size)
        status = np.zeros(n_c, dtype=np.int8)
        for row in s.blocks[-n_blocks:]:  # the first problem of each corner's window, oldest first
            status = np.where(status == _USED, row, status)
        # a window whose only problem is a gap keeps its longest stretch of data between gaps, before or
        # after them, if at least a quarter window: `clean` [first, end) per corner (the whole window
        # where it has no gap). Until 2026-12-05 only the stretch after the last gap: with windows that
        # no longer overlap (8 s updates), a gap then lost the data before it in every window
        clean = np.zeros((n_c, 2), dtype=np.int64)
        clean[:, 1] = t.size
        recent = s.blocks[-n_blocks:]
        gap_only = np.all((recent == _USED) | (recent == _GAP), axis=0) & (status == _GAP)
        for c in np.flatnonzero(gap_only):
            bad = np.flatnonzero(~(np.isfinite(a_s[:, c]) & np.isfinite(a_u[:, c])))
            starts = np.r_[0, bad + 1]  # each stretch between gaps, and its length
            lengths = np.r_[bad, t.size] - starts
            k = int(np.argmax(lengths[::-1]))  # the longest; on a tie the latest
            k = lengths.size - 1 - k
            if lengths[k] >= self.window // 4:
                clean[c], status[c] = (starts[k], starts[k] + lengths[k]), _USED
        tail = clean[:, 1] - clean[:, 0]
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
        wheel_fft, have_fft = None, np.zeros(n_c, dtype=bool)  # the whole windows' wheel transforms
        s.last_segment_t = t_end
        changing_before = s.fit.changing > 0.5
        analysed_rate, analysed_touch = np.full(n_c, np.nan), np.full(n_c, np.nan)
        s.level = math.nan
        self._predict(elapsed)  # time passes: the pressures may drift or change, with or without data
        if np.any(used):
            # weights: overlapping windows' likelihoods tempered to their joint information
            # (_window_weight); a window of fewer samples (while the first fills, or the part after
            # a gap) is zero-padded and counts for the share of a window it holds
            w_c = self._window_weight[hop] * np.minimum(tail, t.size) / self.window
            whole = used & (tail == t.size)
            spec = np.zeros((n_c, 1, self.freq.size, 3), dtype=complex)
            if np.any(whole):
                transforms = self._transforms(np.stack([a_s[:, whole].T, a_u[:, whole].T]))
                spec[whole, 0] = self._cross_spectra(a_s[:, whole], a_u[:, whole], transforms)
                wheel_fft, have_fft = np.zeros((n_c, transforms.shape[-1]), dtype=complex), whole.copy()
                wheel_fft[whole] = transforms[1]
            for c in np.flatnonzero(used & ~whole):
                part = slice(clean[c, 0], clean[c, 1])
                spec[c, 0] = self._cross_spectra(a_s[part, c : c + 1], a_u[part, c : c + 1])[0]
            band_weight = self._band(np.array([speed]))[0][0]  # the window's band (F,), both checks'
            silent = used & self._silent(spec, band_weight)
            if np.any(silent):  # one sensor reads noise while the road moves the other: a sensor fault
                status[silent] = _SILENT
                s.counts["used"][silent] -= 1
                s.counts["silent"][silent] += 1
                used = used & ~silent
        if np.any(used):
            # each corner's gain tables at this window's travel, and their blend
            table = np.repeat(np.arange(n_c)[:, None], 4, axis=1)
            blend = np.zeros(table.shape)
            blend[:, 0] = 1.0
            table[used], blend[used], rough, rate_c, touch_c = self._tables_for(np.flatnonzero(used),
                                                                                spec[used, 0])  # fmt: skip
            analysed_rate[used], analysed_touch[used] = rate_c, touch_c
            share_c = np.zeros(n_c)  # time on a stop or off the ground, per corner (0 where unused)
            share_c[used] = rough
            rough_c = share_c > cfg.max_nonlinear_share
            # toward the limit the linearized model's error grows: the window's likelihood is
            # tempered, its weight falling linearly to 0 from nonlinear_taper_from to the limit
            span = cfg.max_nonlinear_share - cfg.nonlinear_taper_from
            if span > 0:
                w_c = w_c * np.clip((cfg.max_nonlinear_share - share_c) / span, 0.0, 1.0)
            if np.any(rough_c):  # no linear model holds: the window is not used for k_t
                status[rough_c] = _ROUGH
                s.counts["used"][rough_c] -= 1
                s.counts["rough"][rough_c] += 1
                used = used & ~rough_c
        # the preview gets the block where both of a track's corners passed every check, the rough
        # and low-speed ones too: there the ratio of the two wheels' responses leaves its model
        self._feed_previews(block, status, elapsed)
        self._update_coherence(wheel_fft, have_fft & used, t.size, speed, elapsed)
        if np.any(used):
            ll, lam = self._window_grid(spec, used, speed, table, blend)
            smooth = used & ((self._road_signal_z(spec, band_weight) < cfg.min_signal_z)
                             | _at_level_floor(ll, lam))  # fmt: skip
            if np.any(smooth):  # no road signal above the sensors' noise: nothing to read k_t from
                status[smooth] = _SMOOTH
                s.counts["used"][smooth] -= 1
                s.counts["smooth"][smooth] += 1
                used = used & ~smooth
        if np.any(used):
            self._correct(ll, np.where(used, w_c, 0.0), used)
            s.level = self._window_level(lam, used)
        self._correct_closure(block, s.blocks[-1], status, elapsed)
        s.fit = self._moments()
        changes = (s.fit.changing > 0.5) & ~changing_before
        s.counts["changes"] += changes
        for track, (f, r) in zip(self._previews, self.tracks, strict=True):
            if s.fit.changing[f] > 0.5 or s.fit.changing[r] > 0.5:
                track.reset()  # its ratio is changing: start it afresh
        s.closure_info[s.fit.changing > 0.5] = 0.0  # a changing tyre: the closure's floor starts afresh
        self._n_updates += 1
        s.changing = bool(np.any(s.fit.changing >= cfg.change_update_probability))
        return self._output(t_end, speed, status, analysed_rate, analysed_touch)

    def _feed_previews(self, block, status: np.ndarray, elapsed: float) -> None:
        """Forget and add the new block to each track's preview (NaN unless both corners' windows
        are used: `status` the update's per corner)."""
        if not self._previews:
            return
        _, v, a_s, a_u = block
        decay = math.exp(-elapsed / self.config.preview_memory_s)
        for track, (f, r) in zip(self._previews, self.tracks, strict=True):
            track.decay(decay)
            ok = status[f] == _USED and status[r] == _USED
            pick = (lambda x, c: x[:, c]) if ok else (lambda x, c: np.full(x.shape[0], np.nan))  # noqa: E731
            track.add(pick(a_u, f), pick(a_u, r), v, acc_s_front=pick(a_s, f), acc_s_rear=pick(a_s, r))

    def _update_coherence(self, wheel_fft: np.ndarray | None, ready: np.ndarray, n: int, speed: float,
                          elapsed: float) -> None:  # fmt: skip
        r"""The tracks' coherence γ per band from the two axles' wheels' transforms `wheel_fft` (C, F) of
        the window's `n` samples (:meth:`_transforms`), where all four corners are `ready` (C,) (whole
        windows, used) at `speed` (m/s); the sums decay over `elapsed` s first.

        Per band, the window's four wheels' summed periodograms less their noise, T̂, and the two
        axles' left–right cross periodograms (real part), Ĉ, with the linear full car's terms at the
        window's front→rear delay (:func:`suvtwin.estimators.full_car.axle_coherence_terms`, from its
        parts tabulated at start) give
        the estimating equation a = γ b, :math:`a = (\hat T C_0 - \hat C T_0)/s`,
        :math:`b = (\hat C T_1 - \hat T C_1)/s`, s = (T̂ + the noise) T_0: scale-free, and a
        window whose wheels read mostly noise counts for little (b → 0). The windows' Σab and Σb²
        decay with ``coherence_memory_s`` (the first window, while it fills, zero-padded and counted
        for its share); γ is their least-squares ratio pooled over the bands within half an octave
        (real roads' coherence changes slowly with wavelength), with a prior in Σb² per band
        (:data:`_COHERENCE_PRIOR` of a window at full signal, T̂ = S_v T_0 and Ĉ = S_v C_0, that
        read γ = 0), clipped to [0, 1]: a road's tracks are not anti-correlated, and on the MuJoCo
        SUV the estimate of independent tracks leans negative (−0.07 at 8–12 Hz, −0.04 at
        12–16 Hz, the mean over 16 ``constant`` runs: the SUV's wheels are coupled less at the
        wheel hop than the linear car's), which read the tyres 1–2 kPa low. Measured, with the
        effect on the pressures, in docs/monitor.md ("Roads whose two tracks are alike")."""
        s = self._state
        if not self._estimate_coherence:
            return
        decay = math.exp(-elapsed / self.config.coherence_memory_s)
        s.coh_ab *= decay
        s.coh_bb *= decay
        if wheel_fft is not None and np.all(ready[self._axles]) and np.isfinite(speed):
            X = wheel_fft[self._axles]  # fl, fr, rl, rr
            share = n / self.window  # the first window, while it fills, counts for its share
            k = 2.0 * self.dt / n
            fine = np.stack([np.sum(np.abs(X) ** 2, axis=0),
                             np.real(X[0] * np.conj(X[1]) + X[2] * np.conj(X[3]))]) * k  # fmt: skip
            auto, cross = np.add.reduceat(fine, self._group_start, axis=1) / self._group_size
            phase = np.exp(2j * np.pi * self.freq * self._coherence_car.wheelbase / speed)
            t0, t1, c0, c1 = self._coherence_x + np.real(self._coherence_y * phase)  # axle_coherence_terms
            signal = auto - 4.0 * self.noise
            scale = auto * t0
            a = (signal * c0 - cross * t0) / scale
            b = (cross * t1 - signal * c1) / scale
            s.coh_ab += share * a * b
            s.coh_bb += share * b * b
            # the prior: _COHERENCE_PRIOR windows at full signal (T̂ = S_v T_0, Ĉ = S_v C_0) that read γ = 0
            s.coh_prior = _COHERENCE_PRIOR * ((c0 * t1 - t0 * c1) / t0**2) ** 2
        if np.any(s.coh_bb > 0.0):
            ratio = (self._coherence_pool @ s.coh_ab) / (self._coherence_pool @ (s.coh_bb + s.coh_prior))
            s.coherence = np.clip(ratio, 0.0, 1.0)

    def _window_grid(self, spec: np.ndarray, used: np.ndarray, speed: float, table: np.ndarray,
                     blend: np.ndarray):  # fmt: skip
        """Log-likelihood (level integrated out) and the level's estimate of one window's spectra
        `spec` (C, 1, F, 3) on the grid, for the corners `used` with gain-table slots `table` (C, K)
        blended with weights `blend` (C, K) (each at its analysed suspension rate and tyre contact
        share, :meth:`_tables_for`): two (C, D, B, G) arrays (zero for the other corners);
        :func:`_window_loglik`. With the damper's even part (:meth:`_damper_distortion`, e) the
        noise beside the road's signal is N(1 + e), which depends on (d, p)."""
        n_c = len(self.models)
        proj = np.ascontiguousarray(self._project(spec[:, 0], table, blend))  # (C, D, F)
        # the damper's even part: known extra power beside the noise, N + D_f = N (1 + extra)
        extra = self._damper_distortion(spec[:, 0], used, table, blend) if self._distortion else None
        noise = np.empty((0, 0, 0, 0)) if extra is None else extra + 1.0
        weight, x, log_cv = self._band(np.array([speed]))
        weight = np.ascontiguousarray(weight[0])
        inside = np.flatnonzero(weight > 0)
        beta = 2.0 - self.waviness_grid
        base = np.exp(beta[:, None] * x[0][None, :] + log_cv[0])
        shape = (n_c, self.config.damping_points, beta.size, self._p_coarse.size)
        ll, lam = np.zeros(shape), np.zeros(shape)
        if inside.size == 0:
            return ll, lam
        rows = np.flatnonzero(used)
        if self._per_window_gain or np.any(blend[rows, 1:] > 0.0):  # per corner, at this window's speed
            gain = np.zeros((n_c,) + self._gain.shape[1:])
            plain = [c for c in rows if self.models[c].full_car is None]
            if plain:
                gain[plain] = self._blend(self._gain, table[plain], blend[plain])
            # corners in a full car: the gain at this window's front→rear delay (linear in the
            # tables, so blended after), all corners and slots of one wheelbase in one call
            by_wheelbase: dict[float, list[int]] = {}
            by_contact: dict[float, list[int]] = {}
            for c in rows:
                if self.models[c].full_car is not None:
                    by_wheelbase.setdefault(self.models[c].full_car.wheelbase, []).append(c)
                by_contact.setdefault(self.models[c].envelope_half_length, []).append(c)
            # with the tracks' cross term where they are coherent (γ per band)
            coherence = self._state.coherence
            coherent = (self._car_a1, self._car_b1, coherence) if np.any(coherence != 0.0) else None
            for wheelbase, same in by_wheelbase.items():
                blend_gain_at_delay(self._car_a, self._car_b, self._fine, wheelbase / speed,
                                    self._group_start, np.array(same), table[same], blend[same],
                                    gain, coherent)  # fmt: skip
            # the tyre's enveloping filters the road it reads: once per contact length
            for half, same in by_contact.items():
                if half > 0.0:
                    fine = envelope_power(self._fine / speed, half)
                    gain[same] *= np.add.reduceat(fine, self._group_start) / self._group_size
            slot = np.where(used, np.arange(n_c), -1).astype(np.int64)
        else:
            gain = self._gain
            slot = np.where(used, table[:, 0], -1).astype(np.int64)
        _window_loglik(proj, noise, weight, int(inside[0]), int(inside[-1]) + 1, base, gain, slot,
                       *_LEVEL_BOUNDS, ll, lam)  # fmt: skip
        return ll, lam

    def _damper_distortion(self, spec: np.ndarray, used: np.ndarray, table: np.ndarray, blend: np.ndarray):
        r"""Power of the damper's even part along the signal direction over the noise, e: (C, D, G, F).

        Per used corner with a suspension law: the suspension velocity's PSD from the window's
        relative acceleration (S11 + S22 − 2 Re S12 less the sensors' noise, not clipped per bin,
        /(2πf)², from ``travel_min_hz``), the even part's slope b on |v|
        (:func:`suvtwin.suspension_law.damper_even_slope`) and the rectified velocity's PSD
        (:func:`suvtwin.suspension_law.rectified_psd`) give the force pair's PSD :math:`b^2 S_{|v|}`
        (equal and opposite on body and wheel); the corner's heave quarter car (damping d of the
        grid, the suspension rate and tyre contact share of its gain-table slots `table` (C, K)
        blended by `blend` (C, K), the tyre at each grid pressure; tabulated with the slot,
        :meth:`_fill_slot`) carries it to the
        two accelerations, projected on the signal direction. The window's likelihood then has the
        noise N(1 + e) beside the road's signal (:meth:`_window_grid`)."""
        n_c = len(self.models)
        out = np.zeros((n_c, self.config.damping_points, self._p_coarse.size, self.freq.size))
        # less the noise but not clipped per bin: a clipped periodogram of noise is biased up
        rel = spec[..., 0].real + spec[..., 1].real - 2.0 * spec[..., 2].real - 2.0 * self.noise
        omega2 = (2.0 * np.pi * self.freq) ** 2
        vel = np.where(self._travel_weight > 0.0, rel / omega2, 0.0)  # (C, F): from travel_min_hz
        df = self._group_size / self.config.segment_s
        rows = [c for c in np.flatnonzero(used) if self.models[c].suspension is not None]
        if not rows:
            return None
        # lags within half the coarsest bin's period (bins above merge_above_hz are merged)
        s_abs = rectified_psd(self.freq, vel[rows], df, self.freq, max_lag_s=0.5 / float(df.max()))
        sigma_v = np.sqrt(np.maximum(rel @ self._travel_weight, 1e-12))  # the velocity's σ, m/s
        slope = np.empty(len(self.models))
        for law in {self.models[c].suspension for c in rows}:  # one call per damper law
            same = [c for c in rows if self.models[c].suspension == law]
            slope[same] = damper_even_slope(law, sigma_v[same])
        force = slope[rows, None] ** 2 * np.maximum(s_abs, 0.0)  # (rows, F): b² S_|v|
        out[rows] = force[:, None, None, :] * self._blend(self._along, table[rows], blend[rows])
        return out

    def _window_level(self, lam: np.ndarray, used: np.ndarray) -> float:
        """The window's road level Gd(n0), m³: each used corner's λ̂ at its likeliest (damping, slope)
        and the grid pressure nearest its estimate, averaged over the corners in log."""
        fit = self._state.fit
        values = []
        for c in np.flatnonzero(used):
            d, b = fit.mode[c]
            g = int(np.argmin(np.abs(self._p_coarse - fit.p_mean[c])))
            values.append(lam[c, d, b, g])
        return math.exp(float(np.mean(values)))

    # ------------------------------------------------------------------ the filter
    def _kernel(self, elapsed: float) -> tuple[np.ndarray, list, float, float]:
        r"""The transition over `elapsed` seconds: the regimes' Markov matrix (2, 2) (row: from,
        column: to; steady 0, changing 1; exact for a two-state chain with rates
        1/``change_every_s`` and 1/``change_lasts_s``), the random walk of each regime as a
        matrix on the 1 kPa grid (P, P) each (Gaussian of σ = q √elapsed, each column normalized
        within the range; a narrow one stored as a band, :class:`_BandedWalk`), the probability of a
        redraw from the prior and of a change of the road's (damping, slope). Cached per elapsed time."""
        key = round(float(elapsed), 6)
        hit = self._kernels.get(key)
        if hit is not None:
            return hit
        cfg = self.config
        a, b = 1.0 / cfg.change_every_s, 1.0 / cfg.change_lasts_s
        e = math.exp(-(a + b) * elapsed)
        markov = np.array([[(b + a * e) / (a + b), a * (1.0 - e) / (a + b)],
                           [b * (1.0 - e) / (a + b), (a + b * e) / (a + b)]])  # fmt: skip
        step = self._p_grid[:, None] - self._p_grid[None, :]  # (to, from)
        walks = []
        for q in (cfg.steady_drift_kpa, cfg.change_drift_kpa):
            sd = q * math.sqrt(max(elapsed, 0.0))
            if sd < 0.05:  # narrower than the grid can hold: no move
                walks.append(_BandedWalk.of(np.eye(self._p_grid.size)))
                continue
            # beyond 8.6 σ the Gaussian is below 1e-16 of its peak: dropped, so a narrow walk is a band
            k = np.where(np.abs(step) <= 8.6 * sd, np.exp(-0.5 * (step / sd) ** 2), 0.0)
            k /= k.sum(axis=0, keepdims=True)
            walks.append(_BandedWalk.of(k) if 8.6 * sd < 0.25 * self._p_grid.size else k)
        redraw = -math.expm1(-elapsed / cfg.redraw_every_s)
        road = -math.expm1(-elapsed / cfg.road_change_s)
        out = (markov, walks, redraw, road)
        if len(self._kernels) < 64:
            self._kernels[key] = out
        return out

    def _predict(self, elapsed: float) -> None:
        r"""The filter's prediction over `elapsed` seconds, exact on the grid: the regimes switch
        (Markov), each regime's pressure walks (its random walk), a redraw from the prior
        replaces a share of the mass, and each corner's (damping, slope) is redrawn from its prior
        with the road's change rate (the pressure kept)."""
        if elapsed <= 0.0:
            return
        markov, walks, redraw, road = self._kernel(elapsed)
        post = self._state.post  # (C, R, D, B, P)
        moved = np.empty_like(post)
        n_p = post.shape[-1]
        for to, walk in enumerate(walks):  # (to, from): a banded or dense product per regime
            if isinstance(walk, _BandedWalk):
                _mix_walk_banded(post, markov[0, to], markov[1, to], walk.start, walk.band, moved, to)
            else:
                mixed = markov[0, to] * post[:, 0] + markov[1, to] * post[:, 1]
                moved[:, to] = (mixed.reshape(-1, n_p) @ walk.T).reshape(mixed.shape)
        _redraw(moved, redraw, road, self._prior_db, self._prior_full)
        self._state.post = moved

    def _correct(self, ll: np.ndarray, weight: np.ndarray, used: np.ndarray) -> None:
        r"""Bayes' rule with one window: the posterior of each used corner times
        :math:`e^{w\,\ell(d, b, p)}`, ℓ the window's log-likelihood (its level integrated out)
        spline-interpolated from the coarse grid to 1 kPa, w the window's weight (each sample
        lies in segment/update windows: w = update/segment for a whole window)."""
        s = self._state
        rows = np.flatnonzero(used)
        if rows.size == 0:
            return
        fine = weight[rows, None, None, None] * (ll[rows] @ self._to_fine.T)  # (U, D, B, P)
        _bayes(s.post, rows.astype(np.int64), fine)

    def _new_closure(self, wheelbase_m: float | None, config: ClosureConfig | None):
        """The force closure's stream and each track's weights of J on the coarse pressure grid
        (:func:`~suvtwin.estimators.force_closure.closure_weights`), or (None, []) where it cannot
        run: off in the config, not two tracks, or a corner without its suspension law."""
        cfg = self.config
        if not (cfg.force_closure and len(self.tracks) == 2 and wheelbase_m is not None
                and all(qc.suspension is not None for qc in self.models)):  # fmt: skip
            return None, []
        parts = [
            CornerParts(unsprung_mass=qc.unsprung_mass, law=qc.suspension, anti_roll=qc.anti_roll,
                        static_travel=qc.static_travel, static_load=float(self._corner_static_load[c]))
            for c, qc in enumerate(self.models)
        ]  # fmt: skip
        stream = ClosureStream(parts, self.tracks, float(wheelbase_m), self.dt, config)
        # per track, its windows' weights and its short windows' (None where the stream reads none)
        weights = []
        for f, r in self.tracks:
            damping = 0.5 * (self.models[f].tire_damping + self.models[r].tire_damping)
            weights.append(tuple(
                stream.weights(f, r, self._kt_coarse[f], self._kt_coarse[r], tyre_damping=damping,
                               noise_sigma=cfg.sigma_accel, short=short)
                if not short or stream.m_short else None
                for short in (False, True)
            ))  # fmt: skip
        return stream, weights

    def _correct_closure(self, block, checks: np.ndarray, status: np.ndarray, elapsed: float) -> None:
        r"""Bayes' rule with the force closure's new windows (:class:`~.force_closure.ClosureStream`,
        fed the update's `block` where every corner's samples passed the block's `checks` (C,) and
        no corner's window was found ``silent`` (`status` (C,)): a disconnected accelerometer reads
        noise the closure would take for a wheel or body at rest; with it, the ``faults`` bench's
        disconnected sensor moved the pressures by 69 kPa RMS). A track one of whose corners found
        no road signal above the noise (``smooth``) takes none of its windows: on a flat road the
        0.5 s windows read the tyres 66–68 kPa and warned.

        Per track, J over the two tyres' coarse pressure grids from the windows' moments, scaled as a
        quasi-likelihood: :math:`\ell = -(J - J_{min}) / (2 κ s)`, s = J_min over its degrees of freedom
        (2 per frequency and window over 1.5, the Hann window's bins' overlap: the model's error, not
        the sensors' noise, sets the residual's level), κ ``closure_tempering`` (the windows' shared
        error, :class:`MonitorConfig`). Each tyre's posterior is
        then multiplied by exp(ℓ) summed over the other tyre's pressure grid (its marginal likelihood,
        the other's pressure uniform), spline-interpolated from the coarse grid as the windows'
        likelihoods are. Not over the other's current posterior (the exact update of the pair's
        marginals were they independent): that posterior holds the track's earlier windows, which the
        closure's valley in (p_f, p_r) would then count again; on the first 30 ``constant`` runs
        class A's tyres read +2.6 ± 4.4 kPa after 32 s with ±2σ holding 80 % that way, +0.9 ± 3.5 and
        100 % this way (all classes ± 5.7 and ± 5.6 kPa, ±2σ 96 % and 98 %).

        The closure's model errors (the parts' values, the tyre's departures from a linear spring and
        damper) do not average out over windows as the sensors' noise does: each tyre's closure
        evidence is taken as a measurement of p + b, b an offset constant over ``closure_memory_s``
        of σ ``closure_floor_kpa``. The filter takes the evidence whole (its posterior stays sharp,
        so a change stands out against it); the output adds φ²σ_b² to the variance, φ the closure's
        share of the posterior's precision (:meth:`_closure_floor_var`): a linear fusion's bias."""
        if self._closure is None:
            return
        cfg = self.config
        self._state.closure_info *= math.exp(-elapsed / cfg.closure_memory_s)
        _, v, a_s, a_u = block
        valid = np.full(v.size, bool(np.all(checks == _USED) and not np.any(status == _SILENT)))
        found = self._closure.add(v, a_s, a_u, valid)
        post = self._state.post
        counts = self._state.counts
        for i, (f, r) in enumerate(self.tracks):
            if status[f] == _SMOOTH or status[r] == _SMOOTH:
                # no road signal above the sensors' noise on the track: its windows hold noise, whose
                # departures from the noise model would be read as stiffness (a flat road read 66 kPa)
                counts["closure_skipped"][[f, r]] += found.windows[i] + found.skipped[i]
                continue
            counts["closure_windows"][[f, r]] += found.windows[i]
            counts["closure_skipped"][[f, r]] += found.skipped[i]
            n_short = int(found.short_windows[i])
            counts["closure_short_windows"][[f, r]] += n_short
            if found.windows[i] == 0 and n_short == 0:
                continue
            # J on the two tyres' coarse grids (f, r) from the windows' moments, the short windows' apart
            # (their own bins and residual level)
            ll = 0.0
            for moments, n_w, weights in ((found.moments, found.windows[i], self._closure_weights[i][0]),
                                          (found.short_moments, n_short, self._closure_weights[i][1])):
                if n_w == 0:
                    continue
                j = objective_on_grid(moments[i], weights)
                j_min = float(j.min())
                dof = 2.0 * moments.shape[-1] * n_w / 1.5
                ll = ll - (j - j_min) / (2.0 * cfg.closure_tempering * max(j_min / dof, 1e-12))
            marg = np.stack([post[f].sum(axis=(0, 1, 2)), post[r].sum(axis=(0, 1, 2))])  # (2, P) marginals
            marg /= marg.sum(axis=1, keepdims=True)
            # the log-likelihood of each coarse pressure of one tyre, the other's summed out (fine grid)
            fine = pair_messages(ll, self._to_fine) @ self._to_fine.T  # (2, P)
            self._take_closure_information([f, r], marg, fine)
            _bayes(post, np.array([f, r], dtype=np.int64), np.ascontiguousarray(fine[:, None, None, :]))

    def _take_closure_information(self, corners: list[int], marg: np.ndarray, fine: np.ndarray) -> None:
        """Add to each of `corners` the precision (1/kPa²) the closure's log-likelihood `fine` (U, P)
        gives its marginal `marg` (U, P): from the variance before and after it."""
        info = self._state.closure_info
        for u, c in enumerate(corners):
            after = marg[u] * np.exp(fine[u] - fine[u].max())
            after /= after.sum()
            var0 = max(float(marg[u] @ self._p_grid**2 - (marg[u] @ self._p_grid) ** 2), 1e-6)
            var1 = max(float(after @ self._p_grid**2 - (after @ self._p_grid) ** 2), 1e-6)
            info[c] += max(1.0 / var1 - 1.0 / var0, 0.0)

    def _closure_floor_var(self, p_var: np.ndarray) -> np.ndarray:
        """The variance (kPa², (C,)) the closure's model error adds to the posteriors' `p_var`: φ²σ_b²,
        φ = the closure's share of the posterior's precision (its information taken in, decayed,
        times the variance; at most 1), σ_b ``closure_floor_kpa`` (:meth:`_correct_closure`)."""
        share = np.clip(self._state.closure_info * p_var, 0.0, 1.0)
        return share**2 * self.config.closure_floor_kpa**2

    def _floor_tails(self, floor: np.ndarray) -> np.ndarray:
        """The :data:`TAIL_LEVELS` quantiles (C, 2), kPa, of each pressure's posterior convolved with a
        centred normal of variance `floor` (C,) kPa² (the closure's model error, added to the estimate);
        the posterior's marginals as :meth:`_moments` took them (the fit being output)."""
        marg = self._state.fit.p_marg
        marg = marg / marg.sum(axis=1, keepdims=True)
        out = self._state.fit.p_tails.copy()
        rows = np.flatnonzero(floor > 0.0)
        spread = []
        for c in rows:
            width = math.sqrt(floor[c])
            offsets = np.arange(-math.ceil(6.0 * width), math.ceil(6.0 * width) + 1, dtype=float)
            kernel = np.exp(-0.5 * (offsets / width) ** 2)
            spread.append(np.convolve(marg[c], kernel / kernel.sum(), mode="same"))
        if spread:
            out[rows] = self._tails(np.array(spread))
        return out

    def _tails(self, marg: np.ndarray) -> np.ndarray:
        """The :data:`TAIL_LEVELS` quantiles (U, 2), kPa, of pressure distributions `marg` (U, P) on the
        1 kPa grid: each grid value's mass spread over its cell, the CDF linear within it."""
        cdf = np.concatenate([np.zeros((marg.shape[0], 1)), np.cumsum(marg, axis=1)], axis=1)
        cdf /= cdf[:, -1:]
        return np.array([np.interp(TAIL_LEVELS, row, self._p_edges) for row in cdf])

    def _moments(self) -> _Fit:
        """The posterior's moments per corner: pressure (kPa) and waviness mean and variance, the
        probability of the changing regime, the likeliest (damping, slope)."""
        post = self._state.post
        p_marg = post.sum(axis=(1, 2, 3))  # (C, P)
        p_mean = p_marg @ self._p_grid
        p_var = np.maximum(p_marg @ self._p_grid**2 - p_mean**2, 0.0)
        p_tails = self._tails(p_marg)
        db = post.sum(axis=(1, 4))  # (C, D, B)
        w_marg = db.sum(axis=1)  # (C, B)
        w_mean = w_marg @ self.waviness_grid
        w_var = np.maximum(w_marg @ self.waviness_grid**2 - w_mean**2, 0.0)
        flat = db.reshape(db.shape[0], -1)
        mode = np.stack(np.unravel_index(np.argmax(flat, axis=1), db.shape[1:]), axis=-1)
        changing = post[:, 1].sum(axis=(1, 2, 3))
        return _Fit(p_mean=p_mean, p_var=p_var, p_tails=p_tails, p_marg=p_marg, w_mean=w_mean, w_var=w_var,
                    changing=changing, mode=mode)  # fmt: skip

    def _road_signal_z(self, spec: np.ndarray, band_weight: np.ndarray) -> np.ndarray:
        """Per corner (C,), how far the window's unsprung power over its band (`band_weight` (F,),
        :meth:`_band`'s at the window's speed) stands above the sensor's noise (:func:`_energy_z`;
        `spec` (C, 1, F, 3)). The road's signal is there to read k_t from only where z is large."""
        return _energy_z(spec[:, 0, :, 1].real, self.noise, band_weight)

    def _silent(self, spec: np.ndarray, band_weight: np.ndarray) -> np.ndarray:
        """Per corner (C,), whether one of its two accelerometers is silent: over the window's band
        (`band_weight` (F,), :meth:`_band`'s) up to ``silent_band_hz`` (`spec` (C, 1, F, 3)), the
        energy detector (:func:`_energy_z`) of one channel is below ``min_signal_z`` while the
        other's is at least ``silent_other_z`` (:class:`MonitorConfig`). False where the band holds
        no frequency there."""
        cfg = self.config
        weight = band_weight * self._silent_bins
        if not np.any(weight > 0):
            return np.zeros(spec.shape[0], dtype=bool)
        body = _energy_z(spec[:, 0, :, 0].real, self.noise, weight)
        wheel = _energy_z(spec[:, 0, :, 1].real, self.noise, weight)
        return ((body < cfg.min_signal_z) & (wheel >= cfg.silent_other_z)) | (
            (wheel < cfg.min_signal_z) & (body >= cfg.silent_other_z)
        )

    def _transforms(self, x: np.ndarray) -> np.ndarray:
        """The linearly detrended discrete Fourier transform of samples `x` (..., n) at the window's kept
        frequencies (..., F): fewer samples than a window zero-padded to it (:meth:`_cross_spectra`)."""
        if x.shape[-1] == self.window:
            slope = (x @ self._ramp) / self._ramp_norm
            return np.fft.rfft(x, axis=-1)[..., self._f_index] - slope[..., None] * self._ramp_dft
        return np.fft.rfft(_detrend(x), n=self.window, axis=-1)[..., self._f_index]

    def _cross_spectra(
        self, a_s: np.ndarray, a_u: np.ndarray, transforms: np.ndarray | None = None
    ) -> np.ndarray:
        r"""One-sided cross-periodogram per Hz of (sprung, unsprung) (n, C) each on the window's
        frequencies, (C, F, 3): S11, S22, S12. Linear detrend, rectangular window; fewer samples than a
        window are zero-padded to it (the periodogram of the data there, sampled on the window's grid).
        `transforms` (2, C, F): the two channels' :meth:`_transforms`, if already taken.

        A whole window's line is taken out after the transform: at Fourier frequency k ≠ 0 the
        window's mean adds nothing and the ramp n − n̄ (n = 0 … N−1) adds
        :math:`\sum_n n z^n = N/(z - 1)`, :math:`z = e^{-i2\pi k/N}`, so the detrended transform is
        X_k − b N/(z_k − 1), b the least-squares slope (the same within 1e-13 of the largest bin, at
        a fifth of the cost of detrending the samples)."""
        X = self._transforms(np.stack([a_s.T, a_u.T])) if transforms is None else transforms  # (2, C, F)
        k = 2.0 * self.dt / a_s.shape[0]
        fine = np.empty(X.shape[1:] + (3,), dtype=complex)
        fine[..., 0] = np.abs(X[0]) ** 2 * k
        fine[..., 1] = np.abs(X[1]) ** 2 * k
        fine[..., 2] = X[0] * np.conj(X[1]) * k
        return np.add.reduceat(fine, self._group_start, axis=1) / self._group_size[:, None]

    def _project(self, spec: np.ndarray, table: np.ndarray, blend: np.ndarray) -> np.ndarray:
        """u^H S u / N for each damping: spec (C, F, 3) → (C, D, F), row c with the signal direction's
        terms of gain-table slots `table[c]` blended by `blend[c]` (C, K)."""
        u11 = self._blend(self._u11, table, blend)[:, :, 0]  # (C, D, F)
        u22 = self._blend(self._u22, table, blend)[:, :, 0]
        u12 = self._blend(self._u12, table, blend)[:, :, 0]
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

    def _fuse_previews(self, means: np.ndarray, vars_: np.ndarray):
        """Each track's two estimates fused with its preview given the front's
        (:func:`suvtwin.estimators.preview.fuse_track`, errors correlated by ``preview_correlation``);
        the front only if the rear is observable (a rear at its prior has nothing to pass on): (C,)
        kPa, kPa². Output only: the filters keep their own posteriors, so nothing is counted twice."""
        if not self._previews:
            return means, vars_
        means, vars_ = means.copy(), vars_.copy()
        lo, hi = self._previews[0].config.pressure_range_kpa
        limit = self.config.observable_sigma_kpa**2
        for track, (f, r) in zip(self._previews, self.tracks, strict=True):
            # a front without information of its own (not observable: at its prior) has none to pass on
            if not np.isfinite(means[f]) or vars_[f] > limit:
                continue
            p_f = float(np.clip(means[f], lo, hi))
            cond = track.conditional(p_f, math.sqrt(vars_[f]))
            if not cond.informative:
                continue
            # innovation gate: a preview that contradicts the rear's own estimate (the tracks differ:
            # a weave, a curve; a model error) is not fused
            if (cond.mean_kpa - means[r]) ** 2 > self.config.preview_gate**2 * (cond.sigma_kpa**2 + vars_[r]):
                self._state.counts["preview_rejected"][r] += 1
                continue
            # a rear at its prior shares no road with the front's estimate: no correlation, and
            # nothing for the front to learn from it
            rear_observable = bool(vars_[r] <= limit)
            rho = self.config.preview_correlation if rear_observable else 0.0
            sf, sr = math.sqrt(vars_[f]), math.sqrt(vars_[r])
            mean, cov = fuse_track(p_f, sf, means[r], sr, cond, correlation=rho)
            if rear_observable:
                means[f], vars_[f] = mean[0], cov[0, 0]
            means[r], vars_[r] = mean[1], cov[1, 1]
        return means, vars_

    # ------------------------------------------------------------------ output
    def _output(self, t_end, speed, status, spring_rate, tyre_contact) -> MonitorUpdate:
        cfg = self.config
        s = self._state
        fit = s.fit
        floor = self._closure_floor_var(fit.p_var)
        p, var = self._fuse_previews(fit.p_mean, fit.p_var + floor)
        sigma = np.sqrt(var)
        # the posterior's tails carried through the fusion as its mean and σ are (an affine map of the
        # filter's distribution onto the fused mean and σ, as the ensemble adjustment filter moves its
        # members, Anderson 2001 [6]_): the shape the regimes and the grid give is kept; the closure's
        # floor, an error independent of the filter's, convolved in first (_floor_tails). The quantiles
        # spread each 1 kPa cell's mass evenly over it (_moments), which adds a cell's variance, 1/12
        # kPa², to the distribution they are quantiles of (with the closure a posterior's σ falls to
        # about 1 kPa, where that is no longer negligible)
        p_tails = self._floor_tails(floor) if np.any(floor > 0.0) else fit.p_tails
        scale = sigma / np.sqrt(fit.p_var + floor + 1.0 / 12.0)
        tails = p[:, None] + (p_tails - fit.p_mean[:, None]) * scale[:, None]
        # the road's waviness: the corners' estimates pooled (inverse-variance), those with data
        ok = fit.p_var <= cfg.observable_sigma_kpa**2
        waviness = math.nan
        if np.any(ok):
            spread = np.maximum(fit.w_var[ok], 1e-6)
            waviness = float(np.average(fit.w_mean[ok], weights=1.0 / spread))
        kt = stiffness_at_pressure_array(p * 1e3, *self._laws)
        kt_sig = np.abs(stiffness_sigma_at_pressure_sigma(sigma * 1e3, *self._laws))
        return MonitorUpdate(
            t_s=np.array([t_end]),
            pressure_pa=p[None] * 1e3,
            pressure_sigma_pa=sigma[None] * 1e3,
            pressure_lower_pa=tails[None, :, 0] * 1e3,
            pressure_upper_pa=tails[None, :, 1] * 1e3,
            stiffness=kt[None],
            stiffness_sigma=kt_sig[None],
            observable=(sigma <= cfg.observable_sigma_kpa)[None],
            status=status[None].astype(np.int8),
            road_level=np.array([s.level]),
            waviness=np.array([waviness]),
            speed_mps=np.array([speed]),
            change_probability=fit.changing[None].copy(),
            spring_rate=spring_rate[None],
            tyre_contact=tyre_contact[None],
            track_coherence=np.array([self._coherence_in_band(speed)]),
        )

    def _coherence_in_band(self, speed: float) -> float:
        """The tracks' coherence in use averaged over the band at `speed` (by the bins each band
        holds); NaN without a speed, before the estimate has a window, or with no corner in a full car
        (where it is not used)."""
        s = self._state
        if self._car_a is None or not np.isfinite(speed) or (
            self._estimate_coherence and not np.any(s.coh_bb > 0.0)
        ):  # fmt: skip
            return math.nan
        weight = self._band(np.array([speed]))[0][0]
        return float(weight @ s.coherence / weight.sum()) if weight.sum() > 0 else math.nan


def _energy_z(power: np.ndarray, noise: float, weight: np.ndarray) -> np.ndarray:
    r"""An energy detector: how far a periodogram stands above white noise of PSD `noise`, in
    standard errors of a noise-only one, :math:`z = \sum_f w_f(P_f/N - 1)/\sqrt{\sum_f w_f}` per row
    of `power` (…, F), w_f (F,) the Fourier frequencies averaged in band f (0 outside the band).
    With noise alone each periodogram bin is exponential about N, so z is about standard normal."""
    return (power / noise - 1.0) @ weight / math.sqrt(max(float(weight.sum()), 1.0))


def _lattice(position: np.ndarray, dead: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    """The two lattice points around each `position` (in steps) and their weights: (U, 2) ints
    (floor, floor + 1) and (U, 2) weights (1 − w, w), w the position's fraction past the floor
    mapped piecewise linearly so that within `dead` of a lattice point the point takes it whole:
    w = clip((frac − dead)/(1 − 2 dead), 0, 1). Continuous in the position, and one table instead
    of two there (a tyre's contact share is almost always within 0.05 steps of 1; the rate off
    the point's by at most dead·rate_step, 0.1 % by default)."""
    lo = np.floor(position)
    w = np.clip((position - lo - dead) / (1.0 - 2.0 * dead), 0.0, 1.0)
    up = w >= 1.0  # the upper point alone: make it the first
    lo = np.where(up, lo + 1.0, lo)
    w = np.where(up, 0.0, w)
    points = lo.astype(int)[:, None] + np.arange(2)
    return points, np.stack([1.0 - w, w], axis=1)


def _detrend(x: np.ndarray) -> np.ndarray:
    """x less its least-squares line along the last axis."""
    n = np.arange(x.shape[-1], dtype=float)
    n -= n.mean()
    centred = x - x.mean(axis=-1, keepdims=True)
    return centred - (centred @ n / (n @ n))[..., None] * n


@cached_njit
def _block_extremes(a_s, a_u):
    """Per row of the block's samples (n, C) each, sprung rows then unsprung rows (2C,): the largest
    and smallest value (0 where a value is missing), whether all are finite, and whether three or
    more consecutive samples sit at the row's largest or smallest value (a flat top: clipped). One
    pass over the samples and a second only where an extreme repeats."""
    n, n_c = a_s.shape
    top = np.zeros(2 * n_c)
    bottom = np.zeros(2 * n_c)
    finite = np.ones(2 * n_c, dtype=np.bool_)
    clipped = np.zeros(2 * n_c, dtype=np.bool_)
    for r in range(2 * n_c):
        x = a_s if r < n_c else a_u
        c = r % n_c
        hi = lo = x[0, c]
        ok = math.isfinite(hi)
        for i in range(1, n):
            v = x[i, c]
            if not math.isfinite(v):
                ok = False
            elif v > hi:
                hi = v
            elif v < lo:
                lo = v
        if not ok:
            finite[r] = False
            clipped[r] = True  # as a row of zeros: the checks that follow refuse it anyway
            continue
        top[r], bottom[r] = hi, lo
        run_hi = run_lo = 0
        for i in range(n):
            v = x[i, c]
            run_hi = run_hi + 1 if v == hi else 0
            run_lo = run_lo + 1 if v == lo else 0
            if run_hi >= 3 or run_lo >= 3:
                clipped[r] = True
                break
    return top, bottom, finite, clipped


def _spiky(sub: np.ndarray, top: np.ndarray, bottom: np.ndarray, z: float):
    """Per row: a sample more than z robust σ (1.4826 × median absolute deviation) from the median;
    and the rows' medians and robust σ.

    `sub`: every 16th sample of each row, whose median and MAD are taken (a robust scale at a 16th
    of the cost); only the row's extremes `top` and `bottom` need comparing with them."""
    med, mad = _median_mad(sub)
    return np.maximum(top - med, med - bottom) > z * np.maximum(mad, 1e-12), med, mad


@cached_njit
def _median_mad(sub):
    """Per row of `sub` (R, n): the median and 1.4826 × the median absolute deviation from it (as
    :func:`numpy.median`, NaN where a row holds one; compiled: numpy's two calls cost three times more)."""
    n_r = sub.shape[0]
    med = np.empty(n_r)
    mad = np.empty(n_r)
    for r in range(n_r):
        if np.any(np.isnan(sub[r])):  # numba's median would pass over it
            med[r] = mad[r] = np.nan
            continue
        med[r] = np.median(sub[r])
        mad[r] = 1.4826 * np.median(np.abs(sub[r] - med[r]))
    return med, mad


def pressure_at(update: MonitorUpdate, t_s: np.ndarray, prior_pa: np.ndarray, prior_sigma_pa: npt.ArrayLike):
    """The monitor's estimate on another time axis (step-hold: each row holds until the next).

    Before the first row: `prior_pa` (C,) ± `prior_sigma_pa` (one σ or one per corner, (C,);
    :attr:`TyreMonitor.prior_pa`, :attr:`TyreMonitor.prior_sigma_pa`). Returns pressure and σ, (T, C), Pa.
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
