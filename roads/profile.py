r"""ISO 8608 random road profiles on two wheel tracks, with segments and obstacles.

Usual call: ``road = generate_road(RoadSpec(segments=[SegmentSpec(length_m=300, road_class="C")]), seed=7)``.

Three generators, each seeded by a :class:`numpy.random.Generator`, each
vectorized (no per-sample Python loop):

``shape-filter``
    The first-order shape filter of Brancati & Tufano 2022, eq. 5–6, written
    over distance x (α = 0.127 rad/m):
    :math:`dz/dx = -\alpha z + \xi(x)`, whose one-sided angular PSD is
    :math:`G(\Omega) = q / (\alpha^2 + \Omega^2)`. It is discretized exactly as
    an AR(1) process (:func:`scipy.signal.lfilter`). The paper sets the
    variance to σ² = 4·Gd(Ω0), which puts the PSD at Ω0 = 1 rad/m at
    :math:`2\alpha\sigma^2/(\pi(1+\alpha^2)) \approx 0.32\,G_d(\Omega_0)`, a road
    three times too smooth; here `q` is calibrated so that the PSD at
    Ω0 = 1 rad/m *is* the ISO level (:func:`shape_filter_intensity`).
    Above α/2π ≈ 0.02 cycle/m the PSD follows the ISO slope w = 2; below it
    flattens (that is the filter's purpose).

``superposition``
    Sinusoid superposition, Lin et al. 2021, eq. 31:
    :math:`z(x) = \sum_i A_i \sin(2\pi n_i x - \psi_i)` with random phases
    over ``n_min … n_max`` (default 0.01–10 cycles/m), evaluated by one inverse
    real FFT on a grid of at least ``8/n_min`` metres so the profile never
    repeats within a road. :math:`A_i^2/2` is the ISO PSD integrated over the
    line's bin, so the profile variance equals the integral of the target PSD
    over the band exactly (eq. 31's :math:`A_i = \sqrt{2\Phi(n_i)\Delta n}`
    overstates it by ~30 % at the 0.01 cycle/m edge, where the PSD is steep).
    Any waviness w is possible. Every line's amplitude is fixed; only its phase is random, so over
    the road's length the profile's periodogram *is* the target PSD, line for line (the random-phase
    spectral representation is ergodic in its autocorrelation over its period: Shinozuka & Deodatis
    1991 [6]_): averaged over a few windows of a road it converges to the PSD far faster than a
    measured road's would (over 8 windows of 160 m, hop 80 m, band means of 0.025 cycles/m at
    0.1–2 cycles/m scatter by 0.15 against 0.22–0.23 for the two Gaussian generators' roads, over
    13 windows 0.075 against 0.18; on one window alike, 0.45–0.48; ``tests/test_roads.py``), which
    flatters any estimator that reads a road's spectrum.

``gaussian``
    The same superposition with random amplitudes: each line's coefficient
    :math:`a_i\cos + b_i\sin` with :math:`a_i, b_i \sim \mathcal N(0, A_i^2/2)` independent
    (Rice 1944 [7]_), i.e. a Rayleigh amplitude and a uniform phase. The profile is then a stationary
    Gaussian process with the ISO PSD (any waviness, the band of ``superposition``), and its
    periodogram scatters as a Gaussian process's does (each line's power exponentially distributed
    about the PSD): the road for validating estimators that read the road's spectrum.

Segments are generated independently and joined by a power-complementary
(cos/sin) cross-fade of ``transition_m``, so the profile has no step at a
class change and its variance does not dip. Left/right tracks are independent,
identical, correlated with coefficient ρ at every wavelength
(:math:`z_r = \rho z_l + \sqrt{1-\rho^2} z_2`, which keeps each track's PSD), or
``isotropic``: two parallel lines a distance B apart on a surface whose roughness is the same in
every direction (the isotropic road of Dodds & Robson 1973 [4]_), whose coherence falls with the
wavelength as :func:`isotropic_coherence` gives; built line by line in the frequency domain,
:math:`Z_r(n) = \gamma(n) Z_l(n) + \sqrt{1-\gamma(n)^2}\,Z_2(n)` (the construction of Liu et al.
2015 [5]_ for a given coherence function).

References
----------
.. [1] R. Brancati, F. Tufano, "Indirect estimation of tire pressure on several
   road pavements via Interacting Multiple Model approach", Machines 10(12), 1221, 2022.
   doi:10.3390/machines10121221
.. [2] Lin et al., "Vertical vehicle dynamics estimated inputs", 2021.
.. [3] ISO 8608:2016, "Mechanical vibration — Road surface profiles".
.. [4] C. J. Dodds, J. D. Robson, "The description of road surface roughness", J. Sound Vib.
   31(2), 175–183, 1973.
.. [5] X. Liu, H. Wang, Y. Shan, T. He, "Construction of road roughness in left and right wheel
   paths based on PSD and coherence function", Mech. Syst. Signal Process., 2015.
   doi:10.1016/j.ymssp.2015.01.034
.. [6] M. Shinozuka, G. Deodatis, "Simulation of stochastic processes by spectral representation",
   Appl. Mech. Rev. 44(4), 191–204, 1991.
.. [7] S. O. Rice, "Mathematical analysis of random noise", Bell Syst. Tech. J. 23(3), 282–332, 1944.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.files import atomic_write, package_versions, read_parquet_table
from suvtwin.roads.iso8608 import N0_CYCLES_PER_M, OMEGA0_RAD_PER_M
from suvtwin.roads.spec import ObstacleSpec, RoadSpec

__all__ = [
    "SHAPE_FILTER_ALPHA",
    "Road",
    "add_obstacles",
    "isotropic_coherence",
    "fast_fft_length",
    "generate_road",
    "obstacle_profile",
    "read_road",
    "shape_filter_intensity",
    "shape_filter_profile",
    "superposition_profile",
    "write_road",
]

SHAPE_FILTER_ALPHA = 0.127
"""Shape-filter low-frequency cut-off α, rad/m (Brancati & Tufano 2022, §2)."""

_ISOTROPIC_PAD_M = 60.0
"""Length added to each end of an isotropic segment's draws before their tracks are mixed in the
frequency domain, then cut, m: the mixing's kernel spans a few track spacings."""

_METADATA_KEY = b"suvtwin.road"
_COLUMNS = ("x_m", "z_left_m", "z_right_m")


def shape_filter_intensity(gd_n0: float, *, alpha: float = SHAPE_FILTER_ALPHA) -> float:
    r"""Intensity `q` of the shape filter so its PSD at Ω0 = 1 rad/m is the ISO level, m.

    The filter's one-sided angular PSD is :math:`G(\Omega) = q/(\alpha^2+\Omega^2)`
    (Brancati & Tufano 2022, eq. 5 with :math:`q = 2\alpha\sigma^2/\pi`).
    Setting :math:`G(\Omega_0)` to the ISO angular level
    :math:`G_d(\Omega_0) = G_d(n_0)(2\pi n_0/\Omega_0)^2/(2\pi)` (w = 2) gives
    :math:`q = G_d(\Omega_0)(\alpha^2 + \Omega_0^2)`.
    """
    gd_omega0 = gd_n0 * (2.0 * np.pi * N0_CYCLES_PER_M / OMEGA0_RAD_PER_M) ** 2 / (2.0 * np.pi)
    return gd_omega0 * (alpha**2 + OMEGA0_RAD_PER_M**2)


def shape_filter_profile(
    n_samples: int,
    spacing_m: float,
    *,
    gd_n0: float,
    rng: np.random.Generator,
    n_tracks: int = 1,
    alpha: float = SHAPE_FILTER_ALPHA,
) -> np.ndarray:
    r"""Road profile from the first-order shape filter, m.

    Exact discretization of :math:`dz/dx = -\alpha z + \xi` (Brancati & Tufano
    2022, eq. 6 over distance): :math:`z_{k+1} = \phi z_k + s\,e_k`,
    :math:`\phi = e^{-\alpha\Delta x}`,
    :math:`s^2 = \sigma_z^2(1-\phi^2)`, stationary variance
    :math:`\sigma_z^2 = \pi q/(2\alpha)`, started in the stationary state.

    Parameters
    ----------
    n_samples : int
        Number of samples along x.
    spacing_m : float
        Grid spacing Δx, m.
    gd_n0 : float
        ISO level Gd(n0), m³ at n0 = 0.1 cycle/m (:func:`shape_filter_intensity`).
    rng : numpy.random.Generator
        Source of the white noise.
    n_tracks : int, optional
        Number of independent profiles (default 1).
    alpha : float, optional
        Low-frequency cut-off α, rad/m (default 0.127).

    Returns
    -------
    numpy.ndarray, shape (n_tracks, n_samples)
        Elevation, m.
    """
    q = shape_filter_intensity(gd_n0, alpha=alpha)
    variance = np.pi * q / (2.0 * alpha)
    phi = np.exp(-alpha * spacing_m)
    noise = rng.standard_normal((n_tracks, n_samples))
    drive = noise * np.sqrt(variance * (1.0 - phi**2))
    drive[:, 0] = noise[:, 0] * np.sqrt(variance)  # stationary start z_0 ~ N(0, σ_z²)
    import scipy.signal  # here: slow to import (scipy.stats, …) and only this generator needs it

    return scipy.signal.lfilter([1.0], [1.0, -phi], drive, axis=-1)


def fast_fft_length(n: int) -> int:
    """Smallest 2^a·3^b·5^c ≥ `n`: a length that pocketfft (numpy.fft, scipy.fft) transforms fast.

    The same number as ``scipy.fft.next_fast_len(n, real=True)``, without importing scipy.fft
    (slow to import; the road generator needs nothing else from it).
    """
    if n < 1:
        raise ValueError(f"n must be ≥ 1, got {n}")
    best = 1 << (n - 1).bit_length()  # the smallest power of two ≥ n
    p5 = 1
    while p5 < best:
        p35 = p5
        while p35 < best:
            p = p35
            while p < n:
                p *= 2
            best = min(best, p)
            p35 *= 3
        p5 *= 5
    return best


def superposition_profile(
    n_samples: int,
    spacing_m: float,
    *,
    gd_n0: float,
    rng: np.random.Generator,
    waviness: float = 2.0,
    n_min: float = 0.01,
    n_max: float = 10.0,
    n_tracks: int = 1,
    random_amplitudes: bool = False,
) -> np.ndarray:
    r"""Road profile as a sum of sinusoids with random phases, m.

    :math:`z(x) = \sum_i A_i \sin(2\pi n_i x - \psi_i)`, :math:`\psi_i \sim U[0, 2\pi)`
    (Lin et al. 2021, eq. 31), on the lines :math:`n_i = i\,\Delta n` of an FFT
    grid inside ``[n_min, n_max]``, with
    :math:`A_i^2/2 = \int_{\text{bin } i} G_d(n)\,dn` (ISO 8608 PSD, bins clipped
    to the band). Evaluated by one inverse real FFT. With `random_amplitudes`, each line is
    :math:`a_i \cos(2\pi n_i x) + b_i \sin(2\pi n_i x)`, :math:`a_i, b_i \sim \mathcal N(0, A_i^2/2)`
    (Rice 1944): the same PSD in expectation, a Gaussian process.

    Parameters
    ----------
    n_samples : int
        Number of samples along x.
    spacing_m : float
        Grid spacing Δx, m; ``n_max`` must not exceed 1/(2Δx).
    gd_n0 : float
        ISO level Gd(n0), m³ at n0 = 0.1 cycle/m.
    rng : numpy.random.Generator
        Source of the phases.
    waviness : float, optional
        PSD exponent w (default 2).
    n_min, n_max : float, optional
        Generated band, cycles/m (default 0.01–10).
    n_tracks : int, optional
        Number of independent profiles (default 1).
    random_amplitudes : bool, optional
        Draw each line's amplitude too (Rayleigh, a Gaussian road) instead of fixing it at
        :math:`A_i` (default False, the random-phase road).

    Returns
    -------
    numpy.ndarray, shape (n_tracks, n_samples)
        Elevation, m.
    """
    n_fft = fast_fft_length(max(n_samples, int(np.ceil(8.0 / (n_min * spacing_m)))))
    dn = 1.0 / (n_fft * spacing_m)
    k = np.arange(n_fft // 2 + 1)
    lines = k * dn
    lower = np.clip(lines - dn / 2.0, n_min, n_max)
    upper = np.clip(lines + dn / 2.0, n_min, n_max)
    inside = (upper > lower) & (k > 0) & (k < n_fft / 2.0)
    bin_power = np.zeros_like(lines)
    bin_power[inside] = _psd_integral(lower[inside], upper[inside], gd_n0=gd_n0, waviness=waviness)
    amplitude = np.sqrt(2.0 * bin_power)
    # irfft(X)[j] = (2/N) Re sum_k X_k exp(i 2π k j / N)
    if random_amplitudes:
        # X_k = (N/2) (a_k - i b_k) gives a_k cos(2π n_k x_j) + b_k sin(2π n_k x_j), a, b ~ N(0, A_k²/2)
        a, b = rng.standard_normal((2, n_tracks, lines.size))
        spectrum = (n_fft / 2.0) * amplitude / np.sqrt(2.0) * (a - 1j * b)
    else:
        # X_k = (N/2) A_k exp(-i(ψ_k + π/2)) gives A_k sin(2π n_k x_j - ψ_k)
        phase = rng.uniform(0.0, 2.0 * np.pi, size=(n_tracks, lines.size))
        spectrum = (n_fft / 2.0) * amplitude * np.exp(-1j * (phase + np.pi / 2.0))
    return np.fft.irfft(spectrum, n=n_fft, axis=-1)[:, :n_samples]


def _psd_integral(lower: np.ndarray, upper: np.ndarray, *, gd_n0: float, waviness: float) -> np.ndarray:
    """∫ Gd(n) dn from `lower` to `upper` (cycles/m) of the ISO PSD, m²."""
    scale = gd_n0 * N0_CYCLES_PER_M**waviness
    if np.isclose(waviness, 1.0):
        return scale * np.log(upper / lower)
    e = 1.0 - waviness
    return scale * (upper**e - lower**e) / e


def obstacle_profile(x: npt.ArrayLike, obstacle: ObstacleSpec) -> np.ndarray:
    """Elevation added by one obstacle along `x` (m), m.

    ``sine_bump``: :math:`h_0 \\sin(\\pi (x - x_0)/D)` on :math:`[x_0, x_0 + D]`
    (Lin et al. 2021, eq. 23 with :math:`w_f t = \\pi v t / D = \\pi s / D`);
    ``cleat``: `height_m` on :math:`[x_0, x_0 + D)`; ``pothole``: `-height_m`
    on :math:`[x_0, x_0 + D)`.
    """
    x = np.asarray(x, dtype=float)
    s = x - obstacle.position_m
    if obstacle.kind == "sine_bump":
        on = (s >= 0.0) & (s <= obstacle.length_m)
        return np.where(on, obstacle.height_m * np.sin(np.pi * s / obstacle.length_m), 0.0)
    on = (s >= 0.0) & (s < obstacle.length_m)
    sign = 1.0 if obstacle.kind == "cleat" else -1.0
    return np.where(on, sign * obstacle.height_m, 0.0)


def add_obstacles(x: np.ndarray, z: np.ndarray, obstacles: list[ObstacleSpec]) -> np.ndarray:
    """Return `z` (shape (2, n): left, right) with every obstacle added on its track(s), m."""
    z = z.copy()
    for obstacle in obstacles:
        bump = obstacle_profile(x, obstacle)
        if obstacle.track in ("left", "both"):
            z[0] += bump
        if obstacle.track in ("right", "both"):
            z[1] += bump
    return z


@dataclass(frozen=True)
class Road:
    """A road on a uniform grid: two wheel tracks and how they were made.

    Attributes
    ----------
    x : numpy.ndarray, shape (n,)
        Distance along the road, m, uniformly spaced, increasing.
    z : numpy.ndarray, shape (2, n)
        Elevation of the left (row 0) and right (row 1) wheel track, m.
    spec : RoadSpec or None
        Description the road was generated from (None for a road read from a
        file that does not carry one, e.g. a measured profile).
    seed : int or None
        Seed of the generator (None if not generated here).
    """

    x: np.ndarray
    z: np.ndarray
    spec: RoadSpec | None = None
    seed: int | None = None

    def __post_init__(self) -> None:
        x = np.array(self.x, dtype=float)
        z = np.array(self.z, dtype=float)
        if x.ndim != 1 or z.shape != (2, x.size):
            raise InputError(f"road arrays: x must be (n,) and z (2, n), got {x.shape} and {z.shape}")
        x.setflags(write=False)
        z.setflags(write=False)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "z", z)

    @property
    def spacing_m(self) -> float:
        """Grid spacing, m."""
        return float(self.x[1] - self.x[0])

    @property
    def length_m(self) -> float:
        """Distance from first to last sample, m."""
        return float(self.x[-1] - self.x[0])

    def height(self, x: npt.ArrayLike, track: int) -> np.ndarray:
        """Elevation of track `track` (0 left, 1 right) at distances `x` (m), m.

        Linear interpolation; held constant beyond the ends.
        """
        return np.interp(x, self.x, self.z[track])


def generate_road(spec: RoadSpec, *, seed: int) -> Road:
    """Generate the road described by `spec`, reproducibly from `seed`.

    Segments are drawn in order, each track after the other, from one
    ``numpy.random.default_rng(seed)``: the same spec and seed give the same
    road, bit for bit.
    """
    rng = np.random.default_rng(seed)
    n_samples = int(np.floor(spec.length_m / spec.spacing_m + 1e-9)) + 1
    x = np.arange(n_samples) * spec.spacing_m
    bounds = np.cumsum([0.0] + [seg.length_m for seg in spec.segments])
    half_fade = spec.transition_m / 2.0
    z = np.zeros((2, n_samples))
    for i in range(len(spec.segments)):
        start = bounds[i] - (half_fade if i > 0 else 0.0)
        end = bounds[i + 1] + (half_fade if i < len(spec.segments) - 1 else 0.0)
        first = max(int(np.floor(start / spec.spacing_m)), 0)
        last = min(int(np.ceil(end / spec.spacing_m)), n_samples - 1)
        piece = _segment_tracks(spec, segment_index=i, n_samples=last - first + 1, rng=rng)
        weight = _fade_weight(x[first : last + 1], bounds, i, half_fade)
        z[:, first : last + 1] += weight * piece
    z = add_obstacles(x, z, spec.obstacles)
    return Road(x=x, z=z, spec=spec, seed=seed)


def _segment_tracks(
    spec: RoadSpec, *, segment_index: int, n_samples: int, rng: np.random.Generator
) -> np.ndarray:
    """Left and right profile of one segment, shape (2, n_samples), m."""
    segment = spec.segments[segment_index]
    n_draw = 1 if spec.tracks == "identical" else 2
    # isotropic tracks are mixed in the frequency domain over longer draws, cropped: no wrap at the ends
    pad = int(math.ceil(_ISOTROPIC_PAD_M / spec.spacing_m)) if spec.tracks == "isotropic" else 0
    if spec.method == "shape-filter":
        draws = shape_filter_profile(n_samples + 2 * pad, spec.spacing_m, gd_n0=segment.level, rng=rng,
                                     n_tracks=n_draw)  # fmt: skip
    else:
        draws = superposition_profile(
            n_samples + 2 * pad,
            spec.spacing_m,
            gd_n0=segment.level,
            waviness=segment.waviness,
            n_min=spec.n_min,
            n_max=spec.n_max,
            rng=rng,
            n_tracks=n_draw,
            random_amplitudes=spec.method == "gaussian",
        )
    if spec.tracks == "identical":
        return np.vstack([draws[0], draws[0]])
    if spec.tracks == "correlated":
        rho = spec.track_correlation
        return np.vstack([draws[0], rho * draws[0] + np.sqrt(1.0 - rho**2) * draws[1]])
    if spec.tracks == "isotropic":
        return _isotropic_pair(draws[:, : n_samples + 2 * pad], spec.spacing_m, spec.track_spacing_m,
                               segment.waviness)[:, pad : pad + n_samples]  # fmt: skip
    return draws


def _isotropic_pair(
    draws: np.ndarray, spacing_m: float, track_spacing_m: float, waviness: float
) -> np.ndarray:
    r"""Two independent draws (2, n) made into the left and right lines of an isotropic surface:
    the right line's spectrum :math:`\gamma Z_l + \sqrt{1-\gamma^2} Z_2` per spatial frequency
    (:func:`isotropic_coherence`), circular over the draws (the caller pads and crops them)."""
    n = draws.shape[1]
    spectra = np.fft.rfft(draws, axis=1)
    gamma = isotropic_coherence(np.fft.rfftfreq(n, spacing_m), track_spacing_m, waviness)
    right = np.fft.irfft(gamma * spectra[0] + np.sqrt(1.0 - gamma**2) * spectra[1], n=n)
    return np.vstack([draws[0], right])


def isotropic_coherence(n: npt.ArrayLike, track_spacing_m: float, waviness: float = 2.0) -> np.ndarray:
    r"""Coherence of two parallel lines a distance B apart on an isotropic road, at spatial frequency n.

    A surface whose roughness is the same in every direction and whose profile along any line has
    the displacement PSD :math:`G_d(n) \propto n^{-w}` has the two-dimensional spectrum
    :math:`\propto (n^2 + m^2)^{-(w+1)/2}` (n along, m across the road; Dodds & Robson 1973 [4]_).
    The cross spectrum of two lines B apart is its integral over m weighted by
    :math:`\cos(2\pi m B)`, the PSD of one line the plain integral; their ratio (G. N. Watson's
    integral of :math:`\cos(bm)/(n^2+m^2)^{s}`) is

    .. math:: \gamma(n) = \frac{2^{1-\nu}}{\Gamma(\nu)}\,x^{\nu} K_\nu(x), \qquad
       x = 2\pi n B,\quad \nu = w/2,

    K_ν the modified Bessel function of the second kind: 1 at n = 0, falling with n B (for w = 2,
    :math:`x K_1(x)`: 0.98 at 100 m wavelengths, 0.59 at 10 m, 0.13 at 3.5 m, on tracks 1.62 m apart). Real
    and positive (the lines' spectra are in phase); `n` in cycles/m."""
    if not (np.isfinite(track_spacing_m) and track_spacing_m > 0):
        raise InputError(f"track_spacing_m must be > 0 m, got {track_spacing_m!r}")
    if not 1.0 <= waviness <= 3.5:
        raise InputError(f"waviness must be in [1, 3.5], got {waviness!r}")
    import scipy.special  # here: only this option needs it

    nu = 0.5 * waviness
    x = 2.0 * np.pi * np.abs(np.asarray(n, dtype=float)) * track_spacing_m
    with np.errstate(invalid="ignore", over="ignore"):
        gamma = 2.0 ** (1.0 - nu) / scipy.special.gamma(nu) * x**nu * scipy.special.kv(nu, x)
    return np.where(x > 0.0, np.nan_to_num(gamma, nan=0.0), 1.0)


def _fade_weight(x: np.ndarray, bounds: np.ndarray, i: int, half_fade: float) -> np.ndarray:
    """Power-complementary weight of segment `i` at `x`: 1 inside, cos/sin ramps at joins."""
    weight = np.ones_like(x)
    if half_fade == 0.0:
        inside = (x >= bounds[i]) & ((x < bounds[i + 1]) | (i == bounds.size - 2))
        return inside.astype(float)
    if i > 0:  # ramp up across the join at bounds[i]
        s = np.clip((x - (bounds[i] - half_fade)) / (2.0 * half_fade), 0.0, 1.0)
        weight *= np.sin(0.5 * np.pi * s)
    if i < bounds.size - 2:  # ramp down across the join at bounds[i + 1]
        s = np.clip((x - (bounds[i + 1] - half_fade)) / (2.0 * half_fade), 0.0, 1.0)
        weight *= np.cos(0.5 * np.pi * s)
    return weight


def write_road(road: Road, path: str | os.PathLike) -> None:
    """Write `road` to a Parquet file: columns ``x_m``, ``z_left_m``, ``z_right_m``.

    The spec, seed and package versions go into the file's metadata under
    ``suvtwin.road`` (JSON). The file is written to a temporary name and renamed,
    so a failure never leaves a partial file; the same road gives the same bytes.
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.table({"x_m": road.x, "z_left_m": road.z[0], "z_right_m": road.z[1]})
    info = {
        "spec": None if road.spec is None else road.spec.model_dump(mode="json"),
        "seed": road.seed,
        "versions": package_versions(("suvtwin", "numpy", "scipy", "pyarrow")),
    }
    table = table.replace_schema_metadata({_METADATA_KEY: json.dumps(info, sort_keys=True).encode()})
    atomic_write(path, lambda tmp: pq.write_table(table, tmp, compression="zstd"))


def read_road(path: str | os.PathLike) -> Road:
    """Read a road from a Parquet file with columns ``x_m``, ``z_left_m``, ``z_right_m``.

    Any file with those columns is accepted (a measured profile, too): x in m,
    strictly increasing and uniformly spaced, elevations in m, no NaN.

    Raises
    ------
    InputError
        If the file is missing, not Parquet, lacks a column, or holds bad values.
    """
    import pyarrow as pa

    path = Path(path)
    table = read_parquet_table(path, what="road file")
    missing = [c for c in _COLUMNS if c not in table.column_names]
    if missing:
        raise InputError(
            f"road file {str(path)!r} lacks column(s) {', '.join(missing)}; expected {', '.join(_COLUMNS)}"
        )
    try:
        x, left, right = (table.column(c).to_numpy().astype(float) for c in _COLUMNS)
    except (TypeError, ValueError, pa.ArrowException) as error:
        raise InputError(f"road file {str(path)!r}: columns must be numeric ({error})") from None
    if x.size < 16:
        raise InputError(f"road file {str(path)!r}: needs at least 16 samples, got {x.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(left)) and np.all(np.isfinite(right))):
        raise InputError(f"road file {str(path)!r}: x_m, z_left_m and z_right_m must be finite (no NaN)")
    step = np.diff(x)
    if np.any(step <= 0.0):
        raise InputError(f"road file {str(path)!r}: x_m must be strictly increasing")
    if np.ptp(step) > 1e-6 * np.mean(step) + 1e-12:
        raise InputError(
            f"road file {str(path)!r}: x_m must be uniformly spaced "
            f"(steps from {step.min():.6g} to {step.max():.6g} m)"
        )
    spec, seed = None, None
    raw = (table.schema.metadata or {}).get(_METADATA_KEY)
    if raw is not None:
        info = json.loads(raw)
        if info.get("spec") is not None:
            spec = RoadSpec.model_validate(info["spec"])
        seed = info.get("seed")
    return Road(x=x, z=np.vstack([left, right]), spec=spec, seed=seed)
