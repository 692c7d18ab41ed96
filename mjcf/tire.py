r"""Tire model of the SUV: radial stiffness vs pressure, vertical force, MF-Tyre 6.1 forces.

Usual call (inside the step kernel): ``fx, fy = tire_forces(fz, kappa, alpha, pressure, tp)``
with ``tp = TireParams().to_array()``.

- Vertical: :math:`F_z = k_t(p)\,\delta + c_t\,\dot\delta` for :math:`\delta > 0`, never
  negative, zero when lifted off, with :math:`k_t = k_{t0}(1 + p_{Fz1}\,dp_i)`,
  :math:`dp_i = (p - p_0)/p_0` (Brancati & Tufano 2022, eq. 3–4; MF-Tyre 6.1 PFZ1).
- Longitudinal and lateral: MF-Tyre 6.1 pure slip with the inflation-pressure terms
  PPX1–4 (slip stiffness, friction) and PPY1–4 (cornering stiffness, its load at the
  peak, friction), combined slip by the cosine weighting functions
  :math:`G_{x\alpha}`, :math:`G_{y\kappa}` [1]_ [2]_. Camber is zero; the small
  horizontal/vertical shifts of the fitted tyre (ply steer, conicity: PHX, PVX, PHY,
  PVY, RHX, RHY, RVY, RBY3) are set to zero so the car runs straight on a flat road.
- Effective rolling radius (MF-Tyre 6.1): :math:`R_e = R_0 - (F_{z0}/C_z)
  (D_{reff}\arctan(B_{reff} F_z/F_{z0}) + F_{reff} F_z/F_{z0})` with
  :math:`C_z = k_t(p)`: it depends on load and pressure.

Sign convention (ISO-W axes: x forward, y left, z up): slip ratio
:math:`\kappa = (\Omega R_e - V_x)/|V_x|` (> 0 when driving) gives :math:`F_x > 0`
forward; slip angle :math:`\alpha = \arctan(V_y/|V_x|)` with :math:`V_y` the contact
point's lateral velocity (left positive) gives :math:`F_y < 0` for :math:`\alpha > 0`
(PKY1 < 0, as in the .tir file).

Coefficients: the MF-Tyre 6.1 example car tyre 205/60R15 (NOMPRES 220 kPa) as
published with MF-Tyre 6.1 (Besselink et al. 2010; Pacejka 2012, Appendix 3), with
the pressure terms of DESIGN.md; they were transcribed, not read from a .tir file
here. The dimensionless shape is kept; the nominal pressure is moved to the SUV's
p0 = 250 kPa (paper 000) and the nominal load to 5000 N (an SUV corner), so
:math:`dp_i` and :math:`df_z` are measured from the SUV's operating point.

Written by hand: the per-step kernel needs scalar functions compiled with numba;
the MF evaluators on PyPI are object-oriented, per-call Python, or MF 5.2 only.

References
----------
.. [1] H. B. Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., Butterworth-Heinemann, 2012,
   §4.3.2 and Appendix 3. doi:10.1016/C2010-0-68548-8
.. [2] I. J. M. Besselink, A. J. C. Schmeitz, H. B. Pacejka, "An improved Magic Formula/Swift
   tyre model that can handle inflation pressure changes", Vehicle System Dynamics 48(S1),
   2010. doi:10.1080/00423111003748088
.. [3] R. Brancati, F. Tufano, "Indirect estimation of tire pressure on several road pavements
   via Interacting Multiple Model approach", Sensors, 2022.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numba
import numpy as np
import numpy.typing as npt

from pipeline.errors import InputError

__all__ = [
    "TireParams",
    "effective_rolling_radius",
    "pressure_from_stiffness",
    "tire_forces",
    "tire_forces_array",
    "vertical_force",
    "vertical_stiffness",
]

_EPS = 1e-9


@dataclass(frozen=True)
class TireParams:
    """Tyre parameters, SI units (Pa, N, m, N/m, N s/m); MF coefficients dimensionless."""

    unloaded_radius: float = 0.37  # m, 235/60R18 SUV tyre
    nominal_pressure: float = 250e3  # Pa, p0 of paper 000
    nominal_load: float = 5000.0  # N, FNOMIN: about an SUV corner's static load
    vertical_stiffness_nominal: float = 264700.0  # N/m, kt0 of paper 000 Table 1
    vertical_damping: float = 200.0  # N s/m, MF-Swift-class value (50-500); the paper neglects it
    pfz1: float = 0.7097  # MF-Tyre 6.1 PFZ1 (DESIGN.md)
    lambda_mu: float = 1.0  # friction scaling (1: dry asphalt)
    # longitudinal, pure slip
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
    ppx1: float = -0.3489
    ppx2: float = 0.382
    ppx3: float = -0.0963
    ppx4: float = 0.0645
    # lateral, pure slip
    pcy1: float = 1.338
    pdy1: float = 0.8785
    pdy2: float = -0.06452
    pey1: float = -0.8057
    pey2: float = -0.6046
    pey3: float = 0.09854
    pky1: float = -15.324
    pky2: float = 1.715
    pky4: float = 2.0005
    ppy1: float = -0.6249
    ppy2: float = -0.0654
    ppy3: float = -0.1668
    ppy4: float = 0.2834
    # combined slip
    rbx1: float = 13.046
    rbx2: float = 9.718
    rcx1: float = 0.9995
    rex1: float = -0.4403
    rex2: float = -0.4663
    rby1: float = 10.622
    rby2: float = 7.82
    rcy1: float = 1.0587
    rey1: float = 0.3148
    rey2: float = 0.004867
    # effective rolling radius
    breff: float = 8.386
    dreff: float = 0.25826
    freff: float = 0.07394

    def to_array(self) -> np.ndarray:
        """Packed float64 vector in field order (index constants ``I_<NAME>`` of this module)."""
        return np.array([getattr(self, f.name) for f in fields(self)], dtype=float)

    @classmethod
    def from_mapping(cls, values: dict) -> TireParams:
        """Defaults overridden by `values` (name → number); unknown names raise InputError."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise InputError(f"tire: unknown parameter(s) {', '.join(unknown)}")
        return cls(**{**asdict(cls()), **{k: float(v) for k, v in values.items()}})


# positions in TireParams.to_array() (field order); tests/test_tire.py checks them against the fields
I_UNLOADED_RADIUS, I_NOMINAL_PRESSURE, I_NOMINAL_LOAD = 0, 1, 2
I_KT0, I_CT, I_PFZ1, I_LAMBDA_MU = 3, 4, 5, 6
(I_PCX1, I_PDX1, I_PDX2, I_PEX1, I_PEX2, I_PEX3, I_PEX4, I_PKX1, I_PKX2, I_PKX3) = range(7, 17)
(I_PPX1, I_PPX2, I_PPX3, I_PPX4) = range(17, 21)
(I_PCY1, I_PDY1, I_PDY2, I_PEY1, I_PEY2, I_PEY3, I_PKY1, I_PKY2, I_PKY4) = range(21, 30)
(I_PPY1, I_PPY2, I_PPY3, I_PPY4) = range(30, 34)
(I_RBX1, I_RBX2, I_RCX1, I_REX1, I_REX2, I_RBY1, I_RBY2, I_RCY1, I_REY1, I_REY2) = range(34, 44)
(I_BREFF, I_DREFF, I_FREFF) = range(44, 47)


@numba.njit(cache=True)
def vertical_stiffness(pressure, tp):
    """Radial stiffness kt(p) = kt0·(1 + pFz1·dpi), N/m (Brancati & Tufano 2022, eq. 3–4)."""
    dpi = (pressure - tp[I_NOMINAL_PRESSURE]) / tp[I_NOMINAL_PRESSURE]
    return tp[I_KT0] * (1.0 + tp[I_PFZ1] * dpi)


def pressure_from_stiffness(kt: npt.ArrayLike, params: TireParams) -> np.ndarray:
    """Inverse of eq. 3–4: p = p0·(1 + (kt/kt0 - 1)/pFz1), Pa."""
    kt = np.asarray(kt, dtype=float)
    return params.nominal_pressure * (1.0 + (kt / params.vertical_stiffness_nominal - 1.0) / params.pfz1)


@numba.njit(cache=True)
def vertical_force(deflection, deflection_rate, pressure, tp):
    """Fz = kt(p)·δ + ct·δ̇ for δ > 0 (m, m/s), clipped at 0; 0 when lifted off, N."""
    if deflection <= 0.0:
        return 0.0
    return max(vertical_stiffness(pressure, tp) * deflection + tp[I_CT] * deflection_rate, 0.0)


@numba.njit(cache=True)
def effective_rolling_radius(fz, pressure, tp):
    """MF-Tyre 6.1 effective rolling radius at load `fz` (N) and `pressure` (Pa), m."""
    fz0 = tp[I_NOMINAL_LOAD]
    rho = max(fz, 0.0) / fz0
    cz = vertical_stiffness(pressure, tp)
    return tp[I_UNLOADED_RADIUS] - fz0 / cz * (tp[I_DREFF] * np.arctan(tp[I_BREFF] * rho) + tp[I_FREFF] * rho)


@numba.njit(cache=True)
def _magic(b, c, d, e, x):
    return d * np.sin(c * np.arctan(b * x - e * (b * x - np.arctan(b * x))))


@numba.njit(cache=True)
def tire_forces(fz, kappa, alpha, pressure, tp):
    """MF-Tyre 6.1 longitudinal and lateral force (N) at load `fz` (N), slip ratio `kappa` (-),
    slip angle `alpha` (rad) and `pressure` (Pa); camber 0. Returns ``(fx, fy)``.

    Pacejka 2012, eq. 4.E9–4.E30 (pure slip) and 4.E50–4.E67 (combined slip), with the
    MF 6.1 pressure terms of Besselink et al. 2010.
    """
    if fz <= 0.0:
        return 0.0, 0.0
    fz0 = tp[I_NOMINAL_LOAD]
    dfz = (fz - fz0) / fz0
    dpi = (pressure - tp[I_NOMINAL_PRESSURE]) / tp[I_NOMINAL_PRESSURE]
    lmu = tp[I_LAMBDA_MU]
    # ---- longitudinal, pure slip ----
    cx = tp[I_PCX1]
    mux = (tp[I_PDX1] + tp[I_PDX2] * dfz) * (1.0 + tp[I_PPX3] * dpi + tp[I_PPX4] * dpi * dpi) * lmu
    dx = mux * fz
    ex = (tp[I_PEX1] + tp[I_PEX2] * dfz + tp[I_PEX3] * dfz * dfz) * (1.0 - tp[I_PEX4] * np.sign(kappa))
    ex = min(ex, 1.0)
    kxk = (
        fz
        * (tp[I_PKX1] + tp[I_PKX2] * dfz)
        * np.exp(tp[I_PKX3] * dfz)
        * (1.0 + tp[I_PPX1] * dpi + tp[I_PPX2] * dpi * dpi)
    )
    bx = kxk / (cx * dx + _EPS)
    fx0 = _magic(bx, cx, dx, ex, kappa)
    # ---- lateral, pure slip ----
    cy = tp[I_PCY1]
    muy = (tp[I_PDY1] + tp[I_PDY2] * dfz) * (1.0 + tp[I_PPY3] * dpi + tp[I_PPY4] * dpi * dpi) * lmu
    dy = muy * fz
    ey = (tp[I_PEY1] + tp[I_PEY2] * dfz) * (1.0 - tp[I_PEY3] * np.sign(alpha))
    ey = min(ey, 1.0)
    kya = (
        tp[I_PKY1]
        * fz0
        * (1.0 + tp[I_PPY1] * dpi)
        * np.sin(tp[I_PKY4] * np.arctan(fz / (tp[I_PKY2] * (1.0 + tp[I_PPY2] * dpi) * fz0)))
    )
    by = kya / (cy * dy + _EPS)
    fy0 = _magic(by, cy, dy, ey, alpha)
    # ---- combined slip weighting ----
    bxa = tp[I_RBX1] * np.cos(np.arctan(tp[I_RBX2] * kappa))
    exa = min(tp[I_REX1] + tp[I_REX2] * dfz, 1.0)
    gxa = np.cos(tp[I_RCX1] * np.arctan(bxa * alpha - exa * (bxa * alpha - np.arctan(bxa * alpha))))
    byk = tp[I_RBY1] * np.cos(np.arctan(tp[I_RBY2] * alpha))
    eyk = min(tp[I_REY1] + tp[I_REY2] * dfz, 1.0)
    gyk = np.cos(tp[I_RCY1] * np.arctan(byk * kappa - eyk * (byk * kappa - np.arctan(byk * kappa))))
    return gxa * fx0, gyk * fy0


def tire_forces_array(
    fz: npt.ArrayLike, kappa: npt.ArrayLike, alpha: npt.ArrayLike, pressure: npt.ArrayLike, params: TireParams
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`tire_forces` over broadcast arrays (for plots and tests), N."""
    fz, kappa, alpha, pressure = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (fz, kappa, alpha, pressure))
    )
    tp = params.to_array()
    fx, fy = np.empty(fz.shape), np.empty(fz.shape)
    for index in np.ndindex(fz.shape):
        fx[index], fy[index] = tire_forces(fz[index], kappa[index], alpha[index], pressure[index], tp)
    return fx, fy
