r"""Front→rear preview: the rear tyre's pressure given the front's, from one track's unsprung accelerations.

Usual call::

    track = PreviewTrack(front_model, rear_model, tire_front, tire_rear, dt=1e-3, wheelbase_m=2.818)
    track.add(acc_u_front, acc_u_rear, speed_mps)          # any chunk length, in time order
    out = track.conditional(p_front_kpa=210.0, sigma_front_kpa=8.0)
    out.mean_kpa, out.sigma_kpa, out.informative

Idea: the rear wheel runs over the front wheel's track a wheelbase later, τ = L/v. The road, its
level and its slope then cancel in the ratio of the two unsprung responses, and what is left is a
frequency-response-function estimation problem with noise on the input (the front's accelerometer):
errors in variables [1]_ (ch. 6–9: the frequency response function from an input measured with
noise, its bias and random error). Per Fourier frequency f of a rectangular segment k (1 s, linear
detrend), the front segment shifted back by the whole samples of τ and the fractional rest δ removed
as a phase:

.. math:: Y_k(f) = G(f)\,X_k(f) + E_k(f),\qquad
   G(f) = \frac{H_{u,\mathrm{rear}}(f;\,k_{t,r})}{H_{u,\mathrm{front}}(f;\,k_{t,f})},

X, Y the front's and rear's unsprung-acceleration DFTs, H_u each corner's own-track response
(the roll-plane model's :math:`\tfrac12(h_\mathrm{heave} + h_\mathrm{roll})`,
:func:`suvtwin.estimators.joint.corner_response`), k_t(p) Brancati & Tufano 2022, eq. 3–4 [2]_.
The residual E (the rear's noise, the front's noise through G, what the ratio model leaves out)
has a variance free per band g of ``group_hz``, profiled out; the front's known noise (DFT variance
:math:`n\sigma_a^2`) is subtracted from its power (the errors-in-variables correction: without it
the least-squares ratio is attenuated). The profile log-likelihood is

.. math:: \ell(p_f, p_r) = -\sum_g K_g \log\frac{Q_g}{K_g},\qquad
   Q_g = \sum_{f\in g}\left[B_f - 2\,\mathrm{Re}(\bar G_f C_f) + |G_f|^2 (A_f - K n\sigma_a^2)\right],

with the sufficient statistics :math:`A = \sum_k w_k|X_k|^2`, :math:`B = \sum_k w_k|Y_k|^2`,
:math:`C = \sum_k w_k \bar X_k Y_k e^{+i2\pi f\delta_k}`, :math:`K = \sum_k w_k` and
:math:`K_g = K\times` (frequencies in g): three numbers per frequency per track, forgotten by
multiplying them by :math:`e^{-\Delta t/\tau}` (:meth:`PreviewTrack.decay`). Bands whose front
power is below ``snr_min`` times its noise are left out.

The preview pins the ratio k_t,r/k_t,f well but not the pressures themselves (above the wheel hop
:math:`G \to (k_{t,r}/m_{us,r})/(k_{t,f}/m_{us,f})`), so it is used conditionally,
:math:`\ell_c(p_r\,|\,p_f) = \ell - \max_{p_r}\ell`, with the front's Gaussian from elsewhere (the
monitor's single-corner estimate). By Laplace's method along the ridge
:math:`p_r^*(p_f) = \arg\max_{p_r}\ell`:

.. math:: p_r \sim \mathcal N\!\left(p_r^*(\hat p_f),\;
   \frac{c_w\,s_\ell^2}{H_{rr}} + \Big(\frac{dp_r^*}{dp_f}\Big)^2\sigma_f^2 + \sigma_\mathrm{floor}^2\right),
   \qquad H_{rr} = -\partial^2\ell/\partial p_r^2,

:math:`c_w = \sum w_k^2/\sum w_k` the sandwich factor of a weighted likelihood (1 without
forgetting), :math:`s_\ell` = ``sigma_scale`` (default 2: on linear truth the error's std was 1.3–2.3
times the likelihood's own σ, leakage correlating neighbouring frequencies),
:math:`\sigma_\mathrm{floor}` the model error: ``floor_kpa`` where the track's dynamic load
coefficient DLC = std(m_s a_s + m_us a_us)/((m_s + m_us) g) is at most ``rough_dlc``,
``rough_floor_kpa`` above (tyre lift-off and the suspension's stops: the linear ratio fails there).

Band 20–40 Hz: above the wheel hop, where the ratio depends on k_t,r at 20–40 kPa per dB, and
below where the simulated tyre's model error grows. Each corner's damping is fixed (default the
low-speed end of its ``damping_range``), which was nearly as good as profiling it and 9× cheaper.

Measured (``python bench/preview_mujoco.py --runs-dir bench/_runs/constant``: 100 MuJoCo runs,
constant pressures 130–230 kPa, 40–120 km/h, classes A–D, 0–300 kg, 200 tracks; error kPa, mean ±
std [share within ±2σ]). At 30 s, the rear at the TRUE front pressure: −1.8 ± 2.6 [1.00] where
DLC ≤ 1/3 (144 tracks), −9.7 ± 11.2 [0.96] above (56); on linear truth −0.6 to −1.0 ± 0.4–0.7
(the 1 s segments' leakage). Given the online monitor's front estimate (at fc7192b): −2.9 ± 13.8
[0.98], against the monitor's own rear +6.6 ± 17.6 [0.97]; both fused (:func:`fuse_track`):
rear +0.7 ± 11.7 [0.96], front +2.5 ± 10.5 [0.94] (the monitor's own front +0.9 ± 10.7 [0.97]).
At 10 s: fused rear +4.2 ± 20.1 [0.95], the monitor's own +10.6 ± 25.4 [0.99]. So the preview
improves the rear; it does not improve the front.

Use in a monitor (:class:`suvtwin.estimators.monitor.TyreMonitor` with ``tracks``, off by
default): one :class:`PreviewTrack` per track (fl→rl, fr→rr); before each update
``decay(exp(−Δt/τ))`` (τ the monitor's ``preview_memory_s``), then ``add`` the update's samples
(NaN where the monitor's checks rejected a sample); after it ``conditional(p̂_f, σ_f)`` with the
monitor's front and ``fuse_track`` with its rear, keeping the front's own estimate. Several
``memories`` (each forgotten at its own rate) are supported for other uses. Cost (one core of a
loaded 2-core machine, 3 memories): ``add`` 0.17–0.21 ms per second of data in 4 s chunks
(0.3–0.4 ms in 1 s chunks), ``conditional`` 0.3–0.5 ms per call; state 13 kB per track and memory.

No MuJoCo here: the preview consumes arrays.

References
----------
.. [1] J. S. Bendat, A. G. Piersol, "Random Data: Analysis and Measurement Procedures", 4th ed.,
   Wiley, 2010, ch. 6–9 (single-input/single-output relationships, frequency response functions
   with noise on the input, statistical errors of the estimates).
.. [2] R. Brancati, F. Tufano, Machines 10(12), 1221, 2022, eq. 3–4 (k_t(p)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.estimators.joint import LinearQuarterCar, corner_response
from suvtwin.jit import cached_njit
from suvtwin.tire_stiffness import TireStiffness, stiffness_at_pressure_array

__all__ = [
    "SKIP_REASONS",
    "PreviewConditional",
    "PreviewConfig",
    "PreviewTrack",
    "fuse_track",
    "own_track_response",
]

SKIP_REASONS = ("used", "gap", "speed", "warmup")
"""What became of a completed rear segment (counts in :attr:`PreviewTrack.counts`): ``used``;
``gap``: a non-finite acceleration in the rear segment or its delayed front segment (mark bad
samples NaN to have the segment skipped); ``speed``: speed not finite, below ``min_speed_mps`` or
changing by more than ``max_speed_change`` within the segment; ``warmup``: the delayed front
segment starts before the first sample seen."""

_GRAVITY = 9.81  # m/s²


@dataclass(frozen=True)
class PreviewConfig:
    """Settings of :class:`PreviewTrack` (units in the names).

    Attributes
    ----------
    segment_s : float
        Length of the rectangular segments, s (resolution 1/segment_s Hz).
    band_hz : (float, float)
        Frequency band used, Hz.
    group_hz : float
        Width of the bands whose residual variance is free (profiled out), Hz.
    snr_min : float
        A band is used only if the front's power there is this many times its noise power (minus 1).
    sigma_accel : float
        Accelerometer noise std of each channel, m/s².
    floor_kpa, rough_floor_kpa : float
        Model-error std added to the rear's σ where the DLC is at most / above ``rough_dlc``, kPa.
    rough_dlc : float
        Dynamic load coefficient above which the road counts as rough (−).
    min_speed_mps : float
        Slowest speed used, m/s (it also bounds the front history kept: L/min_speed). 11 m/s
        (40 km/h): slower, the band's wavelengths (0.25–0.5 m at 36 km/h) approach the tyre's
        contact length, where its enveloping and the wheel's non-linear response leave the ratio's
        model: on a ``nominal_long`` run at 36 km/h the rears read 17–20 kPa low (coherence
        0.8–0.9), and with 5 m/s the ``low_speed`` runs (20–35 km/h) had 6 of 560 updates beyond 3σ,
        without the preview 2.
    max_speed_change : float
        Largest (max − min)/mean speed within a used segment (τ must be one number per segment).
    pressure_range_kpa : (float, float)
        Range searched for the rear pressure, kPa.
    grid_step_kpa : float
        Step of the coarse search grid, kPa (refined by a parabola and a Newton step).
    slope_step_kpa : float
        Front-pressure step of the ridge slope's central difference, kPa.
    damping_fraction : float
        Where in each corner model's ``damping_range`` its fixed damping lies: 0 the smaller
        (high-speed) end, 1 the larger (low-speed) end; a model without a range keeps its damping.
    min_segments : float
        Fewest effective segments, (Σw)²/Σw², for the preview to count as informative.
    sigma_scale : float
        Factor on the likelihood's own σ: leakage makes the residuals of neighbouring frequencies
        correlated, which the likelihood does not know. On linear truth (two corner models on an
        ISO road profile, 50–120 km/h, 0.5 m/s² noise, 10 seeds each) the rear's error std at the
        true front was 1.3–2.3 times the likelihood's σ at 10 s and 30 s, hence 2.
    min_coherence : float
        The preview is used only if the two wheels' accelerations are this coherent: the mean over
        the used bands of :math:`|C_g|^2/(A'_g B'_g)` (band sums, noise-corrected powers). Where
        the rear wheel does not follow the front's road (wheels off the ground or on their stops,
        the enveloping tyre at low speed) the least-squares ratio is attenuated by the coherence
        and reads the rear soft. On 30 cached ``constant`` runs at 30 s (60 tracks, the rear given
        the true front) the error was −1.4 ± 1.7 kPa at coherence ≥ 0.96, −2.3 ± 2.6 at 0.93–0.96,
        −2.3 ± 3.2 at 0.90–0.93 and −8.1 ± 9.6 below 0.85; on ``nominal_long`` runs it fell to
        0.35–0.6 on class D stretches (rears read 40–60 kPa low) and to 0.8–0.9 at 36 km/h
        (17–20 kPa low).
    """

    segment_s: float = 1.0
    band_hz: tuple[float, float] = (20.0, 40.0)
    group_hz: float = 4.0
    snr_min: float = 3.0
    sigma_accel: float = 0.5
    floor_kpa: float = 4.0
    rough_floor_kpa: float = 15.0
    rough_dlc: float = 1.0 / 3.0
    min_speed_mps: float = 11.0
    max_speed_change: float = 0.1
    pressure_range_kpa: tuple[float, float] = (60.0, 400.0)
    grid_step_kpa: float = 2.0
    slope_step_kpa: float = 5.0
    damping_fraction: float = 1.0
    min_segments: float = 3.0
    sigma_scale: float = 2.0
    min_coherence: float = 0.9

    def __post_init__(self) -> None:
        checks = [
            ("segment_s", 0.1 <= self.segment_s <= 60.0, "0.1–60 s"),
            (
                "band_hz",
                len(self.band_hz) == 2 and 0 < self.band_hz[0] < self.band_hz[1],
                "0 < low < high Hz",
            ),
            ("group_hz", 0 < self.group_hz <= 100.0, "(0, 100] Hz"),
            ("snr_min", 0 <= self.snr_min <= 1e3, "0–1000"),
            ("sigma_accel", 0 < self.sigma_accel <= 100.0, "(0, 100] m/s²"),
            ("floor_kpa", 0 <= self.floor_kpa <= 100.0, "0–100 kPa"),
            ("rough_floor_kpa", 0 <= self.rough_floor_kpa <= 200.0, "0–200 kPa"),
            ("rough_dlc", 0 < self.rough_dlc <= 2.0, "(0, 2]"),
            ("min_speed_mps", 0.5 <= self.min_speed_mps <= 100.0, "0.5–100 m/s"),
            ("max_speed_change", 0 < self.max_speed_change <= 1.0, "(0, 1]"),
            (
                "pressure_range_kpa",
                len(self.pressure_range_kpa) == 2
                and 10 <= self.pressure_range_kpa[0] < self.pressure_range_kpa[1],
                "10 ≤ low < high kPa",
            ),
            ("grid_step_kpa", 0.1 <= self.grid_step_kpa <= 20.0, "0.1–20 kPa"),
            ("slope_step_kpa", 0.1 <= self.slope_step_kpa <= 50.0, "0.1–50 kPa"),
            ("damping_fraction", 0 <= self.damping_fraction <= 1, "[0, 1]"),
            ("min_segments", 1 <= self.min_segments <= 1e4, "1–10000"),
            ("sigma_scale", 0.1 <= self.sigma_scale <= 10.0, "0.1–10"),
            ("min_coherence", 0 <= self.min_coherence < 1, "[0, 1)"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"preview setting {name} must be {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class PreviewConditional:
    """The rear's pressure given the front's Gaussian (:meth:`PreviewTrack.conditional`).

    Attributes
    ----------
    mean_kpa, sigma_kpa : float
        The rear's mean and std, kPa (NaN and inf when nothing could be computed).
    informative : bool
        Enough effective segments, at least one band above the SNR gate, the maximum inside the
        search range and a negative curvature: use the preview only if True.
    reason : str
        Why not informative ("" when it is): ``no_segments``, ``few_segments``, ``low_snr``,
        ``incoherent``, ``edge``, ``flat``.
    sigma_likelihood_kpa : float
        The likelihood's own std at the front's mean (sandwich- and ``sigma_scale``-corrected), kPa.
    ridge_slope : float
        dp_r*/dp_f, −.
    cov_front_rear_kpa2 : float
        Covariance of the front and rear pressures, ridge_slope·σ_f², kPa².
    floor_kpa : float
        The model-error std included, kPa.
    dlc : float
        The dynamic load coefficient the floor was chosen by (NaN: unknown, rough floor used).
    segments : float
        Effective number of segments, (Σw)²/Σw².
    bands_used : int
        Bands (of ``group_hz``) above the SNR gate.
    coherence : float
        The two wheels' mean coherence over those bands (``min_coherence``; NaN without any).
    """

    mean_kpa: float
    sigma_kpa: float
    informative: bool
    reason: str
    sigma_likelihood_kpa: float
    ridge_slope: float
    cov_front_rear_kpa2: float
    floor_kpa: float
    dlc: float
    segments: float
    bands_used: int
    coherence: float = float("nan")


def own_track_response(f: npt.ArrayLike, kt: npt.ArrayLike, qc: LinearQuarterCar) -> np.ndarray:
    r"""Unsprung acceleration per unit road velocity of the corner's OWN track, shape broadcast(kt, f).

    Roll-plane model (``roll_mass`` set): a left road is a heave input plus a roll input of half its
    height each, so the response is :math:`\tfrac12(h_\mathrm{heave} + h_\mathrm{roll})`
    (:func:`suvtwin.estimators.joint.corner_response`); otherwise the heave quarter car's. `f` in Hz,
    `kt` in N/m; the result in (m/s²)/(m/s).
    """
    f = np.asarray(f, dtype=float)
    kt = np.asarray(kt, dtype=float)
    h = corner_response(f, kt, qc)[1]
    if qc.roll_mass is None:
        return h
    return 0.5 * (h + corner_response(f, kt, qc, roll=True)[1])


def fuse_track(
    p_front_kpa: float,
    sigma_front_kpa: float,
    p_rear_kpa: float,
    sigma_rear_kpa: float,
    preview: PreviewConditional,
    correlation: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Both pressures of a track from their own Gaussians and the preview.

    The preview, linearized along its ridge, is one linear-Gaussian measurement of the two pressures,

    .. math:: y = p_r - s\,p_f,\qquad y_\mathrm{obs} = p_r^*(\hat p_f) - s\,\hat p_f,\qquad
       R = \sigma_\mathrm{lik}^2 + \sigma_\mathrm{floor}^2,

    s the ridge slope, taken at the front's mean `p_front_kpa` (``preview`` must be
    :meth:`PreviewTrack.conditional` at that mean); the prior is N((p̂_f, p̂_r), Σ) with
    :math:`\Sigma = [[\sigma_f^2, \rho\sigma_f\sigma_r], [\rho\sigma_f\sigma_r, \sigma_r^2]]` (kPa²),
    ρ = `correlation` the correlation of the two estimates' errors, and the update is Kalman's.
    With ρ = 0 the rear's mean is the inverse-variance mean of its own estimate and the preview's
    (``preview.mean_kpa``, ``preview.sigma_kpa``) and the front moves by −s σ_f²/S times the same
    innovation. The two wheels of a track run over the same road, so their own estimates share that
    road's realized departures from the model's spectrum: on the MuJoCo SUV (100 ``constant`` runs,
    each tyre on its own) the front's and the rear's errors correlated by 0.76 at 10 s, 0.56 at
    30 s and 0.32 at 40 s (the two tracks' fronts: −0.2 to 0.15); with ρ > 0 the preview, which
    pins only the difference along its ridge, narrows the two less. Returns the mean (2,) (front,
    rear) and covariance (2, 2), kPa and kPa²; the prior unchanged if the preview is not informative.
    """
    mean = np.array([p_front_kpa, p_rear_kpa], dtype=float)
    off = correlation * sigma_front_kpa * sigma_rear_kpa
    cov = np.array([[sigma_front_kpa**2, off], [off, sigma_rear_kpa**2]], dtype=float)
    if not (
        np.all(np.isfinite(mean)) and np.all(np.isfinite(cov)) and sigma_front_kpa >= 0 and sigma_rear_kpa > 0
    ):
        raise InputError(
            "fuse_track needs finite pressures and σ (sigma_front_kpa ≥ 0, sigma_rear_kpa > 0 kPa), got "
            f"{p_front_kpa!r} ± {sigma_front_kpa!r}, {p_rear_kpa!r} ± {sigma_rear_kpa!r}"
        )
    if not -1.0 < correlation < 1.0:
        raise InputError(f"fuse_track correlation must be in (−1, 1), got {correlation!r}")
    if not preview.informative:
        return mean, cov
    s = preview.ridge_slope
    h = np.array([-s, 1.0])
    r = preview.sigma_likelihood_kpa**2 + preview.floor_kpa**2
    innovation = preview.mean_kpa - p_rear_kpa  # y_obs − h·mean
    big_s = float(h @ cov @ h) + r
    gain = cov @ h / big_s
    return mean + gain * innovation, cov - np.outer(gain, gain) * big_s


def _fixed_damping(qc: LinearQuarterCar, fraction: float) -> LinearQuarterCar:
    if qc.damping_range is None:
        return qc
    lo, hi = sorted(qc.damping_range)
    return replace(qc, damping=float(lo + fraction * (hi - lo)), damping_range=None)


def _per_memory(value, memories: int) -> np.ndarray | None:
    """`value` as one float per memory (a number is repeated); None if it is neither."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    if a.ndim == 0:
        return np.full(memories, float(a))
    return a if a.shape == (memories,) else None


@cached_njit
def _loglik_point(table, i, bg, cr, ci, ar, group, keep, kg, v0, work):
    """ℓ at row i of a rear table (3, P, F) (Re h_r, Im h_r, |h_r|²), given the per-band sums of B
    `bg` (G,) and the front-normalized C/h̄_f (`cr`, `ci`) and A'/|h_f|² (`ar`), (F,); each band's
    term is :func:`_band_term`."""
    for g in range(bg.size):
        work[g] = bg[g]
    for j in range(cr.size):
        work[group[j]] += -2.0 * (table[0, i, j] * cr[j] + table[1, i, j] * ci[j]) + table[2, i, j] * ar[j]
    ll = 0.0
    for g in range(bg.size):
        if keep[g]:
            ll += _band_term(work[g], kg[g], v0)
    return ll


@cached_njit
def _band_term(q, k, v0):
    """One band's profile log-likelihood, −K log(Q/K) with the residual variance σ² = Q/K, but σ² not
    below `v0`, the rear accelerometer's own noise (DFT variance n σ_a²): with few segments the
    noise-corrected Q can fall to zero or below (an estimated coherence above 1). Where Q/K < v0 the
    term is −K log v0 − Q/v0 + K, which meets −K log(Q/K) with the same value and slope."""
    if q >= k * v0:
        return -k * np.log(q / k)
    return -k * np.log(v0) - q / v0 + k


@cached_njit
def _add_segments(a, b, c, k, k2, load, w, axx, ayy, cxy, moments):
    """The segments' statistics added in place to each memory's with its weight w (M,), one segment at a
    time in order: A (M, F) += w |X|², B += w |Y|², C += w X̄Y e^{…} (`axx`, `ayy`, `cxy` (S, F)), K += w,
    K2 += w², the loads' (M, 2, 3) += w `moments` (S, 2, 3) (:meth:`PreviewTrack._accumulate`: the same
    products and sums, in the same order, as adding each segment's arrays in numpy, without its
    per-segment temporaries)."""
    for s in range(axx.shape[0]):
        for m in range(w.size):
            for f in range(axx.shape[1]):
                a[m, f] += w[m] * axx[s, f]
                b[m, f] += w[m] * ayy[s, f]
                c[m, f] += w[m] * cxy[s, f]
            k[m] += w[m]
            k2[m] += w[m] * w[m]
            for i in range(moments.shape[1]):
                for j in range(moments.shape[2]):
                    load[m, i, j] += w[m] * moments[s, i, j]


@cached_njit
def _detrended(x, ramp, ramp_norm):
    """Each row of `x` (S, n) less its least-squares line: its mean and its slope on `ramp` (n,), the
    centred sample index, whose Σ ramp² is `ramp_norm` (:meth:`PreviewTrack._accumulate`; compiled, one
    pass for the sums and one for the result)."""
    out = np.empty(x.shape)
    n = x.shape[1]
    for s in range(x.shape[0]):
        total = moment = 0.0
        for i in range(n):
            total += x[s, i]
            moment += x[s, i] * ramp[i]
        mean, slope = total / n, moment / ramp_norm
        for i in range(n):
            out[s, i] = x[s, i] - mean - ramp[i] * slope
    return out


@cached_njit
def _load_moments(unsprung_front, unsprung_rear, sprung_front, sprung_rear, masses):
    """Per segment (rows of the accelerations (S, n), m/s²) and tyre (front, rear): the sample count,
    Σ F and Σ F² of its dynamic load F = m_s a_s + m_us a_us (N), `masses` the front's m_s and m_us
    then the rear's (kg): (S, 2, 3) (:meth:`PreviewTrack.dlc`'s statistics)."""
    n_s, n = unsprung_front.shape
    out = np.empty((n_s, 2, 3))
    for s in range(n_s):
        for t in range(2):
            sprung = sprung_front if t == 0 else sprung_rear
            unsprung = unsprung_front if t == 0 else unsprung_rear
            total = square = 0.0
            for i in range(n):
                f = masses[2 * t] * sprung[s, i] + masses[2 * t + 1] * unsprung[s, i]
                total += f
                square += f * f
            out[s, t, 0], out[s, t, 1], out[s, t, 2] = float(n), total, square
    return out


@cached_njit
def _ridge_kernel(b, c_re, c_im, a, group, keep, kg, v0, coarse, fine, p_fine, step, window):
    """For each front response r (rows of `c_re`, `c_im`, `a`, (R, F)): the coarse grid's best rear
    pressure, refined by the least-squares parabola through ℓ at the 9 fine points within ±`step`
    (kPa) of it. Row 0 searches the whole grid, the others `window` coarse points either side of
    row 0's best (neighbouring front pressures). Returns p_r* (R,) kPa, H_rr = −ℓ'' (R,) per kPa²
    (NaN: not concave) and whether the coarse maximum is inside the grid and the window (R,)."""
    n_r = c_re.shape[0]
    n_g = kg.size
    work = np.zeros(n_g)
    bg = np.zeros(n_g)
    for j in range(b.size):
        bg[group[j]] += b[j]
    p_out = np.empty(n_r)
    h_out = np.full(n_r, np.nan)
    inside = np.zeros(n_r, dtype=np.bool_)
    h = 0.25 * step
    n_p = coarse.shape[1]
    lo, hi, ib0 = 0, n_p - 1, 0
    for r in range(n_r):
        if r > 0:
            lo, hi = max(ib0 - window, 0), min(ib0 + window, n_p - 1)
        best, ib = -np.inf, lo
        for i in range(lo, hi + 1):
            ll = _loglik_point(coarse, i, bg, c_re[r], c_im[r], a[r], group, keep, kg, v0, work)
            if ll > best:
                best, ib = ll, i
        if r == 0:
            ib0 = ib
        p_out[r] = p_fine[4 * ib]
        if ib == 0 or ib == n_p - 1 or (r > 0 and (ib == lo or ib == hi)):
            continue
        inside[r] = True
        # parabola ℓ ≈ c0 + c1 x + c2 x² on x = (k − 4) h, k = 0..8: x and x² − mean(x²) are orthogonal
        s1 = s2 = 0.0
        for k in range(9):
            ll = _loglik_point(fine, 4 * ib - 4 + k, bg, c_re[r], c_im[r], a[r], group, keep, kg, v0, work)
            x = (k - 4) * h
            s1 += x * ll
            s2 += (x * x - 60.0 * h * h / 9.0) * ll
        c1 = s1 / (60.0 * h * h)
        c2 = s2 / (h**4 * 2772.0 / 9.0)
        if c2 < 0.0:
            p_out[r] += min(max(-c1 / (2.0 * c2), -step), step)
            h_out[r] = -2.0 * c2
    return p_out, h_out, inside


class PreviewTrack:
    r"""Streaming sufficient statistics of one track (front and rear corner on the same side).

    Parameters
    ----------
    front_model, rear_model : LinearQuarterCar
        The two corners' linear models (masses kg, rates N/m, dampings N s/m); the damping is fixed
        within ``damping_range`` (``config.damping_fraction``).
    tire_front, tire_rear : TireStiffness
        Each tyre's k_t(p) (eq. 3–4 of [2]_ in the module docstring).
    dt : float
        Sample interval, s.
    wheelbase_m : float
        Distance the rear wheel runs behind the front one, m.
    config : PreviewConfig, optional
        Settings; default ``PreviewConfig()``.
    memories : int, optional
        Number of accumulators fed by the same segments (e.g. one per forgetting time constant of
        the monitor; each is decayed and weighted on its own). Default 1.

    Notes
    -----
    Segments are fixed on the rear's time axis: segment j holds the rear's samples
    [j n, (j+1) n) counted from the first sample given, n = segment_s/dt. Samples of an unfinished
    segment are kept until it completes, and the front's last n + L/(min_speed dt) samples are kept
    so the delay is applied across calls: chunks of any length give the same statistics. The state
    is bounded (about 3 n + L/(min_speed dt) samples and 4 numbers per frequency per memory).
    τ is the wheelbase over the segment's mean speed, known when its last rear sample arrives:
    everything uses data up to now only.
    """

    def __init__(
        self,
        front_model: LinearQuarterCar,
        rear_model: LinearQuarterCar,
        tire_front: TireStiffness,
        tire_rear: TireStiffness,
        dt: float,
        wheelbase_m: float,
        config: PreviewConfig | None = None,
        *,
        memories: int = 1,
    ) -> None:
        cfg = config or PreviewConfig()
        if not isinstance(cfg, PreviewConfig):
            raise InputError(f"config must be a PreviewConfig, got {type(cfg).__name__}")
        if not (np.isfinite(dt) and 1e-5 <= dt <= 0.05):
            raise InputError(f"dt must be 1e-5–0.05 s, got {dt!r}")
        if not (np.isfinite(wheelbase_m) and 0.5 <= wheelbase_m <= 20.0):
            raise InputError(f"wheelbase_m must be 0.5–20 m, got {wheelbase_m!r}")
        if not (isinstance(memories, int) and 1 <= memories <= 64):
            raise InputError(f"memories must be an integer 1–64, got {memories!r}")
        for name, m in (("front_model", front_model), ("rear_model", rear_model)):
            if not isinstance(m, LinearQuarterCar):
                raise InputError(f"{name} must be a LinearQuarterCar, got {type(m).__name__}")
        for name, t in (("tire_front", tire_front), ("tire_rear", tire_rear)):
            if not isinstance(t, TireStiffness):
                raise InputError(f"{name} must be a TireStiffness, got {type(t).__name__}")
        n = int(round(cfg.segment_s / dt))
        # within 0.1 %: a file's interval from timestamps rounded in float32 is a few 1e-5 off its rate
        if abs(n * dt - cfg.segment_s) > 1e-3 * cfg.segment_s or n < 16:
            raise InputError(
                f"config.segment_s must be a whole number (≥ 16) of dt = {dt:g} s, got {cfg.segment_s}"
            )
        if cfg.band_hz[1] > 0.5 / dt:
            raise InputError(
                f"config.band_hz must stay below the Nyquist frequency {0.5 / dt:g} Hz, got {cfg.band_hz}"
            )
        freqs = np.fft.rfftfreq(n, dt)
        index = np.flatnonzero((freqs >= cfg.band_hz[0] - 1e-9) & (freqs <= cfg.band_hz[1] + 1e-9))
        if index.size == 0:
            raise InputError(
                f"config.band_hz {cfg.band_hz} holds no frequency of a {cfg.segment_s} s segment"
            )
        self.config = cfg
        self.dt = float(dt)
        self.wheelbase_m = float(wheelbase_m)
        self.n = n
        self.f = freqs[index]
        self._index = index
        group = np.floor((self.f - self.f[0]) / cfg.group_hz + 1e-9).astype(int)
        self._group = group
        self._group_size = np.bincount(group).astype(float)
        self._indicator = (group[:, None] == np.arange(self._group_size.size)[None, :]).astype(
            float
        )  # (F, G)
        self._ramp = np.arange(n) - 0.5 * (n - 1)  # for the linear detrend
        self._ramp_norm = float(self._ramp @ self._ramp)
        self._noise_dft = n * cfg.sigma_accel**2  # E|DFT of white noise|², (m/s²)²
        self._history = n + int(math.ceil(self.wheelbase_m / (cfg.min_speed_mps * self.dt))) + 1
        # the search grid: a fine one (a quarter of grid_step_kpa), every 4th point the coarse one
        lo, hi = cfg.pressure_range_kpa
        n_coarse = int(math.floor((hi - lo) / cfg.grid_step_kpa + 1e-9)) + 1
        self._p_fine = lo + 0.25 * cfg.grid_step_kpa * np.arange(4 * (n_coarse - 1) + 1)
        self.set_models(front_model, rear_model, tire_front, tire_rear)
        self._memories = memories
        self.reset()

    # ----------------------------------------------------------------------------------- state
    def set_models(
        self,
        front_model: LinearQuarterCar,
        rear_model: LinearQuarterCar,
        tire_front: TireStiffness,
        tire_rear: TireStiffness,
    ) -> None:
        """Replace the corner models (e.g. a new load); the statistics are kept (they are model-free)."""
        self.front_model = _fixed_damping(front_model, self.config.damping_fraction)
        self.rear_model = _fixed_damping(rear_model, self.config.damping_fraction)
        self.tire_front, self.tire_rear = tire_front, tire_rear
        hr = self._response(self.rear_model, self.tire_rear, self._p_fine)  # (P, F)
        self._hr_fine = np.stack([hr.real, hr.imag, np.abs(hr) ** 2])  # (3, P, F)
        self._hr_coarse = np.ascontiguousarray(self._hr_fine[:, ::4])

    def reset(self) -> None:
        """Forget everything: statistics, buffers and counts."""
        m, nf = self._memories, self.f.size
        self.A = np.zeros((m, nf))
        self.B = np.zeros((m, nf))
        self.C = np.zeros((m, nf), dtype=complex)
        self.K = np.zeros(m)  # Σ w
        self.K2 = np.zeros(m)  # Σ w²
        self._load = np.zeros(
            (m, 2, 3)
        )  # per corner (front, rear): Σ w·n, Σ w·Σx, Σ w·Σx² of the load signal
        self.counts = dict.fromkeys(SKIP_REASONS, 0)
        self._seen = 0  # samples received
        self._front = np.zeros(0)  # the front's last samples, ending at sample `_seen`
        self._pending = np.zeros(
            (5, 0)
        )  # rear, speed, sprung front, sprung rear, unsprung front since segment start
        self._sprung = None  # whether sprung accelerations are given (fixed by the first call)

    def break_stream(self) -> None:
        """The stream jumps in time: drop the buffered samples (the front's history and the rear's
        unfinished segment), keep the statistics."""
        self._front = np.zeros(0)
        self._pending = np.zeros((5, 0))

    @property
    def state_nbytes(self) -> int:
        """Bytes held by the statistics and buffers (bounded)."""
        arrays = (self.A, self.B, self.C, self.K, self.K2, self._load, self._front, self._pending)
        return int(sum(a.nbytes for a in arrays))

    def decay(self, factor: float | npt.ArrayLike) -> None:
        """Multiply the statistics by `factor` (scalar or one per memory, in (0, 1]): forgetting,
        e.g. ``exp(-elapsed_s / tau_s)``."""
        f = _per_memory(factor, self._memories)
        if f is None or not np.all(np.isfinite(f) & (f > 0) & (f <= 1)):
            raise InputError(f"decay factor must lie in (0, 1], got {factor!r}")
        self.A *= f[:, None]
        self.B *= f[:, None]
        self.C *= f[:, None]
        self.K *= f
        self.K2 *= f * f
        self._load *= f[:, None, None]

    # ------------------------------------------------------------------------------- streaming
    def add(
        self,
        acc_u_front: npt.ArrayLike,
        acc_u_rear: npt.ArrayLike,
        speed_mps: float | npt.ArrayLike,
        weight: float | npt.ArrayLike = 1.0,
        *,
        acc_s_front: npt.ArrayLike | None = None,
        acc_s_rear: npt.ArrayLike | None = None,
    ) -> int:
        """Add a chunk of samples (any length, in time order); returns the segments used from it.

        Parameters
        ----------
        acc_u_front, acc_u_rear : array_like, shape (T,)
            Unsprung accelerations of the front and rear corner of the track, m/s² (NaN: bad sample,
            its segment is skipped).
        speed_mps : float or array_like, shape (T,)
            Vehicle speed, m/s.
        weight : float or array_like, shape (memories,)
            Weight of the segments completed in this call (≥ 0), per memory or one for all.
        acc_s_front, acc_s_rear : array_like, shape (T,), optional
            Sprung accelerations, m/s², for the dynamic load coefficient (both or neither; given
            from the first call on or never).
        """
        xf = self._vector("acc_u_front", acc_u_front)
        xr = self._vector("acc_u_rear", acc_u_rear, xf.size)
        v = np.asarray(speed_mps, dtype=float)
        v = np.full(xf.size, float(v)) if v.ndim == 0 else self._vector("speed_mps", v, xf.size)
        w = _per_memory(weight, self._memories)
        if w is None or not np.all(np.isfinite(w) & (w >= 0)):
            raise InputError(f"weight must be ≥ 0, a number or {self._memories} of them, got {weight!r}")
        if (acc_s_front is None) != (acc_s_rear is None):
            raise InputError("acc_s_front and acc_s_rear must be given together (or neither)")
        sprung = acc_s_front is not None
        if self._sprung is None:
            self._sprung = sprung
        elif sprung != self._sprung:
            raise InputError("acc_s_front/acc_s_rear must be given in every call or in none")
        if sprung:
            sf = self._vector("acc_s_front", acc_s_front, xf.size)
            sr = self._vector("acc_s_rear", acc_s_rear, xf.size)
        else:
            sf = sr = np.zeros(xf.size)
        start = self._seen  # global index of the chunk's first sample
        self._seen += xf.size
        front = np.concatenate([self._front, xf])  # ends at global index self._seen
        front_start = self._seen - front.size
        held = self._pending.shape[1]
        pending = np.empty((5, held + xf.size))  # the held samples, then the chunk's
        pending[:, :held] = self._pending
        for row, x in enumerate((xr, v, sf, sr, xf)):
            pending[row, held:] = x
        seg0 = start - self._pending.shape[1]  # global index of the pending segment's first sample
        n = self.n
        n_seg = pending.shape[1] // n
        # the finished segments, all at once: (5, S, n)
        blocks = pending[:, : n_seg * n].reshape(5, n_seg, n)
        speed = blocks[1]
        mean_v = speed.mean(axis=1)  # NaN where a speed is missing: refused below
        moving = (mean_v >= self.config.min_speed_mps) & (
            np.ptp(speed, axis=1) <= self.config.max_speed_change * mean_v
        )
        tau = self.wheelbase_m / np.where(moving, mean_v, 1.0)
        m = np.floor(tau / self.dt).astype(np.int64)
        s = seg0 + n * np.arange(n_seg)
        lo = s - m - front_start
        ready = moving & (s - m >= 0) & (lo >= 0)
        lo = np.where(ready, lo, 0)
        seg_f = front[lo[:, None] + np.arange(n)[None, :]] if n_seg else np.zeros((0, n))  # (S, n)
        sound = ready & np.all(np.isfinite(seg_f), axis=1)
        sound &= np.all(np.isfinite(blocks[[0, 2, 3]]), axis=(0, 2))  # rear, sprung front and rear
        self.counts["speed"] += int(np.sum(~moving))
        self.counts["warmup"] += int(np.sum(moving & ~ready))
        self.counts["gap"] += int(np.sum(ready & ~sound))
        self.counts["used"] += int(np.sum(sound))
        if np.any(sound):
            used = blocks if sound.all() else blocks[:, sound]
            self._accumulate(seg_f[sound], used, (tau - m * self.dt)[sound], w)
        self._pending = pending[:, n_seg * n :].copy()
        self._front = front[-self._history :].copy()
        return int(np.sum(sound))

    def _vector(self, name: str, x, size: int | None = None) -> np.ndarray:
        a = np.asarray(x, dtype=float)
        if a.ndim != 1 or (size is not None and a.size != size):
            want = f"shape ({size},)" if size is not None else "one dimension"
            raise InputError(f"{name} must be a 1-D array of {want}, got shape {a.shape}")
        return a

    def _accumulate(self, fronts, blocks, deltas, w) -> None:
        """Add S segment pairs: the fronts' (S, n) delayed by the fractional delays `deltas` (S,) s and the
        rears' rows of `blocks` (5, S, n) (:meth:`add`'s: unsprung rear, speed, sprung front, sprung rear,
        unsprung front). Every row is transformed on its own and the sums are taken one segment at a
        time, so they are the same, bit for bit, however the samples were chunked."""
        fm, rm = self.front_model, self.rear_model
        x = np.fft.rfft(_detrended(fronts, self._ramp, self._ramp_norm), axis=1)[:, self._index]
        y = np.fft.rfft(_detrended(blocks[0], self._ramp, self._ramp_norm), axis=1)[:, self._index]
        axx = np.abs(x) ** 2
        ayy = np.abs(y) ** 2
        cxy = np.conj(x) * y * np.exp(2j * np.pi * deltas[:, None] * self.f[None, :])
        # each tyre's dynamic load, m_s a_s + m_us a_us (N): its sum and sum of squares per segment
        masses = np.array([fm.sprung_mass, fm.unsprung_mass, rm.sprung_mass, rm.unsprung_mass])
        moments = _load_moments(blocks[4], blocks[0], blocks[2], blocks[3], masses)
        _add_segments(self.A, self.B, self.C, self.K, self.K2, self._load, w, axx, ayy, cxy, moments)

    # ------------------------------------------------------------------------------ likelihood
    def _response(self, qc: LinearQuarterCar, tire: TireStiffness, p_kpa: np.ndarray) -> np.ndarray:
        kt = stiffness_at_pressure_array(np.asarray(p_kpa, dtype=float) * 1e3, tire.kt0, tire.p0, tire.pfz1)
        return own_track_response(self.f[None, :], np.asarray(kt)[..., None], qc)

    def _terms(self, memory: int):
        """Noise-corrected front power A' (F,), kept bands (G,) and K_g (G,), for one memory."""
        cfg = self.config
        a, k = self.A[memory], self.K[memory]
        noise = k * self._noise_dft
        kg = self._group_size * k
        snr = (a @ self._indicator) / np.maximum(kg * self._noise_dft, 1e-300) - 1.0
        keep = snr >= cfg.snr_min
        return np.maximum(a - noise, 0.05 * a), keep, kg

    def _loglik_rows(self, hf: np.ndarray, hr: np.ndarray, memory: int, terms) -> np.ndarray:
        """ℓ for one front response hf (F,) and rear responses hr (3, P, F) (real part, imaginary
        part, squared modulus): shape (P,). Q_g is linear in (Re h_r, Im h_r, |h_r|²): three
        matrix products with the per-band sums."""
        a_corr, keep, kg = terms
        ind = self._indicator[:, keep]
        c = self.C[memory] / np.conj(hf)
        a = a_corr / np.abs(hf) ** 2
        qg = (
            (self.B[memory] @ ind)[None, :]
            - 2.0 * (hr[0] @ (c.real[:, None] * ind) + hr[1] @ (c.imag[:, None] * ind))
            + hr[2] @ (a[:, None] * ind)
        )
        kk = kg[keep]
        v0 = self._noise_dft
        terms = np.where(
            qg >= kk * v0, -kk * np.log(np.maximum(qg, kk * v0) / kk), -kk * np.log(v0) - qg / v0 + kk
        )  # _band_term
        return np.sum(terms, axis=-1)

    def loglik(self, p_front_kpa: npt.ArrayLike, p_rear_kpa: npt.ArrayLike, *, memory: int = 0) -> np.ndarray:
        """The profile log-likelihood ℓ(p_f, p_r) of the module docstring, any broadcastable shapes
        (kPa); bands below the SNR gate left out (−0 everywhere if none passes)."""
        pf, pr = np.broadcast_arrays(
            np.asarray(p_front_kpa, dtype=float), np.asarray(p_rear_kpa, dtype=float)
        )
        mem = self._memory(memory)
        terms = self._terms(mem)
        hf = self._response(self.front_model, self.tire_front, pf.ravel())
        hr = self._response(self.rear_model, self.tire_rear, pr.ravel())
        hr = np.stack([hr.real, hr.imag, np.abs(hr) ** 2])
        out = np.array([self._loglik_rows(hf[i], hr[:, i : i + 1], mem, terms)[0] for i in range(pf.size)])
        return out.reshape(pf.shape)

    def _memory(self, memory: int) -> int:
        if not (isinstance(memory, (int, np.integer)) and 0 <= memory < self._memories):
            raise InputError(f"memory must be an integer 0–{self._memories - 1}, got {memory!r}")
        return int(memory)

    def dlc(self, *, memory: int = 0) -> float:
        """The track's dynamic load coefficient: the larger of its two corners'
        std(m_s a_s + m_us a_us)/((m_s + m_us) g), the accelerometers' noise variance removed (−);
        NaN without sprung accelerations or data."""
        mem = self._memory(memory)
        if not self._sprung or self._load[mem, 0, 0] <= 0:
            return float("nan")
        out = []
        for c, qc in enumerate((self.front_model, self.rear_model)):
            s0, s1, s2 = self._load[mem, c]
            var = s2 / s0 - (s1 / s0) ** 2
            var -= self.config.sigma_accel**2 * (qc.sprung_mass**2 + qc.unsprung_mass**2)
            out.append(math.sqrt(max(var, 0.0)) / ((qc.sprung_mass + qc.unsprung_mass) * _GRAVITY))
        return float(max(out))

    def coherence(self, *, memory: int = 0) -> float:
        r"""The two wheels' coherence: the mean over the bands above the SNR gate of
        :math:`|C_g|^2/(A'_g B'_g)`, C, A, B summed over the band, A' and B' less the
        accelerometers' noise (−, clipped to [0, 1]; NaN without such a band)."""
        mem = self._memory(memory)
        return self._coherence(mem, self._terms(mem))

    def _coherence(self, mem: int, terms) -> float:
        _, keep, kg = terms
        if not np.any(keep):
            return float("nan")
        noise = kg * self._noise_dft
        a = self.A[mem] @ self._indicator - noise
        b = self.B[mem] @ self._indicator - noise
        c = np.abs(self.C[mem] @ self._indicator) ** 2
        coh = np.clip(c / np.maximum(a * b, 1e-300), 0.0, 1.0)
        return float(np.mean(coh[keep]))

    def conditional(
        self,
        p_front_kpa: float,
        sigma_front_kpa: float,
        *,
        memory: int = 0,
        dlc: float | None = None,
    ) -> PreviewConditional:
        """The rear's pressure (Gaussian, kPa) given the front's N(`p_front_kpa`, `sigma_front_kpa`²).

        Laplace's method along the ridge of ℓ (module docstring): mean p_r*(p̂_f), variance
        c_w/H_rr·sigma_scale² + (dp_r*/dp_f)²σ_f² + floor², the ridge slope by a central difference
        of ±``slope_step_kpa``. `dlc`: the dynamic load coefficient choosing the floor (default the
        accumulated one, :meth:`dlc`; unknown: the rough floor).
        """
        mem = self._memory(memory)
        cfg = self.config
        if not (
            np.isfinite(p_front_kpa) and cfg.pressure_range_kpa[0] <= p_front_kpa <= cfg.pressure_range_kpa[1]
        ):
            raise InputError(f"p_front_kpa must lie within {cfg.pressure_range_kpa} kPa, got {p_front_kpa!r}")
        if not (np.isfinite(sigma_front_kpa) and sigma_front_kpa >= 0):
            raise InputError(f"sigma_front_kpa must be finite and ≥ 0 kPa, got {sigma_front_kpa!r}")
        if dlc is not None and not (np.isfinite(dlc) and dlc >= 0):
            raise InputError(f"dlc must be finite and ≥ 0, got {dlc!r}")
        d = self.dlc(memory=mem) if dlc is None else float(dlc)
        floor = cfg.floor_kpa if (np.isfinite(d) and d <= cfg.rough_dlc) else cfg.rough_floor_kpa
        k, k2 = float(self.K[mem]), float(self.K2[mem])
        n_eff = k * k / k2 if k2 > 0 else 0.0
        terms = self._terms(mem)
        bands = int(np.sum(terms[1]))
        coherence = self._coherence(mem, terms)

        def result(mean, sigma, reason, sig_lik=float("nan"), slope=float("nan")):
            return PreviewConditional(
                mean_kpa=float(mean), sigma_kpa=float(sigma), informative=reason == "", reason=reason,
                sigma_likelihood_kpa=float(sig_lik), ridge_slope=float(slope),
                cov_front_rear_kpa2=float(slope * sigma_front_kpa**2), floor_kpa=float(floor), dlc=d,
                segments=float(n_eff), bands_used=bands, coherence=coherence,
            )  # fmt: skip

        if k <= 0:
            return result(np.nan, np.inf, "no_segments")
        if bands == 0:
            return result(np.nan, np.inf, "low_snr")
        if not coherence >= cfg.min_coherence:
            return result(np.nan, np.inf, "incoherent")
        dp = cfg.slope_step_kpa
        lo = max(p_front_kpa - dp, cfg.pressure_range_kpa[0])
        hi = min(p_front_kpa + dp, cfg.pressure_range_kpa[1])
        hf = self._response(self.front_model, self.tire_front, np.array([p_front_kpa, lo, hi]))  # (3, F)
        a_corr, keep, kg = terms
        c = self.C[mem][None, :] / np.conj(hf)
        ps, hs, inside = _ridge_kernel(
            self.B[mem], np.ascontiguousarray(c.real), np.ascontiguousarray(c.imag),
            a_corr[None, :] / np.abs(hf) ** 2, self._group, keep, kg, self._noise_dft, self._hr_coarse,
            self._hr_fine, self._p_fine, cfg.grid_step_kpa,
            int(math.ceil(4.0 * cfg.slope_step_kpa / cfg.grid_step_kpa)),
        )  # fmt: skip
        p_star, h_rr, interior = float(ps[0]), float(hs[0]), bool(inside[0])
        if not interior:
            return result(p_star, np.inf, "edge")
        if not np.isfinite(h_rr):
            return result(p_star, np.inf, "flat")
        slope = (ps[2] - ps[1]) / (hi - lo) if (inside[1] and inside[2]) else float("nan")
        var_lik = (k2 / k) / h_rr * cfg.sigma_scale**2
        slope_term = slope**2 * sigma_front_kpa**2 if np.isfinite(slope) else np.inf
        sigma = math.sqrt(var_lik + slope_term + floor**2)
        reason = "" if n_eff >= cfg.min_segments else "few_segments"
        if not np.isfinite(slope):
            reason = reason or "edge"
        return result(p_star, sigma, reason, math.sqrt(var_lik), slope)
