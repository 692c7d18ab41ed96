r"""Road roughness from a profile: Welch PSD and ISO 8608 level, waviness and class.

Usual call: ``fit = classify_profile(road.z[0], road.spacing_m)``.

The profile's one-sided displacement PSD is estimated with Welch's method
(:func:`scipy.signal.welch`, Hann window, 50 % overlap, after removing the
profile's linear trend), averaged in log-spaced bands (10 per decade) so that
every octave weighs the same in the fit, and fitted in log-log by least squares
to :math:`G_d(n) = G_d(n_0)(n/n_0)^{-w}`, n0 = 0.1 cycle/m — once with w = 2 (the
ISO 8608 classification) and once with w free [1]_.

The default fit band is 0.05–5 cycles/m: it spans the road wavelengths that
excite an SUV's body and wheel-hop modes at 40–120 km/h (about 0.5 Hz at the low
end at 40 km/h, 11 Hz wheel hop at 1–0.3 cycles/m), and stays clear of the shape
filter's low-frequency corner (α/2π ≈ 0.02 cycle/m) and of the generators'
10 cycles/m upper edge. Any band inside the data's resolution can be asked for.

References
----------
.. [1] ISO 8608:2016, "Mechanical vibration — Road surface profiles — Reporting
   of measured data", International Organization for Standardization.
.. [2] P. Welch, "The use of fast Fourier transform for the estimation of power
   spectra", IEEE Trans. Audio Electroacoust., 15(2), 1967. doi:10.1109/TAU.1967.1161901
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.signal

from suvtwin.errors import InputError
from suvtwin.roads.iso8608 import N0_CYCLES_PER_M, class_of_level

__all__ = ["DEFAULT_FIT_BAND", "IsoFit", "classify_profile", "fit_iso", "profile_psd"]

DEFAULT_FIT_BAND: tuple[float, float] = (0.05, 5.0)
"""Spatial-frequency band of the ISO fit, cycles/m."""

_BANDS_PER_DECADE = 10
_RESOLUTION_FACTOR = 4.0  # Welch segment = 4 / (lowest fitted frequency)


@dataclass(frozen=True)
class IsoFit:
    """ISO 8608 fit of one track.

    Attributes
    ----------
    gd_n0 : float
        Level Gd(n0) with w fixed at 2, m³ at n0 = 0.1 cycle/m.
    road_class : str
        ISO class holding `gd_n0`.
    gd_n0_free : float
        Level Gd(n0) with w fitted, m³.
    waviness : float
        Fitted exponent w, -.
    band : tuple of float
        Band actually fitted, cycles/m.
    """

    gd_n0: float
    road_class: str
    gd_n0_free: float
    waviness: float
    band: tuple[float, float]


def profile_psd(z: npt.ArrayLike, spacing_m: float, *, segment_m: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided displacement PSD of a profile by Welch's method.

    Parameters
    ----------
    z : array_like, shape (..., n)
        Elevation, m, on a uniform grid.
    spacing_m : float
        Grid spacing, m.
    segment_m : float
        Welch segment length, m (clipped to the profile length); the frequency
        resolution is 1/segment_m cycles/m.

    Returns
    -------
    n : numpy.ndarray, shape (k,)
        Spatial frequency, cycles/m.
    psd : numpy.ndarray, shape (..., k)
        PSD, m³ (m² per cycle/m) if `z` is in m.
    """
    z = scipy.signal.detrend(np.asarray(z, dtype=float), axis=-1, type="linear")
    nperseg = min(int(round(segment_m / spacing_m)), z.shape[-1])
    return scipy.signal.welch(z, fs=1.0 / spacing_m, window="hann", nperseg=nperseg, axis=-1)


def fit_iso(n: npt.ArrayLike, psd: npt.ArrayLike, *, band: tuple[float, float] = DEFAULT_FIT_BAND) -> IsoFit:
    r"""Fit ISO 8608 level and waviness to a PSD over `band` (cycles/m).

    The PSD values are averaged in log-spaced bands (10 per decade) and
    :math:`\log_{10} G = \log_{10} G_d(n_0) - w \log_{10}(n/n_0)` is solved by
    least squares over the bands, once with w = 2 and once with w free. Each
    band's mean is placed at the frequency where the power law equals its mean
    over the band's bins (iterated with the fitted w), so an exact power law is
    recovered exactly.

    Parameters
    ----------
    n : array_like, shape (k,)
        Spatial frequency, cycles/m.
    psd : array_like, shape (k,)
        One-sided displacement PSD, m³.
    band : tuple of float, optional
        Fit band, cycles/m (default 0.05–5).
    """
    n = np.asarray(n, dtype=float)
    psd = np.asarray(psd, dtype=float)
    lo, hi = band
    edges = np.logspace(np.log10(lo), np.log10(hi), int(round(np.log10(hi / lo) * _BANDS_PER_DECADE)) + 1)
    which = np.digitize(n, edges) - 1
    keep = (which >= 0) & (which < edges.size - 1) & (psd > 0.0)
    bands = np.unique(which[keep])
    if bands.size < 3:
        raise InputError(
            f"fit band {lo:g}–{hi:g} cycles/m holds too few PSD values; "
            "use a longer or finer profile or a wider band"
        )
    members = [n[keep & (which == b)] / N0_CYCLES_PER_M for b in bands]
    log_g = np.array([np.log10(np.mean(psd[keep & (which == b)])) for b in bands])

    def log_n_eff(w: float) -> np.ndarray:
        # frequency at which the power law equals its band mean: exact for a pure power law
        return np.array([np.log10(np.mean(m ** (-w))) / (-w) for m in members])

    gd_n0 = 10.0 ** np.mean(log_g + 2.0 * log_n_eff(2.0))
    slope, intercept = np.polyfit(log_n_eff(2.0), log_g, 1)
    for _ in range(3):  # refine the effective frequencies with the fitted exponent
        slope, intercept = np.polyfit(log_n_eff(max(-slope, 0.1)), log_g, 1)
    return IsoFit(
        gd_n0=float(gd_n0),
        road_class=class_of_level(gd_n0),
        gd_n0_free=float(10.0**intercept),
        waviness=float(-slope),
        band=(float(lo), float(hi)),
    )


def classify_profile(
    z: npt.ArrayLike, spacing_m: float, *, band: tuple[float, float] = DEFAULT_FIT_BAND
) -> IsoFit:
    """ISO 8608 level, waviness and class of one track's profile.

    The Welch segment is long enough for a resolution of a quarter of the band's
    lower edge (4/band[0] m): coarser segments bias the steep n^-2 spectrum up
    through the Hann window's main lobe (leakage from the stronger low
    frequencies). A profile too short for that raises
    the lower edge to 4/length (with a warning); the band used is in the result.

    Parameters
    ----------
    z : array_like, shape (n,)
        Elevation, m, uniform grid.
    spacing_m : float
        Grid spacing, m.
    band : tuple of float, optional
        Fit band, cycles/m (default 0.05–5); its upper end is clipped to 0.8 of
        the grid's Nyquist frequency.
    """
    z = np.asarray(z, dtype=float)
    length = z.size * spacing_m
    lo, hi = band
    if not 0.0 < lo < hi:
        raise InputError(f"fit band must satisfy 0 < low < high cycles/m, got {band}")
    hi = min(hi, 0.8 * 0.5 / spacing_m)
    if length < _RESOLUTION_FACTOR / lo:
        new_lo = _RESOLUTION_FACTOR / length
        warnings.warn(
            f"profile of {length:.3g} m cannot resolve {lo:g} cycles/m; fitting from {new_lo:.3g} cycles/m",
            stacklevel=2,
        )
        lo = new_lo
    if lo >= hi:
        raise InputError(f"profile of {length:.3g} m at {spacing_m:g} m spacing is too short to classify")
    n, psd = profile_psd(z, spacing_m, segment_m=_RESOLUTION_FACTOR / lo)
    return fit_iso(n, psd, band=(lo, hi))
