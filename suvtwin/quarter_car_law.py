r"""The 2-DOF non-linear quarter car of paper 000, eq. 1, as compiled scalar functions: the one source.

Usual call (inside a numba loop or from Python, scalars)::

    a_s, a_us = accelerations(z_s, z_us, v_s, v_us, k_t, z_r, ks, ksnl, cs, csnl, m_s, m_us, signed)

Brancati & Tufano 2022, eq. 1: :math:`m_s\ddot z_s = -F`,
:math:`m_{us}\ddot z_{us} = F - k_t(z_{us} - z_r)`, with the suspension force

.. math::

    F = k_s d + k_{snl} d^3 + c_s \dot d + c_{snl}\,g(\dot d), \qquad d = z_s - z_{us}.

The paper prints the damper term as :math:`c_{snl}\dot d^2`, which never changes sign;
``signed=True`` uses the sign-preserving :math:`g(\dot d) = |\dot d|\,\dot d`, ``signed=False``
the literal :math:`\dot d^2`. Units: m, m/s, N/m, N/m³, N s/m, N s²/m², kg; forces in N,
accelerations in m/s².

Callers: the estimators' numpy reference (:mod:`suvtwin.estimators.quarter_car`, through
ufuncs wrapping these functions), the compiled IMM-UKF
(:mod:`suvtwin.estimators.imm_ukf_kernel`) and the identification objectives
(:mod:`suvtwin.identification.quarter_car_fit`).

References
----------
.. [1] R. Brancati, F. Tufano, "Indirect estimation of tire pressure on several road pavements
   via Interacting Multiple Model approach", Machines 10(12), 1221, 2022, eq. 1 (paper 000 of
   this project). doi:10.3390/machines10121221
"""

from __future__ import annotations

from suvtwin.jit import cached_njit

# Compiled callers in other modules use suvtwin.jit.cached_njit, whose on-disk cache key includes
# the code and constants of what they call: editing a law here recompiles them (never stale code).

__all__ = ["accelerations", "sprung_acceleration", "suspension_force", "unsprung_acceleration"]


@cached_njit
def suspension_force(z_s, z_us, v_s, v_us, ks, ksnl, cs, csnl, signed):
    """Suspension force F of eq. 1, N (F > 0 pulls the body down and the wheel up).

    `z_s`, `z_us` in m, `v_s`, `v_us` in m/s; `ks` N/m, `ksnl` N/m³, `cs` N s/m, `csnl`
    N s²/m²; `signed` selects |v|·v (True) or the paper's v² (False) for the damper term.
    """
    d = z_s - z_us
    v = v_s - v_us
    g = abs(v) if signed else v
    return (ks + ksnl * (d * d)) * d + (cs + csnl * g) * v  # eq. 1: ks d + ksnl d^3 + cs v + csnl g(v)


@cached_njit
def sprung_acceleration(force, m_s):
    """Sprung-mass acceleration (m/s²) under suspension force `force` (N), mass `m_s` (kg): eq. 1."""
    return -force / m_s


@cached_njit
def unsprung_acceleration(force, kt, z_us, z_r, m_us):
    """Unsprung-mass acceleration (m/s²): suspension force `force` (N) and the tyre spring
    `kt` (N/m) between the wheel at `z_us` and the road at `z_r` (m); mass `m_us` (kg): eq. 1."""
    return (force - kt * (z_us - z_r)) / m_us


@cached_njit
def accelerations(z_s, z_us, v_s, v_us, kt, z_r, ks, ksnl, cs, csnl, m_s, m_us, signed):
    """Sprung and unsprung accelerations (m/s²) of eq. 1 (paper 003 eq. 16: the measurement)."""
    force = suspension_force(z_s, z_us, v_s, v_us, ks, ksnl, cs, csnl, signed)
    return sprung_acceleration(force, m_s), unsprung_acceleration(force, kt, z_us, z_r, m_us)
