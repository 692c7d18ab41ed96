r"""Solmaz's 16-model deflation detector (:mod:`suvtwin.estimators.lateral_detection`) on MuJoCo runs.

Usual calls::

    bank = fit_bank(tire_file=None)                         # arctan tyres fitted to the SUV's MF tyre
    det = detect_run(table, two_track_vehicle(scenario), bank)  # one run's table (read_run)
    det.result.selected                                     # (1, steps): model 1..16

What this module adds to the estimator (which never sees MuJoCo):

- **The ISO 3888-1 double lane change** (:func:`lane_change_scenario`): the driver follows
  :func:`suvtwin.pipeline.scenario.iso3888_centreline` by pure pursuit on a flat road at a held
  speed, one tyre at a chosen pressure, an optional extra load.
- **The vehicle** (:func:`two_track_vehicle`): the two-track model's m, l_v, l_h, h, J_zz and T
  from the SUV's parameter file and the scenario's extra loads: m the chassis, four unsprung
  corners and the loads; the centre of gravity (x and height) their mass-weighted mean (unsprung
  masses at the wheel centres, ``a1``/``a2`` ahead of/behind the chassis CoG, at the unloaded
  tyre radius); J_zz the file's whole-vehicle yaw inertia plus the loads' point-mass terms,
  moved to the combined CoG; T the mean of the front and rear tracks (the model has one).
- **The measured signals** (:func:`detector_signals`): δ = the driver's bicycle road-wheel angle
  ``steer_rad`` (the Ackermann split of eq. 2 is the model's, the kernel's is exact), v_x =
  ``speed_mps``, ψ̇ = ``yaw_rate_radps``, and a_y either as an ESC sensor fixed to the body
  reads it (``accel="body"``: the run's ``lat_accel_mps2`` is horizontal, gravity-free, in the
  heading frame, so the sensor's reading is :math:`a_y\cos\varphi + g\sin\varphi` with the
  body roll φ, positive with the left side up, i.e. outward roll adds to the reading) or the
  horizontal value itself (``accel="horizontal"``, a roll-compensated sensor); optional white
  noise of ESC grade; optionally the true sideslip (from the chassis track and yaw angle) in
  place of eq. 10's open-loop integral.
- **The bank's tyres** (:func:`fit_bank`): the arctan tyre :math:`S = (k_1 - F_Z/k_2)F_Z
  \arctan(k_3\alpha)` (eq. 3) fitted by least squares to the per-wheel load, slip angle and
  side force the simulator records (``tire_fz_n``, ``tire_slip_angle_rad``, ``tire_fy_n``:
  MF-Tyre 6.1 with its pressure terms) in calibration lane changes at 80, 100 and 120 km/h,
  left and right, no extra load, all four tyres at the nominal pressure and, separately, at
  the bank's one deflated pressure (:data:`DEFLATED_KPA`, the middle of the 130–180 kPa the
  Monte Carlo draws). MF's slip angle has the opposite sign to the paper's (MF: F_y < 0 for
  α > 0), so α_paper = −α_MF with S = F_y (left-positive). Cached in memory per tyre file.

Every number that depends on the vehicle or the tyre is computed here from parameter files
and simulator runs, none is typed in.
"""

from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.estimators.lateral_detection import (
    GRAVITY,
    ArctanTire,
    DetectionResult,
    TwoTrackVehicle,
    detect_deflation,
    model_number,
)
from suvtwin.pipeline.scenario import ISO3888_SECTIONS_M, Scenario, parse_scenario

__all__ = [
    "CORNERS",
    "DEFLATED_KPA",
    "ESC_NOISE",
    "NOMINAL_KPA",
    "PAPER_COST",
    "RunDetection",
    "TireBank",
    "CASES",
    "CALIBRATION_SLIP",
    "RIGID_STEERING",
    "SENSITIVITY_TIRE",
    "VARIANTS",
    "case_tire_file",
    "cornering_stiffness_table",
    "monte_carlo_study",
    "score_rows",
    "study_draw",
    "study_scenario",
    "detect_run",
    "detect_run_file",
    "detection_columns",
    "detection_delay",
    "detector_signals",
    "fit_arctan_tire",
    "fit_bank",
    "lane_change_scenario",
    "steering_onset",
    "truth_model",
    "two_track_vehicle",
    "write_detection",
]

CORNERS = ("fl", "fr", "rl", "rr")  # the estimator's WHEELS order
NOMINAL_KPA = 250.0
"""The SUV's nominal pressure, kPa (``NOMPRES`` of its .tir, Brancati & Tufano 2022, Table 1)."""
DEFLATED_KPA = 155.0
"""The bank's one deflated level, kPa: the middle of the 130–180 kPa the Monte Carlo draws."""
DEFLATION_THRESHOLD = 0.85
"""A tyre below this share of the nominal pressure counts as deflated in the truth (:func:`truth_model`)."""
PAPER_COST = {"instant_weight": 0.0, "integral_weight": 1.0, "forgetting_rate": 0.0}
"""Eq. 13 as in ``bench/lateral_detection_paper.py``: the running integral of the error norm."""
ESC_NOISE = (0.05, np.deg2rad(0.2))
"""White noise σ on a_y (m/s²) and ψ̇ (rad/s): ESC grade, as in the paper bench (the paper gives none)."""
RUN_IN_S = 3.0
"""Straight driving at the set speed before section 1 of the lane change, s."""
RUN_OUT_S = 3.0
"""Driving after the end of section 6, s."""
CALIBRATION_SPEEDS_KMH = (80.0, 100.0, 120.0)
SAMPLE_RATE_HZ = 100.0
"""Output rate of the lane-change runs (ESC sampling)."""


def lane_change_scenario(
    *,
    speed_kmh: float,
    pressure_kpa: dict[str, float] | float = NOMINAL_KPA,
    direction: Literal["left", "right"] = "left",
    load_kg: float = 0.0,
    load_position_m: tuple[float, float, float] = (0.0, 0.0, 0.0),
    tire_file: str | Path | None = None,
    seed: int = 0,
    timestep_s: float = 1e-3,
    vehicle: dict | None = None,
) -> Scenario:
    """An ISO 3888-1 double lane change on a flat road (:class:`~suvtwin.pipeline.scenario.Scenario`).

    :data:`RUN_IN_S` of straight driving before section 1 and :data:`RUN_OUT_S` after section 6
    at `speed_kmh`, held by the speed controller; sampled at :data:`SAMPLE_RATE_HZ`. `vehicle`:
    the scenario's vehicle overrides (e.g. :data:`RIGID_STEERING`).
    """
    if not 10.0 <= speed_kmh <= 180.0:
        raise InputError(f"speed_kmh must be in [10, 180] km/h, got {speed_kmh!r}")
    v = speed_kmh / 3.6
    start = RUN_IN_S * v
    duration = (start + sum(ISO3888_SECTIONS_M)) / v + RUN_OUT_S
    duration = round(np.ceil(duration * SAMPLE_RATE_HZ) / SAMPLE_RATE_HZ, 6)
    data: dict = {
        "duration_s": duration,
        "timestep_s": timestep_s,
        "output_rate_hz": SAMPLE_RATE_HZ,
        "seed": seed,
        "speed_kmh": speed_kmh,
        "road": "flat",
        "pressure_kpa": pressure_kpa,
        "steering": {"mode": "iso3888", "direction": direction, "iso3888_start_m": round(start, 3)},
    }
    if load_kg > 0:
        data["load"] = [{"mass_kg": load_kg, "position_m": list(load_position_m)}]
    if tire_file is not None:
        data["tire_file"] = str(tire_file)
    if vehicle:
        data["vehicle"] = vehicle
    return parse_scenario(data, source="lane change")


def two_track_vehicle(scenario: Scenario | None = None) -> TwoTrackVehicle:
    """The SUV (with the scenario's extra loads and vehicle overrides) as the two-track model's vehicle.

    See the module docstring for the mapping.
    """
    from suvtwin.mjcf.tire import load_tire
    from suvtwin.mjcf.vehicle import load_vehicle

    vehicle = load_vehicle(overrides=(scenario.vehicle or None) if scenario else None)
    c = vehicle.chassis
    tire_file = (scenario.tire_file if scenario else None) or vehicle.tire_file
    radius = load_tire(tire_file).unloaded_radius
    # point masses relative to the chassis CoG: (mass, x, y, z)
    masses = [(c.mass, 0.0, 0.0, 0.0)]
    for m, (x, y) in zip(vehicle.unsprung_mass, vehicle.corner_xy, strict=True):
        masses.append((float(m), float(x), float(y), radius - c.cog_height))
    loads = [(ld.mass_kg, *ld.position_m) for ld in scenario.load] if scenario else []
    everything = np.array(masses + loads, dtype=float)
    m = everything[:, 0]
    total = float(m.sum())
    xg, yg, zg = (m @ everything[:, 1:]) / total
    jzz = c.inertia_yaw_total  # whole vehicle about the chassis CoG's vertical axis (parameter file)
    if loads:
        ld = np.array(loads, dtype=float)
        jzz += float(ld[:, 0] @ (ld[:, 1] ** 2 + ld[:, 2] ** 2))
    jzz -= total * (xg**2 + yg**2)  # parallel axis: to the combined CoG
    return TwoTrackVehicle(
        mass=total,
        yaw_inertia=float(jzz),
        front_length=float(c.a1 - xg),
        rear_length=float(c.a2 + xg),
        cog_height=float(c.cog_height + zg),
        track=0.5 * (c.track_front + c.track_rear),
    )


def _column(table, name: str) -> np.ndarray:
    if name not in table:
        raise InputError(f"run table has no column {name!r} (is it a suvtwin simulate run?)")
    return np.asarray(table[name], dtype=float)


def detector_signals(
    table,
    *,
    accel: Literal["body", "horizontal"] = "body",
    noise: tuple[float, float] | None = None,
    seed: int = 0,
) -> dict[str, np.ndarray | float]:
    """The detector's inputs from a run's table: ``steer``, ``speed``, ``lateral_acceleration``,
    ``yaw_rate``, ``true_sideslip`` (arrays, SI) and ``dt`` (s).

    `accel`: ``"body"`` (an ESC sensor fixed to the body: :math:`a_y\\cos\\varphi + g\\sin\\varphi`)
    or ``"horizontal"`` (the run's roll-free value). `noise`: σ of white noise on a_y (m/s²) and
    ψ̇ (rad/s), from ``numpy.random.default_rng(seed)``; `None`: clean. The true sideslip is
    the direction of the chassis's horizontal velocity (finite differences of ``x_m``, ``y_m``)
    minus its yaw angle.
    """
    if accel not in ("body", "horizontal"):
        raise InputError(f"accel must be 'body' or 'horizontal', got {accel!r}")
    t = _column(table, "t_s")
    if t.size < 3:
        raise InputError(f"run must have at least 3 samples, got {t.size}")
    dt = float(np.median(np.diff(t)))
    if not dt > 0 or np.max(np.abs(np.diff(t) - dt)) > 1e-6 * max(dt, 1.0):
        raise InputError("run samples must be evenly spaced in t_s")
    speed = _column(table, "speed_mps")
    if np.any(speed <= 0.5):
        raise InputError(f"the detector needs the car moving (speed > 0.5 m/s), got {speed.min():.3g} m/s")
    ay = _column(table, "lat_accel_mps2")
    if accel == "body":
        roll = _column(table, "roll_rad")
        ay = ay * np.cos(roll) + GRAVITY * np.sin(roll)
    r = _column(table, "yaw_rate_radps").copy()
    if noise is not None:
        rng = np.random.default_rng(seed)
        ay = ay + noise[0] * rng.standard_normal(ay.size)
        r = r + noise[1] * rng.standard_normal(r.size)
    x, y, yaw = _column(table, "x_m"), _column(table, "y_m"), _column(table, "yaw_rad")
    course = np.arctan2(np.gradient(y, dt), np.gradient(x, dt))
    beta = np.angle(np.exp(1j * (course - yaw)))
    return {"steer": _column(table, "steer_rad"), "speed": speed, "lateral_acceleration": ay,
            "yaw_rate": r, "true_sideslip": beta, "dt": dt}  # fmt: skip


def truth_model(table, *, nominal_kpa: float = NOMINAL_KPA) -> int:
    """The run's true model number (1..16; 16 none deflated): tyres whose median pressure is below
    :data:`DEFLATION_THRESHOLD` of `nominal_kpa` are deflated."""
    flags = [float(np.median(_column(table, f"{c}_pressure_kpa"))) < DEFLATION_THRESHOLD * nominal_kpa
             for c in CORNERS]  # fmt: skip
    return model_number(np.array(flags))


def steering_onset(steer: npt.ArrayLike, dt: float, *, share: float = 0.1) -> float:
    """Time the steering starts, s: first sample where |δ| reaches `share` of its peak."""
    d = np.abs(np.asarray(steer, dtype=float))
    if d.max() <= 0:
        return float("nan")
    return float(np.argmax(d >= share * d.max()) * dt)


def detection_delay(selected: npt.ArrayLike, truth: int, dt: float, onset: float) -> float:
    """Time from `onset` to the first sample after which the selection is `truth` to the end, s
    (0 if it already was at the onset); NaN if the final pick is wrong."""
    sel = np.asarray(selected)
    if sel[-1] != truth:
        return float("nan")
    wrong = np.nonzero(sel != truth)[0]
    first_right = 0 if wrong.size == 0 else int(wrong[-1]) + 1
    return max(0.0, first_right * dt - onset)


# ------------------------------------------------------------------------ the bank's tyres
@dataclass(frozen=True)
class TireBank:
    """The bank's two arctan tyres, fitted to one MF tyre file at two pressures.

    Attributes: `nominal`, `deflated` (:class:`ArctanTire`), the pressures (kPa), the tyre
    file, and per tyre the fit's rms residual (N) and the load and slip ranges of its data.
    """

    nominal: ArctanTire
    deflated: ArctanTire
    nominal_kpa: float
    deflated_kpa: float
    tire_file: str
    fit: dict

    def as_dict(self) -> dict:
        """JSON-ready summary."""
        return {
            "tire_file": self.tire_file,
            "nominal_kpa": self.nominal_kpa,
            "deflated_kpa": self.deflated_kpa,
            "nominal": _tire_dict(self.nominal),
            "deflated": _tire_dict(self.deflated),
            "fit": self.fit,
        }


def _tire_dict(tire: ArctanTire | tuple[ArctanTire, ArctanTire]) -> dict:
    if isinstance(tire, tuple):
        return {"front": _tire_dict(tire[0]), "rear": _tire_dict(tire[1])}
    return {"k1": tire.k1, "k2_n": tire.k2, "k3_per_rad": tire.k3}


def fit_arctan_tire(
    load: npt.ArrayLike, slip: npt.ArrayLike, force: npt.ArrayLike
) -> tuple[ArctanTire, dict]:
    r"""Least-squares arctan tyre (eq. 3) to samples of load F_Z (N), slip α and side force S (N),
    both in the paper's sign (S has the sign of α).

    Returns the tyre and ``{"rms_n", "max_abs_n", "samples", "load_n": [min, max],
    "slip_deg": max |α|}``.
    """
    from scipy.optimize import least_squares

    fz, a, s = (np.ravel(np.asarray(v, dtype=float)) for v in (load, slip, force))
    keep = np.isfinite(fz) & np.isfinite(a) & np.isfinite(s) & (fz > 100.0)
    fz, a, s = fz[keep], a[keep], s[keep]
    if fz.size < 10:
        raise InputError(f"the arctan fit needs at least 10 loaded samples, got {fz.size}")
    # start: k3 from the secant at small slip, k2 large (load factor nearly linear)
    c0 = np.sum(s * a) / np.sum(a * a) / np.mean(fz)  # N/rad per N
    x0 = np.log([1.0, 10.0 * fz.max(), max(c0, 1.0)])

    def residual(logk):
        k1, k2, k3 = np.exp(logk)
        return (k1 - fz / k2) * fz * np.arctan(k3 * a) - s

    sol = least_squares(residual, x0, method="lm", x_scale=1.0)
    k1, k2, k3 = np.exp(sol.x)
    res = residual(sol.x)
    info = {"rms_n": float(np.sqrt(np.mean(res**2))), "max_abs_n": float(np.max(np.abs(res))),
            "samples": int(fz.size), "load_n": [float(fz.min()), float(fz.max())],
            "slip_deg": float(np.degrees(np.max(np.abs(a))))}  # fmt: skip
    return ArctanTire(k1=float(k1), k2=float(k2), k3=float(k3)), info


RIGID_STEERING = {"steering": {"compliance_steer_front": 0.0, "bump_steer_front": 0.0,
                               "compliance_steer_rear": 0.0}}  # fmt: skip
"""Vehicle overrides that take the SUV's compliance and bump steer out: the wheels steer exactly as
commanded, the kinematics the two-track model assumes (a sensitivity case of the study)."""

CALIBRATION_SLIP = ("detector", "tyre")
"""Slip angles the bank's tyres are fitted against (:func:`fit_bank`): ``"detector"`` — eq. 8
from the steering command, the true sideslip and the yaw rate (the detector's own coordinates:
the effective axle characteristic, compliance and bump steer folded in); ``"tyre"`` — each tyre's
own slip angle as the simulator records it."""


def _calibration_data(
    tire_file: str | None, pressure_kpa: float, slip: str, vehicle: dict | None
) -> tuple[np.ndarray, ...]:
    """Per-wheel (F_Z, α_paper, S) of the calibration lane changes, all tyres at `pressure_kpa`."""
    from suvtwin.estimators.lateral_detection import slip_angles, wheel_loads
    from suvtwin.pipeline.simulator import simulate

    fz, alpha, s, axle = [], [], [], []
    for speed in CALIBRATION_SPEEDS_KMH:
        for direction in ("left", "right"):
            sc = lane_change_scenario(speed_kmh=speed, pressure_kpa=pressure_kpa, direction=direction,
                                      tire_file=tire_file, vehicle=vehicle)  # fmt: skip
            result = simulate(sc)
            cols = result.columns
            if slip == "detector":
                sig = detector_signals(result.table, accel="horizontal", noise=None)
                car = two_track_vehicle(sc)
                modelled = slip_angles(sig["steer"], sig["true_sideslip"], sig["yaw_rate"], sig["speed"], car)
                loads = wheel_loads(sig["lateral_acceleration"], car)
            for i, c in enumerate(CORNERS):
                fz.append(loads[:, i] if slip == "detector" else cols[f"{c}_tire_fz_n"])
                if slip == "detector":
                    alpha.append(modelled[:, i])
                else:
                    alpha.append(-cols[f"{c}_tire_slip_angle_rad"])  # MF sign → paper sign
                s.append(cols[f"{c}_tire_fy_n"])
                axle.append(np.full(s[-1].size, i // 2))
    return np.concatenate(fz), np.concatenate(alpha), np.concatenate(s), np.concatenate(axle)


@functools.lru_cache(maxsize=8)
def _fit_bank_cached(
    tire_file: str | None, digest: str, nominal_kpa: float, deflated_kpa: float, slip: str, vehicle_json: str
) -> TireBank:
    vehicle = json.loads(vehicle_json) or None
    fits = {}
    tires = {}
    for name, p in (("nominal", nominal_kpa), ("deflated", deflated_kpa)):
        fz, alpha, force, axle = _calibration_data(tire_file, p, slip, vehicle)
        if slip == "tyre":  # the paper's bank: one tyre on all four wheels
            tires[name], fits[name] = fit_arctan_tire(fz, alpha, force)
        else:  # per-axle effective characteristics: each axle's compliance steer is its own
            pair = [fit_arctan_tire(fz[axle == a], alpha[axle == a], force[axle == a]) for a in (0, 1)]
            tires[name] = (pair[0][0], pair[1][0])
            fits[name] = {"front": pair[0][1], "rear": pair[1][1]}
        fits[name]["slip_angles"] = slip
    return TireBank(nominal=tires["nominal"], deflated=tires["deflated"], nominal_kpa=nominal_kpa,
                    deflated_kpa=deflated_kpa, tire_file=tire_file or "(the SUV's)", fit=fits)  # fmt: skip


def fit_bank(
    tire_file: str | Path | None = None,
    *,
    nominal_kpa: float = NOMINAL_KPA,
    deflated_kpa: float = DEFLATED_KPA,
    slip: str = "detector",
    vehicle: dict | None = None,
) -> TireBank:
    """The bank's nominal and deflated arctan tyres fitted to `tire_file` (default the SUV's .tir)
    from simulator runs (module docstring), against the slip angles `slip` names
    (:data:`CALIBRATION_SLIP`), on the SUV with the scenario `vehicle` overrides (the car the
    detector will watch). ~3 s; cached in memory by the file's content, the overrides and the
    simulator's code."""
    if slip not in CALIBRATION_SLIP:
        raise InputError(f"slip must be one of {CALIBRATION_SLIP}, got {slip!r}")
    from suvtwin.pipeline.campaign.cache import model_fingerprint

    for name, p in (("nominal_kpa", nominal_kpa), ("deflated_kpa", deflated_kpa)):
        if not (np.isfinite(p) and 80.0 <= p <= 350.0):
            raise InputError(f"{name} must be in [80, 350] kPa, got {p!r}")
    sha = hashlib.sha256(str(model_fingerprint()).encode())
    if tire_file is not None:
        path = Path(tire_file)
        if not path.is_file():
            raise InputError(f"tire_file {str(path)!r} does not exist")
        sha.update(path.read_bytes())
    return _fit_bank_cached(None if tire_file is None else str(tire_file), sha.hexdigest(),
                            float(nominal_kpa), float(deflated_kpa), slip,
                            json.dumps(vehicle or {}, sort_keys=True))  # fmt: skip


# ------------------------------------------------------------------------ detection of one run
@dataclass(frozen=True)
class RunDetection:
    """:func:`detect_run`'s answer: the estimator's result, the run's truth, onset and delay."""

    result: DetectionResult
    truth: int
    onset_s: float
    delay_s: float
    final: int

    @property
    def correct(self) -> bool:
        """The final pick is the true model."""
        return self.final == self.truth


def detect_run(
    table,
    vehicle: TwoTrackVehicle,
    bank: TireBank,
    *,
    accel: Literal["body", "horizontal"] = "body",
    noise: tuple[float, float] | None = ESC_NOISE,
    seed: int = 0,
    true_sideslip: bool = False,
    cost: dict | None = None,
) -> RunDetection:
    """Run the 16-model detector on one run's table (paper's cost unless `cost` is given)."""
    sig = detector_signals(table, accel=accel, noise=noise, seed=seed)
    result = detect_deflation(
        sig["steer"], sig["speed"], sig["lateral_acceleration"], sig["yaw_rate"], vehicle,
        dt=sig["dt"], sideslip=sig["true_sideslip"] if true_sideslip else None,
        nominal=bank.nominal, deflated=bank.deflated, **(cost or PAPER_COST),
    )  # fmt: skip
    truth = truth_model(table, nominal_kpa=bank.nominal_kpa)
    onset = steering_onset(sig["steer"], sig["dt"])
    selected = result.selected[0]
    delay = detection_delay(selected, truth, sig["dt"], onset)
    return RunDetection(result=result, truth=truth, onset_s=onset, delay_s=delay, final=int(selected[-1]))


# ------------------------------------------------------------------------ a run file in, a file out
def detect_run_file(
    run: str | Path,
    *,
    tire_file: str | Path | None = None,
    nominal_kpa: float = NOMINAL_KPA,
    deflated_kpa: float = DEFLATED_KPA,
    accel: Literal["body", "horizontal"] = "body",
    noise: tuple[float, float] | None = ESC_NOISE,
    seed: int = 0,
    true_sideslip: bool = False,
) -> tuple[RunDetection, TireBank, dict, dict]:
    """:func:`detect_run` on a run file (``suvtwin simulate``): the vehicle from the run's scenario
    (its loads, overrides and tyre), the bank fitted to `tire_file` (default the run's tyre).

    Returns the detection, the bank, the output columns (:func:`detection_columns`) and metadata.
    """
    from suvtwin.pipeline.simulator import read_run

    table, meta = read_run(run)
    scenario = None
    if isinstance(meta.get("scenario"), dict):
        scenario = parse_scenario(meta["scenario"], source=f"scenario of {Path(run).name}")
    run_tire = scenario.tire_file if scenario is not None else None
    bank = fit_bank(tire_file if tire_file is not None else run_tire,
                    nominal_kpa=nominal_kpa, deflated_kpa=deflated_kpa,
                    vehicle=scenario.vehicle if scenario is not None else None)  # fmt: skip
    vehicle = two_track_vehicle(scenario)
    det = detect_run(table, vehicle, bank, accel=accel, noise=noise, seed=seed, true_sideslip=true_sideslip)
    metadata = {
        "run": str(run), "accel": accel, "noise": None if noise is None else list(noise), "seed": seed,
        "true_sideslip": true_sideslip, "bank": bank.as_dict(), "vehicle": vehicle.__dict__,
        "vehicle_from_scenario": scenario is not None, "truth": det.truth, "final": det.final,
        "onset_s": det.onset_s, "delay_s": None if not np.isfinite(det.delay_s) else det.delay_s,
    }  # fmt: skip
    return det, bank, detection_columns(det), metadata


def detection_columns(det: RunDetection) -> dict[str, np.ndarray]:
    """Output columns: ``t_s``, ``selected`` (model 1..16), ``deflated_{c}`` (0/1 of the selected
    model), ``cost_model_{i}`` (eq. 13, i = 1..16), ``stiffness_{c}_npr`` (eq. 15, N/rad)."""
    from suvtwin.estimators.lateral_detection import N_MODELS, deflated_wheels

    r = det.result
    sel = r.selected[0]
    flags = np.array([deflated_wheels(int(n)) for n in range(1, N_MODELS + 1)], dtype=float)[sel - 1]
    out = {"t_s": r.time, "selected": sel.astype(float)}
    for j, c in enumerate(CORNERS):
        out[f"deflated_{c}"] = flags[:, j]
    for i in range(N_MODELS):
        out[f"cost_model_{i + 1}"] = r.cost[0, :, i]
    for j, c in enumerate(CORNERS):
        out[f"stiffness_{c}_npr"] = r.cornering_stiffness[0, :, j]
    return out


def write_detection(columns: dict[str, np.ndarray], path: str | Path, metadata: dict) -> None:
    """Write :func:`detection_columns` to Parquet (atomically), `metadata` as JSON in the schema."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    from suvtwin.files import atomic_write

    table = pa.Table.from_pydict({k: np.asarray(v, dtype=float) for k, v in columns.items()})
    table = table.replace_schema_metadata(
        {b"suvtwin.lateral_detection": json.dumps(metadata, sort_keys=True, default=float).encode()}
    )
    atomic_write(path, lambda tmp: pq.write_table(table, tmp, compression="zstd"))


# ------------------------------------------------------------------------ the Monte Carlo study
SENSITIVITY_TIRE = "suv_235_60R18_softer_deflated.tir"
"""The labelled sensitivity-case tyre beside the SUV's .tir: cornering stiffness 20 % lower at 150 kPa."""
CASES = ("shipped", "softer_deflated")
"""Tyre cases of the study: the SUV's .tir (PPY1 < 0) and :data:`SENSITIVITY_TIRE`."""
VARIANTS = {"esc_body": ("body", False), "roll_compensated": ("horizontal", False),
            "ideal_sideslip": ("horizontal", True)}  # fmt: skip
"""Detector variants: (a_y frame, true sideslip instead of eq. 10)."""
STUDY_SEED0 = 900000
_CHOICES = ("fl", "fr", "rl", "rr", None)


def case_tire_file(case: str) -> str | None:
    """The .tir of a tyre case (None: the SUV's own)."""
    from suvtwin.mjcf.vehicle import load_vehicle

    if case not in CASES:
        raise InputError(f"tyre case must be one of {', '.join(CASES)}, got {case!r}")
    return None if case == "shipped" else str(load_vehicle().tire_file.with_name(SENSITIVITY_TIRE))


def study_draw(i: int) -> dict:
    """Run i's random conditions (the same in every tyre case), from ``default_rng(STUDY_SEED0 + i)``:
    speed 80–120 km/h, direction, the deflated tyre FL, FR, RL, RR or none in turn (``i % 5``: 20 %
    none), its pressure 130–180 kPa, an extra load 0–300 kg at x ∈ [−1.8, 0.5] m, y ∈ [−0.5, 0.5] m,
    z ∈ [−0.2, 0.2] m from the chassis CoG (boot to front seats)."""
    rng = np.random.default_rng(STUDY_SEED0 + i)
    speed = float(rng.uniform(80.0, 120.0))
    direction = "left" if rng.random() < 0.5 else "right"
    pressure = float(rng.uniform(130.0, 180.0))
    load = float(rng.uniform(0.0, 300.0))
    position = [float(rng.uniform(-1.8, 0.5)), float(rng.uniform(-0.5, 0.5)), float(rng.uniform(-0.2, 0.2))]
    return {"i": i, "speed_kmh": round(speed, 2), "direction": direction, "tyre": _CHOICES[i % 5],
            "pressure_kpa": round(pressure, 1), "load_kg": round(load, 1),
            "load_position_m": [round(p, 3) for p in position]}  # fmt: skip


def study_scenario(draw: dict, case: str, vehicle: dict | None = None) -> Scenario:
    """The lane change of a :func:`study_draw` with the tyre of `case` (and `vehicle` overrides)."""
    p = {c: (draw["pressure_kpa"] if c == draw["tyre"] else NOMINAL_KPA) for c in CORNERS}
    return lane_change_scenario(speed_kmh=draw["speed_kmh"], pressure_kpa=p, direction=draw["direction"],
                                load_kg=draw["load_kg"], load_position_m=tuple(draw["load_position_m"]),
                                tire_file=case_tire_file(case), seed=draw["i"], vehicle=vehicle)  # fmt: skip


def _detect_study_run(item: tuple) -> dict:
    path, draw, case, bank, keep_series, overrides = item
    from suvtwin.pipeline.simulator import read_run

    table, _ = read_run(path)
    vehicle = two_track_vehicle(study_scenario(draw, case, overrides))
    row = {"draw": draw, "peak_ay_mps2": float(np.abs(table["lat_accel_mps2"]).max()),
           "peak_roll_deg": float(np.degrees(np.abs(table["roll_rad"]).max()))}  # fmt: skip
    for name, (accel, beta) in VARIANTS.items():
        det = detect_run(
            table, vehicle, bank, accel=accel, noise=ESC_NOISE, seed=draw["i"], true_sideslip=beta
        )
        row[name] = {"truth": det.truth, "final": det.final, "delay_s": det.delay_s, "onset_s": det.onset_s}
        if keep_series:
            row[name]["selected"] = det.result.selected[0].tolist()
            row[name]["t_s"] = det.result.time.tolist()
    return row


def score_rows(rows: list[dict], variant: str) -> dict:
    """Confusion matrix (true model → final pick → runs), correct rates, delay distribution (runs
    with a deflated tyre whose final pick is right) and false-alarm rate of one variant."""
    truths = sorted({r[variant]["truth"] for r in rows})
    picks = sorted({r[variant]["final"] for r in rows} | set(truths))
    matrix = {str(t): {str(p): sum(1 for r in rows if r[variant]["truth"] == t and r[variant]["final"] == p)
                       for p in picks} for t in truths}  # fmt: skip
    delays = np.array([r[variant]["delay_s"] for r in rows if r[variant]["truth"] != 16], dtype=float)
    delays = delays[np.isfinite(delays)]
    nominal = [r for r in rows if r[variant]["truth"] == 16]
    edges = [0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 10.0, 30.0]
    return {
        "runs": len(rows),
        "correct_rate": float(np.mean([r[variant]["final"] == r[variant]["truth"] for r in rows])),
        "correct_rate_per_truth": {str(t): float(np.mean([r[variant]["final"] == t for r in rows
                                                           if r[variant]["truth"] == t])) for t in truths},
        "confusion_truth_vs_final": matrix,
        "delay_s": {
            "n": int(delays.size),
            "quantiles_0_25_50_75_90_100": (np.quantile(delays, [0, .25, .5, .75, .9, 1]).tolist()
                                            if delays.size else None),
            "histogram_edges_s": edges,
            "histogram_counts": np.histogram(delays, bins=edges)[0].tolist(),
        },
        "false_alarm_rate_no_deflation": (float(np.mean([r[variant]["final"] != 16 for r in nominal]))
                                          if nominal else None),
    }  # fmt: skip


def monte_carlo_study(
    n_runs: int,
    runs_dir: str | Path,
    *,
    jobs: int = 1,
    cases: tuple[str, ...] = CASES,
    slip: str = "detector",
    vehicle: dict | None = None,
) -> dict:
    """The detector over `n_runs` ISO 3888-1 lane changes per tyre case (:func:`study_draw`).

    Runs are simulated (and reused) in ``runs_dir/<case>/`` by
    :func:`suvtwin.pipeline.monitor_scenarios.simulate_cached`. Returns per case the fitted bank,
    the simulation cost, peak a_y and roll, per variant :func:`score_rows`, and an example run
    (the first with the front-left tyre deflated: its selected model over time per variant).
    `slip`: how the bank is fitted (:data:`CALIBRATION_SLIP`, :func:`fit_bank`); `vehicle`: scenario
    vehicle overrides for every run and the bank's calibration (e.g. :data:`RIGID_STEERING`).
    """
    import multiprocessing
    import os
    import time

    from suvtwin.pipeline.monitor_scenarios import BenchRun, simulate_cached

    if not (isinstance(n_runs, int) and n_runs >= 1):
        raise InputError(f"n_runs must be a positive whole number, got {n_runs!r}")
    out = {"runs_per_case": n_runs, "cases": {}}
    for case in cases:
        started = time.perf_counter()
        bank = fit_bank(case_tire_file(case), slip=slip, vehicle=vehicle)
        fit_s = time.perf_counter() - started
        draws = [study_draw(i) for i in range(n_runs)]
        runs = [BenchRun(name=f"{case}-{d['i']}", set="lateral_detection",
                         scenario=study_scenario(d, case, vehicle)) for d in draws]  # fmt: skip
        paths, cost = simulate_cached(runs, Path(runs_dir) / case, jobs=jobs)
        items = [
            (str(p), d, case, bank, d["i"] == 0, vehicle)
            for p, d in zip(paths, draws, strict=True)
            if p is not None
        ]
        started = time.perf_counter()
        if jobs > 1 and len(items) > 1:
            ctx = multiprocessing.get_context("spawn" if os.name == "nt" else "forkserver")
            with ctx.Pool(min(jobs, len(items))) as pool:
                rows = pool.map(_detect_study_run, items)
        else:
            rows = [_detect_study_run(it) for it in items]
        example = next((r for r in rows if r["draw"]["i"] == 0), None)
        out["cases"][case] = {
            "tire_file": case_tire_file(case) or "(the SUV's)",
            "bank": bank.as_dict(),
            "bank_fit_s": round(fit_s, 2),
            "simulation": cost,
            "detection_wall_s": round(time.perf_counter() - started, 2),
            "peak_ay_mps2_quantiles_0_50_100": _quantiles([r["peak_ay_mps2"] for r in rows]),
            "peak_roll_deg_quantiles_0_50_100": _quantiles([r["peak_roll_deg"] for r in rows]),
            "variants": {v: score_rows(rows, v) for v in VARIANTS},
            "example": None if example is None else {"draw": example["draw"], **{
                v: {k: example[v][k] for k in ("t_s", "selected", "truth", "onset_s")} for v in VARIANTS}},
        }  # fmt: skip
    out["cornering_stiffness_vs_pressure"] = cornering_stiffness_table()
    return out


def _quantiles(values: list[float]) -> list[float]:
    return np.quantile(values, [0.0, 0.5, 1.0]).tolist()


def cornering_stiffness_table(loads_n=(3000.0, 4500.0, 6000.0), pressures_kpa=(250.0, 150.0)) -> dict:
    """Zero-slip cornering stiffness of each case's MF tyre, N/rad, at `loads_n` and `pressures_kpa`
    (the simulator's tyre force function, finite difference at α = 1e-4 rad), and the change from
    the first pressure to the last, %."""
    from suvtwin.mjcf.tire import load_tire, tire_forces_array
    from suvtwin.mjcf.vehicle import load_vehicle

    table = {}
    for case in CASES:
        tire = load_tire(case_tire_file(case) or load_vehicle().tire_file)
        k = np.array([[-tire_forces_array(fz, 0.0, 1e-4, p * 1e3, tire)[1] / 1e-4 for p in pressures_kpa]
                      for fz in loads_n])  # fmt: skip
        table[case] = {"loads_n": list(loads_n), "pressures_kpa": list(pressures_kpa),
                       "stiffness_n_per_rad": k.tolist(),
                       "change_percent": (100.0 * (k[:, -1] / k[:, 0] - 1.0)).tolist()}  # fmt: skip
    return table
