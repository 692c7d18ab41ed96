r"""Each track's two tyre stiffnesses from the road its wheels share, closed by each wheel's force balance.

Usual call::

    front = corner_signals(acc_u_fl, acc_s_fl, acc_u_fr, acc_s_fr, parts_fl, dt=1e-3)
    rear = corner_signals(acc_u_rl, acc_s_rl, acc_u_rr, acc_s_rr, parts_rl, dt=1e-3)
    fit = closure_objective(front, rear, delay_s=wheelbase / speed, dt=1e-3, stiffness_grid=k)
    k_front, k_rear = k[fit.best]

Idea: under each wheel the road is the wheel's height plus its tyre's deflection, and the deflection
is the tyre's dynamic force through the tyre's spring and damper. The rear wheel meets the front
wheel's road a wheelbase later (τ = L/v), so per frequency f (ω = 2πf) of a window

.. math:: Z_{u,r} + \frac{F_r}{k_r + i\omega c_t}
          = e^{-i\omega\tau}\Big(Z_{u,f} + \frac{F_f}{k_f + i\omega c_t}\Big),

with no road spectrum, level or waviness in it: two unknowns and hundreds of equations per window.
The wheel's height enters with coefficient 1, so the relation fixes each tyre's stiffness, not only
the two's ratio (the acceleration ratio of :mod:`suvtwin.estimators.preview` fixes only the ratio
above the wheel hop). Each wheel's dynamic tyre force comes from its force balance,

.. math:: F = m_{us} a_u + F_s(s_0 + s) - F_s(s_0) + F_d(\dot s) + k_{arb}(s - s_o),

the suspension's spring (with its stops) and damper laws (:class:`suvtwin.suspension_law.SuspensionLaw`)
at the travel s and its rate, integrated from the wheel's and the body's vertical accelerometers
(:func:`integrate`, above 0.3 Hz), s_0 the static travel, s_o the other wheel of the axle's travel
(the anti-roll bar). The accelerometers' white noise (σ per sample) reaches the relation's residual
through known gains (the laws linearized at their design rates), so the fit is a generalized total
least squares: minimize :math:`J = \sum_{w,f} |r_{w,f}|^2 / \mathrm{Var}(r_{w,f})` over a grid of
(k_f, k_r), the variance evaluated at each grid point (errors in variables: a plain least squares
would attenuate 1/k toward zero; adding :math:`\log\mathrm{Var}` to J, a Gaussian likelihood of the
residual, biases it toward stiff tyres on smooth roads, measured).

Where a wheel leaves the road (its reconstructed load below ``min_load_share`` of the static load)
or its suspension reaches a stop, the relation fails (no contact; a spring force at the stop that
the integrated travel, whose sub-hertz part is lost, cannot place): a window is used only if every
sample of the rear wheel's window and of the front wheel's delayed window is clear of both.
Hann windows of ``window_s`` hop by half a window; the delay's fractional sample is a phase.

Measured on MuJoCo runs (``python bench/force_closure.py --runs 30``: the first 30 ``constant`` runs,
Gaussian roads, the minimum of J on a 1 kPa pressure grid, from 5 s on): on classes A–C 72 of 84
tyres had a usable window after 10 s, estimate − truth +2.5 ± 9.6 kPa (median magnitude 4.5), and 76
after 30 s, +4.7 ± 4.3 kPa (the monitor reads ± 15 / 10 kPa on these roads, all classes); on class D
none (the stops are hit every few seconds). The travel's mean at the static travel instead of less
the jacking: +2.8 ± 9.5 and +5.1 ± 4.3. Most of the +4.7 is timing: the simulator's integrator
(semi-implicit Euler) gives the damper a velocity half a step (0.5 ms) behind the travel. Read from
the data (``damper_lag_s`` of 0, 0.25, 0.5, 0.75 and 1 ms, per track the least J; the bench's
default): −1.9 ± 9.3 kPa (median 3.8) after 10 s and −0.0 ± 3.1 (median 1.1) after 30 s on the same
tyres. J scaled by its minimum over its degrees of freedom (as if the model's error, which dominates
the noise, were white) is too sharp: ±2σ held the truth for 78 % of the tyres at 10 s and at 30 s.

Online (:class:`ClosureStream`): J is a quadratic form in each window's DFTs, so a window is kept as
its six moments per frequency (:func:`window_moments`) and J on any grid follows from their sums
(:func:`objective_from_moments`; compiled, :func:`objective_on_grid`; the noise's weights made once per
grid by :func:`closure_weights`).
The stream takes the four corners' samples in time order and analyses each window once the stream
holds ``margin_s`` beyond it, from a span (the windows ready, their fronts' delay and a margin each
side, tapered; on a fixed lattice instead, ``spans="lattice"``, a window's moments do not depend on
how the stream was cut; the online monitor feeds fixed blocks, one per update, so its estimates do not
either);
at 200 Hz (the spectrum cut there first). With 4 s windows, two a lattice span, on the first 30
``constant`` runs fed from the start in 2 s blocks, the damper's timing half the simulator's step:
−0.9 ± 7.1 kPa at 10 s, +0.1 ± 3.0 at 20 s, +0.5 ± 2.2 at 30 s (80 of 120 tyres: classes A–C);
cost 0.39–0.57 ms per second of four-corner data fed in 4 s blocks, the monitor's (0.75–0.85 before
the spans' samples, forces and moments were taken in compiled passes: alternated on one core of the
2-core machine, 2026-12-05; with 0.5 s windows, 16 a ready span, about 0.6 ms). With the defaults, over
an hour's varied drive fed in the monitor's 8 s blocks (replayed, one core, alternated): 0.30 ms per
second of data before the span's two integrals shared one transform, numpy's, into reused arrays and the
speed checks, tapering, forces and usable windows were taken in compiled passes; 0.13 ms after (the two
transforms nearly half of it). The online
monitor (:mod:`suvtwin.estimators.monitor`) takes each update's windows as a likelihood of the two
tyres' pressures and adds a model-error floor to its σ.

Short windows read better (:class:`ClosureConfig`'s ``window_s``, 0.5 s since the eighteenth
session): in the monitor on the 100 ``constant`` runs, with the radii, 4 s windows read the tyres
+1.9 ± 10.8 kPa at 10 s and ± 6.2 at 30 s, 2 s ± 10.1 / 5.7, 1 s ± 8.1 / 5.1, 0.5 s ± 6.6 / 3.6
(four to a lattice span; ± 6.4 / 3.3 with those ready at each update sharing one, the default),
0.25 s −1.5 ± 12.8 / −3.4 ± 6.2 (class A's tyres ± 14 kPa at 30 s: a 4 Hz bin spacing leaves the
relation four frequencies). More short windows are clear of the stops and of lift-off on rough roads
(class D's tyres, the monitor's own output at 30 s, ± 14.2 → ± 9.3 kPa with the default; class C
± 4.1 → 2.7), and the relation's sub-hertz model error (the integrals' drift, the spring's operating
point) falls below the lowest bin (2 Hz). Not the band alone: 4 s windows with the band from 2 Hz
read as with it from 0.5 Hz (± 10.8 / 6.2). A short window lets more of a speed change through the
speed check unless it is per second (``max_speed_change_per_s``).

Rough roads are read in shorter windows still (:class:`ClosureConfig`'s ``short_window_s``, 0.25 s,
and ``short_below``, since 2026-12-05): where fewer than half of a span's 0.5 s windows that pass the
speed checks are clear of the stops and of lift-off on a track, that track's span is read in 0.25 s
windows instead, two in each 0.5 s window's hop, each kept as its own moments (their bins 4 Hz
apart) and weighed by its own residual level in the monitor. On the 100 ``constant`` runs the share
of clear 0.5 s windows separates the classes (a median 1.00 on A and B, 0.99 on C, 0.20 on D); in
the monitor, with the radii, class D's tyres read +0.72 ± 4.98 / +0.08 ± 2.64 kPa at 10 / 30 s
against +1.60 ± 9.98 / −0.26 ± 4.57 with 0.5 s windows only, classes A and B to the bit as before,
all 100 runs ± 4.22 / 2.55 against ± 6.50 / 3.34 (the monitor's own output at 30 s, class D, ± 4.85
against ± 10.77).

No MuJoCo here: the functions consume arrays.
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.fft
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit
from suvtwin.suspension_law import (  # the laws' compiled forms, for _force_balance and _span_forces
    _SIGMA_FLOOR,
    SuspensionLaw,
    _damper,
    _equivalent,
    _force,
    equivalent_spring_rate,
)

__all__ = ["MOMENTS", "ClosureFit", "CornerParts", "CornerSignals", "band_of", "closure_objective",
           "closure_weights", "corner_signals", "integrate", "objective_from_moments", "objective_on_grid",
           "pair_messages", "window_moments", "windows_moments", "ClosureBlock", "ClosureConfig",
           "ClosureStream"]  # fmt: skip


@dataclass(frozen=True)
class CornerParts:
    """What one corner's force balance needs (SI units).

    unsprung_mass : kg; law : the corner's suspension at the wheel; anti_roll : the axle's
    anti-roll bar rate at the wheel, N/m; static_travel : the suspension's travel at rest with the
    car's loads, m (the law's frame: compression > 0); static_load : the tyre's static load, N.
    """

    unsprung_mass: float
    law: SuspensionLaw
    anti_roll: float
    static_travel: float
    static_load: float


@dataclass(frozen=True)
class CornerSignals:
    """A corner's reconstructed signals on the samples' time axis: wheel height z_u (m, above
    ``highpass_hz``), dynamic tyre force (N), whether the relation holds at the sample (in contact,
    off the stops), and the parts they came from."""

    z_u: np.ndarray
    force: np.ndarray
    usable: np.ndarray
    parts: CornerParts


@dataclass(frozen=True)
class ClosureFit:
    """J over the (k_f, k_r) grid (rows: front), its minimum's indices `best` (None if no window
    was usable), and the windows used of those the record held."""

    objective: np.ndarray
    best: tuple[int, int] | None
    windows_used: int
    windows: int


def integrate(acc: npt.ArrayLike, dt: float, order: int | tuple[int, ...], highpass_hz: float = 0.3,
              lag_s: float = 0.0, step: int = 1):  # fmt: skip
    """The `order`-fold time integral of `acc` (0: itself, 1: velocity, 2: displacement; a tuple of
    orders gives a tuple of integrals from one transform) along its last axis, by the FFT over the
    whole array (its mean removed, zero-padded to a fast length), frequencies below `highpass_hz`
    (Hz) removed (circular: use the middle, or a tapered window, of what it returns); the first
    order's integral delayed by `lag_s` (s, a phase) if given. `step` > 1: every step-th sample
    returned, the spectrum cut at the new Nyquist frequency first (an ideal low-pass)."""
    x = np.asarray(acc, dtype=float)
    n = x.shape[-1]
    size = step * scipy.fft.next_fast_len(-(-n // step), real=True)
    spectrum = scipy.fft.rfft(x - x.mean(axis=-1, keepdims=True), n=size, axis=-1)
    orders = (order,) if isinstance(order, int) else tuple(order)
    gains = _integration_gains(size, float(dt), orders, float(highpass_hz), float(lag_s), step)
    spectrum = spectrum[..., : gains.shape[1]]
    out = [scipy.fft.irfft(spectrum * gain, n=size // step, axis=-1)[..., : -(-n // step)] for gain in gains]
    return out[0] if isinstance(order, int) else tuple(out)


@functools.lru_cache(maxsize=64)
def _integration_gains(size: int, dt: float, orders: tuple[int, ...], highpass_hz: float, lag_s: float,
                       step: int) -> np.ndarray:  # fmt: skip
    """:func:`integrate`'s gain per order (len(orders), size // step // 2 + 1) on a `size`-point
    transform's bins up to the new Nyquist frequency: 1/(iω)^k/step above `highpass_hz`, 0 below,
    the first order's delayed by `lag_s`. Made once per transform and settings (read only)."""
    kept = size // step // 2 + 1
    omega = 2.0 * np.pi * np.fft.rfftfreq(size, dt)[:kept]
    keep = omega > 2.0 * np.pi * highpass_hz
    gains = np.zeros((len(orders), kept), dtype=complex)
    for gain, k in zip(gains, orders, strict=True):
        gain[keep] = 1.0 / (1j * omega[keep]) ** k / step
        if k == 1 and lag_s:
            gain *= np.exp(-1j * omega * lag_s)
    gains.flags.writeable = False
    return gains


def corner_signals(
    acc_u: npt.ArrayLike, acc_s: npt.ArrayLike, acc_u_other: npt.ArrayLike, acc_s_other: npt.ArrayLike,
    parts: CornerParts, *, dt: float, min_load_share: float = 0.1, highpass_hz: float = 0.3,
    jacking: bool = True, damper_lag_s: float = 0.0,
) -> CornerSignals:  # fmt: skip
    """A corner's wheel height, dynamic tyre force and usable samples from its wheel (`acc_u`) and
    body (`acc_s`) vertical accelerations and those of the other wheel of its axle (m/s², gravity
    removed, one sample per `dt` s). The travel's mean is the static travel less the asymmetric
    damper's jacking down (:func:`suvtwin.suspension_law.equivalent_spring_rate` at the record's
    travel and rate spreads), or the static travel with `jacking` False; the anti-roll bar acts on
    the two travels' motion about their means. The damper acts on the rate `damper_lag_s` (s) late:
    a timing between the damper's force and the accelerometers (the damper's own, the sensors', or a
    simulator's step) that the closure can read from the data (:func:`closure_objective` per lag,
    the least J)."""
    acc_u, acc_s = np.asarray(acc_u, dtype=float), np.asarray(acc_s, dtype=float)
    acc_u_other, acc_s_other = np.asarray(acc_u_other, dtype=float), np.asarray(acc_s_other, dtype=float)
    if not (acc_u.shape == acc_s.shape == acc_u_other.shape == acc_s_other.shape and acc_u.ndim == 1):
        raise InputError("corner_signals: the four acceleration arrays must be 1-D and of one length")
    if not all(np.all(np.isfinite(a)) for a in (acc_u, acc_s, acc_u_other, acc_s_other)):
        raise InputError("corner_signals: the accelerations must be finite (cut the record at its gaps)")
    motion, rate = integrate(np.stack([acc_u - acc_s, acc_u_other - acc_s_other]), dt, (2, 1), highpass_hz,
                             damper_lag_s)  # fmt: skip
    z_u = integrate(acc_u, dt, 2, highpass_hz)
    return _corner_signal(acc_u, z_u, motion[0], rate[0], motion[1], parts, min_load_share, jacking)


def _corner_signal(acc_u, z_u, motion, rate, motion_other, parts: CornerParts, min_load_share: float,
                   jacking: bool = True) -> CornerSignals:  # fmt: skip
    """:func:`corner_signals` from the integrals: the wheel's height `z_u`, the travel's `motion` about
    its mean and its (lagged) `rate`, the axle's other travel's `motion_other` (m, m/s)."""
    s0 = parts.static_travel
    law = parts.law
    # the mean travel: the static one less the asymmetric damper's jacking down (and the progressive
    # spring's push up), for a Gaussian travel of the measured spreads (the monitor's linearization)
    mean = s0
    if jacking:
        mean = float(equivalent_spring_rate(law, s0, _spread(motion), _spread(rate))[0])
    force, usable = np.empty(motion.size), np.empty(motion.size, dtype=bool)
    _force_balance(np.ascontiguousarray(acc_u, dtype=float), np.ascontiguousarray(motion, dtype=float),
                   np.ascontiguousarray(rate, dtype=float), np.ascontiguousarray(motion_other, dtype=float),
                   law.values, mean, s0, parts.unsprung_mass, parts.anti_roll, parts.static_load,
                   min_load_share, force, usable)  # fmt: skip
    return CornerSignals(z_u, force, usable, parts)


@cached_njit
def _spread(x):
    """The standard deviation of `x` (n,) about its mean (numpy's std; compiled: a tenth of its cost on a
    span's travel, :func:`_corner_signal`)."""
    mean = 0.0
    for v in x:
        mean += v
    mean /= x.size
    total = 0.0
    for v in x:
        total += (v - mean) * (v - mean)
    return math.sqrt(total / x.size)


@cached_njit
def _force_balance(acc_u, motion, rate, motion_other, q, mean, s0, mass, anti_roll, static_load, min_share,
                   force, usable):  # fmt: skip
    """Per sample, the wheel's dynamic tyre force (N) m_us a_u + F_s(mean + motion) − F_s(s0) + F_d(rate)
    + k_arb (motion − motion_other) into `force`, and into `usable` whether the tyre's load exceeds
    `min_share` of `static_load` with the travel mean + motion between the stops; `q` the law's
    :attr:`~suvtwin.suspension_law.SuspensionLaw.values` (:func:`_corner_signal`, in one pass)."""
    spring0 = _force(q, s0)
    for i in range(motion.size):
        travel = motion[i] + mean
        f = mass * acc_u[i] + (_force(q, travel) - spring0) + _damper(q, rate[i])
        f += anti_roll * (motion[i] - motion_other[i])
        force[i] = f
        usable[i] = (static_load + f > min_share * static_load) and travel < q[2] and travel > -q[5]


def _noise_gain(parts: CornerParts, x: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Σ|gain|² of the residual term Z_u + x F on the corner's accelerometer noises (its wheel's,
    its body's, and the axle's other corner's two through the bar), the laws at their design rates."""
    law = parts.law
    rate = law.spring_rate + parts.anti_roll
    damping = 0.5 * (law.compression_low + law.rebound_low)
    wheel = -1.0 / omega**2 + x * (parts.unsprung_mass - rate / omega**2 + damping / (1j * omega))
    body = x * (rate / omega**2 - damping / (1j * omega))
    other = x * parts.anti_roll / omega**2
    return np.abs(wheel) ** 2 + np.abs(body) ** 2 + 2.0 * np.abs(other) ** 2


def closure_objective(
    front: CornerSignals, rear: CornerSignals, *, delay_s: float, dt: float, stiffness_grid: npt.ArrayLike,
    tyre_damping: float = 200.0, noise_sigma: float = 0.5, window_s: float = 4.0,
    band_hz: tuple[float, float] = (0.5, 20.0),
) -> ClosureFit:  # fmt: skip
    """J over the grid of front × rear tyre stiffness `stiffness_grid` (N/m) for one track: the
    rear's samples against the front's `delay_s` (s, the wheelbase over the speed) earlier, in Hann
    windows of `window_s` (s) hopping by half, frequencies in `band_hz`, each window used only where
    both wheels are usable throughout; `tyre_damping` c_t (N s/m), `noise_sigma` the accelerometers'
    white noise per sample (m/s²). The windows' :func:`window_moments` summed, then
    :func:`objective_from_moments`."""
    k = _stiffness_grid(stiffness_grid)
    m = int(round(window_s / dt))
    n = front.z_u.size
    starts = list(range(int(round(delay_s / dt)), n - m + 1, m // 2))
    moments, used = window_moments(front, rear, starts, m, delay_s=delay_s, dt=dt, band_hz=band_hz)
    objective = objective_from_moments(moments, front.parts, rear.parts, k, k, m=m, dt=dt, band_hz=band_hz,
                                       tyre_damping=tyre_damping, noise_sigma=noise_sigma)  # fmt: skip
    best = tuple(int(i) for i in np.unravel_index(np.argmin(objective), objective.shape)) if used else None
    return ClosureFit(objective, best, used, len(starts))


MOMENTS = 6
"""Per frequency a window's closure moments: with a = Z_u,r − Z_u,f e^{−iωτ}, b = F_r, c = F_f e^{−iωτ}
(Hann-windowed DFTs): |a|², |b|², |c|², b ā, c ā, b c̄ (:func:`window_moments`)."""


def _stiffness_grid(stiffness_grid: npt.ArrayLike) -> np.ndarray:
    k = np.asarray(stiffness_grid, dtype=float)
    if k.ndim != 1 or k.size < 2 or not np.all(k > 0):
        raise InputError("closure_objective: stiffness_grid must be 1-D, at least 2 values, all > 0 N/m")
    return k


def band_of(m: int, dt: float, band_hz: tuple[float, float]) -> np.ndarray:
    """The angular frequencies (rad/s) of an `m`-sample window's DFT bins strictly inside `band_hz`."""
    return 2.0 * np.pi * _window_basis(m, float(dt), tuple(band_hz))[0]


def window_moments(
    front: CornerSignals, rear: CornerSignals, starts, m: int, *, delay_s: float, dt: float,
    band_hz: tuple[float, float] = (0.5, 20.0),
) -> tuple[np.ndarray, int]:  # fmt: skip
    """The closure's moments (:data:`MOMENTS`, F) summed over the usable `m`-sample Hann windows of
    the rear starting at `starts` (sample indices), each against the front's window `delay_s` (s)
    earlier (the integer samples a shift, the fraction a phase), and how many were usable: every
    sample of both windows clear of the stops and in contact. The residual of the closure relation
    at (k_f, k_r) is a + x_r b − x_f c, x = 1/(k + iωc_t), so these sums are all J needs.

    Windows with a few such samples masked out instead (a Hann-edged mask, 20 ms, at most a quarter
    of the window's energy; x is a filter of time constant c_t/k ≈ 1 ms, so a mask applied alike to
    the four signals keeps the relation) were tried on the first 40 ``constant`` runs: class D's
    tyres read −7.4 ± 10.0 kPa after 30 s and class C's went from +0.5 ± 1.2 to −2.1 ± 5.4: the
    model fails near a stop or a lift-off beyond the samples flagged, so such windows are left out."""
    if not (np.isfinite(delay_s) and delay_s > 0):
        raise InputError(f"closure_objective: delay_s must be > 0 s, got {delay_s!r}")
    shift = int(round(delay_s / dt))
    rear_at = np.array([s for s in starts if s - shift >= 0 and s + m <= rear.z_u.size], dtype=np.int64)
    fraction = np.full(rear_at.size, delay_s - shift * dt)
    out, used = windows_moments([front], [rear], rear_at, rear_at - shift, fraction, m, dt=dt,
                                band_hz=band_hz)
    return out[0], int(used[0])


def windows_moments(
    fronts, rears, rear_at: np.ndarray, front_at: np.ndarray, fraction_s: np.ndarray, m: int, *, dt: float,
    band_hz: tuple[float, float] = (0.5, 20.0),
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`window_moments` of several tracks' windows at once, each window its own delay: per track
    (`fronts`, `rears`: (T,) :class:`CornerSignals` on one time axis) the moments (T, :data:`MOMENTS`,
    F) summed over the usable `m`-sample Hann windows whose rear starts at `rear_at` (W,) and front at
    `front_at` (W,) (sample indices: the delay's whole samples), the delay's remaining `fraction_s`
    (W,) s a phase; and how many were usable per track (T,)."""
    signals = [*fronts, *rears]
    n_t = len(rears)
    rows = np.arange(2 * n_t, dtype=np.int64)
    return _rows_moments(np.stack([s.z_u for s in signals]), np.stack([s.force for s in signals]),
                         np.stack([s.usable for s in signals]), rows[:n_t], rows[n_t:], rear_at, front_at,
                         fraction_s, m, dt=dt, band_hz=band_hz)  # fmt: skip


def _rows_moments(
    z_u: np.ndarray, force: np.ndarray, usable: np.ndarray, front_rows: np.ndarray, rear_rows: np.ndarray,
    rear_at: np.ndarray, front_at: np.ndarray, fraction_s: np.ndarray, m: int, *, dt: float,
    band_hz: tuple[float, float],
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """:func:`windows_moments` from the corners' signals as rows: heights `z_u` (m), forces `force` (N)
    and `usable` (K, n), each track's front and rear rows `front_rows`, `rear_rows` (T,) (the stream's
    form: its span's corners as they came, none copied). Only the usable windows are transformed (one
    batched FFT; on an hour's varied drive the stream passed over a third of each track's windows:
    a stop, lift-off or the speed), their moments summed in one compiled pass."""
    band_freq, band, hann = _window_basis(m, float(dt), tuple(band_hz))
    n_t = rear_rows.size
    out = np.zeros((n_t, MOMENTS, band_freq.size), dtype=complex)
    if rear_at.size == 0:
        return out, np.zeros(n_t, dtype=int)
    ok, stack = _usable_windows(z_u, force, usable, front_rows, rear_rows,
                                np.asarray(rear_at, dtype=np.int64), np.asarray(front_at, dtype=np.int64),
                                hann)  # fmt: skip
    if stack.shape[0]:  # the usable windows' DFTs (U, 4, m // 2 + 1), the band's taken
        _moment_sums(np.fft.rfft(stack, axis=-1), band.start, band_freq, np.asarray(fraction_s, dtype=float),
                     ok, out)  # fmt: skip
    return out, ok.sum(axis=1)


@cached_njit
def _usable_windows(z_u, force, usable, front_rows, rear_rows, rear_at, front_at, hann):
    """Which windows are usable per track, ok (T, W) (every sample of the rear's window at `rear_at` and
    of the front's at `front_at` usable), and those windows' (Z_u,r, F_r, Z_u,f, F_f), each less its
    mean under the Hann window `hann` (m,) and times it, stacked (U, 4, m) in (track, window) order
    (:func:`_rows_moments`)."""
    n_t, n_w, m = rear_rows.size, rear_at.size, hann.size
    ok = np.zeros((n_t, n_w), dtype=np.bool_)
    count = 0
    for t in range(n_t):
        for w in range(n_w):
            good = True
            for j in range(m):
                if not (usable[rear_rows[t], rear_at[w] + j] and usable[front_rows[t], front_at[w] + j]):
                    good = False
                    break
            ok[t, w] = good
            count += good
    weight = 0.0
    for j in range(m):
        weight += hann[j]
    stack = np.empty((count, 4, m))
    u = 0
    for t in range(n_t):
        for w in range(n_w):
            if not ok[t, w]:
                continue
            _hann_row(z_u[rear_rows[t]], rear_at[w], hann, weight, stack[u, 0])
            _hann_row(force[rear_rows[t]], rear_at[w], hann, weight, stack[u, 1])
            _hann_row(z_u[front_rows[t]], front_at[w], hann, weight, stack[u, 2])
            _hann_row(force[front_rows[t]], front_at[w], hann, weight, stack[u, 3])
            u += 1
    return ok, stack


@cached_njit
def _hann_row(x, at, hann, weight, out):
    """x[at : at + m] less its mean under the Hann window `hann` (m,) (its weights summing to `weight`),
    times the window, into `out` (m,): the signal's mean leaks into the band otherwise."""
    mean = 0.0
    for j in range(hann.size):
        mean += x[at + j] * hann[j]
    mean /= weight
    for j in range(hann.size):
        out[j] = (x[at + j] - mean) * hann[j]


@cached_njit
def _moment_sums(dft, first, freq, fraction, ok, out):
    """Add to `out` (T, :data:`MOMENTS`, F) each usable window's moments from its DFTs `dft` (U, 4, bins)
    of (Z_u,r, F_r, Z_u,f, F_f), the band's F from bin `first` on (frequencies `freq` (F,), Hz), U the
    True entries of `ok` (T, W) in order, and its delay's fractional `fraction` (W,) s, a phase
    e^{−i2πfτ}: with a = Z_u,r − Z_u,f·phase, b = F_r, c = F_f·phase, |a|², |b|², |c|², b ā, c ā, b c̄
    (:func:`window_moments`), each track's windows in order."""
    u = 0
    for t in range(ok.shape[0]):
        for w in range(ok.shape[1]):
            if not ok[t, w]:
                continue
            for f in range(freq.size):
                phase = cmath.exp(-1j * 2.0 * np.pi * (fraction[w] * freq[f]))
                a = dft[u, 0, first + f] - dft[u, 2, first + f] * phase
                b = dft[u, 1, first + f]
                c = dft[u, 3, first + f] * phase
                out[t, 0, f] += abs(a) ** 2
                out[t, 1, f] += abs(b) ** 2
                out[t, 2, f] += abs(c) ** 2
                out[t, 3, f] += b * a.conjugate()
                out[t, 4, f] += c * a.conjugate()
                out[t, 5, f] += b * c.conjugate()
            u += 1


@functools.lru_cache(maxsize=16)
def _window_basis(m: int, dt: float, band_hz: tuple[float, float]) -> tuple[np.ndarray, slice, np.ndarray]:
    """An `m`-sample window's DFT frequencies strictly inside `band_hz` (Hz), the slice of the bins
    that holds them, and the Hann window (:func:`window_moments`); made once per window (read only)."""
    freq = np.fft.rfftfreq(m, dt)
    inside = np.flatnonzero((freq > band_hz[0]) & (freq < band_hz[1]))
    band = slice(int(inside[0]), int(inside[-1]) + 1) if inside.size else slice(0, 0)
    hann = np.hanning(m)
    for a in (freq, hann):
        a.flags.writeable = False
    return freq[band], band, hann


def closure_weights(
    front: CornerParts, rear: CornerParts, k_front: np.ndarray, k_rear: np.ndarray, *, m: int, dt: float,
    band_hz: tuple[float, float] = (0.5, 20.0), tyre_damping: float = 200.0, noise_sigma: float = 0.5,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """What J needs beside the moments on a (k_front, k_rear) grid (N/m): x_f (G_f, F), x_r (G_r, F)
    and 1/Var of the residual (G_f, G_r, F) from the accelerometers' white noise `noise_sigma` (m/s²
    per sample) through an `m`-sample Hann window (:func:`_noise_gain`). Fixed for a track: made once."""
    omega = band_of(m, dt, band_hz)
    x_f = 1.0 / (np.asarray(k_front, dtype=float)[:, None] + 1j * omega[None, :] * tyre_damping)
    x_r = 1.0 / (np.asarray(k_rear, dtype=float)[:, None] + 1j * omega[None, :] * tyre_damping)
    hann = np.hanning(m)
    gains = _noise_gain(front, x_f, omega)[:, None, :] + _noise_gain(rear, x_r, omega)[None, :, :]
    return x_f, x_r, 1.0 / (noise_sigma**2 * np.sum(hann**2) * gains)


def objective_on_grid(moments: np.ndarray, weights: tuple[np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """J (G_f, G_r) on the grid of `weights` (:func:`closure_weights`) from the summed moments
    (:data:`MOMENTS`, F): the sums of :func:`objective_from_moments` (the reference the tests compare
    it against), compiled and without its (G_f, G_r, F) temporaries: the online monitor's J per update
    (44 × 44 grid, 77 frequencies: 0.08 ms, against 0.2 ms in a loop for the product with a 10.7 MB
    matrix that it replaced, and about 0.8 ms for that product in the monitor, its matrix out of cache)."""
    x_f, x_r, inv_var = weights
    out = np.empty(inv_var.shape[:2])
    _objective_sums(np.ascontiguousarray(x_f), np.ascontiguousarray(x_r), np.ascontiguousarray(inv_var),
                    np.ascontiguousarray(moments, dtype=complex), out)  # fmt: skip
    return out


def pair_messages(ll: np.ndarray, to_fine: np.ndarray) -> np.ndarray:
    """Each tyre's log-likelihood on its coarse pressure grid with the other tyre's pressure summed out
    (uniform) on the fine grid: from a track's ℓ (G_f, G_r) on the two coarse grids and the spline
    `to_fine` (P, G) that takes a coarse grid's values to the fine grid, log Σ_p exp of ℓ's rows (the
    front's pressures) and columns (the rear's) splined to the fine grid, (2, G) (the online monitor's
    closure update). Both in one matrix product and one compiled pass (:func:`_log_sums`)."""
    return _log_sums(np.concatenate([ll, ll.T]) @ to_fine.T).reshape(2, -1)


_LOG_SUM_CUT = -50.0
"""Terms of a log-sum more than this below the row's largest are not taken: each is below 2e-22 of the
largest, so a thousand of them change the sum (≥ 1 after the shift) by under 1e-18 of it, far below
its last bit (1.1e-16); they were seven in ten of the exponentials the monitor's closure updates took
on an hour's varied drive (the log-sums' time halved), and all 757 updates' sums came out the same to
the bit (as did the 95 of a 300 s run and three short ones)."""


@cached_njit
def _log_sums(a):
    """log Σ exp along the last axis of `a` (R, N), each row shifted by its maximum (by 0 where that is not
    finite), the terms below :data:`_LOG_SUM_CUT` after the shift left out (:func:`pair_messages`)."""
    n_r, n_n = a.shape
    out = np.empty(n_r)
    for i in range(n_r):
        top = -np.inf
        for j in range(n_n):
            top = max(top, a[i, j])
        if not math.isfinite(top):
            top = 0.0
        total = 0.0
        for j in range(n_n):
            x = a[i, j] - top
            if x > _LOG_SUM_CUT:
                total += math.exp(x)
        out[i] = top + math.log(total)
    return out


@cached_njit(fastmath={"reassoc", "contract"})
def _objective_sums(x_f, x_r, inv_var, moments, out):
    """out[g, h] = Σ_f inv_var[g, h, f] (R[h, f] + Q[g, f] − 2 Re(x_r[h, f] conj(x_f[g, f]) s_bc[f])):
    R the rear's terms, Q the front's (:func:`objective_from_moments`), each made once per grid row."""
    g_f, g_r, n_f = inv_var.shape
    rear = np.empty((g_r, n_f))
    cross_re, cross_im = np.empty((g_r, n_f)), np.empty((g_r, n_f))
    front = np.empty((g_f, n_f))
    for h in range(g_r):
        for f in range(n_f):
            x = x_r[h, f]
            rear[h, f] = (moments[0, f].real + (x.real * x.real + x.imag * x.imag) * moments[1, f].real
                          + 2.0 * (x * moments[3, f]).real)  # fmt: skip
            xb = x * moments[5, f]  # x_r s_bc: its product with conj(x_f) is the cross term
            cross_re[h, f], cross_im[h, f] = xb.real, xb.imag
    for g in range(g_f):
        for f in range(n_f):
            x = x_f[g, f]
            front[g, f] = ((x.real * x.real + x.imag * x.imag) * moments[2, f].real
                           - 2.0 * (x * moments[4, f]).real)  # fmt: skip
    for g in range(g_f):
        for h in range(g_r):
            total = 0.0
            for f in range(n_f):
                cross = cross_re[h, f] * x_f[g, f].real + cross_im[h, f] * x_f[g, f].imag
                total += inv_var[g, h, f] * (rear[h, f] + front[g, f] - 2.0 * cross)
            out[g, h] = total


def objective_from_moments(
    moments: np.ndarray, front: CornerParts | None = None, rear: CornerParts | None = None,
    k_front: np.ndarray | None = None, k_rear: np.ndarray | None = None, *, m: int = 0, dt: float = 0.0,
    band_hz: tuple[float, float] = (0.5, 20.0), tyre_damping: float = 200.0, noise_sigma: float = 0.5,
    weights: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:  # fmt: skip
    r"""J (G_f, G_r) = Σ_f |a + x_r b − x_f c|² / Var from the summed :func:`window_moments`, on the
    grid of :func:`closure_weights` (given as `weights`, or made from the parts, grids and window)."""
    x_f, x_r, inv_var = weights if weights is not None else closure_weights(
        front, rear, k_front, k_rear, m=m, dt=dt, band_hz=band_hz, tyre_damping=tyre_damping,
        noise_sigma=noise_sigma)  # fmt: skip
    saa, sbb, scc, sba, sca, sbc = moments
    rear_part = saa.real + np.abs(x_r) ** 2 * sbb.real + 2.0 * (x_r * sba).real  # (G_r, F)
    front_part = np.abs(x_f) ** 2 * scc.real - 2.0 * (x_f * sca).real  # (G_f, F)
    cross = (x_r[None, :, :] * x_f.conj()[:, None, :] * sbc).real  # (G_f, G_r, F)
    return np.einsum("grf,grf->gr", rear_part[None] + front_part[:, None] - 2.0 * cross, inv_var)


@dataclass(frozen=True)
class ClosureConfig:
    """Settings of :class:`ClosureStream` (units in the names).

    window_s : the Hann windows' length, s (they hop by half; 0.5 s: the module's docstring has the
    lengths measured); margin_s : s of data each side of a
    window (and of its rear's delayed front) over which its accelerations are integrated, tapered to
    zero there (on the first 30 ``constant`` runs, 1 s tapered read the tyres ± 7.1 / 3.0 / 2.2 kPa
    at 10 / 20 / 30 s, 1 s untapered ± 8.0 / 4.0 / 2.8, 2 s tapered ± 10.2 / 3.9 / 2.2: a longer
    margin starts later);
    band_hz : the relation's frequencies; highpass_hz : the integrals' lower limit (:func:`integrate`);
    min_load_share : the share of the static load below which a wheel is taken off the road;
    damper_lag_s : the damper's timing (:func:`corner_signals`); min_speed_mps : slower windows
    are not used (the delay grows past the margin); max_speed_change_per_s : a window whose speed, over
    the window and the largest delay before it, spans more than this share of its mean per second of
    that span is not used (one delay per window; under braking or acceleration the delay drifts
    within the window and the load moves between the axles: on ``nominal_long`` a braking from 115
    to 33 km/h at 1.2 m/s² read all four tyres 30–73 kPa low and warned them with a share of 0.1
    per window, which passed most 0.5 s windows; 0.022 per s is the share 4 s windows had);
    analysis_rate_hz : the rate the integrals and moments run at; spans, span_windows : which windows
    share one span (one integration over them, their delays and the margins): ``ready``, those ready
    at one :meth:`ClosureStream.add`, at most span_windows of them (the monitor feeds its update
    blocks, 8 s: two spans of 16 windows of 0.5 s); ``lattice``, groups of span_windows on a fixed
    lattice, so a window's moments do not depend on how the stream is cut, but a group waits for its
    last window.
    With 0.5 s windows in the monitor (scratch timing on one core of the 2-core machine): lattice
    groups of 2, 4 and 8 cost 6.3, 4.7 and 4.0 ms per second of four-corner data before the stream's
    loops were compiled; after, lattice 4 3.3 and ready 16 2.7 (2.0–2.2 without the closure), at
    alike accuracy (``constant`` with the radii ± 6.56 / 3.62 and ± 6.43 / 3.27 kPa at 10 / 30 s).
    short_window_s, short_below : where fewer than `short_below` of a span's windows that pass the
    speed checks are clear of the stops and of lift-off on a track (a rough road), that track's span
    is read in windows of `short_window_s` instead (hopping by half; it must divide the windows' hop
    of half a window), more of which fit between the wheel's stops and lift-offs; None: never.
    Measured on the 100 ``constant`` runs in the monitor: the share of clear 0.5 s windows per run
    was a median 1.00 on classes A and B, 0.99 on C (0.24 at least) and 0.20 on D (0.75 at most);
    with 0.25 s windows throughout, the monitor read class D's tyres ± 6.6 / 3.0 kPa at 10 / 30 s
    with the radii against ± 10.0 / 4.6 with 0.5 s, but class A's −10.5 ± 6.7 kPa at 30 s against
    −0.7 ± 3.8 (the bins 4 Hz apart leave the relation four frequencies); so the short windows are
    read only where the long ones mostly fail (the module's docstring has the result).
    """

    window_s: float = 0.5
    margin_s: float = 1.0
    band_hz: tuple[float, float] = (0.5, 20.0)
    highpass_hz: float = 0.3
    min_load_share: float = 0.1
    damper_lag_s: float = 0.0
    min_speed_mps: float = 5.0
    max_speed_change_per_s: float = 0.022
    analysis_rate_hz: float = 200.0
    span_windows: int = 16
    spans: str = "ready"
    short_window_s: float | None = 0.25
    short_below: float = 0.5

    def __post_init__(self) -> None:
        checks = [
            ("window_s", 0.5 <= self.window_s <= 30.0, "0.5–30 s"),
            ("margin_s", 0.0 <= self.margin_s <= 30.0, "0–30 s"),
            ("band_hz", 0.0 <= self.band_hz[0] < self.band_hz[1], "0 ≤ low < high, Hz"),
            ("highpass_hz", 0.0 <= self.highpass_hz < self.band_hz[0] + 1e-12, "0 up to band_hz's low end"),
            ("min_load_share", 0.0 <= self.min_load_share < 1.0, "0–1"),
            ("damper_lag_s", 0.0 <= self.damper_lag_s <= 0.01, "0–0.01 s"),
            ("min_speed_mps", 0.5 <= self.min_speed_mps <= 50.0, "0.5–50 m/s"),
            ("max_speed_change_per_s", 0.0 < self.max_speed_change_per_s <= 1.0, "0–1 per s"),
            ("span_windows", isinstance(self.span_windows, int) and 1 <= self.span_windows <= 64, "1–64"),
            ("spans", self.spans in ("ready", "lattice"), "'ready' or 'lattice'"),
            ("short_window_s",
             self.short_window_s is None or 0.05 <= self.short_window_s <= self.window_s / 2,
             "None or 0.05 s up to half window_s"),
            ("short_below", 0.0 <= self.short_below <= 1.0, "0–1"),
            ("analysis_rate_hz", self.analysis_rate_hz >= 2.0 * self.band_hz[1],
             "at least twice band_hz's top"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"ClosureConfig.{name} = {getattr(self, name)!r} is outside {allowed}")


@dataclass(frozen=True)
class ClosureBlock:
    """What one :meth:`ClosureStream.add` found: per track its new windows' summed moments
    (T, :data:`MOMENTS`, F) and how many windows (T,); windows passed over (no contact, a stop, the
    speed) beside them (T,); and the same of the short windows read where the windows were mostly
    not clear (:class:`ClosureConfig`'s ``short_window_s``; moments (T, MOMENTS, F_short): their bins
    are wider; F_short 0 and no windows where the stream reads none)."""

    moments: np.ndarray
    windows: np.ndarray
    skipped: np.ndarray
    short_moments: np.ndarray | None = None
    short_windows: np.ndarray | None = None
    short_skipped: np.ndarray | None = None


class ClosureStream:
    """The force closure fed in time order: each track's window moments, each window once.

    `parts` (C,) the corners' :class:`CornerParts`; `tracks` ((front, rear), ...) corner indices, each
    corner's anti-roll partner the same place on the other track (so two tracks); `wheelbase_m` the
    front-to-rear distance; `dt` the sampling interval, s. Windows start every half window on the
    stream's sample count; a window is analysed once the stream holds ``margin_s`` beyond it, from a
    span (:class:`ClosureConfig`'s ``spans``) of the windows, their fronts' delay and the margins,
    all four corners' samples valid
    (:meth:`add`'s `valid`); an invalid sample restarts the buffer after it. The state is that buffer:
    bounded by the window, the margins, the largest delay and the longest block given.
    """

    def __init__(self, parts, tracks, wheelbase_m: float, dt: float, config: ClosureConfig | None = None):
        self.config = cfg = config or ClosureConfig()
        self.parts = tuple(parts)
        self.tracks = tuple((int(f), int(r)) for f, r in tracks)
        if len(self.tracks) != 2 or len({c for pair in self.tracks for c in pair}) != 4:
            raise InputError("ClosureStream needs two tracks of distinct corners, ((fl, rl), (fr, rr))")
        if not (np.isfinite(wheelbase_m) and wheelbase_m > 0):
            raise InputError(f"ClosureStream: wheelbase_m must be > 0 m, got {wheelbase_m!r}")
        (fl, rl), (fr, rr) = self.tracks
        self.partner = {fl: fr, fr: fl, rl: rr, rr: rl}
        self.wheelbase = float(wheelbase_m)
        self.dt = float(dt)
        # the analysis runs on every q-th sample (the spectrum cut at the new Nyquist frequency); the
        # lattice, margins and largest delay in input samples, multiples of q
        self.q = q = max(1, int(round(1.0 / (cfg.analysis_rate_hz * dt))))
        self.m = q * max(int(round(cfg.window_s / (q * dt))) // 2 * 2, 2)
        self.margin = q * int(math.ceil(cfg.margin_s / (q * dt)))
        self.max_shift = q * int(math.ceil(self.wheelbase / cfg.min_speed_mps / (q * dt)) + 1)
        self.n_bins = band_of(self.m // q, q * dt, cfg.band_hz).size
        # the short windows (ClosureConfig.short_window_s): a whole number of their hops in the windows' hop
        self.m_short = 0
        if cfg.short_window_s is not None:
            self.m_short = q * max(int(round(cfg.short_window_s / (q * dt))) // 2 * 2, 2)
            if (self.m // 2) % (self.m_short // 2) or self.m_short >= self.m:
                raise InputError(f"ClosureConfig.short_window_s = {cfg.short_window_s!r} must hop a whole "
                                 f"number of times in window_s's hop of {cfg.window_s / 2!r} s")  # fmt: skip
        self.n_bins_short = band_of(self.m_short // q, q * dt, cfg.band_hz).size if self.m_short else 0
        self._tapers: dict[int, np.ndarray] = {}  # the spans' tapers by length (_analyse)
        self._spans: dict[int, tuple[np.ndarray, ...]] = {}  # the spans' work arrays by length (_arrays)
        # what _analyse's compiled passes take, made once: the corners in the tracks (sorted) as rows,
        # each one's axle partner's row, each track's front and rear rows, the corners' parts as arrays
        corners = sorted({c for pair in self.tracks for c in pair})
        row = {c: i for i, c in enumerate(corners)}
        self._corners = np.array(corners, dtype=np.int64)
        self._partner_rows = np.array([row[self.partner[c]] for c in corners], dtype=np.int64)
        self._front_rows = np.array([row[f] for f, _ in self.tracks], dtype=np.int64)
        self._rear_rows = np.array([row[r] for _, r in self.tracks], dtype=np.int64)
        self._law_values = np.array([self.parts[c].law.values for c in corners], dtype=float)
        self._corner_values = np.array([(p.unsprung_mass, p.anti_roll, p.static_travel, p.static_load)
                                        for p in (self.parts[c] for c in corners)], dtype=float)  # fmt: skip
        self.reset()

    def weights(self, front: int, rear: int, k_front, k_rear, *, tyre_damping: float, noise_sigma: float,
                short: bool = False):
        """:func:`closure_weights` of the track (`front`, `rear`) on the grids `k_front`, `k_rear` (N/m) for
        this stream's windows (`short`: its short windows'): the accelerometers' white noise
        `noise_sigma` (m/s² per input sample) is σ/√q per analysed sample (its power cut at the
        analysis's Nyquist frequency)."""
        m = self.m_short if short else self.m
        if m == 0:
            raise InputError("ClosureStream.weights(short=True): the stream reads no short windows")
        return closure_weights(self.parts[front], self.parts[rear], np.asarray(k_front, dtype=float),
                               np.asarray(k_rear, dtype=float), m=m // self.q, dt=self.q * self.dt,
                               band_hz=self.config.band_hz, tyre_damping=tyre_damping,
                               noise_sigma=noise_sigma / math.sqrt(self.q))  # fmt: skip

    def _taper(self, n: int) -> np.ndarray:
        """The `n`-sample span's Tukey taper (n,): the margins each side from zero up to one (made once
        per span length: a stream's spans have one length)."""
        if n not in self._tapers:
            self._tapers[n] = scipy.signal.windows.tukey(n, 2.0 * self.margin / n)
        return self._tapers[n]

    def _arrays(self, n: int) -> tuple[np.ndarray, ...]:
        """An `n`-sample span's work arrays, made once per span length and reused (the span's tapered
        accelerations (2K, size), their spectrum, the integrals' spectra (4K, bins), the integrals (4K,
        size / q), the corners' forces and usable samples (K, n / q); K corners, size the transform's
        fast length): with 0.5 s windows a span's arrays are about half a megabyte each; reused, the
        stream took 0.51 s instead of 0.58 s over an hour's drive (replayed on one core)."""
        if n not in self._spans:
            if len(self._spans) > 8:  # a stream's spans have a few lengths: a bound all the same
                self._spans.clear()
            q, n_k = self.q, self._corners.size
            size = q * scipy.fft.next_fast_len(-(-n // q), real=True)
            kept = size // q // 2 + 1
            n_q = -(-n // q)
            self._spans[n] = (np.empty((2 * n_k, size)), np.empty((2 * n_k, size // 2 + 1), dtype=complex),
                              np.empty((4 * n_k, kept), dtype=complex), np.empty((4 * n_k, size // q)),
                              np.empty((n_k, n_q)), np.empty((n_k, n_q), dtype=bool))  # fmt: skip
        return self._spans[n]

    def reset(self) -> None:
        """Forget the buffer (the next window starts once enough valid samples are in)."""
        n_c = len(self.parts)
        self._v = np.empty(0)
        # the accelerations as (C, samples): each corner's a row, as _tapered_span reads them
        self._a_s, self._a_u = np.empty((n_c, 0)), np.empty((n_c, 0))
        self._first = 0  # the stream's sample index of the buffer's first sample
        self._next = None  # the stream's sample index of the next window's start (rear)

    def add(self, speed_mps, acc_sprung, acc_unsprung, valid) -> ClosureBlock:
        """Consume the next samples: speed (n,) m/s, body and wheel vertical accelerations (n, C) m/s²
        (gravity removed), `valid` (n,) bool (False: a gap or a faulty sample in any corner)."""
        v = np.asarray(speed_mps, dtype=float)
        a_s, a_u = np.asarray(acc_sprung, dtype=float), np.asarray(acc_unsprung, dtype=float)
        ok = _valid_samples(np.asarray(valid, dtype=bool), v, a_s, a_u)
        n_t = len(self.tracks)
        moments = np.zeros((n_t, MOMENTS, self.n_bins), dtype=complex)
        windows, skipped = np.zeros(n_t, dtype=int), np.zeros(n_t, dtype=int)
        short = (np.zeros((n_t, MOMENTS, self.n_bins_short), dtype=complex), np.zeros(n_t, dtype=int),
                 np.zeros(n_t, dtype=int))  # fmt: skip
        end = self._first + self._v.size + v.size
        bad = np.flatnonzero(~ok)
        if bad.size:  # start afresh after the last invalid sample
            keep = slice(int(bad[-1]) + 1, None)
            self._v = v[keep]
            self._a_s, self._a_u = np.ascontiguousarray(a_s[keep].T), np.ascontiguousarray(a_u[keep].T)
            self._first = end - self._v.size
            self._next = None
        else:
            self._v = np.concatenate([self._v, v])
            self._a_s = np.concatenate([self._a_s, a_s.T], axis=1)
            self._a_u = np.concatenate([self._a_u, a_u.T], axis=1)
        cfg = self.config
        half = self.m // 2
        if self._next is None:  # the first start on the half-window lattice with room for the delay
            earliest = self._first + self.margin + self.max_shift
            self._next = -(-earliest // half) * half
        group = cfg.span_windows * half  # the windows of a group share one span
        while True:
            if cfg.spans == "lattice":
                last = (self._next // group) * group + group - half  # the group's last start
            else:  # the windows ready now, at most span_windows of them
                ready = (end - self.m - self.margin) // half * half
                last = min(ready, self._next + group - half)
            if last < self._next or last + self.m + self.margin > end:
                break
            self._analyse(list(range(self._next, last + 1, half)), moments, windows, skipped, short)
            self._next = last + half
        # keep what the next window needs: its delayed front and the margin before it
        drop = max(0, min(self._next - self.max_shift - self.margin, end) - self._first)
        self._v, self._a_s, self._a_u = self._v[drop:], self._a_s[:, drop:], self._a_u[:, drop:]
        self._first += drop
        return ClosureBlock(moments, windows, skipped, *short)

    def _analyse(self, starts, moments, windows, skipped, short) -> None:
        """The moments of the windows starting at `starts` (a group: those ready, or a group on the fixed
        lattice) from one span: their delayed fronts and the margins. The speed checks come first: a
        group none of whose windows passes them needs no integrals. A track fewer than
        ``short_below`` of whose windows passing the speed checks are clear is read in the short
        windows instead (`short`: their moments, counts used and passed over, added to): those
        starting from `starts[0]` every half short window up to the next group's first start."""
        cfg = self.config
        q, dt = self.q, self.q * self.dt
        lo = starts[0] - self.max_shift - self.margin - self._first
        hi = starts[-1] + self.m + self.margin - self._first
        # each window's speed over it and the largest delay before it, the windows a half window apart
        # (those passing: their rear windows' and delayed fronts' first samples in the span, analysed
        # samples, and the delays' fractions of a sample, s)
        length = self.max_shift + self.m
        rear_at, front_at, fraction = _window_speeds(
            self._v, starts[0] - self._first - self.max_shift, self.m // 2, length, len(starts),
            cfg.min_speed_mps, cfg.max_speed_change_per_s, length * self.dt, self.wheelbase, dt,
            (starts[0] - self._first - lo) // q, self.m // 2 // q)  # fmt: skip
        skipped += len(starts) - rear_at.size
        if rear_at.size == 0:
            return
        # the margins tapered (Tukey) to zero: the integrals' error from the span's ends becomes a slow
        # drift in the windows instead of the circular FFT's jump
        n = hi - lo
        taper = self._taper(n)
        # each corner's relative and wheel accelerations less their means, tapered, zero-padded: one
        # transform for the two integrals (:func:`integrate`'s, the travel's and its rate from the
        # first, the wheel's height and its decimated acceleration from the second), into the span
        # length's arrays (numpy's transforms write into them: scipy's, which :func:`integrate` uses,
        # give the same numbers to the bit here, but allocate)
        acc, spectrum, product, series, force, usable = self._arrays(n)
        size, n_k = acc.shape[1], self._corners.size
        _tapered_span(self._a_s, self._a_u, lo, hi, taper, self._corners, acc)
        np.fft.rfft(acc, axis=-1, out=spectrum)
        gains = _integration_gains(size, self.dt, (2, 1, 0), cfg.highpass_hz, cfg.damper_lag_s, q)
        kept = gains.shape[1]
        np.multiply(spectrum[:, :kept], gains[0], out=product[: 2 * n_k])  # the travels', the heights
        np.multiply(spectrum[:n_k, :kept], gains[1], out=product[2 * n_k : 3 * n_k])  # the rates
        np.multiply(spectrum[n_k:, :kept], gains[2], out=product[3 * n_k :])  # the wheels' accelerations
        np.fft.irfft(product, n=size // q, axis=-1, out=series)
        motion, z_u, rate, wheel = (series[i * n_k : (i + 1) * n_k, : force.shape[1]] for i in range(4))
        _span_forces(wheel, motion, rate, self._partner_rows, self._law_values, self._corner_values,
                     cfg.min_load_share, force, usable)  # fmt: skip
        part, used = _rows_moments(z_u, force, usable, self._front_rows, self._rear_rows, rear_at, front_at,
                                   fraction, self.m // q, dt=dt, band_hz=cfg.band_hz)  # fmt: skip
        rough = (used < cfg.short_below * rear_at.size) if self.m_short else np.zeros(used.size, dtype=bool)
        keep = ~rough
        moments[keep] += part[keep]
        windows[keep] += used[keep]
        skipped += np.where(keep, rear_at.size - used, 0)
        if not rough.any():
            return
        # the rough tracks' short windows: the same span, a whole number of them in each window's hop
        ms = self.m_short
        n_ws = len(starts) * ((self.m // 2) // (ms // 2))
        length = self.max_shift + ms
        rear_s, front_s, fraction_s = _window_speeds(
            self._v, starts[0] - self._first - self.max_shift, ms // 2, length, n_ws,
            cfg.min_speed_mps, cfg.max_speed_change_per_s, length * self.dt, self.wheelbase, dt,
            (starts[0] - self._first - lo) // q, ms // 2 // q)  # fmt: skip
        rows = np.flatnonzero(rough)
        part_s, used_s = _rows_moments(z_u, force, usable, self._front_rows[rows], self._rear_rows[rows],
                                       rear_s, front_s, fraction_s, ms // q, dt=dt,
                                       band_hz=cfg.band_hz)  # fmt: skip
        short[0][rows] += part_s
        short[1][rows] += used_s
        short[2][rows] += n_ws - used_s


@cached_njit
def _valid_samples(valid, v, a_s, a_u):
    """Per sample (n,), `valid` and the speed `v` (n,) and every corner's accelerations `a_s`, `a_u` (n, C)
    finite, in one pass (:meth:`ClosureStream.add`)."""
    ok = np.empty(v.size, dtype=np.bool_)
    for i in range(v.size):
        good = valid[i] and math.isfinite(v[i])
        for c in range(a_s.shape[1]):
            good = good and math.isfinite(a_s[i, c]) and math.isfinite(a_u[i, c])
        ok[i] = good
    return ok


@cached_njit
def _window_speeds(v, first, hop, length, n_w, min_speed, max_change, span_s, wheelbase, dt, rear_first,
                   rear_hop):  # fmt: skip
    """The speed checks of `n_w` windows (:meth:`ClosureStream._analyse`) and where those passing sit: each
    window's mean speed over `length` samples of `v` from first + w·hop (numpy's mean to the bit,
    :func:`_pairwise_sum`) at least `min_speed` (m/s) and its range (max − min) at most `max_change`
    (per s) times the mean times `span_s` (s); for those, the rear window's first analysed sample
    rear_first + w·rear_hop, the delayed front's (the delay, `wheelbase` over the mean, in whole
    analysed samples of `dt` s, rounded), and the delay's remaining fraction (s): three (U,) arrays."""
    rear_at, front_at, fraction = np.empty(n_w, dtype=np.int64), np.empty(n_w, dtype=np.int64), np.empty(n_w)
    u = 0
    for w in range(n_w):
        lo = first + w * hop
        mean = _pairwise_sum(v, lo, length) / length
        top = bottom = v[lo]
        for j in range(lo + 1, lo + length):
            top = max(top, v[j])
            bottom = min(bottom, v[j])
        if mean < min_speed or top - bottom > max_change * mean * span_s:
            continue
        delay = wheelbase / mean
        shift = np.rint(delay / dt)
        rear_at[u] = rear_first + w * rear_hop
        front_at[u] = rear_at[u] - int(shift)
        fraction[u] = delay - shift * dt
        u += 1
    return rear_at[:u], front_at[:u], fraction[:u]


@cached_njit
def _pairwise_sum(x, lo, n):
    """The sum of x[lo : lo + n] as numpy sums a contiguous float64 array (its pairwise summation: eight
    partial sums over blocks of at most 128, halves above), so a compiled mean is numpy's to the bit."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += x[i]
        return res
    if n <= 128:
        r0, r1, r2, r3 = x[lo], x[lo + 1], x[lo + 2], x[lo + 3]
        r4, r5, r6, r7 = x[lo + 4], x[lo + 5], x[lo + 6], x[lo + 7]
        i = 8
        while i < n - n % 8:
            r0 += x[lo + i]
            r1 += x[lo + i + 1]
            r2 += x[lo + i + 2]
            r3 += x[lo + i + 3]
            r4 += x[lo + i + 4]
            r5 += x[lo + i + 5]
            r6 += x[lo + i + 6]
            r7 += x[lo + i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += x[lo + i]
            i += 1
        return res
    half = n // 2
    half -= half % 8
    return _pairwise_sum(x, lo, half) + _pairwise_sum(x, lo + half, n - half)


@cached_njit
def _tapered_span(a_s, a_u, lo, hi, taper, corners, out):
    """Each of `corners`' (K,) body and wheel accelerations `a_s`, `a_u` (C, n) over the samples `lo`…`hi`,
    less their means there, times `taper` (hi − lo,), less the tapered series' mean (:func:`integrate`'s):
    the wheel's minus the body's into out[:K, :hi − lo], the wheel's into out[K:, :hi − lo] (m/s²), the
    rest of `out` (2K, size) zero: the transform's padding (:meth:`ClosureStream._analyse`). A corner's
    samples side by side (its row): 1.4 times faster than down a column of (n, C)."""
    n = hi - lo
    n_k = corners.size
    for i in range(n_k):
        body, wheel = a_s[corners[i], lo:hi], a_u[corners[i], lo:hi]
        mean_s = mean_u = 0.0
        for j in range(n):
            mean_s += body[j]
            mean_u += wheel[j]
        mean_s /= n
        mean_u /= n
        total_r = total_u = 0.0
        for j in range(n):
            u = (wheel[j] - mean_u) * taper[j]
            r = u - (body[j] - mean_s) * taper[j]
            out[i, j] = r
            out[n_k + i, j] = u
            total_r += r
            total_u += u
        total_r /= n
        total_u /= n
        for j in range(n):
            out[i, j] -= total_r
            out[n_k + i, j] -= total_u
        for j in range(n, out.shape[1]):
            out[i, j] = 0.0
            out[n_k + i, j] = 0.0


@cached_njit
def _span_forces(wheel, motion, rate, partner, values, corner, min_share, force, usable):
    """Each of a span's corners' dynamic tyre force `force` and usable samples `usable` (K, n) from its
    wheel's acceleration, travel about its mean and its rate (K, n), the other corner of its axle at row
    `partner` (K,), its law's values `values` (K, 13) and (unsprung mass, anti-roll rate, static travel,
    static load) `corner` (K, 4): :func:`_corner_signal` for all K in one call (the travel's mean the
    static one less the jacking, :func:`suvtwin.suspension_law.equivalent_spring_rate`)."""
    for i in range(wheel.shape[0]):
        s0 = corner[i, 2]
        mean = _equivalent(values[i], s0, max(_spread(motion[i]), _SIGMA_FLOOR),
                           max(_spread(rate[i]), _SIGMA_FLOOR))[0]  # fmt: skip
        _force_balance(wheel[i], motion[i], rate[i], motion[partner[i]], values[i], mean, s0, corner[i, 0],
                       corner[i, 1], corner[i, 3], min_share, force[i], usable[i])  # fmt: skip
