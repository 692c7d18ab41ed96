r"""Linear full car (seven degrees of freedom) on two road tracks: each corner's acceleration spectrum.

Usual call::

    car = full_car_model(load_vehicle())          # suvtwin.pipeline.estimation, or FullCar(...)
    S = corner_spectrum(f, speed, car, corner=2, kt=kt)   # (F, 2, 2) per unit road-velocity PSD
    G = track_responses(f, car, car.wheelbase / speed)    # (F, 8, 2): all eight channels, S = S_v G G^H

Model (the textbook full-car ride model, e.g. Jazar [1]_ ch. 15; Gillespie [2]_ ch. 5): a rigid
body of mass m with pitch and roll inertias about its centre of gravity rests on four vertical
spring–damper corners at (x_i, y_i) from it (x forward, y left); an anti-roll bar joins the two
wheels of each axle (force :math:`k_{arb}(s_l - s_r)` on each, s the compression); four unsprung
masses stand on radial tyres (stiffness k_t, damping c_t) on the road. Small motions about the
static position: heave z, pitch θ, roll φ and the four wheel heights :math:`z_{u,i}`; the body
point above corner i is at :math:`z_{b,i} = z + x_i\theta + y_i\varphi`. The equations
:math:`M\ddot q + C\dot q + Kq = K_t r + C_t\dot r` follow from the energies

.. math:: V = \tfrac12\sum_i k_i s_i^2 + \tfrac12 k_{f}(s_{fl} - s_{fr})^2
   + \tfrac12 k_{r}(s_{rl} - s_{rr})^2 + \tfrac12\sum_i k_{t,i}(z_{u,i} - r_i)^2,
   \qquad s_i = z_{u,i} - z_{b,i},

and the like dissipation function (dampers c_i, tyre damping c_{t,i}).

Roads: the left track runs under fl and rl, the right under fr and rr; each rear wheel meets its
front wheel's road a wheelbase later, :math:`\tau = L/v`; the two tracks have the same
road-velocity PSD S_v (ISO 8608 roads of waviness 2 have white road velocity) and a real
coherence γ(f) between them (0: independent tracks, 1: identical). Corner i's 2×2 spectrum of
(body acceleration above it, wheel acceleration) is then

.. math:: S(f) = S_v\Big(\sum_{\text{tracks}} g\,g^H + \gamma\,(g_L g_R^H + g_R g_L^H)\Big),\qquad
   g = h_{\text{front}} + h_{\text{rear}}\,e^{-i2\pi f\tau},

h the corner's response to unit road velocity under one wheel. Projected on a fixed direction u,
:math:`|u^H g|^2 = |a|^2 + |b|^2 + 2\,\mathrm{Re}(a\bar b\,e^{i2\pi f\tau})` with
:math:`a = u^H h_{\text{front}}`, :math:`b = u^H h_{\text{rear}}`, and the tracks' cross term
:math:`2\,\mathrm{Re}\big((u^H g_L)\overline{(u^H g_R)}\big) = 2\,\mathrm{Re}(a_L\bar a_R + b_L\bar b_R)
+ 2\,\mathrm{Re}\big((a_L\bar b_R + a_R\bar b_L)\,e^{i2\pi f\tau}\big)`: the speed enters only
through that phase, so :func:`projected_terms` and :func:`projected_cross_terms` return the
speed-free parts and :func:`gain_at_delay` adds the speed. Real roads' tracks are coherent at long
wavelengths and less so at short ones (C. J. Dodds, J. D. Robson, "The description of road surface
roughness", *J. Sound Vib.* 31(2), 1973; X. Liu et al., *Mech. Syst. Signal Process.*, 2015,
doi:10.1016/j.ymssp.2015.01.034, build left and right profiles to a given coherence function); the
online monitor estimates γ per band from the two axles' wheels
(:func:`axle_coherence_terms`): taken as 0, on the MuJoCo SUV the tyres' pressures came out 21 kPa
(tracks correlated by 0.5) to 45 kPa (identical tracks) low (docs/monitor.md).

**The tyres' lateral slip** (optional: a car with ``cornering_stiffness`` and a speed given). The
wheels hang from the body on vertical slides, so when the body rolls about its centre of gravity
the wheel centres, a height :math:`h_w` below it, slide sideways at :math:`h_w\dot\varphi`; the
tyres resist that slip with their cornering stiffness :math:`C_i` (MF-Tyre's :math:`K_{y\alpha}`
at the static load), a force at the ground, :math:`h_c` below the centre of gravity. With the
car's lateral velocity v and yaw rate r as two more coordinates (the linear single-track model
of Pacejka [3]_ ch. 1, Rajamani [4]_ §2.3, here with roll) and the tyres' lateral relaxation
length σ (a first-order lag, :math:`\tilde C_i = C_i/(1 + s\sigma/V)`), at speed V:

.. math:: F_{y,i} = -\tilde C_i\,\frac{v + x_i r + h_w\dot\varphi}{V},\qquad
   M(\dot v + V r) = \sum_i F_{y,i},\qquad I_z\dot r = \sum_i x_i F_{y,i},

and the roll equation gains :math:`-h_c\sum_i F_{y,i}`: roll damping that falls with speed and
a sway the body cannot follow above about 1 Hz. Without it the full car over-predicts MuJoCo's
body acceleration at 2–3 Hz (MuJoCo 0.35–0.72 of its power at 36–100 km/h); with it 0.94–1.16
(``tests/test_vehicle_model.py``). The vertical responses then depend on the speed beyond the
front→rear delay, so :func:`wheel_responses` and :func:`track_responses` take ``speed_mps``
(None: no lateral slip, the speed-free model the tables of :func:`projected_terms` need).

Why this model: the roll-plane corner model of :class:`suvtwin.estimators.joint.LinearQuarterCar`
(half a heave quarter car plus half a roll quarter car with the whole roll inertia on one axle)
misses that the body's roll is carried by both axles' springs and bars, and that the rear wheels
re-excite the body the front wheels excited; on the SUV it biases the fitted tyre stiffness by
speed-dependent amounts of up to 30 kPa (``python bench/monitor_model_bias.py``).

No MuJoCo here: plain arrays.

References
----------
.. [1] R. N. Jazar, *Vehicle Dynamics: Theory and Application*, 3rd ed., Springer, 2017, ch. 15
   (full-car vibrating model).
.. [2] T. D. Gillespie, *Fundamentals of Vehicle Dynamics*, SAE, 1992, ch. 5 (ride).
.. [3] H. B. Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., Butterworth-Heinemann, 2012, ch. 1
   (the linear single-track model) and ch. 7 (relaxation length).
.. [4] R. Rajamani, *Vehicle Dynamics and Control*, 2nd ed., Springer, 2012, §2.3 (lateral
   dynamic model: bicycle model, its eigenvalues).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit

__all__ = [
    "TRACKS",
    "FullCar",
    "axle_coherence_parts",
    "axle_coherence_terms",
    "corner_spectrum",
    "blend_gain_at_delay",
    "gain_at_delay",
    "projected_cross_terms",
    "projected_gains",
    "projected_terms",
    "static_forces",
    "suspension_force_responses",
    "track_responses",
    "wheel_responses",
]

TRACKS = ((0, 2), (1, 3))
"""(front, rear) wheel indices of the left and the right track, corners ordered fl, fr, rl, rr."""


@dataclass(frozen=True)
class FullCar:
    """Linear full car: body and corners, SI units; corners ordered fl, fr, rl, rr.

    ``sprung_mass`` (kg), ``inertia_pitch`` and ``inertia_roll`` (kg m², about the body's centre of
    gravity), ``corner_xy`` (4 × (x, y), m from it, x forward, y left), ``unsprung_mass`` (kg),
    ``spring_rate`` (N/m at the wheel), ``damping`` (N s/m, linear equivalent), ``anti_roll``
    ((front, rear) wheel-rate equivalents of the bars, N/m), ``tire_stiffness`` (N/m) and
    ``tire_damping`` (N s/m) per corner. ``wheelbase`` (m) is the front-to-rear distance.

    The tyres' lateral slip (module docstring), all optional: ``cornering_stiffness`` (N/rad per
    corner; None: no lateral slip), ``cog_height`` (m, the body's centre of gravity above the
    ground), ``wheel_centre_height`` (m above the ground), ``inertia_yaw`` (kg m², the whole car
    about the vertical through the centre of gravity), ``relaxation_length`` (m, lateral)."""

    sprung_mass: float
    inertia_pitch: float
    inertia_roll: float
    corner_xy: tuple[tuple[float, float], ...]
    unsprung_mass: tuple[float, ...]
    spring_rate: tuple[float, ...]
    damping: tuple[float, ...]
    anti_roll: tuple[float, float]
    tire_stiffness: tuple[float, ...]
    tire_damping: tuple[float, ...]
    cornering_stiffness: tuple[float, ...] | None = None
    cog_height: float = 0.0
    wheel_centre_height: float = 0.0
    inertia_yaw: float = 0.0
    relaxation_length: float = 0.0

    def __post_init__(self) -> None:
        per_corner = ("corner_xy", "unsprung_mass", "spring_rate", "damping", "tire_stiffness",
                      "tire_damping")  # fmt: skip
        for name in per_corner:
            if len(getattr(self, name)) != 4:
                raise InputError(f"full car {name} needs one entry per corner (fl, fr, rl, rr)")
        positive = [self.sprung_mass, self.inertia_pitch, self.inertia_roll, *self.unsprung_mass,
                    *self.spring_rate, *self.tire_stiffness]  # fmt: skip
        if not all(np.isfinite(positive)) or min(positive) <= 0:
            raise InputError("full car masses, inertias, spring rates and tyre stiffnesses must be > 0")
        if self.cornering_stiffness is not None:
            lateral = [*self.cornering_stiffness, self.inertia_yaw, self.cog_height]
            if len(self.cornering_stiffness) != 4 or not all(np.isfinite(lateral)) or min(lateral) <= 0:
                raise InputError("full car cornering_stiffness needs 4 entries > 0 N/rad, with "
                                 "inertia_yaw and cog_height > 0")  # fmt: skip
            if not (0.0 <= self.wheel_centre_height < self.cog_height and self.relaxation_length >= 0):
                raise InputError("full car wheel_centre_height must be in [0, cog_height) m and "
                                 "relaxation_length ≥ 0 m")  # fmt: skip

    @property
    def wheelbase(self) -> float:
        """Front to rear axle, m (mean over the two tracks)."""
        xy = np.asarray(self.corner_xy)
        return float(0.5 * ((xy[0, 0] - xy[2, 0]) + (xy[1, 0] - xy[3, 0])))


def _body_matrices(
    car: FullCar, spring_rate: np.ndarray, damping: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""The suspension's part of the equations of motion, coordinates q = (z, θ, φ, z_u fl, fr, rl, rr).

    `spring_rate`, `damping` (4,) per corner (N/m, N s/m). Returns the body points' Jacobian (4, 3)
    (:math:`z_{b,i} = z + x_i\theta + y_i\varphi`, rows fl, fr, rl, rr) and the stiffness (N/m),
    damping (N s/m) and mass (kg) matrices (7, 7) of V and the dissipation function without the
    tyres (module docstring), which act on the wheels' diagonal."""
    xy = np.asarray(car.corner_xy, dtype=float)
    jac = np.c_[np.ones(4), xy[:, 0], xy[:, 1]]  # body point above each corner: z + x θ + y φ
    sel = np.zeros((4, 7))  # compression s = z_u − z_b
    sel[:, :3] = -jac
    sel[np.arange(4), 3 + np.arange(4)] = 1.0
    k_corner = np.diag(spring_rate)
    for (left, right), k_bar in zip(((0, 1), (2, 3)), car.anti_roll, strict=True):
        k_corner[np.ix_((left, right), (left, right))] += k_bar * np.array([[1.0, -1.0], [-1.0, 1.0]])
    stiff = sel.T @ k_corner @ sel
    damp = sel.T @ np.diag(damping) @ sel
    mass = np.diag([car.sprung_mass, car.inertia_pitch, car.inertia_roll, *car.unsprung_mass])
    return jac, stiff, damp, mass


def static_forces(car: FullCar, gravity: float = 9.81) -> tuple[np.ndarray, np.ndarray]:
    r"""The car at rest on level ground: each tyre's vertical force and each corner spring's, N
    (fl, fr, rl, rr; the springs' from their unstressed length, the anti-roll bars carrying the rest).

    Four supports make the weight statically indeterminate: heave, pitch and roll balance fix three
    combinations of the four tyre forces, and the fourth, the warp (fl + rr against fr + rl), is set
    by the stiffnesses. A weight off the car's centre line makes a roll moment that the axles share
    in the ratio of their roll stiffnesses (springs and anti-roll bar in series with the tyres), not
    of their shares of the weight (W. F. Milliken and D. L. Milliken, *Race Car Vehicle Dynamics*,
    SAE, 1995, ch. 18). Here the linear model of the module docstring is solved for
    :math:`(K + K_t)\,q = -g\,(m, 0, 0, m_{u,fl}, \dots, m_{u,rr})` (the body's weight at its centre
    of gravity, each wheel's own); tyre i carries :math:`-k_{t,i} z_{u,i}` and its spring
    :math:`k_i s_i`. `gravity`: m/s²."""
    jac, stiff, _, _ = _body_matrices(car, np.asarray(car.spring_rate, dtype=float),
                                      np.asarray(car.damping, dtype=float))  # fmt: skip
    kt = np.asarray(car.tire_stiffness, dtype=float)
    stiff = stiff.copy()
    stiff[3:, 3:] += np.diag(kt)
    weight = gravity * np.r_[car.sprung_mass, 0.0, 0.0, np.asarray(car.unsprung_mass, dtype=float)]
    q = np.linalg.solve(stiff, -weight)
    compression = q[3:] - jac @ q[:3]
    return -kt * q[3:], np.asarray(car.spring_rate, dtype=float) * compression


def _dynamic_stiffness(car: FullCar, s: np.ndarray, stiff, damp, mass, speed_mps: float | None) -> np.ndarray:
    r"""The suspension's dynamic stiffness :math:`K + sC + s^2M` (F, n, n), s = i2πf (F,), without the
    tyres' vertical terms; with the tyres' lateral slip (module docstring) when the car has
    ``cornering_stiffness`` and `speed_mps` is given: n = 9, coordinates (z, θ, φ, z_u × 4, Y, Ψ),
    the lateral displacement Y and heading Ψ with v = sY and r = sΨ; else n = 7."""
    dyn7 = stiff[None] + s[:, None, None] * damp[None] + (s**2)[:, None, None] * mass[None]
    if car.cornering_stiffness is None or speed_mps is None:
        return dyn7
    if not speed_mps > 0:
        raise InputError(f"speed must be > 0 m/s for the tyres' lateral slip, got {speed_mps!r}")
    v = float(speed_mps)
    x = np.asarray(car.corner_xy, dtype=float)[:, 0]
    lag = 1.0 + s[:, None] * car.relaxation_length / v  # the lateral relaxation's first-order lag
    c = np.asarray(car.cornering_stiffness, dtype=float)[None, :] / lag  # (F, 4) N/rad
    c_sum, c_x, c_xx = c.sum(axis=1) / v, (c * x).sum(axis=1) / v, (c * x * x).sum(axis=1) / v
    h_c = car.cog_height
    h_w = car.cog_height - car.wheel_centre_height
    total = car.sprung_mass + float(np.sum(car.unsprung_mass))
    dyn = np.zeros((s.size, 9, 9), dtype=complex)
    dyn[:, :7, :7] = dyn7
    # −h_c Σ F_y on the roll row; F_y,i = −C̃_i (v + x_i r + h_w φ̇)/V with v = sY, r = sΨ
    dyn[:, 2, 2] += h_c * h_w * c_sum * s
    dyn[:, 2, 7] = h_c * c_sum * s
    dyn[:, 2, 8] = h_c * c_x * s
    # M(v̇ + V r) − Σ F_y = 0
    dyn[:, 7, 7] = total * s**2 + c_sum * s
    dyn[:, 7, 8] = total * v * s + c_x * s
    dyn[:, 7, 2] = h_w * c_sum * s
    # I_z ṙ − Σ x_i F_y = 0
    dyn[:, 8, 8] = car.inertia_yaw * s**2 + c_xx * s
    dyn[:, 8, 7] = c_x * s
    dyn[:, 8, 2] = h_w * c_x * s
    return dyn


def wheel_responses(
    f: npt.ArrayLike,
    car: FullCar,
    corner: int,
    kt: npt.ArrayLike,
    *,
    spring_rate: float | None = None,
    damping: float | npt.ArrayLike | None = None,
    tire_scale: float = 1.0,
    speed_mps: float | None = None,
) -> np.ndarray:
    """Corner `corner`'s (body, wheel) acceleration per unit road velocity under each wheel.

    `f` (F,) Hz; `kt` (P,) N/m: the corner's own tyre stiffness (the other tyres keep the car's);
    `spring_rate`, `damping`: the corner's own (default the car's); `tire_scale`: its tyre's
    stiffness and damping are multiplied by it (the share of time in contact); `speed_mps`: with
    the tyres' lateral slip at that speed (module docstring; None: without). Returns complex
    (P, F, 2, 4): [p, f, 0 body / 1 wheel, road wheel fl, fr, rl, rr], (m/s²)/(m/s). With several
    dampings `damping` (D,), (D, P, F, 2, 4), one block per damping: each damping's dynamic
    stiffness is the first's changed by s δc e eᵀ (e the corner's compression z_u − z_b in the
    coordinates), a rank-one change, so the car is inverted once for all of them (Sherman–Morrison)."""
    f = np.atleast_1d(np.asarray(f, dtype=float))
    kt = np.atleast_1d(np.asarray(kt, dtype=float))
    several = damping is not None and np.ndim(damping) == 1
    ks = np.array(car.spring_rate, dtype=float)
    cs = np.array(car.damping, dtype=float)
    if spring_rate is not None:
        ks[corner] = spring_rate
    dampings = np.atleast_1d(np.asarray(cs[corner] if damping is None else damping, dtype=float))
    cs[corner] = dampings[0]
    jac, stiff, damp, mass = _body_matrices(car, ks, cs)
    kt_all = np.array(car.tire_stiffness, dtype=float)
    ct_all = np.array(car.tire_damping, dtype=float)
    s = 2j * np.pi * f  # (F,)
    n_p, n_f = kt.size, f.size
    # dynamic stiffness (F, 7, 7) with the corner's tyre at the car's, inverted once per frequency;
    # each k_t on the grid is a rank-one change of it (Sherman–Morrison), so the grid costs no solves
    kt_ref = tire_scale * float(car.tire_stiffness[corner])
    ct = ct_all.copy()
    ct[corner] *= tire_scale
    road_ref = np.array(kt_all, dtype=complex)[None, :] + s[:, None] * ct[None, :]  # (F, 4) per elevation
    road_ref[:, corner] += kt_ref - kt_all[corner]
    dyn = _dynamic_stiffness(car, s, stiff, damp, mass, speed_mps)  # (F, n, n)
    n = dyn.shape[-1]
    idx = 3 + np.arange(4)
    dyn[:, idx, idx] += road_ref
    inv = np.linalg.inv(dyn)
    out_rows = np.zeros((2, n))
    out_rows[0, :3] = jac[corner]
    out_rows[1, 3 + corner] = 1.0
    rows = np.einsum("ij,fjk->fik", out_rows, inv)  # (F, 2, n): outputs per unit force on each DOF
    delta = tire_scale * kt - kt_ref  # (P,): the grid's change of the corner's tyre rate
    e = np.zeros(n)  # the corner's compression z_u − z_b (_body_matrices' sel row)
    e[:3], e[3 + corner] = -jac[corner], 1.0
    inv_e, e_inv = inv @ e, e @ inv  # (F, n) each
    out = np.empty((dampings.size, n_p, n_f, 2, 4), dtype=complex)
    for d, cd in enumerate(dampings):
        inv_d, rows_d = inv, rows
        if d > 0:  # D⁻¹ − g (D⁻¹e)(eᵀD⁻¹), g = s δc / (1 + s δc eᵀD⁻¹e)
            g = s * (cd - dampings[0])
            g = g / (1.0 + g * (e_inv @ e))
            inv_d = inv - g[:, None, None] * inv_e[:, :, None] * e_inv[:, None, :]
            rows_d = rows - g[:, None, None] * (inv_e @ out_rows.T)[:, :, None] * e_inv[:, None, :]
        _grid_responses(np.ascontiguousarray(inv_d), np.ascontiguousarray(rows_d),
                        np.ascontiguousarray(road_ref), s, delta, 3 + corner, out[d])  # fmt: skip
    return out if several else out[0]


@cached_njit
def _grid_responses(inv, rows, road_ref, s, delta, j, out):
    """out[p, f, o, w] = s_f · road_w · (C D⁻¹ e_{3+w})_o for the tyre rate of DOF `j` changed by
    delta[p] (:func:`wheel_responses`): with D0⁻¹ = `inv` (F, n, n) and C D0⁻¹ = `rows` (F, 2, n), by
    Sherman–Morrison C D⁻¹ e_w = rows[f, o, w] − δ rows[f, o, j] D0⁻¹[j, w] / (1 + δ D0⁻¹[j, j]),
    and the road's stiffness under wheel w `road_ref[f, w]` (+ δ under the corner's own wheel):
    displacement per unit road elevation, times s for acceleration per road velocity."""
    corner = j - 3
    n_f = s.size
    # the parts that do not depend on δ, with s and the other wheels' road stiffness taken in:
    # a[f, o, w] = s rows[f, o, 3 + w] road_w, b[f, o, w] = s rows[f, o, j] D0⁻¹[j, 3 + w] road_w
    a = np.empty((n_f, 2, 4), dtype=np.complex128)
    b = np.empty((n_f, 2, 4), dtype=np.complex128)
    for f in range(n_f):
        for o in range(2):
            for w in range(4):
                road = 1.0 if w == corner else road_ref[f, w]
                a[f, o, w] = rows[f, o, 3 + w] * s[f] * road
                b[f, o, w] = rows[f, o, j] * inv[f, j, 3 + w] * s[f] * road
    for p in range(delta.size):  # in the output's order
        d = delta[p]
        for f in range(n_f):
            g = d / (1.0 + d * inv[f, j, j])
            own = road_ref[f, corner] + d
            for o in range(2):
                for w in range(4):
                    x = a[f, o, w] - g * b[f, o, w]
                    out[p, f, o, w] = x * own if w == corner else x


def _with_tyres(car: FullCar, f: npt.ArrayLike, speed_mps: float | None):
    """The car at its own rates with every tyre on the ground: f (F,) Hz, s = i2πf, the body
    points' Jacobian, the dynamic stiffness (F, n, n) including the tyres, and the tyres' own
    k_t + s c_t (F, 4)."""
    f = np.atleast_1d(np.asarray(f, dtype=float))
    jac, stiff, damp, mass = _body_matrices(car, np.asarray(car.spring_rate, dtype=float),
                                            np.asarray(car.damping, dtype=float))  # fmt: skip
    s = 2j * np.pi * f  # (F,)
    tyre = np.asarray(car.tire_stiffness, dtype=float)[None, :] + s[:, None] * np.asarray(car.tire_damping)
    dyn = _dynamic_stiffness(car, s, stiff, damp, mass, speed_mps)  # (F, n, n)
    wheels = 3 + np.arange(4)
    dyn[:, wheels, wheels] += tyre
    return f, s, jac, dyn, tyre


def suspension_force_responses(
    f: npt.ArrayLike, car: FullCar, corner: int, *, speed_mps: float | None = None
) -> np.ndarray:
    """Corner `corner`'s (body, wheel) acceleration per unit force pair in its suspension: 1 N up
    on the body point above the corner and 1 N down on its wheel (a force the linear suspension
    does not hold, e.g. what a damper's statistical linearization leaves), all tyres in contact
    with the car's stiffness and damping. `f` (F,) Hz; `speed_mps`: with the tyres' lateral slip at
    that speed (None: without). Returns complex (F, 2), (m/s²)/N."""
    f, s, jac, dyn, _ = _with_tyres(car, f, speed_mps)
    force = np.zeros((f.size, dyn.shape[-1]), dtype=complex)
    force[:, :3] = jac[corner]  # generalized force of 1 N up at the body point
    force[:, 3 + corner] = -1.0
    x = np.linalg.solve(dyn, force[..., None])[..., 0]
    return (s**2)[:, None] * np.stack([x[:, :3] @ jac[corner], x[:, 3 + corner]], axis=1)


def projected_gains(
    h: np.ndarray, u1: np.ndarray, u2: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""The projected gain's speed-free parts over both tracks, independent and coherent, in one pass:
    A, B of :func:`projected_terms` and A', B' of :func:`projected_cross_terms`.

    With :math:`p_w = \bar u_1 h_{\cdot,0,w} + \bar u_2 h_{\cdot,1,w}` the response along the
    direction to wheel w's road, a track's front a = p_front and rear b = p_rear:
    :math:`A = \sum_t |a_t|^2 + |b_t|^2`, :math:`B = \sum_t a_t \bar b_t`,
    :math:`A' = 2\,\mathrm{Re}(a_L\bar a_R + b_L\bar b_R)`, :math:`B' = a_L\bar b_R + a_R\bar b_L`.
    `h` (..., F, 2, 4) from :func:`wheel_responses`; (u1, u2) (F,). Returns A, A' (..., F) real and
    B, B' (..., F) complex."""
    h = np.asarray(h, dtype=complex)
    lead = h.shape[:-3]
    flat = np.ascontiguousarray(h.reshape((-1,) + h.shape[-3:]))
    m, n_f = flat.shape[0], flat.shape[1]
    a_sq, a1 = np.empty((m, n_f)), np.empty((m, n_f))
    cross, b1 = np.empty((m, n_f), dtype=complex), np.empty((m, n_f), dtype=complex)
    u1 = np.ascontiguousarray(np.broadcast_to(u1, n_f), dtype=complex)
    u2 = np.ascontiguousarray(np.broadcast_to(u2, n_f), dtype=complex)
    _projections(flat, u1, u2, a_sq, cross, a1, b1)
    shape = lead + (n_f,)
    return a_sq.reshape(shape), cross.reshape(shape), a1.reshape(shape), b1.reshape(shape)


@cached_njit
def _projections(h, u1, u2, a_sq, cross, a1, b1):
    """:func:`projected_gains` on h (M, F, 2, 4): out arrays (M, F)."""
    (front_l, rear_l), (front_r, rear_r) = TRACKS
    p = np.empty(4, dtype=np.complex128)
    for m in range(h.shape[0]):
        for f in range(h.shape[1]):
            c1, c2 = np.conj(u1[f]), np.conj(u2[f])
            for w in range(4):
                p[w] = c1 * h[m, f, 0, w] + c2 * h[m, f, 1, w]
            al, bl, ar, br = p[front_l], p[rear_l], p[front_r], p[rear_r]
            a_sq[m, f] = (al.real**2 + al.imag**2 + bl.real**2 + bl.imag**2) + (
                ar.real**2 + ar.imag**2 + br.real**2 + br.imag**2)
            cross[m, f] = al * np.conj(bl) + ar * np.conj(br)
            a1[m, f] = 2.0 * (al * np.conj(ar) + bl * np.conj(br)).real
            b1[m, f] = al * np.conj(br) + ar * np.conj(bl)


def projected_terms(h: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Speed-free parts of the projected gain over both tracks: A = Σ (|a|² + |b|²) and B = Σ a b̄.

    `h` (..., F, 2, 4) from :func:`wheel_responses`; (u1, u2) (F,) the unit direction projected on.
    Returns A (..., F) real and B (..., F) complex (:func:`projected_gains`)."""
    a_sq, cross, _, _ = projected_gains(h, u1, u2)
    return a_sq, cross


def projected_cross_terms(h: np.ndarray, u1: np.ndarray, u2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Speed-free parts of the tracks' cross term of the projected gain, per unit coherence γ:
    :math:`A' = 2\,\mathrm{Re}(a_L\bar a_R + b_L\bar b_R)` and :math:`B' = a_L\bar b_R + a_R\bar b_L`
    (module docstring), so the gain at coherence γ and delay τ is
    :math:`A + \gamma A' + 2\,\mathrm{Re}\big((B + \gamma B')\,e^{i2\pi f\tau}\big)`.

    Shapes as :func:`projected_terms`'s: A' (..., F) real and B' (..., F) complex
    (:func:`projected_gains`)."""
    _, _, a1, b1 = projected_gains(h, u1, u2)
    return a1, b1


def axle_coherence_parts(
    f: npt.ArrayLike, car: FullCar, *, speed_mps: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    r"""Speed-free parts of :func:`axle_coherence_terms`: X (4, F) real and Y (4, F) complex with
    terms = X + Re(Y e^{i2πfτ}) at front→rear delay τ.

    With h the wheels' responses to each wheel's road (:func:`track_responses` before the tracks are
    formed), a track's :math:`g = h_F + h_R e^{-i\varphi}` and
    :math:`\mathrm{Re}(g_i\bar g_j) = \mathrm{Re}(h_{F,i}\bar h_{F,j} + h_{R,i}\bar h_{R,j})
    + \mathrm{Re}\big((h_{F,i}\bar h_{R,j} + \bar h_{R,i} h_{F,j})\,e^{i\varphi}\big)`, φ = 2πfτ."""
    _, h = _eight_channels(f, car, speed_mps)
    h = h[:, 1::2, :]  # (F, 4 wheels, 4 road inputs)
    x = np.zeros((4, h.shape[0]))
    y = np.zeros((4, h.shape[0]), dtype=complex)

    def add(row: int, i: int, t: tuple[int, int], j: int, u: tuple[int, int], scale: float = 1.0) -> None:
        fi, ri, fj, rj = h[:, i, t[0]], h[:, i, t[1]], h[:, j, u[0]], h[:, j, u[1]]
        x[row] += scale * np.real(fi * np.conj(fj) + ri * np.conj(rj))
        y[row] += scale * (fi * np.conj(rj) + np.conj(ri) * fj)

    left, right = TRACKS
    for axle in ((0, 1), (2, 3)):
        for w in axle:
            for t in TRACKS:
                add(0, w, t, w, t)  # T0: Σ_t |g_w,t|²
            add(1, w, left, w, right, 2.0)  # T1: 2 Re(g_w,L ḡ_w,R)
        for t in TRACKS:
            add(2, axle[0], t, axle[1], t)  # C0: Σ_t Re(g_l,t ḡ_r,t)
        add(3, axle[0], left, axle[1], right)  # C1: Re(g_l,L ḡ_r,R + g_l,R ḡ_r,L)
        add(3, axle[0], right, axle[1], left)
    return x, y


def axle_coherence_terms(
    f: npt.ArrayLike, car: FullCar, delay_s: float, *, speed_mps: float | None = None
) -> np.ndarray:
    r"""What the two axles' wheel accelerations hold of the tracks' coherence γ, per unit road-velocity PSD.

    Over both axles (wheels fl, fr and rl, rr), the expected sum of the four wheels' acceleration
    spectra and of the two axles' left–right cross spectra (real part) are

    .. math:: \sum_{\text{axles}}(S_{LL} + S_{RR}) = S_v\,(T_0 + \gamma T_1),\qquad
       \sum_{\text{axles}}\mathrm{Re}\,S_{LR} = S_v\,(C_0 + \gamma C_1),

    every tyre at the car's own: with G the wheels' rows of :func:`track_responses`,
    :math:`S_{ij} = S_v\,(\sum_t G_{it}\bar G_{jt} + \gamma(G_{iL}\bar G_{jR} + G_{iR}\bar G_{jL}))`.
    T_0, C_0 are the independent tracks' part (C_0 ≠ 0: the body and the anti-roll bars couple the
    wheels), T_1, C_1 the coherent part; eliminating S_v, a window's measured sums T̂, Ĉ give
    :math:`\gamma\,(\hat C T_1 - \hat T C_1) = \hat T C_0 - \hat C T_0` (a linear estimating
    equation, which :class:`suvtwin.estimators.monitor.TyreMonitor` sums over windows).

    `f` (F,) Hz; `delay_s` the front→rear delay (s); `speed_mps`: with the tyres' lateral slip.
    Returns (4, F) real: T_0, T_1, C_0, C_1 in ((m/s²)/(m/s))², from :func:`axle_coherence_parts`."""
    f = np.atleast_1d(np.asarray(f, dtype=float))
    x, y = axle_coherence_parts(f, car, speed_mps=speed_mps)
    return x + np.real(y * np.exp(2j * np.pi * f * float(delay_s)))


def gain_at_delay(
    a_sq: np.ndarray, cross: np.ndarray, f: np.ndarray, delay_s: float, *,
    band_start: np.ndarray | None = None, rows: np.ndarray | None = None,
) -> np.ndarray:
    r"""Projected gain :math:`\sum|u^H g|^2 = A + 2\,\mathrm{Re}(B e^{i2\pi f\tau})` at front→rear
    delay τ = wheelbase / speed (s); shapes as :func:`projected_terms`'s (…, F).

    `band_start` (K,): averaged over bands of adjacent frequencies instead, band k from index
    ``band_start[k]`` to the next's (increasing, from 0; as :func:`numpy.add.reduceat`): (…, K).
    `rows`: only these rows of the leading axes flattened (…, F) → (N, F): (N, K) — a gain table's
    rows picked without copying the table. Compiled: one pass, no temporary complex arrays."""
    a_sq = np.asarray(a_sq, dtype=float)
    cross = np.asarray(cross, dtype=complex)
    f = np.asarray(f, dtype=float)
    lead = np.broadcast_shapes(a_sq.shape[:-1], cross.shape[:-1])
    n_f = f.size
    a2 = np.ascontiguousarray(np.broadcast_to(a_sq, lead + (n_f,))).reshape(-1, n_f)
    b2 = np.ascontiguousarray(np.broadcast_to(cross, lead + (n_f,))).reshape(-1, n_f)
    start = np.arange(n_f) if band_start is None else np.asarray(band_start, dtype=np.int64)
    if start.size == 0 or start[0] != 0 or np.any(np.diff(start) <= 0) or start[-1] >= n_f:
        raise InputError(f"band_start must increase from 0 within the {n_f} frequencies, got {band_start!r}")
    pick = np.arange(a2.shape[0]) if rows is None else np.asarray(rows, dtype=np.int64)
    phase = np.exp(2j * np.pi * f * float(delay_s))
    out = np.empty((pick.size, start.size))
    _band_gain(a2, b2, *_NO_CROSS, phase.real.copy(), phase.imag.copy(), start.astype(np.int64), pick, out)
    return out.reshape(lead + (start.size,)) if rows is None else out


def blend_gain_at_delay(
    a_sq: np.ndarray, cross: np.ndarray, f: np.ndarray, delay_s: float, band_start: np.ndarray,
    targets: np.ndarray, tables: np.ndarray, weights: np.ndarray, out: np.ndarray,
    coherent: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> None:
    r"""Band-averaged gains at delay τ (:func:`gain_at_delay`) of stacked tables, blended and added in
    place: for each i, ``out[targets[i]] += weights[i, k] * gain(table tables[i, k])`` for the k with a
    positive weight, in order of k.

    `a_sq` (S, …, F) float and `cross` (S, …, F) complex: S tables of :func:`projected_terms`'s terms,
    C-contiguous; `band_start` (K,) int64 as :func:`gain_at_delay`'s (trusted: no checks); `targets`
    (N,), `tables` and `weights` (N, L); `out` (T, …, K) float, C-contiguous. The same sums as
    :func:`gain_at_delay` followed by the blend, bit for bit, without the picked rows' index array and
    a Python loop over the (target, table) pairs (the online monitor calls this every update).

    `coherent`: (A', B', γ) with A', B' shaped as `a_sq`, `cross` (:func:`projected_cross_terms`'s
    terms of the same tables) and γ (K,) the tracks' coherence per band: the gain of each band is
    then its mean of :math:`A + 2\mathrm{Re}(B e^{i\varphi})` plus γ times its mean of
    :math:`A' + 2\mathrm{Re}(B' e^{i\varphi})`, both in the same pass."""
    rows_per = int(np.prod(a_sq.shape[1:-1], dtype=np.int64))
    phase = np.exp(2j * np.pi * f * float(delay_s))
    a1, b1, gamma_f = _NO_CROSS
    if coherent is not None:  # γ per band spread over its frequencies
        a1, b1 = coherent[0].reshape(-1, f.size), coherent[1].reshape(-1, f.size)
        gamma_f = np.repeat(np.asarray(coherent[2], dtype=float), np.diff(np.r_[band_start, f.size]))
    _band_gain_blend(a_sq.reshape(-1, f.size), cross.reshape(-1, f.size), a1, b1, gamma_f, phase.real.copy(),
                     phase.imag.copy(), band_start, rows_per, np.asarray(targets, dtype=np.int64),
                     np.ascontiguousarray(tables, dtype=np.int64), np.ascontiguousarray(weights, dtype=float),
                     out.reshape(out.shape[0] * rows_per, -1))  # fmt: skip


_NO_CROSS = (np.empty((0, 0)), np.empty((0, 0), dtype=complex), np.empty(0))
"""No tracks' cross term for the compiled band gains (:func:`_row_band_means`)."""


@cached_njit
def _row_band_means(a_sq, cross, a1, b1, gamma_f, cos_f, sin_f, band_start, r, row, means):
    """means[k] = mean over band k's frequencies j of a_sq[r, j] + 2 Re(cross[r, j] e^{iφ_j}),
    e^{iφ} = cos_f + i sin_f, plus gamma_f[j] (a1[r, j] + 2 Re(b1[r, j] e^{iφ_j})) where `gamma_f` (F,)
    is not empty (the tracks' cross term, γ per frequency); `row` (F,) is scratch. The row's gain is
    taken over all frequencies in one straight loop (which the compiler vectorizes), the cross term
    added where γ ≠ 0 (elsewhere it adds 0: independent tracks' coherence is 0 in most bands, and
    their tables are not read), then averaged per band: 1.3 times faster than summing band by band,
    the same sums."""
    n_k, n_f = band_start.size, a_sq.shape[1]
    for j in range(n_f):
        b = cross[r, j]
        row[j] = a_sq[r, j] + 2.0 * (b.real * cos_f[j] - b.imag * sin_f[j])
    for j in range(gamma_f.size):
        if gamma_f[j] != 0.0:
            e = b1[r, j]
            row[j] += gamma_f[j] * (a1[r, j] + 2.0 * (e.real * cos_f[j] - e.imag * sin_f[j]))
    for k in range(n_k):
        j1 = band_start[k + 1] if k + 1 < n_k else n_f
        acc = 0.0
        for j in range(band_start[k], j1):
            acc += row[j]
        means[k] = acc / (j1 - band_start[k])


@cached_njit
def _band_gain_blend(a_sq, cross, a1, b1, gamma_f, cos_f, sin_f, band_start, rows_per, targets, tables,
                     weights, out):  # fmt: skip
    """out[targets[i] · rows_per + r, k] += weights[i, l] · (band k's mean of row
    tables[i, l] · rows_per + r of :func:`_row_band_means`'s gain, with the tracks' cross term where
    `gamma_f` is not empty), for each l with a positive weight, in order (:func:`blend_gain_at_delay`)."""
    row = np.empty(a_sq.shape[1])
    means = np.empty(band_start.size)
    for i in range(targets.size):
        for m in range(tables.shape[1]):
            w = weights[i, m]
            if not w > 0.0:
                continue
            for q in range(rows_per):
                r = tables[i, m] * rows_per + q
                _row_band_means(a_sq, cross, a1, b1, gamma_f, cos_f, sin_f, band_start, r, row, means)
                o = targets[i] * rows_per + q
                for k in range(band_start.size):
                    out[o, k] += w * means[k]


@cached_njit
def _band_gain(a_sq, cross, a1, b1, gamma_f, cos_f, sin_f, band_start, rows, out):
    """out[i, k] = mean over band k's frequencies j of a_sq[rows[i], j] + 2 Re(cross[rows[i], j] e^{iφ_j}),
    e^{iφ} = cos_f + i sin_f (:func:`gain_at_delay`; :func:`_row_band_means`, here with `_NO_CROSS`)."""
    row = np.empty(a_sq.shape[1])
    for i in range(rows.size):
        _row_band_means(a_sq, cross, a1, b1, gamma_f, cos_f, sin_f, band_start, rows[i], row, out[i])


def corner_spectrum(
    f: npt.ArrayLike, speed_mps: float, car: FullCar, corner: int, kt: float | None = None,
    *, lateral: bool = False, coherence: float = 0.0,
) -> np.ndarray:
    """Corner `corner`'s 2×2 spectrum of (body, wheel) acceleration per unit road-velocity PSD of each
    track, (F, 2, 2) complex, at `speed_mps`; `kt` its tyre's stiffness (default the car's);
    `lateral`: with the tyres' lateral slip (the car needs ``cornering_stiffness``); `coherence`:
    the tracks' real coherence γ in [−1, 1] (the tracks' covariance [[1, γ], [γ, 1]])."""
    if not speed_mps > 0:
        raise InputError(f"speed must be > 0 m/s, got {speed_mps!r}")
    f = np.atleast_1d(np.asarray(f, dtype=float))
    kt = car.tire_stiffness[corner] if kt is None else kt
    h = wheel_responses(f, car, corner, np.array([kt]), speed_mps=speed_mps if lateral else None)[0]
    if not -1.0 <= coherence <= 1.0:
        raise InputError(f"coherence must be in [-1, 1], got {coherence!r}")
    lag = np.exp(-2j * np.pi * f * car.wheelbase / speed_mps)[:, None]
    g = np.stack([h[:, :, front] + h[:, :, rear] * lag for front, rear in TRACKS], axis=-1)  # (F, 2, track)
    cov = np.array([[1.0, coherence], [coherence, 1.0]])
    return np.einsum("fit,tu,fju->fij", g, cov, np.conj(g))


def track_responses(
    f: npt.ArrayLike, car: FullCar, delay_s: float, *, speed_mps: float | None = None
) -> np.ndarray:
    r"""All eight accelerations per unit road velocity of each track, every tyre at the car's own.

    `f` (F,) Hz; `delay_s` the front→rear delay τ = wheelbase / speed (s). Returns complex
    (F, 8, 2), (m/s²)/(m/s): output 2·corner + (0 body above the corner, 1 its wheel), corners fl,
    fr, rl, rr; column the track (0 left, 1 right, :data:`TRACKS`). One 7 × 7 solve per frequency
    of :math:`(K + sC + s^2M)\,X = (K_t + sC_t)\,R`, s = i2πf (module docstring), then
    acceleration per road velocity :math:`s^2X/(sR) = sX/R` and, per track,

    .. math:: g = h_{\text{front}} + h_{\text{rear}}\,e^{-i2\pi f\tau},

    so the eight channels' spectrum is :math:`S_v\,G G^H` (G the returned (8, 2) per frequency):
    each corner's 2×2 block is :func:`corner_spectrum`'s. `speed_mps`: with the tyres' lateral
    slip at that speed (None: without)."""
    f, h = _eight_channels(f, car, speed_mps)
    lag = np.exp(-2j * np.pi * f * delay_s)[:, None]
    return np.stack([h[:, :, front] + h[:, :, rear] * lag for front, rear in TRACKS], axis=-1)


def _eight_channels(f: npt.ArrayLike, car: FullCar, speed_mps: float | None) -> tuple[np.ndarray, np.ndarray]:
    """f (F,) Hz and all eight accelerations per unit road velocity under each wheel, every tyre at the
    car's own: (F, 8, 4) complex, output 2·corner + (0 body, 1 wheel), input wheel fl, fr, rl, rr."""
    f, s, jac, dyn, tyre = _with_tyres(car, f, speed_mps)
    wheels = 3 + np.arange(4)
    force = np.zeros((f.size, dyn.shape[-1], 4), dtype=complex)  # generalised force per unit road elevation
    force[:, wheels, np.arange(4)] = tyre
    x = np.linalg.solve(dyn, force)[:, :7]  # (F, 7, 4): displacement per road elevation under each wheel
    out = np.zeros((8, 7))
    out[0::2, :3] = jac  # body point above each corner
    out[1::2, 3:] = np.eye(4)  # its wheel
    return f, s[:, None, None] * np.einsum("oj,fjw->fow", out, x)  # (F, 8, 4) per road velocity
