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
tyres. Not yet part of the monitor:
missing are a calibrated scale for J (the noise alone makes it far too sharp: the model's own error
dominates; scaled by its minimum over its degrees of freedom, as if that error were white, ±2σ held
the truth for 78 % of the tyres at 10 s and at 30 s with the timing read from the data, 64 % and
30 % without) and the online form.

No MuJoCo here: the functions consume arrays.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.suspension_law import SuspensionLaw, damper_force, equivalent_spring_rate, spring_force

__all__ = ["ClosureFit", "CornerParts", "CornerSignals", "closure_objective", "corner_signals", "integrate"]


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


def integrate(acc: npt.ArrayLike, dt: float, order: int | tuple[int, ...], highpass_hz: float = 0.3):
    """The `order`-fold time integral of `acc` (1: velocity, 2: displacement; a tuple of orders gives
    a tuple of integrals from one transform), by the FFT over the whole array, frequencies below
    `highpass_hz` (Hz) removed (circular: use the middle, or a tapered window, of what it returns)."""
    x = np.asarray(acc, dtype=float)
    spectrum = np.fft.rfft(x - x.mean())
    omega = 2.0 * np.pi * np.fft.rfftfreq(x.size, dt)
    keep = omega > 2.0 * np.pi * highpass_hz
    out = []
    for k in (order,) if isinstance(order, int) else order:
        part = np.zeros_like(spectrum)
        part[keep] = spectrum[keep] / (1j * omega[keep]) ** k
        out.append(np.fft.irfft(part, n=x.size))
    return out[0] if isinstance(order, int) else tuple(out)


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
    s0 = parts.static_travel
    law = parts.law
    motion, rate = integrate(acc_u - acc_s, dt, (2, 1), highpass_hz)
    if damper_lag_s:
        spectrum = np.fft.rfft(rate)
        rate = np.fft.irfft(spectrum * np.exp(-2j * np.pi * np.fft.rfftfreq(rate.size, dt) * damper_lag_s),
                            n=rate.size)  # fmt: skip
    # the mean travel: the static one less the asymmetric damper's jacking down (and the progressive
    # spring's push up), for a Gaussian travel of the measured spreads (the monitor's linearization)
    mean = s0
    if jacking:
        mean = float(equivalent_spring_rate(law, s0, float(motion.std()), float(rate.std()))[0])
    travel = motion + mean
    motion_other = integrate(acc_u_other - acc_s_other, dt, 2, highpass_hz)
    spring = spring_force(travel, law) - float(spring_force(np.array([s0]), law)[0])
    bar = parts.anti_roll * (motion - motion_other)
    force = parts.unsprung_mass * acc_u + spring + damper_force(rate, law) + bar
    usable = ((parts.static_load + force > min_load_share * parts.static_load)
              & (travel < law.bump_clearance) & (travel > -law.rebound_clearance))  # fmt: skip
    return CornerSignals(integrate(acc_u, dt, 2, highpass_hz), force, usable, parts)


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
    white noise per sample (m/s²)."""
    k = np.asarray(stiffness_grid, dtype=float)
    if k.ndim != 1 or k.size < 2 or not np.all(k > 0):
        raise InputError("closure_objective: stiffness_grid must be 1-D, at least 2 values, all > 0 N/m")
    if not (np.isfinite(delay_s) and delay_s > 0):
        raise InputError(f"closure_objective: delay_s must be > 0 s, got {delay_s!r}")
    m = int(round(window_s / dt))
    n = front.z_u.size
    shift = int(round(delay_s / dt))
    frac = delay_s / dt - shift
    freq = np.fft.rfftfreq(m, dt)
    band = (freq > band_hz[0]) & (freq < band_hz[1])
    omega = 2.0 * np.pi * freq[band]
    hann = np.hanning(m)
    phase = np.exp(-1j * omega * frac * dt)
    x = 1.0 / (k[:, None] + 1j * omega[None, :] * tyre_damping)  # (G, F)
    gains = _noise_gain(front.parts, x, omega)[:, None, :] + _noise_gain(rear.parts, x, omega)[None, :, :]
    variance = noise_sigma**2 * np.sum(hann**2) * gains
    objective = np.zeros((k.size, k.size))
    used = total = 0
    for start in range(shift, n - m + 1, m // 2):
        total += 1
        r, f = slice(start, start + m), slice(start - shift, start - shift + m)
        if not (rear.usable[r].all() and front.usable[f].all()):
            continue
        used += 1
        dft = [np.fft.rfft((s - s.mean()) * hann)[band] for s in (rear.z_u[r], rear.force[r], front.z_u[f],
                                                                   front.force[f])]  # fmt: skip
        zr, fr, zf, ff = dft[0], dft[1], dft[2] * phase, dft[3] * phase
        residual = (zr + x * fr)[None, :, :] - (zf + x * ff)[:, None, :]  # (front, rear, F)
        objective += np.sum(np.abs(residual) ** 2 / variance, axis=-1)
    best = tuple(int(i) for i in np.unravel_index(np.argmin(objective), objective.shape)) if used else None
    return ClosureFit(objective, best, used, total)
