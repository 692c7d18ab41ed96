r"""Tire model of the SUV: radial stiffness vs pressure, vertical force, MF-Tyre 6.1 forces.

Usual call (inside the step kernel): ``fx, fy = tire_forces(fz, kappa, alpha, pressure, tp)``
with ``tp = TireParams().to_array()``.

Units are SI throughout: N, m, m/s, Pa, N/m, N s/m, rad; slip ratio and the MF
coefficients are dimensionless.

- Vertical: :math:`F_z = k_t(p)\,\delta + c_t\,\dot\delta` for :math:`\delta > 0`, never
  negative, zero when lifted off, with :math:`k_t = k_{t0}(1 + p_{Fz1}\,dp_i)`,
  :math:`dp_i = (p - p_0)/p_0` ([3]_ eq. 3–4; MF-Tyre 6.1 PFZ1 [2]_).
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

Coefficients (defaults of :class:`TireParams`):

- Shape, load and combined-slip coefficients, BREFF/DREFF/FREFF: the MF-Tyre 6.1
  example car tyre 205/60R15 (R0 0.3135 m, FNOMIN 4000 N, [1]_ Appendix 3), read from
  the .tir file ``examples/sample.tir`` of github.com/henrytad/tire_model (commit
  86728279fe12; that file's NOMPRES was edited to 200 kPa, its scaling factors are
  not 1 and are not used here). The same values appear in other public transcriptions of the
  book's table, except PCY1, given there as 1.338 (1.337 in the .tir).
- Pressure terms: the TNO MF-Tyre 6.1 example tyre at NOMPRES 220 kPa as quoted by the
  suvtwin developers (not checked against a published file): PFZ1 0.7097; PPX1–4 −0.3489,
  0.382, −0.0963, 0.0645; PPY1–4 −0.6249, −0.0654, −0.1668, 0.2834. The .tir above rounds
  them differently (PFZ1 0.7098; PPX −0.3485, 0.37824, −0.09603, 0.06518; PPY −0.6255,
  −0.06523, −0.16666, −0.2811): its PPY4 has the opposite sign. The quoted values are used.
- Kept dimensionless: the MF shape is that of the 205/60R15 tyre, but the
  operating point is moved to the SUV (235/60R18): :math:`p_0` = 250 kPa (paper 000),
  :math:`F_{z0}` = 5000 N (an SUV corner's static load), :math:`R_0` = 0.37 m,
  :math:`k_{t0}` = 264.7 kN/m (paper 000, Table 1), so :math:`dp_i` and
  :math:`df_z` are measured from the SUV's operating point.

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
>>> tp = TireParams().to_array()
>>> round(vertical_stiffness(200e3, tp))  # 20 % under-inflated: kt drops by 14.2 %
227128
>>> fx, fy = tire_forces(5000.0, 0.05, 0.0, 250e3, tp)
>>> fx > 0.0 and fy == 0.0
True
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numba
import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError

__all__ = [
    "TireParams",
    "effective_rolling_radius",
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

    Field order is the packed order of :meth:`to_array` (index constants ``I_<NAME>``
    of this module). Sources: see the module docstring.
    """

    unloaded_radius: float = 0.37  # m, R0 of a 235/60R18 SUV tyre
    nominal_pressure: float = 250e3  # Pa, p0 of paper 000
    nominal_load: float = 5000.0  # N, FNOMIN: about an SUV corner's static load
    vertical_stiffness_nominal: float = 264700.0  # N/m, kt0 of paper 000 Table 1
    # N s/m: MF-Tyre .tir files give VERTICAL_DAMPING 50-500 N s/m for car tyres (the 205/60R15
    # file: 50; MFeval's MF 6.1 example: 500); paper 000 neglects tyre damping
    vertical_damping: float = 200.0
    pfz1: float = 0.7097  # MF-Tyre 6.1 PFZ1, pressure effect on vertical stiffness
    lambda_mu: float = 1.0  # friction scaling LMUX = LMUY (1: dry asphalt of the fit)
    # longitudinal, pure slip (.tir [LONGITUDINAL_COEFFICIENTS])
    pcx1: float = 1.579
    pdx1: float = 1.0422
    pdx2: float = -0.08285
    pex1: float = 0.11113
    pex2: float = 0.3143
    pex3: float = 0.0
    pex4: float = 0.001719
    pkx1: float = 21.687
    pkx2: float = 13.728
    pkx3: float = -0.4098
    ppx1: float = -0.3489  # PPX1-4, PPY1-4: the quoted values (module docstring)
    ppx2: float = 0.382
    ppx3: float = -0.0963
    ppx4: float = 0.0645
    # lateral, pure slip (.tir [LATERAL_COEFFICIENTS])
    pcy1: float = 1.337
    pdy1: float = 0.8785
    pdy2: float = -0.06452
    pey1: float = -0.8057
    pey2: float = -0.6046
    pey3: float = 0.09854
    pky1: float = -15.324  # ISO-W sign; only |PKY1| is used
    pky2: float = 1.715
    pky4: float = 2.0005
    ppy1: float = -0.6249  # quoted value (module docstring)
    ppy2: float = -0.0654
    ppy3: float = -0.1668
    ppy4: float = 0.2834
    # combined slip (.tir)
    rbx1: float = 13.046
    rbx2: float = 9.718
    rcx1: float = 0.9995
    rex1: float = -0.4403
    rex2: float = -0.4663
    rby1: float = 10.622
    rby2: float = 7.82
    rby3: float = 0.002037
    rcy1: float = 1.0587
    rey1: float = 0.3148
    rey2: float = 0.004867
    # effective rolling radius (.tir [VERTICAL])
    breff: float = 8.386
    dreff: float = 0.25826
    freff: float = 0.07394

    def to_array(self) -> np.ndarray:
        """Packed parameter vector ``tp``, shape ``(47,)``, float64, in field order."""
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=np.float64)

    @classmethod
    def from_mapping(cls, values: dict) -> TireParams:
        """Defaults overridden by `values` (field name → number, SI units).

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
        merged = asdict(cls())
        for name, value in values.items():
            try:
                number = float(value)
            except (TypeError, ValueError):
                raise InputError(f"tire.{name} must be a number, got {value!r}") from None
            if not np.isfinite(number):
                raise InputError(f"tire.{name} must be finite, got {value!r}")
            merged[name] = number
        return cls(**merged)


# positions in TireParams.to_array() (field order); tests/test_tire.py checks them against the fields
I_UNLOADED_RADIUS, I_NOMINAL_PRESSURE, I_NOMINAL_LOAD = 0, 1, 2
I_KT0, I_CT, I_PFZ1, I_LAMBDA_MU = 3, 4, 5, 6
(I_PCX1, I_PDX1, I_PDX2, I_PEX1, I_PEX2, I_PEX3, I_PEX4, I_PKX1, I_PKX2, I_PKX3) = range(7, 17)
(I_PPX1, I_PPX2, I_PPX3, I_PPX4) = range(17, 21)
(I_PCY1, I_PDY1, I_PDY2, I_PEY1, I_PEY2, I_PEY3, I_PKY1, I_PKY2, I_PKY4) = range(21, 30)
(I_PPY1, I_PPY2, I_PPY3, I_PPY4) = range(30, 34)
(I_RBX1, I_RBX2, I_RCX1, I_REX1, I_REX2) = range(34, 39)
(I_RBY1, I_RBY2, I_RBY3, I_RCY1, I_REY1, I_REY2) = range(39, 45)
(I_BREFF, I_DREFF, I_FREFF) = range(45, 48)
N_PARAMS = 48


@numba.njit(cache=True)
def vertical_stiffness(pressure, tp):
    """Radial stiffness kt(p) = kt0·(1 + pFz1·dpi), N/m, at `pressure` (Pa).

    Brancati & Tufano 2022, eq. 3–4; dpi = (p − p0)/p0 (MF 6.1 eq. 4.E2b).
    """
    dpi = (pressure - tp[I_NOMINAL_PRESSURE]) / tp[I_NOMINAL_PRESSURE]  # eq. 4.E2b
    return tp[I_KT0] * (1.0 + tp[I_PFZ1] * dpi)  # paper 000 eq. 3-4


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
    return params.nominal_pressure * (1.0 + (kt / params.vertical_stiffness_nominal - 1.0) / params.pfz1)


@numba.njit(cache=True)
def vertical_force(deflection, deflection_rate, pressure, tp):
    """Radial force Fz = kt(p)·δ + ct·δ̇, N, for δ > 0; clipped at 0; 0 when lifted off.

    `deflection` δ in m (> 0 compressed), `deflection_rate` δ̇ in m/s, `pressure` in Pa.
    """
    if deflection <= 0.0:
        return 0.0  # lifted off
    return max(vertical_stiffness(pressure, tp) * deflection + tp[I_CT] * deflection_rate, 0.0)  # never pulls


@numba.njit(cache=True)
def effective_rolling_radius(fz, pressure, tp):
    """MF-Tyre 6.1 effective rolling radius, m, at load `fz` (N) and `pressure` (Pa).

    Re = R0 − (Fz0/Cz)·(DREFF·atan(BREFF·Fz/Fz0) + FREFF·Fz/Fz0) with Cz = kt(p); a
    negative `fz` counts as 0 (Re = R0).
    """
    fz0 = tp[I_NOMINAL_LOAD]
    rho = max(fz, 0.0) / fz0
    cz = vertical_stiffness(pressure, tp)
    return tp[I_UNLOADED_RADIUS] - fz0 / cz * (tp[I_DREFF] * np.arctan(tp[I_BREFF] * rho) + tp[I_FREFF] * rho)


@numba.njit(cache=True)
def _magic(b, c, d, e, x):
    # eq. 4.E9 / 4.E19 with zero shifts: y = D sin(C atan(Bx − E(Bx − atan Bx)))
    bx = b * x
    return d * np.sin(c * np.arctan(bx - e * (bx - np.arctan(bx))))


@numba.njit(cache=True)
def _weight(b, c, e, x):
    # eq. 4.E51 / 4.E59 with zero shifts (so G0 = 1): G = cos(C atan(Bx − E(Bx − atan Bx)))
    bx = b * x
    return np.cos(c * np.arctan(bx - e * (bx - np.arctan(bx))))


@numba.njit(cache=True)
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
