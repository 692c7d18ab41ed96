r"""Tire model of the SUV: radial stiffness vs pressure, vertical force, MF-Tyre 6.1 forces.

Usual call (inside the step kernel): ``fx, fy = tire_forces(fz, kappa, alpha, pressure, tp)``
with ``tp = load_tire().to_array()``.

Units are SI throughout: N, m, m/s, Pa, N/m, N s/m, rad; slip ratio and the MF
coefficients are dimensionless.

- Vertical: :math:`F_z = k_t(p)\,\delta + c_t\,\dot\delta` for :math:`\delta > 0`, never
  negative, zero when lifted off, with :math:`k_t = k_{t0}(1 + p_{Fz1}\,dp_i)`,
  :math:`dp_i = (p - p_0)/p_0` ([3]_ eq. 3–4; MF-Tyre 6.1 PFZ1 [2]_), evaluated by
  :mod:`suvtwin.tire_stiffness` (the estimators use the same function).
- Longitudinal and lateral: MF-Tyre 6.1 pure slip with the inflation-pressure terms
  PPX1–4 (slip stiffness, friction) and PPY1–4 (cornering stiffness, the load of its
  peak, friction), combined slip by the cosine weighting functions
  :math:`G_{x\alpha}`, :math:`G_{y\kappa}` ([1]_ §4.3.2, eq. 4.E1–4.E67). Camber is zero.
  The horizontal/vertical shifts of the fitted tyre (ply steer, conicity: PHX1–2,
  PVX1–2, PHY1–2, PVY1–2, RHX1, RHY1–2, RVY1–6) are set to zero, so the car runs
  straight on a flat road and zero slip gives zero force. RBY3 (a shift inside
  :math:`B_{y\kappa}`, not a force offset) is kept.
- Effective rolling radius (MF-Tyre 6.1): :math:`R_e = R_0 - (F_{z0}/C_z)
  (D_{reff}\arctan(B_{reff} F_z/F_{z0}) + F_{reff} F_z/F_{z0})` with
  :math:`C_z = k_t(p)`: it depends on load and pressure.

Sign convention (ISO-W axes: x forward, y left, z up). Slip ratio
:math:`\kappa = (\Omega R_e - V_x)/|V_x|` (> 0 when driving) gives :math:`F_x > 0`
(forward). Slip angle :math:`\alpha = \arctan(V_y/|V_x|)`, with :math:`V_y` the
contact point's lateral velocity in the wheel frame (left positive), gives
:math:`F_y < 0` for :math:`\alpha > 0`: the force opposes the lateral sliding. The
.tir file's PKY1 is negative (ISO-W); the code uses :math:`-|PKY1|`, so a PKY1 given
with either sign gives this convention. As in MF 6.1 (eq. 4.E3) the lateral slip
entering the formulas is :math:`\alpha^* = \tan\alpha = V_y/|V_x|`.

Coefficients: read from a TNO MF-Tyre 6.1 property file (``.tir``) by
:meth:`TireParams.from_tir`; the SUV's is ``mjcf/suv/suv_235_60R18.tir``, named by
``mjcf/suv/parameters.toml`` (``[tire.file]``), and its ``$`` comments give every value's
source: the shape, load and combined-slip coefficients of the MF-Tyre 6.1 example car
tyre 205/60R15 ([1]_ Appendix 3), the pressure terms of the TNO example ([2]_), and the
SUV's operating point (p0, FNOMIN, R0, kt0 of [3]_), so that :math:`dp_i` and
:math:`df_z` are measured from the SUV's nominal pressure and load. A scenario or
``suvtwin simulate --tire FILE`` may name another ``.tir``.

Written by hand because the step kernel needs scalar functions compiled with numba.
Searching the PyPI package index for tyre/tire/pacejka/magic-formula names found
no MF-Tyre 6.1 evaluator that fits: ``pacejka`` 0.1.0 is a B, C, D, E formula with
load sensitivity and a friction circle (no MF 6.1 pressure terms, no combined-slip
weighting functions); ``vdsim`` 0.0.0, ``vehicle-dynamics`` and
``vehicle-dynamics-sim`` are whole-vehicle packages, not scalar functions a numba
kernel can call.

References
----------
.. [1] H. B. Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., Butterworth-Heinemann, 2012,
   §4.3.2 (MF-Tyre 6.1 equations 4.E1–4.E78) and Appendix 3. doi:10.1016/C2010-0-68548-8
.. [2] I. J. M. Besselink, A. J. C. Schmeitz, H. B. Pacejka, "An improved Magic Formula/Swift
   tyre model that can handle inflation pressure changes", Vehicle System Dynamics 48(S1),
   pp. 337–352, 2010. doi:10.1080/00423111003748088
.. [3] R. Brancati, F. Tufano, "Indirect estimation of tire pressure on several road pavements
   via Interacting Multiple Model approach", Machines 10(12), 1221, 2022.
   doi:10.3390/machines10121221

Examples
--------
>>> tp = load_tire().to_array()
>>> round(vertical_stiffness(200e3, tp))  # 20 % under-inflated: kt drops by 14.2 %
227128
>>> fx, fy = tire_forces(5000.0, 0.05, 0.0, 250e3, tp)
>>> fx > 0.0 and fy == 0.0
True
"""

from __future__ import annotations

from collections import namedtuple
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit
from suvtwin.tir import read_tir
from suvtwin.tire_stiffness import pressure_at_stiffness_array, stiffness_at_pressure, suv_tire_file

__all__ = [
    "N_PARAMS",
    "SLOT",
    "TIR_KEYS",
    "TIR_RANGES",
    "TireParams",
    "TireSlots",
    "effective_rolling_radius",
    "load_tire",
    "pressure_from_stiffness",
    "tire_forces",
    "tire_forces_array",
    "vertical_force",
    "vertical_stiffness",
]

# added to C·D in B = K/(C·D): keeps B finite at a vanishing load (MF 6.1 eq. 4.E16, 4.E26 use
# epsilon_x, epsilon_y for the same purpose); negligible at any real load (C·D ~ 1e3 N)
_EPS = 1e-9
# |alpha| is clipped below pi/2 before tan(alpha) (eq. 4.E3); the kernel's alpha is an arctan
_ALPHA_MAX = 1.5


@dataclass(frozen=True)
class TireParams:
    """Tyre parameters, SI units (Pa, N, m, N/m, N s/m); MF coefficients dimensionless.

    Read from a TNO MF-Tyre 6.1 property file by :meth:`from_tir` (:func:`load_tire` for
    the SUV's, ``mjcf/suv/suv_235_60R18.tir``, whose comments give each value's source);
    the ``.tir`` section and key of each field are in :data:`TIR_KEYS`. Field order is
    the packed order of :meth:`to_array` (slots :data:`SLOT`, index constants ``I_<NAME>``).
    """

    unloaded_radius: float  # m, R0
    nominal_pressure: float  # Pa, p0 (NOMPRES)
    nominal_load: float  # N, FNOMIN
    vertical_stiffness_nominal: float  # N/m, kt0 at p0
    vertical_damping: float  # N s/m
    pfz1: float  # pressure effect on vertical stiffness
    lambda_mu: float  # friction scaling LMUX = LMUY
    # longitudinal, pure slip
    pcx1: float
    pdx1: float
    pdx2: float
    pex1: float
    pex2: float
    pex3: float
    pex4: float
    pkx1: float
    pkx2: float
    pkx3: float
    ppx1: float
    ppx2: float
    ppx3: float
    ppx4: float
    # lateral, pure slip
    pcy1: float
    pdy1: float
    pdy2: float
    pey1: float
    pey2: float
    pey3: float
    pky1: float  # ISO-W sign; only |PKY1| is used
    pky2: float
    pky4: float
    ppy1: float
    ppy2: float
    ppy3: float
    ppy4: float
    # combined slip
    rbx1: float
    rbx2: float
    rcx1: float
    rex1: float
    rex2: float
    rby1: float
    rby2: float
    rby3: float
    rcy1: float
    rey1: float
    rey2: float
    # effective rolling radius
    breff: float
    dreff: float
    freff: float

    def to_array(self) -> np.ndarray:
        """Packed parameter vector ``tp``, shape ``(N_PARAMS,)``, float64, in field order."""
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=np.float64)

    @classmethod
    def from_tir(cls, path: str | Path) -> TireParams:
        """Read a TNO MF-Tyre 6.1 property file (``.tir``), converting by its [UNITS] to SI.

        Raises
        ------
        InputError
            If the file is malformed, lacks a key of :data:`TIR_KEYS`, gives a value outside
            :data:`TIR_RANGES`, or LMUX ≠ LMUY (this model has one friction scaling); the
            message names the file, line and key.
        """
        tir = read_tir(path)
        values = {
            name: tir.number(section, key, dimension, **TIR_RANGES.get(name, {}))
            for name, (section, key, dimension) in TIR_KEYS.items()
        }
        lmuy = tir.number("SCALING_COEFFICIENTS", "LMUY")
        if lmuy != values["lambda_mu"]:
            line = tir.sections["SCALING_COEFFICIENTS"]["LMUY"].line
            raise InputError(
                f"tyre file {tir.path}, line {line}: [SCALING_COEFFICIENTS] LMUY must equal LMUX "
                f"({values['lambda_mu']:g}: this model has one friction scaling), got {lmuy:g}"
            )
        return cls(**values)

    @classmethod
    def from_mapping(cls, values: dict) -> TireParams:
        """The SUV's tyre (:func:`load_tire`) with `values` replaced (field → number, SI).

        Raises
        ------
        InputError
            If a name is not a field of :class:`TireParams` or a value is not a finite number.
        """
        known = [f.name for f in fields(cls)]
        unknown = sorted(set(values) - set(known))
        if unknown:
            raise InputError(
                f"tire: unknown parameter(s) {', '.join(unknown)}; expected some of {', '.join(known)}"
            )
        merged = asdict(load_tire())
        for name, value in values.items():
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise InputError(f"tire.{name} must be a number, got {value!r}") from None
            if not np.isfinite(number):
                raise InputError(f"tire.{name} must be finite, got {value!r}")
            merged[name] = number
        return cls(**merged)


_LONGITUDINAL = ("pcx1", "pdx1", "pdx2", "pex1", "pex2", "pex3", "pex4", "pkx1", "pkx2", "pkx3",
                 "ppx1", "ppx2", "ppx3", "ppx4", "rbx1", "rbx2", "rcx1", "rex1", "rex2")  # fmt: skip
_LATERAL = ("pcy1", "pdy1", "pdy2", "pey1", "pey2", "pey3", "pky1", "pky2", "pky4",
            "ppy1", "ppy2", "ppy3", "ppy4", "rby1", "rby2", "rby3", "rcy1", "rey1", "rey2")  # fmt: skip

TIR_KEYS: dict[str, tuple[str, str, str]] = {
    "unloaded_radius": ("DIMENSION", "UNLOADED_RADIUS", "length"),
    "nominal_pressure": ("OPERATING_CONDITIONS", "NOMPRES", "pressure"),
    "nominal_load": ("VERTICAL", "FNOMIN", "force"),
    "vertical_stiffness_nominal": ("VERTICAL", "VERTICAL_STIFFNESS", "force/length"),
    "vertical_damping": ("VERTICAL", "VERTICAL_DAMPING", "force*time/length"),
    "pfz1": ("VERTICAL", "PFZ1", ""),
    "lambda_mu": ("SCALING_COEFFICIENTS", "LMUX", ""),
    **{name: ("LONGITUDINAL_COEFFICIENTS", name.upper(), "") for name in _LONGITUDINAL},
    **{name: ("LATERAL_COEFFICIENTS", name.upper(), "") for name in _LATERAL},
    "breff": ("VERTICAL", "BREFF", ""),
    "dreff": ("VERTICAL", "DREFF", ""),
    "freff": ("VERTICAL", "FREFF", ""),
}
"""Where each :class:`TireParams` field stands in a ``.tir`` file: (section, key, dimension)."""
TIR_RANGES: dict[str, dict[str, float]] = {
    "unloaded_radius": {"greater_than": 0.0},
    "nominal_pressure": {"greater_than": 0.0},
    "nominal_load": {"greater_than": 0.0},
    "vertical_stiffness_nominal": {"greater_than": 0.0},
    "vertical_damping": {"at_least": 0.0},
    "pfz1": {"greater_than": 0.0},  # k_t rises with pressure; eq. 3-4 is inverted by dividing by it
    "lambda_mu": {"greater_than": 0.0},
}
"""Allowed range (SI) of the fields that must be positive for the model to mean anything."""


def load_tire(path: str | Path | None = None) -> TireParams:
    """The tyre of the ``.tir`` file at `path`; default the SUV's (named by ``mjcf/suv/parameters.toml``)."""
    return TireParams.from_tir(suv_tire_file() if path is None else path)


TireSlots = namedtuple("TireSlots", [f.name for f in fields(TireParams)])
"""Named positions of the fields in :meth:`TireParams.to_array`."""
SLOT = TireSlots(*range(len(fields(TireParams))))
"""Position of each field in the packed vector ``tp``, by field name (``SLOT.pfz1``)."""
N_PARAMS = len(SLOT)

# module-level ints, frozen by numba as compile-time constants in the kernels; each is bound by
# field name, so the numbers follow the field order of TireParams
I_UNLOADED_RADIUS, I_NOMINAL_PRESSURE = SLOT.unloaded_radius, SLOT.nominal_pressure
I_NOMINAL_LOAD, I_LAMBDA_MU = SLOT.nominal_load, SLOT.lambda_mu
I_KT0, I_CT, I_PFZ1 = SLOT.vertical_stiffness_nominal, SLOT.vertical_damping, SLOT.pfz1
I_PCX1, I_PDX1, I_PDX2, I_PEX1, I_PEX2 = SLOT.pcx1, SLOT.pdx1, SLOT.pdx2, SLOT.pex1, SLOT.pex2
I_PEX3, I_PEX4, I_PKX1, I_PKX2, I_PKX3 = SLOT.pex3, SLOT.pex4, SLOT.pkx1, SLOT.pkx2, SLOT.pkx3
I_PPX1, I_PPX2, I_PPX3, I_PPX4 = SLOT.ppx1, SLOT.ppx2, SLOT.ppx3, SLOT.ppx4
I_PCY1, I_PDY1, I_PDY2, I_PEY1, I_PEY2 = SLOT.pcy1, SLOT.pdy1, SLOT.pdy2, SLOT.pey1, SLOT.pey2
I_PEY3, I_PKY1, I_PKY2, I_PKY4 = SLOT.pey3, SLOT.pky1, SLOT.pky2, SLOT.pky4
I_PPY1, I_PPY2, I_PPY3, I_PPY4 = SLOT.ppy1, SLOT.ppy2, SLOT.ppy3, SLOT.ppy4
I_RBX1, I_RBX2, I_RCX1, I_REX1, I_REX2 = SLOT.rbx1, SLOT.rbx2, SLOT.rcx1, SLOT.rex1, SLOT.rex2
I_RBY1, I_RBY2, I_RBY3 = SLOT.rby1, SLOT.rby2, SLOT.rby3
I_RCY1, I_REY1, I_REY2 = SLOT.rcy1, SLOT.rey1, SLOT.rey2
I_BREFF, I_DREFF, I_FREFF = SLOT.breff, SLOT.dreff, SLOT.freff


@cached_njit
def vertical_stiffness(pressure, tp):
    """Radial stiffness kt(p) = kt0·(1 + pFz1·dpi), N/m, at `pressure` (Pa).

    Brancati & Tufano 2022, eq. 3–4; dpi = (p − p0)/p0 (MF 6.1 eq. 4.E2b); evaluated by
    :func:`suvtwin.tire_stiffness.stiffness_at_pressure`.
    """
    return stiffness_at_pressure(pressure, tp[I_KT0], tp[I_NOMINAL_PRESSURE], tp[I_PFZ1])


def pressure_from_stiffness(kt: npt.ArrayLike, params: TireParams) -> np.ndarray:
    """Inverse of :func:`vertical_stiffness`: p = p0·(1 + (kt/kt0 − 1)/pFz1), Pa.

    Parameters
    ----------
    kt : array_like
        Radial stiffness, N/m, any shape.
    params : TireParams
        Tyre parameters (p0, kt0, pFz1).

    Returns
    -------
    numpy.ndarray
        Inflation pressure, Pa, same shape as `kt`.
    """
    kt = np.asarray(kt, dtype=np.float64)
    return pressure_at_stiffness_array(
        kt, params.vertical_stiffness_nominal, params.nominal_pressure, params.pfz1
    )


@cached_njit
def vertical_force(deflection, deflection_rate, pressure, tp):
    """Radial force Fz = kt(p)·δ + ct·δ̇, N, for δ > 0; clipped at 0; 0 when lifted off.

    `deflection` δ in m (> 0 compressed), `deflection_rate` δ̇ in m/s, `pressure` in Pa.
    """
    if deflection <= 0.0:
        return 0.0  # lifted off
    return max(vertical_stiffness(pressure, tp) * deflection + tp[I_CT] * deflection_rate, 0.0)  # never pulls


@cached_njit
def effective_rolling_radius(fz, pressure, tp):
    """MF-Tyre 6.1 effective rolling radius, m, at load `fz` (N) and `pressure` (Pa).

    Re = R0 − (Fz0/Cz)·(DREFF·atan(BREFF·Fz/Fz0) + FREFF·Fz/Fz0) with Cz = kt(p); a
    negative `fz` counts as 0 (Re = R0).
    """
    fz0 = tp[I_NOMINAL_LOAD]
    rho = max(fz, 0.0) / fz0
    cz = vertical_stiffness(pressure, tp)
    return tp[I_UNLOADED_RADIUS] - fz0 / cz * (tp[I_DREFF] * np.arctan(tp[I_BREFF] * rho) + tp[I_FREFF] * rho)


@cached_njit
def _magic(b, c, d, e, x):
    # eq. 4.E9 / 4.E19 with zero shifts: y = D sin(C atan(Bx − E(Bx − atan Bx)))
    bx = b * x
    return d * np.sin(c * np.arctan(bx - e * (bx - np.arctan(bx))))


@cached_njit
def _weight(b, c, e, x):
    # eq. 4.E51 / 4.E59 with zero shifts (so G0 = 1): G = cos(C atan(Bx − E(Bx − atan Bx)))
    bx = b * x
    return np.cos(c * np.arctan(bx - e * (bx - np.arctan(bx))))


@cached_njit
def tire_forces(fz, kappa, alpha, pressure, tp):
    """MF-Tyre 6.1 combined-slip longitudinal and lateral force, N; camber 0, shifts 0.

    Parameters: `fz` radial load (N), `kappa` slip ratio (−), `alpha` slip angle (rad),
    `pressure` inflation pressure (Pa), `tp` the packed :class:`TireParams`.
    Returns ``(fx, fy)`` in N: fx > 0 forward for kappa > 0, fy < 0 for alpha > 0;
    ``(0.0, 0.0)`` when ``fz <= 0``. Equation numbers: Pacejka 2012, §4.3.2.
    """
    if not fz > 0.0:  # also catches NaN
        return 0.0, 0.0
    fz0 = tp[I_NOMINAL_LOAD]
    dfz = (fz - fz0) / fz0  # eq. 4.E2a
    dpi = (pressure - tp[I_NOMINAL_PRESSURE]) / tp[I_NOMINAL_PRESSURE]  # eq. 4.E2b
    lmu = tp[I_LAMBDA_MU]
    alpha_c = min(max(alpha, -_ALPHA_MAX), _ALPHA_MAX)
    alpha_s = np.tan(alpha_c)  # eq. 4.E3, Vcx > 0

    # ---- longitudinal, pure slip ----
    cx = tp[I_PCX1]  # eq. 4.E11
    mux = (tp[I_PDX1] + tp[I_PDX2] * dfz) * (1.0 + tp[I_PPX3] * dpi + tp[I_PPX4] * dpi * dpi) * lmu  # 4.E13
    dx = mux * fz  # eq. 4.E12
    sgn_k = 1.0 if kappa > 0.0 else (-1.0 if kappa < 0.0 else 0.0)
    ex = (tp[I_PEX1] + tp[I_PEX2] * dfz + tp[I_PEX3] * dfz * dfz) * (1.0 - tp[I_PEX4] * sgn_k)  # 4.E14
    ex = min(ex, 1.0)
    kxk = (
        fz
        * (tp[I_PKX1] + tp[I_PKX2] * dfz)
        * np.exp(tp[I_PKX3] * dfz)
        * (1.0 + tp[I_PPX1] * dpi + tp[I_PPX2] * dpi * dpi)
    )  # eq. 4.E15
    bx = kxk / (cx * dx + _EPS)  # eq. 4.E16
    fx0 = _magic(bx, cx, dx, ex, kappa)  # eq. 4.E9

    # ---- lateral, pure slip ----
    cy = tp[I_PCY1]  # eq. 4.E21
    muy = (tp[I_PDY1] + tp[I_PDY2] * dfz) * (1.0 + tp[I_PPY3] * dpi + tp[I_PPY4] * dpi * dpi) * lmu  # 4.E23
    dy = muy * fz  # eq. 4.E22
    sgn_a = 1.0 if alpha_s > 0.0 else (-1.0 if alpha_s < 0.0 else 0.0)
    ey = min((tp[I_PEY1] + tp[I_PEY2] * dfz) * (1.0 - tp[I_PEY3] * sgn_a), 1.0)  # eq. 4.E24
    kya = (
        -abs(tp[I_PKY1])
        * fz0
        * (1.0 + tp[I_PPY1] * dpi)
        * np.sin(tp[I_PKY4] * np.arctan(fz / (tp[I_PKY2] * (1.0 + tp[I_PPY2] * dpi) * fz0)))
    )  # eq. 4.E25
    by = kya / (cy * dy + _EPS)  # eq. 4.E26
    fy0 = _magic(by, cy, dy, ey, alpha_s)  # eq. 4.E19

    # ---- combined slip ----
    bxa = tp[I_RBX1] * np.cos(np.arctan(tp[I_RBX2] * kappa))  # eq. 4.E54
    exa = min(tp[I_REX1] + tp[I_REX2] * dfz, 1.0)  # eq. 4.E56
    gxa = _weight(bxa, tp[I_RCX1], exa, alpha_s)  # eq. 4.E51
    byk = tp[I_RBY1] * np.cos(np.arctan(tp[I_RBY2] * (alpha_s - tp[I_RBY3])))  # eq. 4.E62
    eyk = min(tp[I_REY1] + tp[I_REY2] * dfz, 1.0)  # eq. 4.E64
    gyk = _weight(byk, tp[I_RCY1], eyk, kappa)  # eq. 4.E59
    return gxa * fx0, gyk * fy0  # eq. 4.E50, 4.E58 (SVyk = 0)


def tire_forces_array(
    fz: npt.ArrayLike,
    kappa: npt.ArrayLike,
    alpha: npt.ArrayLike,
    pressure: npt.ArrayLike,
    params: TireParams,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`tire_forces` over broadcast arrays (for plots and tests).

    Parameters
    ----------
    fz, kappa, alpha, pressure : array_like
        Load (N), slip ratio (−), slip angle (rad), pressure (Pa); broadcast together.
    params : TireParams
        Tyre parameters.

    Returns
    -------
    fx, fy : numpy.ndarray
        Longitudinal and lateral force, N, of the broadcast shape.
    """
    fz, kappa, alpha, pressure = np.broadcast_arrays(
        *(np.asarray(a, dtype=np.float64) for a in (fz, kappa, alpha, pressure))
    )
    tp = params.to_array()
    fx, fy = np.empty(fz.shape), np.empty(fz.shape)
    for index in np.ndindex(fz.shape):
        fx[index], fy[index] = tire_forces(fz[index], kappa[index], alpha[index], pressure[index], tp)
    return fx, fy
