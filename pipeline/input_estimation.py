r"""Half-car input estimation (CIE, AWIE) on the MuJoCo SUV: scenarios, truth, measurements, scores.

Usual call::

    scenario = obstacle_scenario("sine_bump", speed_kmh=60)
    table = simulate(scenario).table                     # or read_run("run.parquet")[0]
    result = estimate_run(table, method="AWIE", measurement_std=1e-8, seed=0)
    result.estimate, result.truth_input, result.truth_suspension   # (steps, 2): N, N m

The estimator (:mod:`suvtwin.estimators.input_estimation`, Lin et al. 2021) sees a linear
two-degree-of-freedom half car whose road excitation is lumped into two inputs, the
vertical force :math:`F_V` and the pitch torque :math:`T_\theta` (eq. 1–5). Here the half
car is the SUV (:func:`half_car_from_vehicle`), the measurements are the simulated body's
heave and pitch with seeded white noise (:func:`body_measurements`), and the truth is what
the four suspensions put on the body in the simulator (:func:`suspension_loads`):

- **Suspension loads** (``truth_suspension``): the vertical force
  :math:`F_s = \sum_i F_i - m g` and the pitch torque about the centre of gravity
  :math:`T_s = a_1 (F_{fl} + F_{fr}) - a_2 (F_{rl} + F_{rr})` (nose up > 0), with
  :math:`F_i` the force of corner i's spring, stops, damper and anti-roll bar along its
  slide joint (the run file's ``{c}_susp_force_n``; > 0 pushes the body up). At rest
  :math:`F_s = 0` and :math:`T_s = 0`: each corner carries its static share of the
  chassis weight (preload, ``VehicleParams.sprung_mass_corner``).
- **The model's input** (``truth_input``): the input that makes the linear half car move
  as the simulated body does, :math:`u^* = [F_s, T_s] + K x + C \dot x` with
  :math:`x = [z, \theta]` the body's true heave and pitch (from the start of the run) and
  K, C the half car's stiffness and damping matrices (eq. 3–4). Whatever the SUV's
  suspension does (progressive springs, stops, asymmetric dampers, wheel hop), the body
  obeys :math:`M\ddot x = [F_s, T_s]` exactly up to the forces the joints' constraints
  carry (below), so :math:`M\ddot x + C\dot x + Kx = u^*`: the linear model driven by
  :math:`u^*` is the body. In the linear car, :math:`u^*` is eq. 3's road side
  :math:`\sum K_i z_i + C_i\dot z_i`, with the wheel's displacement in place of the road.

The estimator's :math:`\hat u` is scored against :math:`u^*`; the suspension loads it
implies, :math:`\hat u - K\bar X - C\dot{\bar X}` with the filter's own state estimate,
are scored against :math:`[F_s, T_s]`.

What the truth leaves out: the slide joints' constraint also carries the tyres'
longitudinal forces to the body, at the wheel centre, 0.2 m below the centre of gravity;
their pitch moment is not in :math:`T_s`. :func:`closure_error` measures how far
:math:`M\ddot x` (from the noise-free heave and pitch) is from :math:`[F_s, T_s]`.

Conventions: SI units; the simulator's ``pitch_rad`` is positive nose down (right-handed
about the body's y axis, which points left), the half car's θ nose up
(Lin et al. 2021, Fig. 1), so :math:`\theta = -` ``pitch_rad``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.estimators.input_estimation import (
    HalfCar,
    continuous_matrices,
    discretize,
    estimate_inputs,
    norm_difference_error,
    normalized_error,
)
from suvtwin.mjcf.vehicle import CORNERS, GRAVITY, VehicleParams, load_vehicle

if TYPE_CHECKING:
    import pandas as pd

    from suvtwin.pipeline.scenario import Scenario

__all__ = [
    "METHODS",
    "PAPER_TABLE2",
    "PAPER_TABLE3",
    "ROADS",
    "SPEEDS_KMH",
    "RunEstimate",
    "body_input",
    "body_measurements",
    "closure_error",
    "estimate_columns",
    "estimate_run",
    "input_estimation_study",
    "half_car_from_vehicle",
    "model_input",
    "obstacle_scenario",
    "scores",
    "stiffness_damping",
    "suspension_loads",
    "write_input_estimate",
]

ROADS = ("sine_bump", "cleat", "random")
"""The three roads of Lin et al. 2021 §3.1 (eq. 23–31)."""

METHODS = {"CIE f=0.1": 0.1, "CIE f=0.9": 0.9, "AWIE": "adaptive"}
"""The estimators of Tables 2–3: name → ``fading`` of :func:`estimate_inputs`."""

PAPER_TABLE2 = {  # Lin et al. 2021, Table 2 (30 km/h), NEE %: [vertical force, pitch torque]
    "sine_bump": {"CIE f=0.1": (1.22, 0.70), "CIE f=0.9": (0.81, 1.24), "AWIE": (4.91, 1.42)},
    "cleat": {"CIE f=0.1": (0.78, 0.91), "CIE f=0.9": (1.36, 1.76), "AWIE": (0.61, 0.63)},
    "random": {"CIE f=0.1": (5.33, 2.24), "CIE f=0.9": (42.85, 43.03), "AWIE": (4.93, 2.13)},
}
"""The paper's Table 2; the metric is its eq. 32 (see :func:`scores`)."""

PAPER_TABLE3 = {  # Lin et al. 2021, Table 3 (CIE f_tr = 0.1 and AWIE), NEE %: [force, torque]
    "sine_bump": {
        30: {"CIE f=0.1": (1.22, 0.70), "AWIE": (4.91, 1.42)},
        60: {"CIE f=0.1": (0.74, 0.30), "AWIE": (0.57, 0.43)},
        90: {"CIE f=0.1": (1.22, 0.71), "AWIE": (1.07, 0.67)},
    },
    "cleat": {
        30: {"CIE f=0.1": (0.78, 0.91), "AWIE": (0.61, 0.63)},
        60: {"CIE f=0.1": (1.85, 1.49), "AWIE": (1.56, 1.11)},
        90: {"CIE f=0.1": (2.93, 2.38), "AWIE": (1.84, 2.50)},
    },
    "random": {
        30: {"CIE f=0.1": (5.33, 2.24), "AWIE": (4.93, 2.13)},
        60: {"CIE f=0.1": (5.23, 2.30), "AWIE": (4.94, 1.85)},
        90: {"CIE f=0.1": (5.28, 1.75), "AWIE": (4.84, 1.71)},
    },
}
"""The paper's Table 3."""

SPEEDS_KMH = (30, 60, 90)
"""The speeds of Table 3, km/h."""

LEAD_S = 0.3
"""Time from the run's start to the front wheel reaching the obstacle, s."""


def half_car_from_vehicle(vehicle: VehicleParams | None = None) -> HalfCar:
    r"""The SUV as the half car of Lin et al. 2021, Fig. 1 and eq. 1–4.

    Each value and where it comes from (``mjcf/suv/parameters.toml``):

    - mass m = ``chassis.mass`` (1788 kg): the sprung body alone, the MuJoCo chassis body;
      wheels and carriers are unsprung and not in the half car.
    - pitch_inertia I = ``chassis.inertia_pitch`` (3200 kg m²): the chassis body's inertia
      about its y axis through the centre of gravity.
    - front/rear_length L_F, L_R = ``chassis.a1``, ``chassis.a2`` (1.347, 1.471 m).
    - front/rear_stiffness K_F, K_R = 2 × ``suspension.spring_rate_front/rear`` (wheel
      rates, two corners per axle: 64, 76 kN/m). The progression, the stops and the
      anti-roll bars are left out (the bars do not act in heave and pitch).
    - front/rear_damping C_F, C_R = 2 × the mean of ``damper_compression_low`` and
      ``damper_rebound_low`` (2 × 2200 N s/m): the low-speed slopes of the asymmetric
      damper, averaged over a symmetric stroke; the digressive high-speed slopes are left out.
    """
    v = vehicle if vehicle is not None else load_vehicle()
    s = v.suspension
    damping = s.damper_compression_low + s.damper_rebound_low  # 2 × the mean of the two slopes
    return HalfCar(
        mass=v.chassis.mass,
        pitch_inertia=v.chassis.inertia_pitch,
        front_stiffness=2.0 * s.spring_rate_front,
        rear_stiffness=2.0 * s.spring_rate_rear,
        front_damping=damping,
        rear_damping=damping,
        front_length=v.chassis.a1,
        rear_length=v.chassis.a2,
    )


def stiffness_damping(car: HalfCar) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mass, stiffness and damping matrices M, K, C (2×2) of the half car, Lin et al. 2021, eq. 3–4.

    :math:`M\\ddot x + C\\dot x + Kx = u`, x = [z, θ] (m, rad), u = [F_V, T_θ] (N, N m).
    """
    F, _, _ = continuous_matrices(car)
    M = np.diag([car.mass, car.pitch_inertia])
    K = -M @ F[[1, 3]][:, [0, 2]]
    C = -M @ F[[1, 3]][:, [1, 3]]
    return M, K, C


def obstacle_scenario(
    road: str,
    *,
    speed_kmh: float,
    duration_s: float = 1.5,
    height_m: float = 0.1,
    length_m: float = 1.0,
    road_class: str = "C",
    seed: int = 0,
    lead_s: float = LEAD_S,
) -> Scenario:
    """The SUV driving straight over one of the paper's three roads.

    ``sine_bump`` and ``cleat``: a road smooth to micrometres (ISO level
    Gd(n0) = 10⁻¹² m³, far below class A's 2·10⁻⁶) with the obstacle on both tracks
    (Lin et al. 2021, eq. 24 and Fig. 3; the paper's h0 = 0.1 m, D = 1 m), placed so that the
    front wheel centre reaches it `lead_s` after the start. ``random``: an ISO 8608 road of
    `road_class` (eq. 29–31, sinusoid superposition), left and right tracks independent.
    The sensor noise of the run's accelerometers is irrelevant here; heave and pitch get
    their noise in :func:`body_measurements`.

    Raises
    ------
    InputError
        Unknown road, or a speed, height or length out of range.
    """
    from suvtwin.pipeline.scenario import START_MARGIN_M, parse_scenario

    if road not in ROADS:
        raise InputError(f"road must be one of {', '.join(ROADS)}, got {road!r}")
    if not 5.0 <= speed_kmh <= 150.0:
        raise InputError(f"speed_kmh must be in [5, 150] km/h, got {speed_kmh!r}")
    if not 0.0 <= lead_s < duration_s:
        raise InputError(f"lead_s must be in [0, duration_s = {duration_s:g}) s, got {lead_s!r}")
    vehicle = load_vehicle()
    speed = speed_kmh / 3.6
    length = START_MARGIN_M + speed * duration_s + 40.0
    front_axle = START_MARGIN_M + vehicle.chassis.a2 + vehicle.chassis.a1
    segment: dict = {"length_m": length, "gd_n0": 1e-12}
    spec: dict = {"segments": [segment]}
    if road == "random":
        spec["segments"] = [{"length_m": length, "road_class": road_class}]
    else:
        spec["obstacles"] = [
            {
                "kind": road,
                "position_m": front_axle + speed * lead_s,
                "length_m": length_m,
                "height_m": height_m,
                "track": "both",
            }
        ]
    return parse_scenario(
        {"duration_s": duration_s, "speed_kmh": speed_kmh, "seed": seed, "road": spec},
        source="input-estimation scenario",
    )


def _column(table: pd.DataFrame, name: str) -> np.ndarray:
    if name not in table:
        raise InputError(f"run file has no column {name!r}: not a suvtwin simulate run")
    values = np.asarray(table[name], dtype=float)
    if not np.all(np.isfinite(values)):
        raise InputError(f"run file column {name!r} holds NaN or infinite values")
    return values


def suspension_loads(table: pd.DataFrame, vehicle: VehicleParams | None = None) -> np.ndarray:
    r"""Vertical force and pitch torque the suspensions put on the body, above their static values.

    :math:`F_s = \sum_i F_i - m g`, :math:`T_s = a_1(F_{fl} + F_{fr}) - a_2(F_{rl} + F_{rr})`
    (N and N m, nose up > 0), from the run's ``{c}_susp_force_n`` (force along each slide
    joint, > 0 pushes the body up; the slide axis is the body's z axis, so at pitch θ the
    vertical part is cos θ of it, > 0.998 at 60 mrad; not corrected). Shape (steps, 2).
    """
    v = vehicle if vehicle is not None else load_vehicle()
    f = np.stack([_column(table, f"{c}_susp_force_n") for c in CORNERS], axis=-1)
    a1, a2 = v.chassis.a1, v.chassis.a2
    force = f.sum(axis=-1) - v.chassis.mass * GRAVITY
    torque = a1 * (f[:, 0] + f[:, 1]) - a2 * (f[:, 2] + f[:, 3])
    return np.stack([force, torque], axis=-1)


def _body_motion(table: pd.DataFrame) -> tuple[np.ndarray, float]:
    """True x = [z, θ] from the run's start (m, rad; θ nose up) and the sampling interval, s."""
    t = _column(table, "t_s")
    if t.size < 3:
        raise InputError(f"run file has {t.size} samples; input estimation needs at least 3")
    dt = np.diff(t)
    if np.any(dt <= 0) or np.ptp(dt) > 1e-6 * dt.mean():
        raise InputError("run file column 't_s' must be uniformly spaced and increasing")
    z = _column(table, "heave_m")
    theta = -_column(table, "pitch_rad")
    x = np.stack([z - z[0], theta - theta[0]], axis=-1)
    return x, float(dt.mean())


def model_input(table: pd.DataFrame, car: HalfCar, vehicle: VehicleParams | None = None) -> np.ndarray:
    r"""The half car's true input :math:`u^* = [F_s, T_s] + Kx + C\dot x`, shape (steps, 2), N and N m.

    x from the run's heave and pitch (from the start), :math:`\dot x` by central
    differences (:func:`numpy.gradient`); K, C of eq. 3–4 (:func:`stiffness_damping`).
    """
    x, dt = _body_motion(table)
    _, K, C = stiffness_damping(car)
    xdot = np.gradient(x, dt, axis=0)
    return suspension_loads(table, vehicle) + x @ K.T + xdot @ C.T


def body_input(table: pd.DataFrame, car: HalfCar) -> np.ndarray:
    r"""The input that moves the linear half car exactly as the simulated body moved, (steps, 2).

    :math:`M\ddot x + C\dot x + Kx` with ẍ from second differences of the run's noise-free
    heave and pitch (the end samples repeat their neighbours). It differs from
    :func:`model_input` by what the joints' constraints put on the body
    (:func:`closure_error`); a diagnostic, not the truth of the study.
    """
    x, dt = _body_motion(table)
    M, K, C = stiffness_damping(car)
    accel = np.empty_like(x)
    accel[1:-1] = (x[2:] - 2 * x[1:-1] + x[:-2]) / dt**2
    accel[0], accel[-1] = accel[1], accel[-2]
    return accel @ M.T + x @ K.T + np.gradient(x, dt, axis=0) @ C.T


def closure_error(table: pd.DataFrame, car: HalfCar, vehicle: VehicleParams | None = None) -> np.ndarray:
    r"""How well the body's motion closes on the suspension loads: 100‖Mẍ − [F_s, T_s]‖/‖[F_s, T_s]‖, %.

    ẍ by second differences of the run's noise-free heave and pitch (exact for MuJoCo's
    semi-implicit Euler step when the output rate is the step rate); one value per channel
    (heave, pitch). What remains is the constraint forces of the slide joints (the tyres'
    longitudinal forces reach the body below its centre of gravity), the cos θ of the
    slide axes and the differencing.
    """
    x, dt = _body_motion(table)
    M, _, _ = stiffness_damping(car)
    loads = suspension_loads(table, vehicle)
    accel = (x[2:] - 2 * x[1:-1] + x[:-2]) / dt**2  # at samples 1..n-2
    # MuJoCo's semi-implicit Euler: v(k+1) = v(k) + a(k)Δt, x(k+1) = x(k) + v(k+1)Δt, so the
    # second difference centred on k is a(k)Δt², the acceleration of row k's forces
    return normalized_error(loads[1:-1], accel @ M.T)


def body_measurements(
    table: pd.DataFrame, *, measurement_std: npt.ArrayLike, seed: int | npt.ArrayLike, runs: int = 1
) -> np.ndarray:
    """Measured heave and pitch Z(k) = [z, θ] (m, rad; θ nose up, both from the run's start) + noise.

    White Gaussian noise of `measurement_std` (σ of z in m and of θ in rad; a scalar for
    both), drawn from ``numpy.random.default_rng(seed)``; `runs` draws give shape
    (runs, steps, 2). Lin et al. 2021, eq. 7.
    """
    sigma = np.broadcast_to(np.asarray(measurement_std, dtype=float), (2,))
    if not np.all(np.isfinite(sigma)) or np.any(sigma < 0) or np.any(sigma > 1.0):
        raise InputError(f"measurement_std must be in [0, 1] m and rad, got {np.asarray(measurement_std)!r}")
    x, _ = _body_motion(table)
    rng = np.random.default_rng(seed)
    return x[None] + rng.standard_normal((int(runs), *x.shape)) * sigma


@dataclass(frozen=True)
class RunEstimate:
    """One method on one run's measurements: estimates (runs, steps, 2), truths (steps, 2).

    Attributes
    ----------
    t : numpy.ndarray, shape (steps,)
        Time, s.
    estimate : numpy.ndarray
        û(k) = [F_V, T_θ], N and N m (estimates u(k−1); Lin et al. 2021, eq. 19 / 22).
    estimate_suspension : numpy.ndarray
        The suspension loads û implies, û − K X̄ − C Ẋ̄ with the filter's state X̄(k|k), N and N m.
    truth_input : numpy.ndarray or None
        u* (:func:`model_input`); None when the run has no suspension forces.
    truth_suspension : numpy.ndarray or None
        [F_s, T_s] (:func:`suspension_loads`); None when the run has no suspension forces.
    """

    t: np.ndarray
    estimate: np.ndarray
    estimate_suspension: np.ndarray
    truth_input: np.ndarray | None
    truth_suspension: np.ndarray | None


def estimate_run(
    table: pd.DataFrame,
    *,
    method: str | float = "AWIE",
    measurement_std: npt.ArrayLike = 1e-8,
    filter_std: npt.ArrayLike | None = None,
    input_noise: float = 1e2,
    seed: int | npt.ArrayLike = 0,
    runs: int = 1,
    car: HalfCar | None = None,
    vehicle: VehicleParams | None = None,
) -> RunEstimate:
    """CIE or AWIE (Lin et al. 2021, eq. 8–22) on a run's noisy heave and pitch.

    `method` is a key of :data:`METHODS` or, for CIE, its fading factor f_tr in (0, 1]; the
    measurements get white noise of
    `measurement_std` (m and rad); the filter's R is diag(`filter_std`²) (default
    `measurement_std`; give it to run the same filter on noise-free data) and Q is
    `input_noise`·I (the paper: σ = 10⁻⁸, Q = 10², §3.2). `runs` noise draws from `seed`
    are estimated as one batch. Initial values as the paper's §3.2.
    """
    if isinstance(method, str) and method in METHODS:
        fading = METHODS[method]
    elif not isinstance(method, str) and np.isfinite(method) and 0.0 < method <= 1.0:
        fading = float(method)  # CIE with this fading factor
    else:
        raise InputError(
            f"method must be one of {', '.join(METHODS)} or a fading factor in (0, 1], got {method!r}"
        )
    if not np.isfinite(input_noise) or input_noise <= 0:
        raise InputError(f"input_noise must be > 0 N^2, got {input_noise!r}")
    vehicle = vehicle if vehicle is not None else load_vehicle()
    car = car if car is not None else half_car_from_vehicle(vehicle)
    z = body_measurements(table, measurement_std=measurement_std, seed=seed, runs=runs)
    _, dt = _body_motion(table)
    system = discretize(car, dt=dt)
    assumed = measurement_std if filter_std is None else filter_std
    sigma = np.broadcast_to(np.asarray(assumed, dtype=float), (2,))
    if not np.all(np.isfinite(sigma)) or np.any(sigma <= 0) or np.any(sigma > 1.0):
        raise InputError(f"filter_std (default measurement_std) must be in (0, 1] m and rad, got {assumed!r}")
    est = estimate_inputs(z, system, input_noise=input_noise, measurement_std=sigma, fading=fading)
    _, K, C = stiffness_damping(car)
    xs = est.states[..., [0, 2]]
    vs = est.states[..., [1, 3]]
    implied = est.inputs - xs @ K.T - vs @ C.T
    has_truth = all(f"{c}_susp_force_n" in table for c in CORNERS)
    return RunEstimate(
        t=_column(table, "t_s"),
        estimate=est.inputs,
        estimate_suspension=implied,
        truth_input=model_input(table, car, vehicle) if has_truth else None,
        truth_suspension=suspension_loads(table, vehicle) if has_truth else None,
    )


def estimate_columns(result: RunEstimate, run: int = 0) -> dict[str, np.ndarray]:
    """One noise draw of `result` as output columns (SI): t, estimates, and the truth if known.

    ``t_s``; ``force_hat_n``, ``torque_hat_nm`` (û, the half car's input, eq. 19 / 22);
    ``suspension_force_hat_n``, ``suspension_torque_hat_nm`` (the loads û implies); and, when
    the run has them, ``force_true_n``, ``torque_true_nm`` (u*) and ``suspension_force_true_n``,
    ``suspension_torque_true_nm`` ([F_s, T_s]). Torques nose up > 0, about the centre of gravity.
    """
    out = {
        "t_s": result.t,
        "force_hat_n": result.estimate[run, :, 0],
        "torque_hat_nm": result.estimate[run, :, 1],
        "suspension_force_hat_n": result.estimate_suspension[run, :, 0],
        "suspension_torque_hat_nm": result.estimate_suspension[run, :, 1],
    }
    if result.truth_input is not None and result.truth_suspension is not None:
        out["force_true_n"] = result.truth_input[:, 0]
        out["torque_true_nm"] = result.truth_input[:, 1]
        out["suspension_force_true_n"] = result.truth_suspension[:, 0]
        out["suspension_torque_true_nm"] = result.truth_suspension[:, 1]
    return out


def write_input_estimate(columns: dict[str, np.ndarray], path, metadata: dict) -> None:
    """Write :func:`estimate_columns` to Parquet (atomically), `metadata` as JSON in the schema."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from suvtwin.files import atomic_write

    table = pa.Table.from_pydict({k: np.asarray(v, dtype=float) for k, v in columns.items()})
    table = table.replace_schema_metadata(
        {b"suvtwin.input_estimate": json.dumps(metadata, sort_keys=True).encode()}
    )
    atomic_write(path, lambda tmp: pq.write_table(table, tmp, compression="zstd"))


def scores(truth: npt.ArrayLike, estimate: npt.ArrayLike) -> dict[str, np.ndarray]:
    """The error readings of the paper part, per channel (…, 2), %.

    ``aligned``: 100‖u(k−1) − û(k)‖/‖u‖ (Z(k) carries inputs up to u(k−1));
    ``same_index``: 100‖u(k) − û(k)‖/‖u‖; ``eq32``: eq. 32 read as
    100(‖u‖ − ‖û‖)/‖u‖ (Lin et al. 2021, eq. 32 divided by ‖u‖ instead of Σu²).
    """
    u = np.asarray(truth, dtype=float)
    uh = np.asarray(estimate, dtype=float)
    return {
        "aligned": normalized_error(u[..., :-1, :], uh[..., 1:, :]),
        "same_index": normalized_error(u, uh),
        "eq32": norm_difference_error(u, uh),
    }


FIGURE_CASES = {30: ("AWIE", "CIE f=0.9"), 90: ("AWIE", "CIE f=0.1")}
"""Speed → the two methods the paper plots: Figures 10–12 (30 km/h: AWIE, CIE f_tr = 0.9) and
13–15 (90 km/h: AWIE, CIE f_tr = 0.1), each for the three roads."""


def input_estimation_study(
    *,
    n_seeds: int = 10,
    measurement_std: float = 1e-8,
    input_noise: float = 1e2,
    roads: tuple[str, ...] = ROADS,
    speeds_kmh: tuple[float, ...] = SPEEDS_KMH,
    seed: int = 0,
) -> dict:
    """The MuJoCo analog of Lin et al. 2021, Tables 2–3 and Figures 10–15, as a JSON-able dict.

    One simulation per road and speed (:func:`obstacle_scenario`, scenario seed `seed`), each
    method of :data:`METHODS` on `n_seeds` noise draws. ``cells``: one row per road, speed,
    method with, per channel [F_V, T_θ] in %: ``eq32`` and ``aligned`` against u*
    (mean and std over the draws; :func:`scores`), ``suspension_aligned`` against the
    suspension loads; ``paper`` is the paper's value or None. ``closure``: :func:`closure_error`
    per road and speed. ``examples``: the time series of the paper's figures
    (:data:`FIGURE_CASES`; first noise draw), ``t_s``, ``truth`` and ``estimate`` as
    [[F_V…], [T_θ…]] in N and N m.
    """
    from suvtwin.pipeline.simulator import simulate

    if not 1 <= n_seeds <= 1000:
        raise InputError(f"n_seeds must be in [1, 1000], got {n_seeds!r}")
    vehicle = load_vehicle()
    car = half_car_from_vehicle(vehicle)
    cells, closure, examples = [], [], []
    for road in roads:
        for speed in speeds_kmh:
            table = simulate(obstacle_scenario(road, speed_kmh=speed, seed=seed)).table
            percent = [round(float(v), 3) for v in closure_error(table, car, vehicle)]
            closure.append({"road": road, "speed_kmh": speed, "percent": percent})
            for method in METHODS:
                r = estimate_run(table, method=method, measurement_std=measurement_std,
                                 input_noise=input_noise, seed=seed, runs=n_seeds, car=car,
                                 vehicle=vehicle)  # fmt: skip
                s = scores(r.truth_input, r.estimate)
                sus = scores(r.truth_suspension, r.estimate_suspension)["aligned"]
                if speed == 30:
                    paper = PAPER_TABLE2.get(road, {}).get(method)
                else:
                    paper = PAPER_TABLE3.get(road, {}).get(int(speed), {}).get(method)
                cells.append({
                    "road": road, "speed_kmh": speed, "method": method,
                    "paper": None if paper is None else list(paper),
                    "eq32": _mean_std(s["eq32"]), "aligned": _mean_std(s["aligned"]),
                    "suspension_aligned": _mean_std(sus),
                })  # fmt: skip
                if method in FIGURE_CASES.get(int(speed), ()):
                    examples.append({
                        "road": road, "speed_kmh": speed, "method": method,
                        "t_s": np.round(r.t, 4).tolist(),
                        "truth": np.round(r.truth_input.T, 1).tolist(),
                        "estimate": np.round(r.estimate[0].T, 1).tolist(),
                    })  # fmt: skip
    return {
        "settings": {
            "n_seeds": n_seeds,
            "measurement_std": measurement_std,
            "q": input_noise,
            "seed": seed,
            "half_car": dict(car.__dict__),
            "lead_s": LEAD_S,
        },  # fmt: skip
        "cells": cells,
        "closure": closure,
        "examples": examples,
    }


def _mean_std(values: np.ndarray) -> dict[str, list[float]]:
    """Mean and std over draws (axis 0) per channel, 4 significant digits."""
    return {
        "mean": [float(f"{v:.4g}") for v in values.mean(axis=0)],
        "std": [float(f"{v:.4g}") for v in values.std(axis=0)],
    }
