r"""ISO 8608 road roughness classes and the displacement PSD they define.

Usual call: ``g = displacement_psd(n, gd_n0=class_level("C"), waviness=2.0)``.

ISO 8608 describes a road track by its one-sided displacement power spectral
density (PSD) over spatial frequency :math:`n` in cycles/m,

.. math:: G_d(n) = G_d(n_0)\,(n / n_0)^{-w}, \qquad n_0 = 0.1\ \text{cycle/m},

with waviness :math:`w = 2` for the classes. Class ``a`` (A = 0 … H = 7) has the
geometric-mean level :math:`G_d(n_0) = 16 \cdot 4^a \cdot 10^{-6}\ \text{m}^3`
and spans a factor 2 either side of it [1]_. In the angular form used by
Brancati & Tufano 2022, eq. 7, :math:`G_d(\Omega_0 = 1\ \text{rad/m}) = 4^a
\cdot 10^{-6}\ \text{m}^3`; both forms describe the same road because
:math:`G_d(\Omega) = G_d(n)/(2\pi)` and :math:`\Omega = 2\pi n`.

All levels here are in the cycle form, m³ at ``n0 = 0.1`` cycle/m, unless a name
says ``omega``.

References
----------
.. [1] ISO 8608:2016, "Mechanical vibration — Road surface profiles — Reporting
   of measured data", International Organization for Standardization.
.. [2] R. Brancati, F. Tufano, "Indirect estimation of tire pressure on several
   road pavements via Interacting Multiple Model approach", Machines 10(12), 1221, 2022.
   doi:10.3390/machines10121221
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError

__all__ = [
    "CLASSES",
    "N0_CYCLES_PER_M",
    "OMEGA0_RAD_PER_M",
    "class_bounds",
    "class_index",
    "class_level",
    "class_of_level",
    "displacement_psd",
    "draw_level_in_class",
    "level_cycle_to_omega",
    "level_omega_to_cycle",
]

CLASSES: tuple[str, ...] = ("A", "B", "C", "D", "E", "F", "G", "H")
"""ISO 8608 class letters, smoothest first."""

N0_CYCLES_PER_M: float = 0.1
"""Reference spatial frequency n0 of the cycle form, cycles/m."""

OMEGA0_RAD_PER_M: float = 1.0
"""Reference angular spatial frequency Ω0 of the angular form, rad/m."""

_A_LEVEL_CYCLE = 16e-6  # m^3, class A geometric mean at n0 = 0.1 cycle/m (ISO 8608 Table)


def class_index(road_class: str) -> int:
    """Index ``a`` of an ISO 8608 class letter (A → 0 … H → 7).

    Raises
    ------
    InputError
        If `road_class` is not one of A–H (case-insensitive).
    """
    letter = str(road_class).strip().upper()
    if letter not in CLASSES:
        raise InputError(f"road class must be one of A–H, got {road_class!r}")
    return CLASSES.index(letter)


def class_level(road_class: str) -> float:
    """Geometric-mean level Gd(n0) of an ISO 8608 class, m³ (n0 = 0.1 cycle/m).

    Class A gives 16e-6 m³, each further class ×4 (Brancati & Tufano 2022,
    eq. 7, in cycle form).
    """
    return _A_LEVEL_CYCLE * 4.0 ** class_index(road_class)


def class_bounds(road_class: str) -> tuple[float, float]:
    """Lower and upper Gd(n0) bound of an ISO 8608 class, m³ (×/÷2 the mean).

    ISO 8608 leaves class A open below and class H open above; these bounds
    are the closed ×/÷2 bands, used to judge whether a generated road of a
    class lies inside it. :func:`class_of_level` is the open-ended classifier.
    """
    level = class_level(road_class)
    return level / 2.0, level * 2.0


def class_of_level(gd_n0: float) -> str:
    """ISO 8608 class holding the level `gd_n0` (m³ at n0 = 0.1 cycle/m).

    Levels below class A's upper bound are A, levels above class H's lower bound
    are H.
    """
    if not np.isfinite(gd_n0) or gd_n0 <= 0.0:
        raise InputError(f"roughness level Gd(n0) must be a positive finite number, got {gd_n0!r}")
    a = int(np.floor(np.log(gd_n0 / _A_LEVEL_CYCLE) / np.log(4.0) + 0.5))
    return CLASSES[min(max(a, 0), len(CLASSES) - 1)]


def draw_level_in_class(road_class: str, rng: np.random.Generator) -> float:
    """Roughness level Gd(n0) drawn log-uniformly inside a class band, m³.

    Real roads sit anywhere inside a class band (which spans 4× in Gd(n0)), not at
    its centre; estimators must be scored on such roads.
    """
    lower, upper = class_bounds(road_class)
    return float(np.exp(rng.uniform(np.log(lower), np.log(upper))))


def displacement_psd(n: npt.ArrayLike, *, gd_n0: float, waviness: float = 2.0) -> np.ndarray:
    r"""One-sided ISO 8608 displacement PSD :math:`G_d(n)`, m³ (m²/(cycle/m)).

    Parameters
    ----------
    n : array_like
        Spatial frequency, cycles/m, > 0.
    gd_n0 : float
        Level :math:`G_d(n_0)` at :math:`n_0 = 0.1` cycle/m, m³.
    waviness : float, optional
        Exponent :math:`w`; ISO 8608 classes use 2 (the default).

    Returns
    -------
    numpy.ndarray
        :math:`G_d(n_0)(n/n_0)^{-w}`, same shape as `n`, m³.
    """
    n = np.asarray(n, dtype=float)
    return gd_n0 * (n / N0_CYCLES_PER_M) ** (-waviness)


def level_cycle_to_omega(gd_n0: float, *, waviness: float = 2.0) -> float:
    r"""Convert a level from the cycle form to the angular form, m³.

    :math:`G_d(\Omega_0) = G_d(n = \Omega_0/2\pi) / 2\pi` with Ω0 = 1 rad/m; for
    w = 2, class A's 16e-6 m³ becomes 1.01e-6 m³ ≈ 4^0·1e-6 (Brancati &
    Tufano 2022, eq. 7; ISO 8608 rounds the two forms to powers of 4 and 2).
    """
    n_at_omega0 = OMEGA0_RAD_PER_M / (2.0 * np.pi)
    return float(displacement_psd(n_at_omega0, gd_n0=gd_n0, waviness=waviness) / (2.0 * np.pi))


def level_omega_to_cycle(gd_omega0: float, *, waviness: float = 2.0) -> float:
    """Inverse of :func:`level_cycle_to_omega`, m³."""
    return gd_omega0 / level_cycle_to_omega(1.0, waviness=waviness)
