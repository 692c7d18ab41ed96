r"""Deflated-tyre detection from lateral dynamics: a bank of 16 two-track models (Solmaz).

Usual call::

    sim = simulate_two_track(steer, speed, bank_tires(8), PAPER_VEHICLE, dt=0.01)  # model 8: front left
    det = detect_deflation(steer, speed, sim.lateral_acceleration, sim.yaw_rate, PAPER_VEHICLE,
                           dt=0.01, instant_weight=0.0, integral_weight=1.0, forgetting_rate=0.0)
    det.selected          # (runs, steps): the chosen model's number, 1..16

The method of Solmaz [1]_: a two-track lateral model with no roll and constant speed
(states sideslip :math:`\beta` and yaw rate :math:`\dot\psi`, eq. 1), the inner and outer
front wheels steered apart (eq. 2), the arctan tyre
:math:`S = (k_1 - F_Z/k_2)F_Z\arctan(k_3\alpha)` (eq. 3, 6), wheel loads from the measured
lateral acceleration (eq. 7), the four slip angles (eq. 8–9), the vehicle sideslip by
integration of the measurements (eq. 10). Sixteen copies of the model, one per combination
of nominal and deflated tyres (eq. 5), are driven by the *measured* slip angles and loads
(Steps 3–6 of the paper); each gives a lateral acceleration (eq. 11) and a yaw rate, whose
errors against the measurements (eq. 12) build a cost (eq. 13); the model of least cost is
selected (eq. 14) and its tyres' secant cornering stiffnesses are reported (eq. 15).

Conventions (one for the module): SI units (rad, m, s, N, kg); ISO 8855 axes, x forward,
y left, z up, so a positive steer turns left and gives positive yaw rate and lateral
acceleration. Arrays are ``(runs, steps)`` per signal, ``(..., 4)`` per wheel in the order
:data:`WHEELS` = front left, front right, rear left, rear right (the paper's vl, vr, hl,
hr: *vorne/hinten, links/rechts*), ``(runs, steps, 16)`` per model, the model axis in the
order of the model numbers 1..16 (index = number − 1). Sample ``k`` is at time
:math:`k\,\Delta t`; every run starts from rest, :math:`\beta = \dot\psi = 0` (the paper's
zero initial conditions).

Model numbering (:func:`model_number`, :func:`deflated_wheels`)
---------------------------------------------------------------
The paper's Figure 4 lists the 16 failure modes; our copy has no legible figure, only the
sentence "8th model indicates the front-left tire failure". The numbering used here is the
binary code that gives exactly that: number :math:`= 8 d_{FL} + 4 d_{FR} + 2 d_{RL} + d_{RR}`
with :math:`d = 1` for a deflated tyre, and the code 0 (no deflation, the nominal model)
numbered 16. So 8 = front left, 4 = front right, 2 = rear left, 1 = rear right, 12 = both
front, 3 = both rear, 15 = all four, 16 = none. It is an inference, not a quotation.

Errors and gaps of the paper handled here (and why)
---------------------------------------------------
- Eq. 2, :math:`\delta_{inner/outer} = \delta \pm \delta^2 T/(2L)`, is right for a left turn
  only: for :math:`\delta < 0` the square keeps its sign, so the *inner* (right) wheel would
  steer *less* than the outer one, against the Ackermann geometry the equation comes from
  (:math:`\cot\delta_o - \cot\delta_i = T/L`, whose first order is
  :math:`|\delta_i| = |\delta| + \delta^2T/(2L)`). Used: inner
  :math:`\delta + \delta|\delta|T/(2L)`, outer :math:`\delta - \delta|\delta|T/(2L)`, i.e.
  the left wheel at :math:`\delta + \delta^2T/(2L)` and the right wheel at
  :math:`\delta - \delta^2T/(2L)` in either direction (inner/outer assigned to the wheels as
  in eq. 8–9). The paper
  calls :math:`\delta` the *steering column* angle but uses it as the road-wheel angle (no
  steering ratio is given); so do we.
- Eq. 9 (turning right) writes the left wheels' longitudinal speed as
  :math:`v_x + 0.5\dot\psi T` and the right wheels' as :math:`v_x - 0.5\dot\psi T`: with a
  signed yaw rate (negative in a right turn) that is the wrong wheel. A point at
  :math:`y = +T/2` moves forward at :math:`v_x - \dot\psi T/2` whatever the direction of the
  turn, which is eq. 8. Used: eq. 8 for both directions (eq. 9 would only hold with
  :math:`|\dot\psi|` in the denominators and a signed one in the numerators). The effect is
  small (:math:`\dot\psi T/v_x` ≈ 0.2 % of the slip in the paper's lane change) but it breaks the mirror
  symmetry of the model, which a test checks.
- Eq. 5 writes :math:`-\dot\psi` (the *measured* yaw rate), not :math:`-\dot\psi_i`, in model
  i's sideslip equation, and Step 5 computes the slip angles from the measured yaw rate
  and the integrated sideslip of eq. 10: the 16 models are driven by the measured state
  and only integrate their own yaw acceleration (a series-parallel identification model).
  That is what is implemented; a parallel bank (each model's slips from its own states)
  is not.
- Eq. 3's load factor :math:`(k_1 - F_Z/k_2)F_Z` peaks at :math:`F_Z = k_1k_2/2` and changes
  sign at :math:`F_Z = k_1k_2`. With the paper's vehicle the static loads (3061 N rear,
  3316 N front) lie *above* the peak of both tyres (2825 N nominal, 2250 N deflated): on
  these tyres more load gives less side force, unlike real tyres, and the deflated front
  tyre's force reverses sign at :math:`F_Z` = 4500 N, i.e. at a lateral acceleration of
  3.75 m/s². :func:`wheel_loads` raises :class:`~suvtwin.errors.InputError` for a lifted
  wheel and the tyre functions warn when a load reaches :math:`k_1k_2`.
- Eq. 7 splits the lateral load transfer between the axles in proportion to their static
  loads (no roll stiffness distribution): the total, :math:`m h a_y/T`, is the moment
  balance; the split is the paper's choice, kept.
- Eq. 12–13 take the Euclidean norm of an error whose components are in m/s² and rad/s, and
  the paper gives no values for :math:`\alpha, \gamma, \lambda`. :func:`detect_deflation`
  takes the three as required arguments and optional weights per component
  (``error_scale``; 1 and 1 reproduce the unweighted norm).
- Eq. 14 does not say how ties are broken. Before the steering starts every model predicts
  zero and all costs are equal; the tie goes to the model with the fewest deflated tyres
  (the nominal model 16 first).
- Eq. 15's secant stiffness :math:`S/\alpha` is 0/0 at zero slip; its limit
  :math:`(k_1 - F_Z/k_2)F_Zk_3` is used there.

The truth of the paper's simulation (Section IV) is the same two-track model with the true
tyre set (:func:`simulate_two_track`): a self-consistent test, in which the right model
fits the data exactly up to integration error. A test on a different vehicle (the MuJoCo
SUV, whose tyres are not arctan tyres) is a separate step.

References
----------
.. [1] S. Solmaz, "A Novel Method for Indirect Estimation of Tire Pressure", Gediz
   University (funded by Enterprise Ireland grant PC/2008/389; our copy does not print the
   venue or year, c. 2011–2012).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.signal import lfilter

from suvtwin.errors import InputError, positive

__all__ = [
    "DEFLATED_TIRE",
    "GRAVITY",
    "N_MODELS",
    "NOMINAL_MODEL",
    "NOMINAL_TIRE",
    "PAPER_VEHICLE",
    "WHEELS",
    "ArctanTire",
    "DetectionResult",
    "TwoTrackResponse",
    "TwoTrackVehicle",
    "bank_tires",
    "cornering_stiffness",
    "deflated_wheels",
    "detect_deflation",
    "lateral_tire_force",
    "model_number",
    "sideslip_from_measurements",
    "simulate_two_track",
    "slip_angles",
    "steering_angles",
    "wheel_loads",
]

GRAVITY = 9.81  # m/s²
WHEELS = ("front_left", "front_right", "rear_left", "rear_right")
N_MODELS = 16
NOMINAL_MODEL = 16
_BIT_WEIGHTS = np.array([8, 4, 2, 1])  # FL, FR, RL, RR: model 8 = front left (paper, Sec. IV)


@dataclass(frozen=True)
class TwoTrackVehicle:
    """The two-track model's vehicle (Solmaz, eq. 1, 7, 8).

    Parameters
    ----------
    mass : float
        m, kg.
    yaw_inertia : float
        J_zz, kg m².
    front_length, rear_length : float
        l_v and l_h, m: centre of gravity to front and rear axle.
    cog_height : float
        h, m: height of the centre of gravity (load transfer, eq. 7).
    track : float
        T, m: track width, the same front and rear.
    """

    mass: float
    yaw_inertia: float
    front_length: float
    rear_length: float
    cog_height: float
    track: float

    def __post_init__(self) -> None:
        units = {"mass": "kg", "yaw_inertia": "kg m²", "front_length": "m", "rear_length": "m",
                 "cog_height": "m", "track": "m"}
        for name, unit in units.items():
            positive(f"vehicle {name}", getattr(self, name), unit)

    @property
    def wheelbase(self) -> float:
        """L = l_v + l_h, m."""
        return self.front_length + self.rear_length


@dataclass(frozen=True)
class ArctanTire:
    """Parameters of the arctan tyre :math:`S = (k_1 - F_Z/k_2)F_Z\\arctan(k_3\\alpha)` (eq. 3).

    Parameters
    ----------
    k1 : float
        Dimensionless (> 0).
    k2 : float
        N (> 0): the load factor peaks at ``k1*k2/2`` and vanishes at ``k1*k2``.
    k3 : float
        1/rad (> 0): slip scale; the cornering stiffness at load F_Z is
        ``(k1 - F_Z/k2) * F_Z * k3`` in N/rad.
    """

    k1: float
    k2: float
    k3: float

    def __post_init__(self) -> None:
        for name, unit in {"k1": "(dimensionless)", "k2": "N", "k3": "1/rad"}.items():
            positive(f"tire {name}", getattr(self, name), unit)

    def as_array(self) -> np.ndarray:
        """``[k1, k2, k3]``, shape (3,)."""
        return np.array([self.k1, self.k2, self.k3], dtype=float)


PAPER_VEHICLE = TwoTrackVehicle(
    mass=1300.0, yaw_inertia=1200.0, front_length=1.2, rear_length=1.3, cog_height=0.7, track=1.5
)  # Sec. IV
NOMINAL_TIRE = ArctanTire(k1=1.0, k2=5650.0, k3=15.0)  # Sec. IV, proper inflation
DEFLATED_TIRE = ArctanTire(k1=1.0, k2=4500.0, k3=12.0)  # Sec. IV, pressure compromised


# --- model numbering -----------------------------------------------------------------------


def model_number(deflated: npt.ArrayLike) -> int:
    """The paper's model number (1..16) of a set of deflated wheels.

    Parameters
    ----------
    deflated : array_like of bool, shape (4,)
        Deflated or not, in the order :data:`WHEELS` (FL, FR, RL, RR).

    Returns
    -------
    int
        ``8*FL + 4*FR + 2*RL + RR``, with 0 (no deflation) numbered 16 (module docstring).
    """
    flags = np.asarray(deflated)
    if flags.shape != (4,) or not np.all((flags == 0) | (flags == 1)):
        raise InputError(f"deflated must be 4 booleans (FL, FR, RL, RR), got {deflated!r}")
    code = int(_BIT_WEIGHTS @ flags.astype(int))
    return NOMINAL_MODEL if code == 0 else code


def deflated_wheels(number: int) -> tuple[bool, bool, bool, bool]:
    """Which wheels model ``number`` (1..16) has deflated, in the order :data:`WHEELS`."""
    if isinstance(number, bool) or not isinstance(number, int | np.integer) or not 1 <= number <= 16:
        raise InputError(f"model number must be an integer in 1..16, got {number!r}")
    code = int(number) % 16
    return tuple(bool(code & int(w)) for w in _BIT_WEIGHTS)  # type: ignore[return-value]


def bank_tires(
    number: int | None = None,
    *,
    nominal: ArctanTire | tuple[ArctanTire, ArctanTire] = NOMINAL_TIRE,
    deflated: ArctanTire | tuple[ArctanTire, ArctanTire] = DEFLATED_TIRE,
) -> np.ndarray:
    """Tyre parameters of the 16-model bank (eq. 5–6), or of one model of it.

    `nominal` and `deflated` are one tyre for all four wheels (the paper's bank) or a pair
    ``(front, rear)``: per-axle effective characteristics (e.g. fitted with the axles'
    compliance steer folded in, as :func:`suvtwin.pipeline.lateral_detection.fit_bank` does).

    Returns
    -------
    numpy.ndarray
        ``(16, 4, 3)``: model (number − 1), wheel (:data:`WHEELS`), ``[k1, k2, k3]``; with
        ``number`` given, that model's ``(4, 3)``.
    """
    nom = nominal if isinstance(nominal, tuple) else (nominal, nominal)
    defl = deflated if isinstance(deflated, tuple) else (deflated, deflated)
    if len(nom) != 2 or len(defl) != 2:
        raise InputError("nominal and deflated must be one ArctanTire or a (front, rear) pair")
    table = np.empty((N_MODELS, 4, 3))
    for n in range(1, N_MODELS + 1):
        flags = deflated_wheels(n)
        table[n - 1] = [(defl[w // 2] if f else nom[w // 2]).as_array() for w, f in enumerate(flags)]
    return table if number is None else table[number - 1]


def _tie_order() -> np.ndarray:
    """Model indices (number − 1) by number of deflated tyres, then number: the tie-break order."""
    counts = [sum(deflated_wheels(n)) for n in range(1, N_MODELS + 1)]
    return np.array(sorted(range(N_MODELS), key=lambda i: (counts[i], i)))


_TIE_ORDER = _tie_order()


# --- the two-track model -------------------------------------------------------------------


def steering_angles(steer: npt.ArrayLike, vehicle: TwoTrackVehicle) -> np.ndarray:
    r"""Front left and right road-wheel angles, rad, shape ``(..., 2)`` (eq. 2, sign-corrected).

    :math:`\delta_l = \delta + \delta^2T/(2L)`, :math:`\delta_r = \delta - \delta^2T/(2L)`: the
    inner wheel (left in a left turn, :math:`\delta > 0`; right in a right turn) steers more.
    ``steer`` in rad, any shape.
    """
    d = np.asarray(steer, dtype=float)
    split = d * d * vehicle.track / (2.0 * vehicle.wheelbase)  # eq. 2: inner δ + δ|δ|T/2L, outer δ − δ|δ|T/2L
    return np.stack([d + split, d - split], axis=-1)


def wheel_loads(lateral_acceleration: npt.ArrayLike, vehicle: TwoTrackVehicle) -> np.ndarray:
    r"""Vertical wheel loads :math:`F_Z`, N, shape ``(..., 4)`` in :data:`WHEELS` order (eq. 7).

    :math:`F_{Z,v l/r} = m l_h g/(2L) \mp m l_h h a_y/(LT)`,
    :math:`F_{Z,h l/r} = m l_v g/(2L) \mp m l_v h a_y/(LT)`; ``lateral_acceleration`` in m/s²
    (positive to the left, unloading the left wheels).

    Raises
    ------
    InputError
        If a wheel would lift, :math:`|a_y| \ge gT/(2h)`.
    """
    ay = np.asarray(lateral_acceleration, dtype=float)
    v = vehicle
    limit = GRAVITY * v.track / (2.0 * v.cog_height)
    if np.any(np.abs(ay) >= limit):
        raise InputError(
            f"lateral_acceleration must lie in (-{limit:.3g}, {limit:.3g}) m/s² (g*T/(2h): no wheel lifts), "
            f"got {np.max(np.abs(ay)):.4g}"
        )
    front_static = v.mass * v.rear_length * GRAVITY / (2.0 * v.wheelbase)
    rear_static = v.mass * v.front_length * GRAVITY / (2.0 * v.wheelbase)
    front_transfer = v.mass * v.rear_length * v.cog_height / (v.wheelbase * v.track) * ay
    rear_transfer = v.mass * v.front_length * v.cog_height / (v.wheelbase * v.track) * ay
    return np.stack(
        [
            front_static - front_transfer,  # eq. 7, F_Zvl
            front_static + front_transfer,  # F_Zvr
            rear_static - rear_transfer,  # F_Zhl
            rear_static + rear_transfer,  # F_Zhr
        ],
        axis=-1,
    )


def slip_angles(
    steer: npt.ArrayLike,
    sideslip: npt.ArrayLike,
    yaw_rate: npt.ArrayLike,
    speed: npt.ArrayLike,
    vehicle: TwoTrackVehicle,
) -> np.ndarray:
    r"""Tyre slip angles :math:`\alpha`, rad, shape ``(..., 4)`` in :data:`WHEELS` order (eq. 8).

    :math:`\alpha_{v l} = \delta_l - \arctan\frac{v_x\beta + \dot\psi l_v}{v_x - \dot\psi T/2}`,
    :math:`\alpha_{v r} = \delta_r - \arctan\frac{v_x\beta + \dot\psi l_v}{v_x + \dot\psi T/2}`,
    :math:`\alpha_{h l/r} = -\arctan\frac{v_x\beta - \dot\psi l_h}{v_x \mp \dot\psi T/2}`,
    for either turning direction (eq. 9 is not used: module docstring). ``steer`` (δ, rad),
    ``sideslip`` (β, rad), ``yaw_rate`` (rad/s) and ``speed`` (:math:`v_x`, m/s) broadcast.
    """
    b, r, vx = (np.asarray(a, dtype=float) for a in (sideslip, yaw_rate, speed))
    v = vehicle
    front = steering_angles(steer, vehicle)
    lat_front = vx * b + r * v.front_length
    lat_rear = vx * b - r * v.rear_length
    lon_left = vx - 0.5 * r * v.track
    lon_right = vx + 0.5 * r * v.track
    return np.stack(
        [
            front[..., 0] - np.arctan(lat_front / lon_left),  # eq. 8, α_vl
            front[..., 1] - np.arctan(lat_front / lon_right),  # α_vr
            -np.arctan(lat_rear / lon_left),  # α_hl
            -np.arctan(lat_rear / lon_right),  # α_hr
        ],
        axis=-1,
    )


def _load_factor(load: np.ndarray, tires: np.ndarray) -> np.ndarray:
    k1, k2 = tires[..., 0], tires[..., 1]
    if np.any(load >= k1 * k2):
        warnings.warn(
            "a wheel load reached k1*k2, where the arctan tyre's side force changes sign (eq. 3): "
            f"max load/(k1*k2) = {np.max(load / (k1 * k2)):.3g}",
            RuntimeWarning,
            stacklevel=3,
        )
    return (k1 - load / k2) * load


def lateral_tire_force(slip: npt.ArrayLike, load: npt.ArrayLike, tires: npt.ArrayLike) -> np.ndarray:
    r"""Side force of the arctan tyre, N (eq. 3, 6): :math:`S = (k_1 - F_Z/k_2)F_Z\arctan(k_3\alpha)`.

    Parameters
    ----------
    slip : array_like
        α, rad.
    load : array_like
        :math:`F_Z`, N.
    tires : array_like, shape (..., 3)
        ``[k1, k2 in N, k3 in 1/rad]`` (:meth:`ArctanTire.as_array`, :func:`bank_tires`);
        the leading axes broadcast with ``slip`` and ``load``.
    """
    t = np.asarray(tires, dtype=float)
    a, fz = np.asarray(slip, dtype=float), np.asarray(load, dtype=float)
    return _load_factor(fz, t) * np.arctan(t[..., 2] * a)  # eq. 3


def cornering_stiffness(slip: npt.ArrayLike, load: npt.ArrayLike, tires: npt.ArrayLike) -> np.ndarray:
    r"""Secant cornering stiffness :math:`C = S/\alpha`, N/rad (eq. 15).

    At zero slip its limit, the tangent stiffness :math:`(k_1 - F_Z/k_2)F_Zk_3`. Arguments as
    :func:`lateral_tire_force`.
    """
    t = np.asarray(tires, dtype=float)
    a, fz = np.asarray(slip, dtype=float), np.asarray(load, dtype=float)
    k3 = t[..., 2]
    x = k3 * a
    small = np.abs(x) < 1e-8
    ratio = np.where(small, 1.0, np.arctan(np.where(small, 1.0, x)) / np.where(small, 1.0, x))
    return _load_factor(fz, t) * k3 * ratio  # eq. 15: S/α = factor · k3 · arctan(k3α)/(k3α)


@dataclass(frozen=True)
class TwoTrackResponse:
    """What :func:`simulate_two_track` returns; every array ``(runs, steps)`` or ``(runs, steps, 4)``.

    Attributes
    ----------
    time : numpy.ndarray, (steps,)
        s.
    sideslip : β, rad.
    yaw_rate : :math:`\\dot\\psi`, rad/s.
    lateral_acceleration : :math:`a_y = \\Sigma S/m`, m/s² (eq. 11).
    wheel_loads : :math:`F_Z`, N, (runs, steps, 4).
    slip_angles : α, rad, (runs, steps, 4).
    tire_forces : S, N, (runs, steps, 4).
    """

    time: np.ndarray
    sideslip: np.ndarray
    yaw_rate: np.ndarray
    lateral_acceleration: np.ndarray
    wheel_loads: np.ndarray
    slip_angles: np.ndarray
    tire_forces: np.ndarray


def _check_signals(names_values: dict) -> tuple[np.ndarray, ...]:
    arrays = []
    for name, value in names_values.items():
        a = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(a)):
            bad = int(np.sum(~np.isfinite(a)))
            raise InputError(f"{name} must be finite (no NaN or inf), got {bad} bad values")
        arrays.append(np.atleast_2d(a))
    return tuple(arrays)


_LOOP_ITERATIONS = 12


def _forces(steer, beta, r, vx, tires, vehicle, ay_guess):
    """Algebraic loop a_y → F_Z → S → a_y (eq. 7, 3, 11) solved by fixed-point iteration.

    The loop's gain, :math:`\\sum_j \\partial S_j/\\partial F_Z\\,\\partial F_Z/\\partial a_y / m`, is about
    1e-2 for the paper's car in its manoeuvre, so 12 iterations from the previous sample's
    value converge to machine precision.
    """
    alpha = slip_angles(steer, beta, r, vx, vehicle)
    ay = ay_guess
    for _ in range(_LOOP_ITERATIONS):  # a fixed count: each run's result independent of the batch
        ay = lateral_tire_force(alpha, wheel_loads(ay, vehicle), tires).sum(axis=-1) / vehicle.mass
    fz = wheel_loads(ay, vehicle)
    s = lateral_tire_force(alpha, fz, tires)
    return ay, fz, alpha, s


def _derivatives(steer, beta, r, vx, tires, vehicle, ay_guess):
    ay, fz, alpha, s = _forces(steer, beta, r, vx, tires, vehicle, ay_guess)
    v = vehicle
    beta_dot = s.sum(axis=-1) / (v.mass * vx) - r  # eq. 1
    return beta_dot, _yaw_acceleration(s, vehicle), ay, fz, alpha, s


def _yaw_acceleration(s: np.ndarray, vehicle: TwoTrackVehicle) -> np.ndarray:
    """Yaw acceleration, rad/s², from the side forces ``(..., 4)`` in N (eq. 1, 5)."""
    v = vehicle
    front, rear = s[..., 0] + s[..., 1], s[..., 2] + s[..., 3]
    return (front * v.front_length - rear * v.rear_length) / v.yaw_inertia  # eq. 1


def simulate_two_track(
    steer: npt.ArrayLike,
    speed: npt.ArrayLike,
    tires: npt.ArrayLike,
    vehicle: TwoTrackVehicle,
    *,
    dt: float,
) -> TwoTrackResponse:
    r"""The two-track model (eq. 1–3, 7–8, 11) driven by a steer signal, from rest: the truth.

    Classic fourth-order Runge–Kutta with the inputs interpolated linearly between samples;
    the wheel loads depend on :math:`a_y`, which depends on the side forces (eq. 7 and 11),
    and this algebraic loop is solved by a fixed number of fixed-point iterations at each stage.

    Parameters
    ----------
    steer : array_like, (runs, steps) or (steps,)
        Road-wheel angle δ, rad (positive left).
    speed : array_like, broadcasting to steer
        :math:`v_x`, m/s, > 0.
    tires : array_like, ([runs or 1], 4, 3)
        Per wheel ``[k1, k2, k3]`` (:func:`bank_tires` of one model, or one per run).
    vehicle : TwoTrackVehicle
    dt : float
        Sample interval, s.

    Returns
    -------
    TwoTrackResponse
    """
    delta, vx = _check_signals({"steer": steer, "speed": speed})
    delta, vx = np.broadcast_arrays(delta, vx)
    if np.any(vx <= 0):
        raise InputError(f"speed must be > 0 m/s, got min {np.min(vx):.4g}")
    if not (np.isfinite(dt) and dt > 0):
        raise InputError(f"dt must be > 0 s, got {dt!r}")
    t_arr = np.asarray(tires, dtype=float)
    if t_arr.ndim == 2:
        t_arr = t_arr[None]
    if t_arr.ndim != 3 or t_arr.shape[1:] != (4, 3) or t_arr.shape[0] not in (1, delta.shape[0]):
        raise InputError(f"tires must have shape ([runs or 1], 4, 3), got {np.shape(tires)}")
    runs, steps = delta.shape
    t_arr = np.broadcast_to(t_arr, (runs, 4, 3))
    out = {k: np.zeros((runs, steps)) for k in ("b", "r", "ay")}
    out4 = {k: np.zeros((runs, steps, 4)) for k in ("fz", "alpha", "s")}
    beta = np.zeros(runs)
    r = np.zeros(runs)
    ay = np.zeros(runs)
    for k in range(steps):
        d0, v0 = delta[:, k], vx[:, k]
        k1b, k1r, ay, fz, alpha, s = _derivatives(d0, beta, r, v0, t_arr, vehicle, ay)
        out["b"][:, k], out["r"][:, k], out["ay"][:, k] = beta, r, ay
        out4["fz"][:, k], out4["alpha"][:, k], out4["s"][:, k] = fz, alpha, s
        if k == steps - 1:
            break
        d1, v1 = delta[:, k + 1], vx[:, k + 1]
        dm, vm = 0.5 * (d0 + d1), 0.5 * (v0 + v1)
        k2b, k2r, *_ = _derivatives(dm, beta + 0.5 * dt * k1b, r + 0.5 * dt * k1r, vm, t_arr, vehicle, ay)
        k3b, k3r, *_ = _derivatives(dm, beta + 0.5 * dt * k2b, r + 0.5 * dt * k2r, vm, t_arr, vehicle, ay)
        k4b, k4r, *_ = _derivatives(d1, beta + dt * k3b, r + dt * k3r, v1, t_arr, vehicle, ay)
        beta = beta + dt / 6.0 * (k1b + 2 * k2b + 2 * k3b + k4b)
        r = r + dt / 6.0 * (k1r + 2 * k2r + 2 * k3r + k4r)
    return TwoTrackResponse(
        time=np.arange(steps) * dt,
        sideslip=out["b"],
        yaw_rate=out["r"],
        lateral_acceleration=out["ay"],
        wheel_loads=out4["fz"],
        slip_angles=out4["alpha"],
        tire_forces=out4["s"],
    )


# --- the detector --------------------------------------------------------------------------


def _cumtrapz(y: np.ndarray, dt: float, axis: int = 1) -> np.ndarray:
    """Cumulative trapezoid along ``axis``, starting at 0."""
    y = np.moveaxis(y, axis, -1)
    out = np.zeros_like(y)
    out[..., 1:] = np.cumsum(0.5 * dt * (y[..., 1:] + y[..., :-1]), axis=-1)
    return np.moveaxis(out, -1, axis)


def sideslip_from_measurements(
    lateral_acceleration: npt.ArrayLike, yaw_rate: npt.ArrayLike, speed: npt.ArrayLike, *, dt: float
) -> np.ndarray:
    r"""Vehicle sideslip by integration, rad (eq. 10).

    :math:`\beta(t) = \int_0^t (a_y/v_x - \dot\psi)\,d\tau`.

    Trapezoidal rule on samples ``dt`` s apart, :math:`\beta(0) = 0`; arrays ``(runs, steps)``
    (m/s², rad/s, m/s). Open-loop: a bias in :math:`a_y` or :math:`\dot\psi` makes β drift
    linearly, noise as a random walk.
    """
    ay, r, vx = np.broadcast_arrays(*_check_signals(
        {"lateral_acceleration": lateral_acceleration, "yaw_rate": yaw_rate, "speed": speed}))
    return _cumtrapz(ay / vx - r, dt)  # eq. 10


@dataclass(frozen=True)
class DetectionResult:
    """What :func:`detect_deflation` returns.

    Attributes
    ----------
    time : (steps,), s.
    selected : (runs, steps) int
        The selected model's number :math:`i^*` (1..16, eq. 14).
    cost : (runs, steps, 16)
        :math:`J_i(t)` (eq. 13), in the units of the weighted error norm (m/s² with the
        default scale) for ``instant_weight`` and times s for ``integral_weight``.
    lateral_acceleration : (runs, steps, 16)
        :math:`a_{y,i}`, m/s² (eq. 11).
    yaw_rate : (runs, steps, 16)
        :math:`\\dot\\psi_i`, rad/s (eq. 5).
    sideslip : (runs, steps, 16)
        :math:`\\beta_i`, rad (eq. 5).
    measured_sideslip : (runs, steps)
        β of eq. 10, rad.
    cornering_stiffness : (runs, steps, 4)
        :math:`C_{ij}` of the selected model's tyres, N/rad (eq. 15).
    """

    time: np.ndarray
    selected: np.ndarray
    cost: np.ndarray
    lateral_acceleration: np.ndarray
    yaw_rate: np.ndarray
    sideslip: np.ndarray
    measured_sideslip: np.ndarray
    cornering_stiffness: np.ndarray


def detect_deflation(
    steer: npt.ArrayLike,
    speed: npt.ArrayLike,
    lateral_acceleration: npt.ArrayLike,
    yaw_rate: npt.ArrayLike,
    vehicle: TwoTrackVehicle,
    *,
    dt: float,
    instant_weight: float,
    integral_weight: float,
    forgetting_rate: float,
    error_scale: tuple[float, float] = (1.0, 1.0),
    sideslip: npt.ArrayLike | None = None,
    nominal: ArctanTire | tuple[ArctanTire, ArctanTire] = NOMINAL_TIRE,
    deflated: ArctanTire | tuple[ArctanTire, ArctanTire] = DEFLATED_TIRE,
    wheel_load: npt.ArrayLike | None = None,
) -> DetectionResult:
    r"""Select the tyre-failure model of least cost among the 16 (Solmaz, Steps 2–9, eq. 5–15).

    Per sample: wheel loads from the measured :math:`a_y` (eq. 7), slip angles from the
    measured δ, :math:`v_x`, :math:`\dot\psi` and the β of eq. 10 (eq. 8), each model's side
    forces (eq. 6), lateral acceleration (eq. 11) and yaw acceleration; each model's yaw rate
    and sideslip integrate eq. 5 from zero (trapezoid); the error (eq. 12), its weighted norm
    :math:`\lVert e\rVert = \sqrt{(e_1/s_1)^2 + (e_2/s_2)^2}` and the cost
    :math:`J_i = \alpha\lVert e_i\rVert + \gamma\int_0^t e^{-\lambda(t-\tau)}\lVert e_i\rVert d\tau`
    (eq. 13, the integral as the exact recursion of a rectangle rule:
    :math:`I_k = e^{-\lambda\Delta t}I_{k-1} + \Delta t\lVert e_k\rVert`); the argmin (eq. 14,
    ties to the fewest deflated tyres) and its secant stiffnesses (eq. 15). Every step is an
    array operation over runs, time and models: no Python loop.

    Parameters
    ----------
    steer, speed, lateral_acceleration, yaw_rate : array_like, (runs, steps) or (steps,)
        Measured δ (rad), :math:`v_x` (m/s, > 0), :math:`a_y` (m/s²), :math:`\dot\psi` (rad/s),
        sampled ``dt`` apart; they broadcast to one shape.
    vehicle : TwoTrackVehicle
    dt : float
        Sample interval, s.
    instant_weight, integral_weight : float
        α and γ of eq. 13, ≥ 0 and not both 0.
    forgetting_rate : float
        λ of eq. 13, 1/s, ≥ 0 (0: the plain running integral).
    error_scale : (float, float), optional
        :math:`s_1` (m/s²) and :math:`s_2` (rad/s) dividing the two error components; the
        default (1, 1) is the paper's unweighted norm.
    sideslip : array_like, (runs, steps) or (steps,), optional
        β in rad from elsewhere (the paper's "state observers can also be utilized"); if
        `None`, eq. 10's open-loop integral of the measurements.
    nominal, deflated : ArctanTire or (ArctanTire, ArctanTire), optional
        The two tyre sets of the bank, one tyre or a (front, rear) pair (:func:`bank_tires`);
        default the paper's (Sec. IV).
    wheel_load : array_like, (runs, steps, 4) or (steps, 4), optional
        F_Z per wheel in N (FL, FR, RL, RR) from elsewhere (e.g. a simulator's true loads, a bound
        on what a better load model could give); if `None`, eq. 7 from the measured a_y.

    Returns
    -------
    DetectionResult
    """
    delta, vx, ay, r = _check_signals(
        {"steer": steer, "speed": speed, "lateral_acceleration": lateral_acceleration, "yaw_rate": yaw_rate}
    )
    try:
        delta, vx, ay, r = np.broadcast_arrays(delta, vx, ay, r)
    except ValueError as err:
        raise InputError(
            f"steer, speed, lateral_acceleration and yaw_rate must broadcast to one (runs, steps) shape, "
            f"got {[np.shape(a) for a in (steer, speed, lateral_acceleration, yaw_rate)]}"
        ) from err
    if np.any(vx <= 0):
        raise InputError(f"speed must be > 0 m/s, got min {np.min(vx):.4g}")
    if not (np.isfinite(dt) and dt > 0):
        raise InputError(f"dt must be > 0 s, got {dt!r}")
    for name, value in (("instant_weight", instant_weight), ("integral_weight", integral_weight),
                        ("forgetting_rate", forgetting_rate)):
        if not (np.isfinite(value) and value >= 0):
            raise InputError(f"{name} must be a finite number >= 0, got {value!r}")
    if instant_weight == 0 and integral_weight == 0:
        raise InputError("instant_weight and integral_weight must not both be 0 (eq. 13 would be 0)")
    scale = np.asarray(error_scale, dtype=float)
    if scale.shape != (2,) or not np.all(np.isfinite(scale) & (scale > 0)):
        raise InputError(f"error_scale must be two numbers > 0 (m/s², rad/s), got {error_scale!r}")

    v = vehicle
    if sideslip is None:
        beta_meas = _cumtrapz(ay / vx - r, dt)  # eq. 10
    else:
        (beta_meas,) = _check_signals({"sideslip": sideslip})
        try:
            beta_meas = np.broadcast_to(beta_meas, delta.shape)
        except ValueError as err:
            raise InputError(f"sideslip must broadcast to {delta.shape}, got {np.shape(sideslip)}") from err
    if wheel_load is None:
        fz = wheel_loads(ay, vehicle)[:, :, None, :]  # eq. 7, (runs, steps, 1, 4)
    else:
        load = np.asarray(wheel_load, dtype=float)
        try:
            load = np.broadcast_to(load, (*delta.shape, 4))
        except ValueError as err:
            raise InputError(f"wheel_load must broadcast to {(*delta.shape, 4)}, got {load.shape}") from err
        if not np.all(np.isfinite(load) & (load >= 0)):
            raise InputError("wheel_load must be finite and >= 0 N")
        fz = load[:, :, None, :]
    alpha = slip_angles(delta, beta_meas, r, vx, vehicle)[:, :, None, :]  # eq. 8
    tires = bank_tires(nominal=nominal, deflated=deflated)  # (16, 4, 3)
    s = lateral_tire_force(alpha, fz, tires)  # eq. 6, (runs, steps, 16, 4)
    ay_i = s.sum(axis=-1) / v.mass  # eq. 11
    yaw_acc = _yaw_acceleration(s, vehicle)  # eq. 5
    r_i = _cumtrapz(yaw_acc, dt)  # eq. 5, ψ̇_i(0) = 0
    beta_i = _cumtrapz(ay_i / vx[..., None] - r[..., None], dt)  # eq. 5 with the measured ψ̇
    e_ay = (ay[..., None] - ay_i) / scale[0]  # eq. 12
    e_r = (r[..., None] - r_i) / scale[1]
    norm = np.hypot(e_ay, e_r)
    decay = np.exp(-forgetting_rate * dt)
    integral = lfilter([dt], [1.0, -decay], norm, axis=1)  # I_k = decay·I_{k-1} + dt·‖e_k‖
    cost = instant_weight * norm + integral_weight * integral  # eq. 13
    pick = _TIE_ORDER[np.argmin(cost[..., _TIE_ORDER], axis=-1)]  # eq. 14, first minimum in tie order
    selected = pick + 1
    sel_tires = tires[pick]  # (runs, steps, 4, 3)
    stiff = cornering_stiffness(alpha[:, :, 0, :], fz[:, :, 0, :], sel_tires)  # eq. 15
    steps = delta.shape[1]
    return DetectionResult(
        time=np.arange(steps) * dt,
        selected=selected,
        cost=cost,
        lateral_acceleration=ay_i,
        yaw_rate=r_i,
        sideslip=beta_i,
        measured_sideslip=beta_meas,
        cornering_stiffness=stiff,
    )

