r"""The 2-DOF non-linear quarter car of paper 000, as the estimators' process model.

Usual call: ``acc_s, acc_us = accelerations(x, z_road, qc)`` with
``x = [z_s, z_us, v_s, v_us, k_t]`` over any leading batch shape.

Brancati & Tufano 2022:

- eq. 1: :math:`m_s\ddot z_s = -F`, :math:`m_{us}\ddot z_{us} = F - k_t(z_{us} - z_r)`, with the
  suspension force
  :math:`F = k_s d + k_{snl} d^3 + c_s \dot d + c_{snl}\,g(\dot d)`, :math:`d = z_s - z_{us}`.
  The paper writes the damper term as :math:`c_{snl}\dot d^2`, which never changes
  sign (a damper that pushes the same way in bump and rebound); the default here is
  the sign-preserving :math:`g(\dot d) = |\dot d|\dot d` (``damper_law="signed"``), the
  literal form is ``damper_law="paper"``. A result says which it used.
- eq. 2: corner sprung mass :math:`m_s = \tfrac12 m_{s,vehicle}\,a_2/l` (front).
- eq. 3–4: :math:`k_t = k_{t0}(1 + p_{Fz1}\,dp_i)`, :math:`dp_i = (p - p_0)/p_0`, and inverse.
- eq. 15: forward-Euler discretization with :math:`k_t` a random walk.
- eq. 16 (paper 003): the measurement is the pair of accelerations of eq. 1.
- eq. 18: :math:`Q = \mathrm{diag}(q_i \Delta t^3)`.
- eq. 19: the paper writes :math:`R = \mathrm{diag}(\sigma_{a z_s}, \sigma_{a z_{us}})` with the
  *standard deviations* on the diagonal; a covariance needs the variances, which is
  what :func:`measurement_noise` returns (the paper's form is ``literal=True``).

Eq. 1 and eq. 3–4 are evaluated by the compiled scalar functions of
:mod:`suvtwin.quarter_car_law` and :mod:`suvtwin.tire_stiffness` (the same ones the
compiled IMM-UKF, the identification and the simulator call), here through ufuncs
over arrays; the tyre constants default to the SUV's ``.tir`` file.

No MuJoCo here: estimators consume arrays.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numba
import numpy as np
import numpy.typing as npt

from suvtwin.quarter_car_law import sprung_acceleration, suspension_force, unsprung_acceleration
from suvtwin.tire_stiffness import (
    pressure_at_stiffness_array,
    pressure_sigma_at_stiffness_sigma,
    stiffness_at_pressure_array,
    suv_tire_stiffness,
)

__all__ = [
    "IX_KT",
    "IX_VS",
    "IX_VUS",
    "IX_ZS",
    "IX_ZUS",
    "QuarterCar",
    "accelerations",
    "measurement_noise",
    "pressure_from_stiffness",
    "pressure_sigma_from_stiffness_sigma",
    "process_euler",
    "process_noise",
    "process_semi_implicit",
    "simulate_quarter_car",
    "sprung_mass_share",
    "stiffness_from_pressure",
]

IX_ZS, IX_ZUS, IX_VS, IX_VUS, IX_KT = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class QuarterCar:
    """Quarter-car parameters, SI units. Fields broadcast: give arrays of shape (S,) for S modes.

    Attributes
    ----------
    sprung_mass : kg (eq. 2)
    unsprung_mass : kg
    spring_rate : N/m, :math:`k_s`
    spring_cubic : N/m³, :math:`k_{snl}`
    damping : N s/m, :math:`c_s`
    damping_nonlinear : N s²/m², :math:`c_{snl}`
    damper_law : "signed" (|v|·v, default) or "paper" (v², eq. 1 as printed)
    """

    sprung_mass: npt.ArrayLike
    unsprung_mass: npt.ArrayLike
    spring_rate: npt.ArrayLike
    spring_cubic: npt.ArrayLike
    damping: npt.ArrayLike
    damping_nonlinear: npt.ArrayLike
    damper_law: Literal["signed", "paper"] = "signed"


def sprung_mass_share(
    chassis_mass: float, *, a_opposite: float, wheelbase: float, load: float = 0.0
) -> float:
    """Sprung mass of one corner, kg: ½·(m_chassis + m_load)·a_opposite/l (paper 000 eq. 2).

    For a front corner `a_opposite` is a2 (CoG to rear axle); for a rear corner a1.
    """
    return 0.5 * (chassis_mass + load) * a_opposite / wheelbase


def _law(kt0: float | None, p0: float | None, pfz1: float | None) -> tuple[float, float, float]:
    """(kt0, p0, pfz1) of eq. 3–4: the SUV tyre's (its .tir file), with any given one replacing its own."""
    suv = suv_tire_stiffness()
    return (suv.kt0 if kt0 is None else kt0, suv.p0 if p0 is None else p0, suv.pfz1 if pfz1 is None else pfz1)


def stiffness_from_pressure(
    pressure: npt.ArrayLike, *, kt0: float | None = None, p0: float | None = None, pfz1: float | None = None
):
    """Tire vertical stiffness at inflation pressure `pressure` (Pa), N/m (paper 000 eq. 3–4).

    `kt0` (N/m), `p0` (Pa), `pfz1` (−) default to the SUV's tyre
    (:func:`suvtwin.tire_stiffness.suv_tire_stiffness`, the simulator's .tir file).
    """
    return stiffness_at_pressure_array(np.asarray(pressure, dtype=float), *_law(kt0, p0, pfz1))


def pressure_from_stiffness(
    kt: npt.ArrayLike, *, kt0: float | None = None, p0: float | None = None, pfz1: float | None = None
):
    """Inflation pressure for tire stiffness `kt` (N/m), Pa (inverse of eq. 3–4; defaults as
    :func:`stiffness_from_pressure`)."""
    return pressure_at_stiffness_array(np.asarray(kt, dtype=float), *_law(kt0, p0, pfz1))


def pressure_sigma_from_stiffness_sigma(
    sigma_kt: npt.ArrayLike, *, kt0: float | None = None, p0: float | None = None, pfz1: float | None = None
):
    """Standard deviation of the pressure (Pa) for a k_t standard deviation (N/m): eq. 3–4 is linear."""
    return pressure_sigma_at_stiffness_sigma(np.asarray(sigma_kt, dtype=float), *_law(kt0, p0, pfz1))


# eq. 1 over broadcast arrays: ufuncs wrapping the compiled scalar law (compiled on first use)
@numba.vectorize(cache=False)  # no on-disk cache: it would not see edits to suvtwin.quarter_car_law
def _suspension_force(z_s, z_us, v_s, v_us, ks, ksnl, cs, csnl, signed):
    return suspension_force(z_s, z_us, v_s, v_us, ks, ksnl, cs, csnl, signed)


@numba.vectorize(cache=False)  # no on-disk cache: it would not see edits to suvtwin.quarter_car_law
def _sprung_acceleration(force, m_s):
    return sprung_acceleration(force, m_s)


@numba.vectorize(cache=False)  # no on-disk cache: it would not see edits to suvtwin.quarter_car_law
def _unsprung_acceleration(force, kt, z_us, z_r, m_us):
    return unsprung_acceleration(force, kt, z_us, z_r, m_us)


def accelerations(x: np.ndarray, z_road: npt.ArrayLike, qc: QuarterCar) -> tuple[np.ndarray, np.ndarray]:
    """Sprung and unsprung vertical accelerations, m/s² (paper 000 eq. 1; paper 003 eq. 16).

    Parameters
    ----------
    x : numpy.ndarray, shape (..., 5)
        ``[z_s, z_us, v_s, v_us, k_t]`` in m, m, m/s, m/s, N/m (deviations from static).
    z_road : array_like, broadcast to x[..., 0]
        Road elevation under the tire, m.
    qc : QuarterCar
        Parameters broadcast against ``x[..., 0]``.
    """
    force = _suspension_force(
        x[..., IX_ZS], x[..., IX_ZUS], x[..., IX_VS], x[..., IX_VUS],
        qc.spring_rate, qc.spring_cubic, qc.damping, qc.damping_nonlinear, qc.damper_law == "signed",
    )  # fmt: skip
    acc_s = _sprung_acceleration(force, qc.sprung_mass)
    acc_us = _unsprung_acceleration(force, x[..., IX_KT], x[..., IX_ZUS], z_road, qc.unsprung_mass)
    return acc_s, acc_us


def process_euler(x: np.ndarray, z_road: npt.ArrayLike, qc: QuarterCar, dt: float) -> np.ndarray:
    """One forward-Euler step of eq. 15, x of shape (..., 5); k_t is carried unchanged (random walk mean)."""
    acc_s, acc_us = accelerations(x, z_road, qc)
    out = x.copy()
    out[..., IX_ZS] += x[..., IX_VS] * dt
    out[..., IX_ZUS] += x[..., IX_VUS] * dt
    out[..., IX_VS] += acc_s * dt
    out[..., IX_VUS] += acc_us * dt
    return out


def process_semi_implicit(x: np.ndarray, z_road: npt.ArrayLike, qc: QuarterCar, dt: float) -> np.ndarray:
    """One semi-implicit (symplectic) Euler step: velocities from eq. 1, then positions with the
    new velocities. Same cost as eq. 15, but energy-preserving: forward Euler inflates the
    ~10 Hz wheel-hop oscillation by ~0.2 % per 1 ms step, which biases k_t low."""
    acc_s, acc_us = accelerations(x, z_road, qc)
    out = x.copy()
    out[..., IX_VS] += acc_s * dt
    out[..., IX_VUS] += acc_us * dt
    out[..., IX_ZS] += out[..., IX_VS] * dt
    out[..., IX_ZUS] += out[..., IX_VUS] * dt
    return out


def process_noise(q: npt.ArrayLike, dt: float) -> np.ndarray:
    """Q = diag(q_i·Δt³) (paper 000 eq. 18), shape (len(q), len(q))."""
    return np.diag(np.asarray(q, dtype=float) * dt**3)


def measurement_noise(sigma_sprung: float, sigma_unsprung: float, *, literal: bool = False) -> np.ndarray:
    """Measurement covariance R of the two accelerometers, (m/s²)².

    Variances on the diagonal; ``literal=True`` returns the paper's eq. 19 as printed
    (standard deviations on the diagonal), for reproducing the paper.
    """
    if literal:
        return np.diag([sigma_sprung, sigma_unsprung])
    return np.diag([sigma_sprung**2, sigma_unsprung**2])


def simulate_quarter_car(
    x0: np.ndarray, z_road: np.ndarray, qc: QuarterCar, dt: float, *, substeps: int = 10
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate eq. 1 finely (RK4, `substeps` per sample, road linear in between): truth for tests.

    Parameters
    ----------
    x0 : numpy.ndarray, shape (..., 5)
        Initial state; k_t (last entry) is held constant.
    z_road : numpy.ndarray, shape (..., T)
        Road elevation at the sample times, m.
    dt : float
        Sample interval, s.

    Returns
    -------
    states : numpy.ndarray, shape (..., T, 5)
        State at each sample time.
    acc : numpy.ndarray, shape (..., T, 2)
        Sprung and unsprung acceleration at each sample time, m/s².
    """
    h = dt / substeps
    x = np.array(x0, dtype=float)
    n = z_road.shape[-1]
    states = np.empty(x.shape[:-1] + (n, 5))
    acc = np.empty(x.shape[:-1] + (n, 2))

    def deriv(state, road):
        a_s, a_us = accelerations(state, road, qc)
        out = np.zeros_like(state)
        out[..., IX_ZS] = state[..., IX_VS]
        out[..., IX_ZUS] = state[..., IX_VUS]
        out[..., IX_VS] = a_s
        out[..., IX_VUS] = a_us
        return out

    for k in range(n):
        states[..., k, :] = x
        acc[..., k, 0], acc[..., k, 1] = accelerations(x, z_road[..., k], qc)
        if k == n - 1:
            break
        r0, r1 = z_road[..., k], z_road[..., k + 1]
        for j in range(substeps):
            ra = r0 + (r1 - r0) * j / substeps
            rm = r0 + (r1 - r0) * (j + 0.5) / substeps
            rb = r0 + (r1 - r0) * (j + 1) / substeps
            k1 = deriv(x, ra)
            k2 = deriv(x + 0.5 * h * k1, rm)
            k3 = deriv(x + 0.5 * h * k2, rm)
            k4 = deriv(x + h * k3, rb)
            x = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return states, acc
