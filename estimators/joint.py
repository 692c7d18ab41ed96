r"""Road-level-free tire-stiffness estimator: joint Whittle likelihood over (k_t, road level).

Usual call: ``est = estimate_joint(acc_s, acc_us, dt, qc=qc, speed_mps=16.7)``.

Why (``docs/DESIGN.md``, "Identifiability of tyre stiffness"): from the two accelerations
alone every k_t fits if the road is free; what decides k_t is the road's *spectrum*. Assuming a road
level biases k_t along :math:`k_t \propto G_d^{-1/2}` (above the wheel hop the
unsprung acceleration is :math:`(k_t/m_{us})^2` times the road PSD), and real roads
sit anywhere in a class band (4× in :math:`G_d`). So the level is estimated jointly.

Model: a linear quarter car (``qc``: :math:`m_s, m_{us}, k_s, c_s`) driven by an ISO
road of waviness 2 at speed v, whose road *velocity* is white with one-sided PSD
:math:`S_v = 4\pi^2 G_d(n_0)\,n_0^2\,v`, plus white accelerometer noise of
variance :math:`\sigma^2` on each channel (one-sided PSD :math:`N = 2\sigma^2\Delta t`).
The 2×2 cross-spectral matrix of :math:`[\ddot z_s, \ddot z_{us}]` is

.. math:: S(f) = S_v\,h(f)h(f)^H + N\,I,

with :math:`h` the response to road velocity. Whittle's likelihood [1]_

.. math:: \log L(k_t, G_d) = -K\sum_f \left[\log\det S(f) + \mathrm{tr}(S(f)^{-1}\hat S(f))\right]

(:func:`whittle_loglik`) reduces to a scalar one: the direction :math:`u = h/|h|`
of the signal does not depend on :math:`k_t` (the sprung mass sees only the
suspension, :math:`h_1/h_2 = (k_s + c_s s)/(m_s s^2 + k_s + c_s s)`), the part of
the data orthogonal to it is noise only, and up to a constant

.. math:: \log L = -K\sum_f \left[\log(1 + r_f) + \frac{P_f}{1 + r_f}\right],\qquad
   r_f = S_v |h(f)|^2 / N,\quad P_f = u^H\hat S(f)\,u / N.

By default :math:`\hat S` is the periodogram of the whole record so far (linear
detrend, rectangular window, one term per Fourier frequency, K = 1): the exact
Whittle likelihood, which keeps the record's full frequency resolution. Averaging
Bartlett segments (``segment_s``, the earlier estimator's spectrum) coarsens the
resolution and costs precision (``python bench/joint_accuracy.py 2,11,7,3,5 10 2``
against the default; README, "Benchmarks").
For each k_t on a grid of pressures (1 kPa) the level is profiled out by Fisher
scoring in :math:`\log S_v`, and the marginal over the level (log-uniform prior
over `level_grid`'s range) is taken by Laplace's method. The posterior (flat in
pressure) gives k_t, its σ and the level.
The band is where the road follows the ISO slope and the tire does not envelop it
(default 0.05–1.5 cycles/m times the speed, at most 30 Hz). The estimate is refreshed
every `update_s` seconds on all data so far.

Waviness: the above assumes the ISO classes' slope, w = 2 (road velocity white). Measured
roads bend away from it (w between about 1.5 and 3), and a wrong slope is read as a wrong
k_t, since above the wheel hop the signal is :math:`k_t^2 S_v` times the road's slope. So the
road-velocity PSD is :math:`S_v(n_0)(n/n_0)^{\beta}`, :math:`\beta = 2 - w`, and β is profiled with
the level (:func:`profile_loglik_slope`, Fisher scoring in (λ, β)), the pair marginalized by Laplace.
A free slope is nearly collinear with k_t, so it costs precision on ISO roads. The prior on w is
therefore a spike and slab: w = 2 with probability `waviness_iso_weight` (default 0.8), else
uniform over the range; each profile's marginal likelihood weighs the two, so the default keeps
nearly the w = 2 model's precision on w = 2 roads and removes most of the bias on others
(``python bench/joint_waviness.py``: fixed, free and spike-and-slab slope on quarter-car truth
and on the MuJoCo SUV; numbers in the README, "Benchmarks"). ``waviness=2.0`` is the former
model, bit for bit; the free slope adds a second profiled parameter and so costs run time.

Precision: the pressure-error std is at the Cramér–Rao bound of this Gaussian road model
(``python bench/joint_accuracy.py`` prints both). On the superposition roads of
:mod:`suvtwin.roads.profile`, whose lines have fixed amplitudes, the periodogram scatters less
than a Gaussian road's once the record resolves the lines, so over long records the error can
fall below that bound.

References
----------
.. [1] P. Whittle, "Curve and periodogram smoothing", J. R. Stat. Soc. B 19(1), 1957.
.. [2] R. Brancati, F. Tufano, Machines 10(12), 1221, 2022, eq. 1–4 (the quarter car and k_t(p)).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np
import numpy.typing as npt
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.estimators.full_car import FullCar
from suvtwin.estimators.quarter_car import (
    pressure_from_stiffness,
    pressure_sigma_from_stiffness_sigma,
    stiffness_from_pressure,
)
from suvtwin.jit import cached_njit
from suvtwin.suspension_law import SuspensionLaw
from suvtwin.tire_stiffness import TireStiffness, suv_tire_stiffness

__all__ = [
    "JointEstimate",
    "corner_response",
    "envelope_power",
    "signal_direction",
    "signal_gain",
    "LinearQuarterCar",
    "estimate_joint",
    "profile_loglik",
    "profile_loglik_slope",
    "whittle_loglik",
]

N0 = 0.1  # cycles/m, ISO reference spatial frequency
_2PI = 2.0 * np.pi
_CHUNK = 4_000_000  # elements of the (runs, stiffness, frequency) arrays handled at once


@dataclass(frozen=True)
class LinearQuarterCar:
    r"""Linear corner model: masses (kg), suspension rate k_s (N/m) and damping c_s (N s/m).

    The optional fields (defaults: the plain quarter car) describe a vehicle corner:

    - ``tire_damping`` c_t (N s/m): radial tire damping, the road force is
      :math:`k_t(z_r - z_{us}) + c_t(\dot z_r - \dot z_{us})`.
    - ``roll_mass`` (kg) and ``anti_roll`` (N/m, wheel-rate equivalent of the bar): the roll-plane
      model. With independent left and right tracks of equal PSD, the corner's response is half a
      heave quarter car (``sprung_mass``, k_s) plus half a roll quarter car (``roll_mass``,
      :math:`k_s + 2k_{arb}`) excited by independent roads, so the signal spectrum is
      :math:`\tfrac12 S_v(h_H h_H^H + h_R h_R^H)` (rank 2). None: no roll mode.
    - ``damping_range`` (N s/m): the equivalent linear damping is only known to lie in this range
      (a digressive damper's slopes); the estimator marginalizes over it (uniform prior).
    - ``suspension`` and ``static_travel`` (m, compression from the design position at rest):
      the corner's non-linear spring and damper laws (:class:`suvtwin.suspension_law.SuspensionLaw`,
      whose ``spring_rate`` is ``spring_rate`` here). An estimator that has them replaces
      ``spring_rate`` by the equivalent rate at the travel it measures
      (:func:`suvtwin.suspension_law.equivalent_spring_rate`; the online monitor does); None: the
      spring is linear.
    - ``full_car`` and ``corner`` (index fl 0, fr 1, rl 2, rr 3): the corner's place in a linear
      full car (:class:`suvtwin.estimators.full_car.FullCar`). An estimator that has it and knows
      the speed models the corner's spectrum as the full car's on two tracks, the rear wheels
      re-running the front wheels' road (the online monitor does; ``roll_mass`` is then unused);
      the others use the roll-plane model.
    - ``envelope_half_length`` (m): the tyre reads the road as its cos²-weighted mean over ±this
      length along the track (enveloping over the contact patch, :func:`envelope_power`); an
      estimator that knows the speed multiplies the road's PSD by the mean's power gain (the
      online monitor does). 0: a point contact.
    - ``static_load`` (N): the tyre's static vertical force, the car's weight shared by its centre
      of gravity (loads included); None: (m_s + m_us) g. The online monitor's tyre-contact share
      compares the dynamic wheel load with it.
    """

    sprung_mass: float
    unsprung_mass: float
    spring_rate: float
    damping: float
    tire_damping: float = 0.0
    roll_mass: float | None = None
    anti_roll: float = 0.0
    damping_range: tuple[float, float] | None = None
    suspension: SuspensionLaw | None = None
    static_travel: float = 0.0
    full_car: FullCar | None = None
    corner: int = 0
    envelope_half_length: float = 0.0
    static_load: float | None = None


@dataclass(frozen=True)
class JointEstimate:
    """Per-time-step output (runs first): stiffness and pressure with σ, road level estimate."""

    t_s: np.ndarray
    stiffness: np.ndarray
    stiffness_sigma: np.ndarray
    pressure_pa: np.ndarray
    pressure_sigma_pa: np.ndarray
    road_level: np.ndarray
    info: dict


def envelope_power(n: npt.ArrayLike, half_length: float) -> np.ndarray:
    r"""Power gain of the tyre's enveloping at spatial frequency `n` (cycles/m), (same shape).

    The tyre reads the road as its mean over ±`half_length` (m) weighted by
    :math:`\cos^2(\pi s / 2l)`, the effective road height of enveloping tyre models in their
    simplest form (Schmeitz 2004; Pacejka 2012, §10.2); the weight is a Hann window of length
    L = 2l, whose transform is :math:`\mathrm{sinc}(nL)/(1 - (nL)^2)` (sinc(x) = sin(πx)/(πx)).
    Returned squared (a PSD factor); 1 for `half_length` 0."""
    x = 2.0 * float(half_length) * np.asarray(n, dtype=float)
    near = np.abs(np.abs(x) - 1.0) < 1e-6  # the removable singularity at nL = 1: the limit 1/2
    gain = np.where(near, 0.5, np.sinc(x) / np.where(near, 1.0, 1.0 - x**2))
    return gain**2


def corner_response(
    f: np.ndarray, kt: np.ndarray, qc: LinearQuarterCar, *, roll: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Sprung and unsprung acceleration per unit road velocity, shape broadcast(kt, f).

    `roll`: the roll quarter car of the roll-plane model (``roll_mass``, k_s + 2 k_arb).
    """
    s = 2j * np.pi * f
    ms = qc.roll_mass if roll else qc.sprung_mass
    ksc = qc.spring_rate + (2.0 * qc.anti_roll if roll else 0.0) + qc.damping * s
    ktc = kt + qc.tire_damping * s
    a11 = ms * s**2 + ksc
    a22 = qc.unsprung_mass * s**2 + ksc + ktc
    det = a11 * a22 - ksc**2
    zs = ksc * ktc / det  # per unit road elevation
    zu = a11 * ktc / det
    return s * zs, s * zu  # acceleration s^2 Z per road velocity s Zr


def signal_gain(f: np.ndarray, kt: np.ndarray, qc: LinearQuarterCar) -> np.ndarray:
    r"""Signal power along u per unit road-velocity PSD, :math:`u^H M u`, shape broadcast(kt, f).

    Quarter car: :math:`|h|^2`. Roll-plane model: :math:`\tfrac12(|u^H h_H|^2 + |u^H h_R|^2)`.
    """
    h1, h2 = corner_response(f, kt, qc)
    if qc.roll_mass is None:
        return np.abs(h1) ** 2 + np.abs(h2) ** 2
    u1, u2 = signal_direction(f, qc)
    g1, g2 = corner_response(f, kt, qc, roll=True)
    return 0.5 * (
        np.abs(np.conj(u1) * h1 + np.conj(u2) * h2) ** 2 + np.abs(np.conj(u1) * g1 + np.conj(u2) * g2) ** 2
    )


def signal_direction(f: np.ndarray, qc: LinearQuarterCar) -> tuple[np.ndarray, np.ndarray]:
    """Unit vector u = h/|h| of the road-driven part of [acc_s, acc_us] (independent of k_t), (F,) each.

    For the roll-plane model, the heave quarter car's direction (the projection is then the exact
    likelihood of the projected series, not of the pair)."""
    s = 2j * np.pi * f
    ksc = qc.spring_rate + qc.damping * s
    a11 = qc.sprung_mass * s**2 + ksc
    norm = np.sqrt(np.abs(ksc) ** 2 + np.abs(a11) ** 2)
    return ksc / norm, a11 / norm


def _spectrum(x: np.ndarray, dt: float, segment: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Bartlett cross-spectral matrix of x (2, T): f (F,), S (F, 2, 2) one-sided per Hz, K segments.

    Non-overlapping segments, rectangular window, linear detrend (one segment of the
    whole record gives the raw periodogram).
    """
    k = x.shape[-1] // segment
    seg = x[:, : k * segment].reshape(2, k, segment)
    seg = scipy.signal.detrend(seg, axis=-1, type="linear")
    spec = np.fft.rfft(seg, axis=-1)  # (2, K, F)
    S = np.einsum("ikf,jkf->fij", spec, np.conj(spec)) * (2.0 * dt / segment) / k
    return np.fft.rfftfreq(segment, dt), S, k


def whittle_loglik(
    f: np.ndarray,
    S_hat: np.ndarray,
    n_segments: int,
    *,
    stiffness: np.ndarray,
    level: np.ndarray,
    qc: LinearQuarterCar,
    speed: float,
    sigma: float,
    dt: float,
) -> np.ndarray:
    """Whittle log-likelihood (2×2 form) on the grid stiffness (P,) × level (L,), shape (P, L).

    `S_hat` (F, 2, 2) is the one-sided cross-spectral matrix per Hz at `f` (Hz), averaged
    over `n_segments`; levels Gd(n0) in m³, speed in m/s, noise std `sigma` in m/s².
    """
    h1, h2 = corner_response(f[None, :], stiffness[:, None], qc)  # (P, F)
    a, b = np.abs(h1) ** 2, np.abs(h2) ** 2
    c = h1 * np.conj(h2)  # S12 / Sv
    sv = (4.0 * np.pi**2 * N0**2 * speed) * level[None, :, None]  # (1, L, 1)
    noise = 2.0 * sigma**2 * dt
    s11 = sv * a[:, None, :] + noise
    s22 = sv * b[:, None, :] + noise
    det = noise**2 + noise * sv * (a + b)[:, None, :]
    cross = np.real(sv * c[:, None, :] * S_hat[None, None, :, 1, 0])
    trace = (s22 * np.real(S_hat[:, 0, 0]) + s11 * np.real(S_hat[:, 1, 1]) - 2.0 * cross) / det
    return -n_segments * np.sum(np.log(det) + trace, axis=-1)


def profile_loglik(
    power: np.ndarray,
    gain: np.ndarray,
    weight: np.ndarray,
    *,
    log_sv_bounds: tuple[np.ndarray, np.ndarray],
    log_sv_start: np.ndarray | None = None,
    iterations: int = 50,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Scalar Whittle log-likelihood with :math:`\log S_v` profiled out, per run and stiffness.

    :math:`\ell(k_t, S_v) = -\sum_f w_f[\log(1 + S_v g_f) + P_f/(1 + S_v g_f)]`, maximized over
    :math:`\lambda = \log S_v` within the bounds by Fisher scoring (steps clipped to ±2).

    Parameters
    ----------
    power : (B, F)
        Projected periodogram over the noise PSD, :math:`P_f = u^H\hat S u/N` (dimensionless).
    gain : (P, F)
        :math:`|h(f; k_t)|^2/N`, (m/s)⁻² Hz (road-velocity PSD to signal-to-noise ratio).
    weight : (B, F)
        Number of averaged segments where f is in the run's band, 0 outside.
    log_sv_bounds : two arrays broadcasting to (B, 1)
        Prior range of :math:`\log S_v`, :math:`S_v` in m²/s²/Hz.
    log_sv_start : (B, P), optional
        Starting point (default: the method-of-moments value).

    Returns
    -------
    loglik, log_sv, fisher : (B, P) each
        Profiled log-likelihood, its argmax :math:`\hat\lambda`, and the Fisher information
        in λ there (for Laplace's marginal over the level, :math:`\ell - \tfrac12\log I`).
    """
    lo, hi = log_sv_bounds
    if log_sv_start is None:
        excess = np.einsum("bf,bf->b", weight, np.maximum(power - 1.0, 0.0))[:, None]
        lam = np.log(np.maximum(excess, 1e-12) / np.maximum(weight @ gain.T, 1e-300))
    else:
        lam = log_sv_start.copy()
    lam = np.clip(lam, lo, hi)
    p = power[:, None, :]
    w = weight[:, None, :]
    for _ in range(iterations):
        r = np.exp(lam)[..., None] * gain[None]
        q = r / (1.0 + r)
        score = np.sum(w * q * (p / (1.0 + r) - 1.0), axis=-1)
        fisher = np.sum(w * q * q, axis=-1)
        new = np.clip(lam + np.clip(score / np.maximum(fisher, 1e-300), -2.0, 2.0), lo, hi)
        moved = np.max(np.abs(new - lam))
        lam = new
        if moved < 1e-5:
            break
    r = np.exp(lam)[..., None] * gain[None]
    loglik = -np.sum(w * (np.log1p(r) + p / (1.0 + r)), axis=-1)
    fisher = np.sum(w * (r / (1.0 + r)) ** 2, axis=-1)
    return loglik, lam, fisher


def profile_loglik_slope(
    power: np.ndarray,
    log_gain: np.ndarray,
    weight: np.ndarray,
    log_n: np.ndarray,
    *,
    log_sv_bounds: tuple[np.ndarray, np.ndarray],
    slope_bounds: tuple[float, float],
    start: tuple[np.ndarray, np.ndarray] | None = None,
    iterations: int = 50,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]]:
    r"""As :func:`profile_loglik` with the road's spectral slope profiled out too.

    The road-velocity PSD is :math:`S_v(n_0)\,(n/n_0)^{\beta}`, :math:`\beta = 2 - w` (w the ISO
    waviness), so :math:`r_f = \exp(\lambda + \beta x_f)\,g_f` with :math:`x_f = \log(n_f/n_0)`;
    :math:`(\lambda, \beta)` are maximized within their bounds by Fisher scoring (a step that would
    leave the slope's range ends there, λ then taking the conditional step).

    Parameters
    ----------
    power, weight : (B, F)
        As in :func:`profile_loglik`.
    log_gain : (P, F)
        :math:`\log(|h(f; k_t)|^2/N)`.
    log_n : (B, F)
        :math:`x_f = \log(f/(n_0 v))`, the run's spatial frequency over n0.
    log_sv_bounds : two arrays broadcasting to (B, 1)
        Range of λ, the log road-velocity PSD at n0.
    slope_bounds : (float, float)
        Range of β (equal bounds: a fixed slope).
    start : ((B, P), (B, P)), optional
        Starting λ and β (default: the method-of-moments λ at β = 0, clipped).

    Returns
    -------
    loglik, log_sv, slope : (B, P) each
        Profiled log-likelihood and its argmax (λ̂, β̂).
    fisher : three (B, P) arrays
        The Fisher information's elements :math:`I_{\lambda\lambda}, I_{\lambda\beta}, I_{\beta\beta}` there.
    """
    lo, hi = log_sv_bounds
    b_lo, b_hi = slope_bounds
    if start is None:
        excess = np.einsum("bf,bf->b", weight, np.maximum(power - 1.0, 0.0))[:, None]
        lam = np.log(np.maximum(excess, 1e-12) / np.maximum(weight @ np.exp(log_gain).T, 1e-300))
        beta = np.full(lam.shape, np.clip(0.0, b_lo, b_hi))
    else:
        lam, beta = start[0].copy(), start[1].copy()
    lam = np.clip(lam, lo, hi)
    beta = np.clip(beta, b_lo, b_hi)
    n_runs, n_points = lam.shape
    out = _profile_slope_kernel(
        power, log_gain, weight, log_n, np.broadcast_to(lo, (n_runs, 1))[:, 0].astype(float),
        np.broadcast_to(hi, (n_runs, 1))[:, 0].astype(float), float(b_lo), float(b_hi),
        np.ascontiguousarray(lam, dtype=float), np.ascontiguousarray(beta, dtype=float), iterations,
    )  # fmt: skip
    loglik, lam, beta, i_ll, i_lb, i_bb = out
    return loglik, lam, beta, (i_ll, i_lb, i_bb)


@cached_njit
def _profile_slope_kernel(power, log_gain, weight, log_n, lo, hi, b_lo, b_hi, lam, beta, iterations):
    """Fisher scoring of :func:`profile_loglik_slope`, each (run, stiffness) to its own convergence."""
    n_runs, n_points = lam.shape
    n_freq = power.shape[1]
    loglik = np.empty((n_runs, n_points))
    i_ll_out, i_lb_out, i_bb_out = np.empty_like(loglik), np.empty_like(loglik), np.empty_like(loglik)
    for b in range(n_runs):
        for k in range(n_points):
            lm, bt = lam[b, k], beta[b, k]
            done = False
            for it in range(iterations + 1):
                s_l = s_b = i_ll = i_lb = i_bb = 0.0
                for j in range(n_freq):
                    wf = weight[b, j]
                    x = log_n[b, j]
                    r = np.exp(lm + bt * x + log_gain[k, j])
                    inv = 1.0 / (1.0 + r)
                    q = r * inv
                    e = wf * q * (power[b, j] * inv - 1.0)
                    wq2 = wf * q * q
                    s_l += e
                    s_b += e * x
                    i_ll += wq2
                    i_lb += wq2 * x
                    i_bb += wq2 * x * x
                if done or it == iterations:  # the likelihood and information at the optimum
                    ll = 0.0
                    for j in range(n_freq):
                        r = np.exp(lm + bt * log_n[b, j] + log_gain[k, j])
                        ll -= weight[b, j] * (np.log1p(r) + power[b, j] / (1.0 + r))
                    break
                det = max(i_ll * i_bb - i_lb * i_lb, 1e-300)
                d_b = min(max((i_ll * s_b - i_lb * s_l) / det, -0.5), 0.5)
                new_b = min(max(bt + d_b, b_lo), b_hi)
                # λ's step given the slope's (clipped) step: the quadratic model's conditional optimum
                d_l = min(max((s_l - i_lb * (new_b - bt)) / max(i_ll, 1e-300), -2.0), 2.0)
                new_l = min(max(lm + d_l, lo[b]), hi[b])
                moved = max(abs(new_l - lm), abs(new_b - bt))
                lm, bt = new_l, new_b
                done = moved < 1e-5
            lam[b, k], beta[b, k] = lm, bt
            loglik[b, k], i_ll_out[b, k], i_lb_out[b, k], i_bb_out[b, k] = ll, i_ll, i_lb, i_bb
    return loglik, lam, beta, i_ll_out, i_lb_out, i_bb_out


def estimate_joint(
    acc_sprung: npt.ArrayLike,
    acc_unsprung: npt.ArrayLike,
    dt: float,
    *,
    qc: LinearQuarterCar,
    speed_mps: npt.ArrayLike,
    sigma_accel: float = 0.5,
    segment_s: float | None = None,
    min_record_s: float = 2.0,
    update_s: float = 0.5,
    band_cycles_per_m: tuple[float, float] = (0.05, 1.5),
    max_frequency_hz: float = 30.0,
    pressure_grid_kpa: tuple[float, float, float] = (60.0, 400.0, 1.0),
    level_grid: npt.ArrayLike | None = None,
    fixed_level: float | None = None,
    damping_points: int = 4,
    waviness: float | tuple[float, float] = (1.5, 3.0),
    waviness_iso_weight: float = 0.8,
    tire: TireStiffness | None = None,
) -> JointEstimate:
    """Estimate k_t (and p) jointly with the road level from the two accelerations.

    Parameters
    ----------
    acc_sprung, acc_unsprung : array_like, shape (B, T) or (T,)
        Vertical accelerations, m/s², every `dt` s.
    qc : LinearQuarterCar
    speed_mps : float or (B,)
        Speed, m/s (sets the road-velocity PSD and the frequency band).
    sigma_accel : float
        Accelerometer noise std (each channel), m/s².
    segment_s : float, optional
        None (default): the periodogram of the whole record so far (exact Whittle,
        resolution 1/record). A length in s: average non-overlapping (Bartlett) segments
        of that length (resolution 1/segment_s, the earlier estimator's spectrum).
    min_record_s : float
        First estimate after this much data, s (with `segment_s`, after one segment).
    update_s : float
        Refresh interval of the estimate, s.
    band_cycles_per_m : (float, float)
        Spatial-frequency band used, cycles/m (times the speed gives Hz).
    max_frequency_hz : float
        Upper limit of the band, Hz.
    pressure_grid_kpa : (start, stop, step)
        Pressure grid, kPa; the prior is flat on it.
    level_grid : array_like, optional
        Road levels Gd(n0), m³: the prior on the level is log-uniform between their
        minimum and maximum (default 1e-6 to 1e-2).
    fixed_level : float, optional
        Assume this level instead of estimating it (shows the fixed-level bias).
    damping_points : int
        If ``qc.damping_range`` is set, the damping is marginalized over this many values evenly
        spaced in the range (uniform prior); otherwise ``qc.damping`` is used.
    waviness : float or (float, float)
        The road's ISO waviness w (displacement PSD :math:`G_d(n_0)(n/n_0)^{-w}`): a range (default
        1.5-3.0, where measured roads lie) to estimate it jointly (profiled, Laplace-marginalized),
        or a value to assume (2.0: the ISO classes' slope, the former model, equal to it bit for bit).
    waviness_iso_weight : float
        With a waviness range, the prior probability that the road is an ISO one, w = 2 exactly (a
        spike and slab prior: the rest uniform over the range). 0: w uniform over the range. The
        default 0.8 keeps nearly the precision of w = 2 on w = 2 roads and removes most of the bias
        elsewhere (see the module's "Waviness").
    tire : TireStiffness, optional
        The tyre's k_t(p) constants (eq. 3–4) for the pressure grid and the result; default the
        SUV's tyre.

    Returns
    -------
    JointEstimate
        Before the first estimate the stiffness is the prior's mean (the grid's centre
        of mass), its σ the prior's spread, and the level NaN.
    """
    acc_s = np.atleast_2d(np.asarray(acc_sprung, dtype=float))
    acc_u = np.atleast_2d(np.asarray(acc_unsprung, dtype=float))
    if acc_s.shape != acc_u.shape or not (np.all(np.isfinite(acc_s)) and np.all(np.isfinite(acc_u))):
        raise InputError("accelerations must be finite arrays of equal shape")
    n_runs, n_steps = acc_s.shape
    speed = np.broadcast_to(np.asarray(speed_mps, dtype=float), (n_runs,))
    if np.any(speed <= 0):
        raise InputError("the joint estimator needs a positive speed")
    p_lo, p_hi, p_step = pressure_grid_kpa
    pressures = np.arange(p_lo, p_hi + 0.5 * p_step, p_step) * 1e3
    tire = tire or suv_tire_stiffness()
    law = asdict(tire)  # kt0, p0, pfz1
    stiffness = stiffness_from_pressure(pressures, **law)
    grid_var = np.diff(stiffness).mean() ** 2 / 12.0 if stiffness.size > 1 else 0.0
    if fixed_level is not None:
        levels = np.array([fixed_level, fixed_level], dtype=float)
    else:
        levels = np.array([1e-6, 1e-2]) if level_grid is None else np.asarray(level_grid, dtype=float)
    if not np.all(levels > 0):
        raise InputError("road levels must be positive")
    w_range = np.broadcast_to(np.asarray(waviness, dtype=float), (2,))
    if not (np.all(np.isfinite(w_range)) and w_range[0] <= w_range[1]):
        raise InputError("waviness must be a finite value or an increasing (low, high) pair")
    slope_bounds = (2.0 - float(w_range[1]), 2.0 - float(w_range[0]))  # β = 2 - w, road-velocity slope
    slope_free = slope_bounds[0] < slope_bounds[1]
    plain = not slope_free and slope_bounds[0] == 0.0  # w = 2: the road velocity is white
    iso_weight = float(waviness_iso_weight) if slope_free else 0.0
    if not 0.0 <= iso_weight < 1.0:
        raise InputError("waviness_iso_weight must be in [0, 1)")
    log_slope_width = np.log(slope_bounds[1] - slope_bounds[0]) if slope_free else 0.0
    sv_per_level = 4.0 * np.pi**2 * N0**2 * speed[:, None]  # (B, 1): Sv = this × Gd(n0)
    bounds = (np.log(sv_per_level * levels.min()), np.log(sv_per_level * levels.max()))
    segment = None if segment_s is None else int(round(segment_s / dt))
    first = int(round(min_record_s / dt)) if segment is None else segment
    every = max(int(round(update_s / dt)), 1)
    noise = 2.0 * sigma_accel**2 * dt
    f_lo = band_cycles_per_m[0] * speed[:, None]
    f_hi = np.minimum(band_cycles_per_m[1] * speed[:, None], max_frequency_hz)

    if qc.damping_range is None:
        models = [qc]
    else:
        c_lo, c_hi = qc.damping_range
        models = [replace(qc, damping=float(c)) for c in np.linspace(c_lo, c_hi, max(int(damping_points), 1))]
    dampings = np.array([m.damping for m in models])

    kt_hat = np.full((n_runs, n_steps), stiffness.mean())
    kt_sig = np.full((n_runs, n_steps), stiffness.std())
    level_hat = np.full((n_runs, n_steps), np.nan)
    damping_hat = np.full((n_runs, n_steps), np.nan)
    waviness_hat = np.full(n_runs, np.nan if slope_free else float(w_range[0]))
    warm = [None] * len(models)  # the previous update's optimum per model, the next one's start
    for start in range(max(first, 1), n_steps, every):  # causal: data before `start` only
        m = start if segment is None else segment
        k = start // m
        x = np.stack([acc_s[:, : k * m], acc_u[:, : k * m]]).reshape(2, n_runs, k, m)
        x = scipy.signal.detrend(x, axis=-1, type="linear")
        f = np.fft.rfftfreq(m, dt)
        inside = (f >= f_lo.min()) & (f <= f_hi.max())
        f = f[inside]
        if f.size == 0:
            continue
        X = np.fft.rfft(x, axis=-1)[..., inside]  # (2, B, K, F)
        weight = k * ((f >= f_lo) & (f <= f_hi)).astype(float)
        lam = np.empty((len(models), n_runs, stiffness.size))
        beta = np.zeros_like(lam)
        log_marginal = np.empty_like(lam)
        log_n = np.log(f[None, :] / (N0 * speed[:, None]))  # (B, F)
        for c, model in enumerate(models):
            u1, u2 = signal_direction(f, model)
            y = np.conj(u1) * X[0] + np.conj(u2) * X[1]
            power = np.mean(np.abs(y) ** 2, axis=1) * (2.0 * dt / m) / noise  # (B, F)
            gain = signal_gain(f[None, :], stiffness[:, None], model) / noise  # (P, F)
            if plain:  # w = 2: the level alone, profiled in numpy (chunked)
                runs_at_once = max(1, _CHUNK // (stiffness.size * f.size))
                for b0 in range(0, n_runs, runs_at_once):
                    sl = slice(b0, b0 + runs_at_once)
                    ll, lam[c, sl], fisher = profile_loglik(
                        power[sl], gain, weight[sl], log_sv_bounds=(bounds[0][sl], bounds[1][sl]),
                        log_sv_start=None if warm[c] is None else warm[c][0][sl],
                    )  # fmt: skip
                    # Laplace: ∫ exp(ℓ) dλ ≈ exp(ℓ̂) sqrt(2π/I); a fixed level is a point prior
                    laplace = 0.0 if fixed_level is not None else 0.5 * np.log(np.maximum(fisher, 1e-300))
                    log_marginal[c, sl] = ll - laplace
                warm[c] = (lam[c],)
                continue
            # (λ, β) profiled; their log marginal by Laplace, ∫ exp(ℓ) ≈ exp(ℓ̂) (2π)^(k/2) det(I)^(-1/2)
            # over the k free ones, times the slope's prior density (a fixed level or slope: a point prior)
            log_gain = np.log(gain)
            ll, lam_f, beta_f, (i_ll, i_lb, i_bb) = profile_loglik_slope(
                power, log_gain, weight, log_n, log_sv_bounds=bounds, slope_bounds=slope_bounds,
                start=None if warm[c] is None else warm[c][:2],
            )  # fmt: skip
            if fixed_level is None:
                info = (i_ll * i_bb - i_lb**2) / _2PI**2 if slope_free else i_ll / _2PI
            else:
                info = i_bb / _2PI if slope_free else 1.0
            log_m_f = ll - 0.5 * np.log(np.maximum(info, 1e-300)) - log_slope_width
            if iso_weight == 0.0:
                lam[c], beta[c], log_marginal[c] = lam_f, beta_f, log_m_f
                warm[c] = (lam_f, beta_f)
                continue
            # spike and slab: the road is an ISO one (w = 2) with prior probability `iso_weight`
            ll, lam_p, _, (i_ll, _, _) = profile_loglik_slope(
                power, log_gain, weight, log_n, log_sv_bounds=bounds, slope_bounds=(0.0, 0.0),
                start=None if warm[c] is None else (warm[c][2], np.zeros_like(warm[c][2])),
            )  # fmt: skip
            log_m_p = ll - (0.5 * np.log(np.maximum(i_ll, 1e-300) / _2PI) if fixed_level is None else 0.0)
            log_m_p = log_m_p + np.log(iso_weight)
            log_m_f = log_m_f + np.log1p(-iso_weight)
            log_marginal[c] = np.logaddexp(log_m_p, log_m_f)
            slab = np.exp(log_m_f - log_marginal[c])  # the slab's posterior share
            lam[c] = slab * lam_f + (1.0 - slab) * lam_p
            beta[c] = slab * beta_f
            warm[c] = (lam_f, beta_f, lam_p)
        # joint posterior over (damping, stiffness), flat in both
        post = np.exp(log_marginal - log_marginal.max(axis=(0, 2), keepdims=True))
        post /= post.sum(axis=(0, 2), keepdims=True)
        post_kt = post.sum(axis=0)  # (B, P)
        mean = post_kt @ stiffness
        spread = np.sqrt(np.maximum(post_kt @ stiffness**2 - mean**2, 0.0) + grid_var)
        level = np.exp(np.einsum("cbp,cbp->b", post, lam)) / sv_per_level[:, 0]
        stop = min(start + every, n_steps)
        kt_hat[:, start:stop] = mean[:, None]
        kt_sig[:, start:stop] = spread[:, None]
        level_hat[:, start:stop] = level[:, None]
        damping_hat[:, start:stop] = (post.sum(axis=2).T @ dampings)[:, None]
        if slope_free:
            waviness_hat = 2.0 - np.einsum("cbp,cbp->b", post, beta)
    return JointEstimate(
        t_s=np.arange(n_steps) * dt,
        stiffness=kt_hat,
        stiffness_sigma=kt_sig,
        pressure_pa=pressure_from_stiffness(kt_hat, **law),
        pressure_sigma_pa=pressure_sigma_from_stiffness_sigma(kt_sig, **law),
        road_level=level_hat,
        info={
            "estimator": "joint",
            "spectrum": "whole-record periodogram" if segment is None else "Bartlett segments",
            "segment_s": segment_s,
            "min_record_s": min_record_s if segment is None else segment_s,
            "band_cycles_per_m": list(band_cycles_per_m),
            "max_frequency_hz": max_frequency_hz,
            "damping_grid": dampings.tolist(),
            "damping_hat_at_end": damping_hat[:, -1].tolist(),  # posterior mean per run, N s/m
            "waviness": float(w_range[0]) if not slope_free else [float(w) for w in w_range],
            "waviness_hat_at_end": waviness_hat.tolist(),  # posterior mean per run (the value if fixed)
        },
    )
