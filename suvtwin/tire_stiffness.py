r"""Tyre radial stiffness vs inflation pressure (paper 000 eq. 3–4; MF-Tyre 6.1 PFZ1): the one source.

Usual call: ``kt = stiffness_at_pressure(p, kt0, p0, pfz1)`` (compiled scalar, also inside
numba kernels), ``kt = stiffness_at_pressure_array(p, kt0, p0, pfz1)`` over arrays, and
``law = suv_tire_stiffness()`` for the SUV's (kt0, p0, pfz1).

.. math::

    k_t = k_{t0}\,(1 + p_{Fz1}\,dp_i), \qquad dp_i = (p - p_0)/p_0,

and its inverse :math:`p = p_0\,(1 + (k_t/k_{t0} - 1)/p_{Fz1})`; SI units: Pa, N/m.
The simulator's tyre (:mod:`suvtwin.mjcf.tire`) and the estimators' process model
(:mod:`suvtwin.estimators.quarter_car`) both evaluate these functions, and both take
:math:`k_{t0}, p_0, p_{Fz1}` from the same ``.tir`` file (VERTICAL_STIFFNESS, NOMPRES,
PFZ1), the one ``mjcf/suv/parameters.toml`` names for the SUV.

The ``_array`` forms are numba ufuncs compiled on first use (``cache=True``): they
broadcast as numpy does and wrap the scalar functions, so the formula is written once.

References
----------
.. [1] R. Brancati, F. Tufano, "Indirect estimation of tire pressure on several road pavements
   via Interacting Multiple Model approach", Machines 10(12), 1221, 2022, eq. 3–4 (paper 000 of
   this project). doi:10.3390/machines10121221
.. [2] I. J. M. Besselink, A. J. C. Schmeitz, H. B. Pacejka, "An improved Magic Formula/Swift
   tyre model that can handle inflation pressure changes", Vehicle System Dynamics 48(S1),
   pp. 337–352, 2010. doi:10.1080/00423111003748088
"""

from __future__ import annotations

import functools
import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numba

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit
from suvtwin.tir import read_tir

# Compiled callers in other modules use suvtwin.jit.cached_njit, whose on-disk cache key includes
# the code and constants of what they call: editing a law here recompiles them (never stale code).

__all__ = [
    "TireStiffness",
    "pressure_at_stiffness",
    "pressure_at_stiffness_array",
    "pressure_sigma_at_stiffness_sigma",
    "stiffness_at_pressure",
    "stiffness_at_pressure_array",
    "stiffness_sigma_at_pressure_sigma",
    "suv_tire_file",
    "suv_tire_stiffness",
    "tire_file_of",
    "tire_stiffness_of",
]


@cached_njit
def stiffness_at_pressure(pressure, kt0, p0, pfz1):
    """Radial stiffness k_t (N/m) at inflation `pressure` (Pa); `kt0` (N/m) at `p0` (Pa), `pfz1` (−).

    Brancati & Tufano 2022, eq. 3–4; dpi of MF-Tyre 6.1 eq. 4.E2b.
    """
    dpi = (pressure - p0) / p0  # MF 6.1 eq. 4.E2b
    return kt0 * (1.0 + pfz1 * dpi)  # paper 000 eq. 3-4


@cached_njit
def pressure_at_stiffness(kt, kt0, p0, pfz1):
    """Inflation pressure (Pa) at radial stiffness `kt` (N/m): the inverse of eq. 3–4."""
    return p0 * (1.0 + (kt / kt0 - 1.0) / pfz1)


@numba.vectorize(cache=True)
def stiffness_at_pressure_array(pressure, kt0, p0, pfz1):
    """:func:`stiffness_at_pressure` as a ufunc (broadcast arrays), N/m."""
    return stiffness_at_pressure(pressure, kt0, p0, pfz1)


@numba.vectorize(cache=True)
def pressure_at_stiffness_array(kt, kt0, p0, pfz1):
    """:func:`pressure_at_stiffness` as a ufunc (broadcast arrays), Pa."""
    return pressure_at_stiffness(kt, kt0, p0, pfz1)


def pressure_sigma_at_stiffness_sigma(sigma_kt, kt0, p0, pfz1):
    """Standard deviation of the pressure (Pa) for a k_t standard deviation `sigma_kt` (N/m), any
    array shape: eq. 3–4 is linear, dp/dk_t = p0 / (kt0·pfz1)."""
    return sigma_kt * p0 / (kt0 * pfz1)


def stiffness_sigma_at_pressure_sigma(sigma_p, kt0, p0, pfz1):
    """Standard deviation of k_t (N/m) for a pressure standard deviation `sigma_p` (Pa), any array
    shape: dk_t/dp = kt0·pfz1 / p0 (eq. 3–4)."""
    return kt0 * pfz1 * sigma_p / p0


@dataclass(frozen=True)
class TireStiffness:
    """The constants of eq. 3–4 for one tyre.

    Attributes
    ----------
    kt0 : float
        Radial stiffness at the nominal pressure, N/m (.tir [VERTICAL] VERTICAL_STIFFNESS).
    p0 : float
        Nominal inflation pressure, Pa (.tir [OPERATING_CONDITIONS] NOMPRES).
    pfz1 : float
        Pressure effect on the stiffness, − (.tir [VERTICAL] PFZ1).
    """

    kt0: float
    p0: float
    pfz1: float

    @classmethod
    def from_tir(cls, path: str | Path) -> TireStiffness:
        """Read the three constants from a tyre property file (SI by its [UNITS])."""
        tir = read_tir(path)
        return cls(
            kt0=tir.number("VERTICAL", "VERTICAL_STIFFNESS", "force/length", greater_than=0.0),
            p0=tir.number("OPERATING_CONDITIONS", "NOMPRES", "pressure", greater_than=0.0),
            pfz1=tir.number("VERTICAL", "PFZ1", greater_than=0.0),
        )


def tire_file_of(parameter_file: str | Path, table: dict | None = None) -> Path:
    """The ``.tir`` file a vehicle parameter file names in ``[tire.file]``, relative to its folder.

    `table`: the parameter file already parsed (it is read here if None).

    Raises
    ------
    InputError
        If the parameter file has no ``[tire.file]`` entry with a string ``value``.
    """
    parameter_file = Path(parameter_file)
    if table is None:
        with open(parameter_file, "rb") as handle:
            table = tomllib.load(handle)
    entry = table.get("tire", {}).get("file", {})
    name = entry.get("value") if isinstance(entry, dict) else None
    if not isinstance(name, str) or not name:
        raise InputError(f'vehicle file {parameter_file}: [tire.file] needs value = "<tyre file>.tir"')
    return parameter_file.parent / name


def suv_tire_file() -> Path:
    """The SUV's tyre property file: the one ``mjcf/suv/parameters.toml`` names.

    Located as package data of :mod:`suvtwin.mjcf` (the vehicle model folder); no module
    of that layer is imported.
    """
    return tire_file_of(Path(str(resources.files("suvtwin.mjcf") / "suv" / "parameters.toml")))


def tire_stiffness_of(tire_file: str | Path | None) -> TireStiffness:
    """The constants of eq. 3–4 of the tyre in `tire_file` (``.tir``); None: the SUV's tyre."""
    return suv_tire_stiffness() if tire_file is None else TireStiffness.from_tir(tire_file)


@functools.cache
def suv_tire_stiffness() -> TireStiffness:
    """The SUV tyre's constants of eq. 3–4, read once from :func:`suv_tire_file`."""
    return TireStiffness.from_tir(suv_tire_file())
