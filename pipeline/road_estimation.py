r"""Road-profile estimation (Wang et al. 2017) on the MuJoCo SUV: the filter's quarter car, truth, score.

Usual call::

    table, meta = read_run("run.parquet")
    scenario = parse_scenario(meta["scenario"])
    vehicle = load_vehicle()
    car, sources = corner_quarter_car(vehicle, load_tire(vehicle.tire_file), corner="fl",
                                      pressure_pa=250e3)
    truth = road_under_wheel(scenario, table, corner="fl")          # raw and enveloped
    est = estimate_corner_road(table, car, gd_n0=class_level("C"), corner="fl",
                               measurement_std=0.02, filter_name="KF")
    error_std_percent(truth.raw, est.road)

``suvtwin road-estimate`` is :func:`estimate_run_road` (both tracks of an axle, written as a
road file); the bench and the campaign's report run :func:`mujoco_study` (Table 2's 18 cells).

The filter (:mod:`suvtwin.estimators.road_estimation`, which never imports MuJoCo) sees
only the corner's two measured accelerations (``{c}_accel_sprung_mps2``: the chassis point
above the wheel; ``{c}_accel_unsprung_mps2``: the wheel centre; both vertical, gravity
removed, with the scenario's sensor noise). Its quarter car is the SUV's corner at the
nominal load (:func:`corner_quarter_car`); a load change goes into the simulated car only
(the paper's experiment, Wang et al. 2017, §4.1).

The truth (:func:`road_under_wheel`) is the heightfield — the one road the simulator's tyres
read — under the tyre:

- ``raw``: the heightfield elevation at the wheel centre's (x, y) (bilinear in the grid, as
  the tyre model reads it, :func:`suvtwin.mjcf.kernel.road_height`);
- ``enveloped``: the effective road height the tyre model used at that step (the cos²
  mean over the contact patch, ±0.12 m; recorded in the run as ``{c}_road_z_m``).

The wheel centre's position is not a column of the run file; it is rebuilt from the
chassis pose: :math:`x_w = x + a\cos\psi - b\sin\psi`, :math:`y_w = y + a\sin\psi + b\cos\psi`
with (a, b) the corner's position in the chassis frame and ψ the yaw. Pitch and roll are
left out (pitch 0.01 rad moves the wheel centre, 0.3 m below the CoG, by 3 mm along x).
A test checks the rebuilt position against the run: the envelope recomputed at it equals
the recorded ``{c}_road_z_m``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.signal import butter, sosfiltfilt

from suvtwin.errors import InputError, RunError
from suvtwin.estimators.road_estimation import (
    QuarterCar,
    RoadEstimate,
    covariance_constraint_weight,
    discretize,
    iso_road_model,
    kalman_filter,
    mme_kalman_filter,
    stationary_covariance,
)
from suvtwin.mjcf.vehicle import CORNERS
from suvtwin.roads.profile import Road

__all__ = [
    "FILTERS",
    "HIGHPASS_CUTOFF_CYCLES_PER_M",
    "PAPER_TABLE2",
    "STUDY_SETTINGS",
    "CornerRoadEstimate",
    "RoadTruth",
    "corner_quarter_car",
    "estimate_corner_road",
    "estimate_run_road",
    "highpass",
    "mujoco_study",
    "road_from_tracks",
    "road_under_wheel",
    "study_scenario",
    "wheel_path",
]

FILTERS = ("KF", "MME&KF")
HIGHPASS_CUTOFF_CYCLES_PER_M = 0.05
"""Lower end of the band scored by the high-passed error, cycles/m: the lower edge of the
classification fit band (``suvtwin.roads.roughness.DEFAULT_FIT_BAND``), 0.56 Hz at 40 km/h,
half the SUV's body-bounce frequency (~1.2 Hz); road content below it barely moves the car."""


def _corner_index(corner: str) -> int:
    if corner not in CORNERS:
        raise InputError(f"corner must be one of {', '.join(CORNERS)}, got {corner!r}")
    return CORNERS.index(corner)


def corner_quarter_car(vehicle, tire, *, corner: str = "fl", pressure_pa: float) -> tuple[QuarterCar, dict]:
    """The filter's linear quarter car (Wang et al. 2017, eq. 1) from one corner of the SUV.

    - sprung mass m_b: the chassis mass the corner carries at rest,
      ``vehicle.sprung_mass_corner`` (½·m·a2/l front, Brancati & Tufano 2022, eq. 2), kg;
    - unsprung mass m_w: ``vehicle.unsprung_mass`` of the corner, kg;
    - spring k_s: the corner's linear wheel rate (``spring_rate_front`` / ``_rear``), N/m;
      the compression-only cubic progression and the stops are left out (linear about the
      design position), and so is the anti-roll bar (it acts on the left–right travel
      difference; the filter sees one corner);
    - damper c: the mean of the low-speed compression and rebound rates
      (the damper is digressive and 3:1 asymmetric; for small symmetric velocities the
      mean is the equivalent linear rate), N s/m;
    - tyre k_t: :func:`suvtwin.mjcf.tire.vertical_stiffness` at `pressure_pa`
      (kt0·(1 + pFz1·dpi), Brancati & Tufano 2022, eq. 3–4), N/m; the tyre's own damping
      is left out (eq. 1 has none).

    Returns
    -------
    (QuarterCar, dict)
        The car and, per parameter, its value and source (for the record).
    """
    from suvtwin.mjcf.tire import vertical_stiffness

    i = _corner_index(corner)
    pressure_pa = float(pressure_pa)
    lo, hi = vehicle.tire.pressure_min, vehicle.tire.pressure_max
    if not lo <= pressure_pa <= hi:
        raise InputError(f"pressure_pa must be in [{lo:g}, {hi:g}] Pa, got {pressure_pa:g}")
    s = vehicle.suspension
    car = QuarterCar(
        sprung_mass=float(vehicle.sprung_mass_corner[i]),
        unsprung_mass=float(vehicle.unsprung_mass[i]),
        suspension_stiffness=float(vehicle.spring_rate[i]),
        tire_stiffness=float(vertical_stiffness(pressure_pa, tire.to_array())),
        damping=0.5 * (s.damper_compression_low + s.damper_rebound_low),
    )
    sources = {
        "sprung_mass_kg": [car.sprung_mass, "chassis mass share at rest, 1/2 m a2/l (front) or a1/l (rear)"],
        "unsprung_mass_kg": [car.unsprung_mass, "wheel.unsprung_mass_front/rear"],
        "suspension_stiffness_npm": [car.suspension_stiffness,
                                     "linear wheel rate; progression, stops and anti-roll bar left out"],
        "damping_nspm": [car.damping, "mean of damper_compression_low and damper_rebound_low"],
        "tire_stiffness_npm": [car.tire_stiffness, f"kt(p) at {pressure_pa / 1e3:g} kPa, kt0 (1 + pFz1 dpi)"],
    }
    return car, sources


def wheel_path(table, vehicle, *, corner: str = "fl") -> tuple[np.ndarray, np.ndarray]:
    """World (x, y) of the corner's wheel centre over the run, m, from the chassis pose.

    Yaw only (module docstring). `table`: a run's table (``x_m``, ``y_m``, ``yaw_rad``).
    """
    i = _corner_index(corner)
    a, b = vehicle.corner_xy[i]
    x, y, yaw = (np.asarray(table[c], dtype=float) for c in ("x_m", "y_m", "yaw_rad"))
    return x + a * np.cos(yaw) - b * np.sin(yaw), y + a * np.sin(yaw) + b * np.cos(yaw)


@dataclass(frozen=True)
class RoadTruth:
    """The road under one tyre over a run.

    Attributes
    ----------
    t : numpy.ndarray, shape (steps,)
        Time, s.
    x, y : numpy.ndarray, shape (steps,)
        Wheel centre, world frame, m.
    raw : numpy.ndarray, shape (steps,)
        Heightfield elevation at (x, y), m.
    enveloped : numpy.ndarray, shape (steps,)
        Effective road height the tyre model used (contact-patch mean), m.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    raw: np.ndarray
    enveloped: np.ndarray


def road_under_wheel(scenario, table, *, corner: str = "fl") -> RoadTruth:
    """The heightfield under the corner's tyre over a run (module docstring).

    Rebuilds the run's heightfield from its scenario (:func:`suvtwin.pipeline.simulator.prepare`;
    the road is seeded by the scenario) and samples it at the wheel centre.
    """
    from suvtwin.mjcf.kernel import H_NCOL, H_NROW, road_height
    from suvtwin.mjcf.vehicle import load_vehicle
    from suvtwin.pipeline.simulator import prepare

    i = _corner_index(corner)
    vehicle = load_vehicle(overrides=scenario.vehicle or None)
    x, y = wheel_path(table, vehicle, corner=corner)
    prep = prepare(scenario)
    hf = prep.vm.hfield
    hdata = np.asarray(prep.vm.model.hfield_data, dtype=float).reshape(int(hf[H_NROW]), int(hf[H_NCOL]))
    raw = np.array([road_height(xi, yi, hf, hdata) for xi, yi in zip(x, y, strict=True)])
    return RoadTruth(t=np.asarray(table["t_s"], dtype=float), x=x, y=y, raw=raw,
                     enveloped=np.asarray(table[f"{CORNERS[i]}_road_z_m"], dtype=float))


@dataclass(frozen=True)
class CornerRoadEstimate:
    """A filter's road estimate under one corner.

    Attributes
    ----------
    road : numpy.ndarray, shape (steps,)
        x̂_r(k), m (sample k at the run's row k; row 0 is the initial value).
    estimate : RoadEstimate
        The filter's full output (states, innovations, gains).
    weight : float or None
        MME weight W used (eq. 20), None for the KF.
    """

    road: np.ndarray
    estimate: RoadEstimate
    weight: float | None


def _initial_state(table, corner: str, road0: float | None) -> np.ndarray | None:
    """x̂0 from the run's first row (the paper's eq. 10, x̂0 = E[x0]); None if road0 is None.

    Heights relative to the static equilibrium, estimated by the run's mean deflections.
    """
    if road0 is None:
        return None
    zs, zu = (np.asarray(table[f"{corner}_z_{p}_m"], dtype=float) for p in ("sprung", "unsprung"))
    vs, vu = (np.asarray(table[f"{corner}_v_{p}_mps"], dtype=float) for p in ("sprung", "unsprung"))
    zr = np.asarray(table[f"{corner}_road_z_m"], dtype=float)
    xw0 = road0 + (zu[0] - zr[0]) - np.mean(zu - zr)
    xb0 = xw0 + (zs[0] - zu[0]) - np.mean(zs - zu)
    return np.array([xb0, vs[0], xw0, vu[0], road0, 0.0])


def estimate_corner_road(
    table,
    car: QuarterCar,
    *,
    gd_n0: float,
    corner: str = "fl",
    measurement_std: float,
    filter_name: str = "KF",
    speed_mps: float | None = None,
    method: str = "euler",
    initial_road_m: float | None = None,
    constraint_window: int = 2001,
    weight: float | None = None,
) -> CornerRoadEstimate:
    """Run the KF (eq. 10–15) or the MME&KF (eq. 16–21) on one corner.

    The MME&KF in the estimator's default reading: the model error an acceleration of the
    body (G = e₂) that the measured body acceleration contains too, W from eq. 20 against the
    KF's innovation covariance on the first `constraint_window` samples
    (docs/road_estimation.md, "The MME&KF: readings").

    Parameters
    ----------
    table : DataFrame or mapping
        A run's table: ``t_s``, ``speed_mps``, ``{corner}_accel_sprung_mps2``,
        ``{corner}_accel_unsprung_mps2`` (and, for a known start, the corner's heights).
    car : QuarterCar
        The filter's (nominal) quarter car, :func:`corner_quarter_car`.
    gd_n0 : float
        ISO 8608 level the filter's road model assumes, m³ (``class_level``).
    corner : str
    measurement_std : float
        Accelerometer noise σ the filter assumes, m/s² (> 0).
    filter_name : {"KF", "MME&KF"}
    speed_mps : float, optional
        Speed for the road model, m/s (default: the run's mean speed).
    method : {"euler", "exact"}
        Discretization (eq. 7 is Euler).
    initial_road_m : float, optional
        Known start (eq. 10): the filter starts from the run's first state with the road at
        this elevation, m, and a tiny covariance (the road's slope excepted). None: unknown
        start, zero state and the model's stationary covariance.
    constraint_window : int
        Samples used to find eq. 20's W (MME&KF).
    weight : float, optional
        W for the MME&KF, overriding eq. 20.
    """
    if filter_name not in FILTERS:
        raise InputError(f"filter must be one of {', '.join(FILTERS)}, got {filter_name!r}")
    _corner_index(corner)
    sigma = float(measurement_std)
    if not np.isfinite(sigma) or sigma <= 0.0:
        raise InputError(f"measurement_std must be a finite number > 0 m/s^2, got {measurement_std!r}")
    t = np.asarray(table["t_s"], dtype=float)
    if t.size < 3:
        raise InputError(f"run must have at least 3 samples, got {t.size}")
    dt = float(np.median(np.diff(t)))
    y = np.stack([np.asarray(table[f"{corner}_accel_{p}_mps2"], dtype=float) for p in ("sprung", "unsprung")],
                 axis=-1)
    if not np.all(np.isfinite(y)):
        raise InputError(f"{corner}_accel_sprung_mps2 / _unsprung_mps2 must be finite (no NaN)")
    speed = float(np.mean(table["speed_mps"])) if speed_mps is None else float(speed_mps)
    if not np.isfinite(speed) or speed <= 0.5:
        raise InputError(f"speed must be > 0.5 m/s for a road model over time, got {speed:g} m/s")
    road = iso_road_model(gd_n0, speed=speed)
    model = discretize(car, road, dt=dt, method=method)
    x0 = _initial_state(table, corner, initial_road_m)
    if x0 is None:
        P0 = stationary_covariance(model)
    else:
        P0 = np.diag([1e-12] * 5 + [road.intensity / (2.0 * road.a2)])
    if filter_name == "KF":
        est = kalman_filter(y, model, measurement_std=sigma, state_covariance0=P0, state0=x0)
        return CornerRoadEstimate(road=est.road, estimate=est, weight=None)
    w = weight
    if w is None:
        w = covariance_constraint_weight(y[:constraint_window], model, measurement_std=sigma,
                                         state_covariance0=P0, state0=x0, bounds=(1e-8, 1e12), iterations=16)
    est = mme_kalman_filter(y, model, measurement_std=sigma, weight=w, state_covariance0=P0, state0=x0)
    return CornerRoadEstimate(road=est.road, estimate=est, weight=float(w))


def highpass(signal: npt.ArrayLike, *, dt: float, cutoff_hz: float) -> np.ndarray:
    """Zero-phase 4th-order Butterworth high-pass over the last axis (time).

    Used to score the estimate without the road content the accelerations barely see
    (below :data:`HIGHPASS_CUTOFF_CYCLES_PER_M` times the speed). dt in s, cutoff in Hz.
    """
    if not 0.0 < cutoff_hz < 0.5 / dt:
        raise InputError(f"cutoff_hz must be in (0, {0.5 / dt:g}) Hz, got {cutoff_hz!r}")
    sos = butter(4, cutoff_hz, btype="highpass", fs=1.0 / dt, output="sos")
    return sosfiltfilt(sos, np.asarray(signal, dtype=float), axis=-1)


def road_from_tracks(
    x_left: npt.ArrayLike, z_left: npt.ArrayLike, x_right: npt.ArrayLike, z_right: npt.ArrayLike,
    *, spacing_m: float,
) -> Road:
    """Two estimated tracks (over the wheels' x) as a road file's uniform grid.

    The grid spans the stretch both wheels covered, at `spacing_m`; each track is linearly
    interpolated from its wheel's path (x must increase: the car drives forward).
    """
    spacing_m = float(spacing_m)
    if not np.isfinite(spacing_m) or spacing_m <= 0.0:
        raise InputError(f"spacing_m must be a finite number > 0 m, got {spacing_m!r}")
    tracks = []
    for name, x, z in (("left", x_left, z_left), ("right", x_right, z_right)):
        x, z = np.asarray(x, dtype=float), np.asarray(z, dtype=float)
        if np.any(np.diff(x) <= 0.0):
            raise InputError(f"{name} wheel's x must increase strictly (the car must drive forward)")
        tracks.append((x, z))
    lo = max(tracks[0][0][0], tracks[1][0][0])
    hi = min(tracks[0][0][-1], tracks[1][0][-1])
    n = int(np.floor((hi - lo) / spacing_m + 1e-9)) + 1
    if n < 16:
        raise InputError(f"the wheels covered {hi - lo:.3g} m in common: too short for a road file")
    grid = lo + np.arange(n) * spacing_m
    return Road(x=grid, z=np.vstack([np.interp(grid, x, z) for x, z in tracks]))


def estimate_run_road(
    run_path,
    *,
    road_class: str = "C",
    filter_name: str = "KF",
    measurement_std: float | None = None,
    axle: str = "front",
    skip_s: float = 2.0,
    spacing_m: float = 0.05,
) -> tuple[Road, dict]:
    """Estimate both tracks of a run's road from one axle's accelerometers; a road file's content.

    The left track from the left corner, the right from the right; each filter is
    :func:`estimate_corner_road` on the SUV's nominal quarter car of that corner
    (:func:`corner_quarter_car`, the vehicle file's values without the run's loads or
    overrides: the paper's filter keeps the nominal mass) at the corner's mean recorded
    pressure, with an unknown start (stationary prior: the filter is not told the road).
    The estimate x̂_r(t) is placed at the wheel centre's x(t) (:func:`wheel_path`) and
    resampled onto a uniform grid (:func:`road_from_tracks`).

    Parameters
    ----------
    run_path : path
        Run file (``suvtwin simulate``).
    road_class : str
        ISO 8608 class A–H whose level the filter's road model assumes.
    filter_name : {"KF", "MME&KF"}
    measurement_std : float, optional
        Accelerometer noise σ the filter assumes, m/s² (default: the run's scenario noise,
        or 0.5 m/s² when it is zero or unknown).
    axle : {"front", "rear"}
    skip_s : float
        Leading seconds not used (the car settling from its placement), s, ≥ 0.
    spacing_m : float
        Grid spacing of the road file, m (> 0).

    Returns
    -------
    (Road, dict)
        The estimated road and what was used (class, filter, σ, pressures, W).
    """
    from suvtwin.mjcf.tire import load_tire
    from suvtwin.mjcf.vehicle import load_vehicle
    from suvtwin.pipeline.estimation import run_accel_noise
    from suvtwin.pipeline.simulator import read_run
    from suvtwin.roads.iso8608 import class_level

    if axle not in ("front", "rear"):
        raise InputError(f"axle must be 'front' or 'rear', got {axle!r}")
    if not np.isfinite(skip_s) or skip_s < 0.0:
        raise InputError(f"skip_s must be a finite number >= 0 s, got {skip_s!r}")
    gd = class_level(road_class)
    table, meta = read_run(run_path)
    if measurement_std is None:
        measurement_std = run_accel_noise(meta) or 0.5
    t = np.asarray(table["t_s"], dtype=float)
    keep = t >= t[0] + skip_s - 1e-9
    if keep.sum() < 16:
        raise InputError(f"skip_s = {skip_s:g} s leaves {int(keep.sum())} samples of the run; need >= 16")
    table = table[keep].reset_index(drop=True)
    vehicle = load_vehicle()
    tire = load_tire(vehicle.tire_file)
    corners = ("fl", "fr") if axle == "front" else ("rl", "rr")
    tracks, info = [], {"road_class": road_class, "gd_n0_m3": gd, "filter": filter_name,
                        "measurement_std_mps2": float(measurement_std), "axle": axle, "skip_s": skip_s,
                        "start": "unknown (stationary prior)", "corners": {}}
    for corner in corners:
        pressure = float(np.mean(table[f"{corner}_pressure_kpa"])) * 1e3
        car, sources = corner_quarter_car(vehicle, tire, corner=corner, pressure_pa=pressure)
        est = estimate_corner_road(table, car, gd_n0=gd, corner=corner, measurement_std=measurement_std,
                                   filter_name=filter_name)
        if not np.all(np.isfinite(est.road)):
            raise RunError(f"the {filter_name} diverged on corner {corner}")
        x, _ = wheel_path(table, vehicle, corner=corner)
        tracks += [x, est.road]
        info["corners"][corner] = {"pressure_kpa": pressure / 1e3, "weight_W": est.weight, "car": sources}
    return road_from_tracks(*tracks, spacing_m=spacing_m), info


# --- Table 2 of Wang et al. 2017 on the SUV (the bench and the campaign) ----------------------

STUDY_CLASSES = ("B", "C", "D")
STUDY_MASS_CHANGES = (0.0, 180.0, -180.0)  # kg, Table 2
STUDY_SETTINGS = {"speed_kmh": 40.0, "duration_s": 12.0, "settle_s": 2.0, "sigma_mps2": 0.02,
                  "pressure_kpa": 250.0, "corner": "fl", "grid_m": 0.05}
"""The study's runs: 12 s at 40 km/h (the first 2 s dropped), σ = 0.02 m/s², 250 kPa, the
front-left corner; estimated tracks classified on a 0.05 m grid."""

PAPER_TABLE2 = {  # Wang et al. 2017, Table 2 (simulation), error STD %: (KF, MME&KF)
    "B": {0.0: (7.3, 3.3), 180.0: (7.6, 3.7), -180.0: (10.3, 5.5)},
    "C": {0.0: (8.1, 4.6), 180.0: (9.5, 5.2), -180.0: (12.1, 8.3)},
    "D": {0.0: (10.5, 6.5), 180.0: (12.8, 7.9), -180.0: (16.4, 11.5)},
}


def study_scenario(road_class: str, delta_m: float, seed: int):
    """The run of one cell and seed: +Δm a scenario load at the chassis CoG, −Δm the chassis
    mass lowered by Δm (a vehicle override: loads cannot be negative)."""
    from suvtwin.mjcf.vehicle import load_vehicle
    from suvtwin.pipeline.scenario import parse_scenario

    s = STUDY_SETTINGS
    data = {
        "duration_s": s["duration_s"], "seed": seed, "speed_kmh": s["speed_kmh"],
        "pressure_kpa": s["pressure_kpa"],
        "road": {"segments": [{"length_m": 200.0, "road_class": road_class}]},
        "noise": {"accel_sprung_mps2": s["sigma_mps2"], "accel_unsprung_mps2": s["sigma_mps2"]},
    }
    if delta_m > 0:
        data["load"] = [{"mass_kg": delta_m, "position_m": [0.0, 0.0, 0.0]}]
    elif delta_m < 0:
        data["vehicle"] = {"chassis": {"mass": load_vehicle().chassis.mass + delta_m}}
    return parse_scenario(data)


def _stats(values) -> dict:
    v = np.asarray(values, dtype=float)
    spread = np.std(v, ddof=1) if v.size > 1 else 0.0
    return {"mean": float(f"{np.mean(v):.4g}"), "std": float(f"{spread:.3g}")}


def _class_of(x: np.ndarray, z: np.ndarray, grid_m: float) -> str:
    from suvtwin.roads.roughness import classify_profile

    grid = np.arange(x[0], x[-1], grid_m)
    return classify_profile(np.interp(grid, x, z), grid_m).road_class


def mujoco_study(
    seeds: list[int],
    *,
    classes: tuple[str, ...] = STUDY_CLASSES,
    mass_changes: tuple[float, ...] = STUDY_MASS_CHANGES,
    variants: bool = False,
) -> dict:
    """Wang et al. 2017's Table 2 on the MuJoCo SUV's front-left corner (docs/road_estimation.md).

    Per class and Δm, over `seeds`: the error STD % (100·std(x̂_r − x_r)/std(x_r)) of the KF
    and the MME&KF (G = e₂ fed through, eq. 20's W against S_k on the first 2 s), known
    start, against the raw and the enveloped heightfield under the tyre, and the same after
    :func:`highpass` at :data:`HIGHPASS_CUTOFF_CYCLES_PER_M` × speed (``_hp``); the class of the true and the
    estimated tracks; the front-left corner's measured share of Δm. `variants`: also the
    unknown start, the same KF on its own linear quarter car (the corner's share of Δm)
    driven by the same raw road, and the classes found by the KF with an unknown start and
    by a KF told class C. The first class, Δm and seed give ``example``: the true
    and estimated road over the wheel's x (every 10th sample).
    """
    from suvtwin.estimators.road_estimation import error_std_percent, simulate_quarter_car
    from suvtwin.mjcf.tire import load_tire
    from suvtwin.mjcf.vehicle import GRAVITY, load_vehicle
    from suvtwin.pipeline.simulator import simulate
    from suvtwin.roads.iso8608 import class_level

    if not seeds:
        raise InputError("seeds must hold at least one seed (>= 0)")
    s = STUDY_SETTINGS
    corner, sigma = s["corner"], s["sigma_mps2"]
    vehicle = load_vehicle()
    tire = load_tire(vehicle.tire_file)
    car, sources = corner_quarter_car(vehicle, tire, corner=corner, pressure_pa=s["pressure_kpa"] * 1e3)
    corner_share = vehicle.sprung_mass_corner[_corner_index(corner)] / vehicle.chassis.mass
    rows, nominal_load, example = [], {}, None
    sim_wall = 0.0
    for road_class in classes:
        gd = class_level(road_class)
        for dm in mass_changes:
            acc: dict[str, list] = {}
            found = {"truth": [], "KF": [], "MME&KF": []}
            if variants:
                found |= {"KF unknown start": [], "KF told C": []}
            weights, corner_dm = [], []

            def add(key, value, acc=acc):
                acc.setdefault(key, []).append(float(value))

            for seed in seeds:
                sc = study_scenario(road_class, dm, seed)
                t0 = time.perf_counter()
                table = simulate(sc).table
                sim_wall += time.perf_counter() - t0
                truth = road_under_wheel(sc, table, corner=corner)
                keep = int(round(s["settle_s"] * sc.output_rate_hz))
                tab = table.iloc[keep:].reset_index(drop=True)
                raw, env, x = truth.raw[keep:], truth.enveloped[keep:], truth.x[keep:]
                dt = 1.0 / sc.output_rate_hz
                fc = HIGHPASS_CUTOFF_CYCLES_PER_M * float(np.mean(tab["speed_mps"]))
                raw_hp, env_hp = highpass(raw, dt=dt, cutoff_hz=fc), highpass(env, dt=dt, cutoff_hz=fc)
                fz = float(np.mean(tab[f"{corner}_tire_fz_n"]))
                if dm == 0.0:
                    nominal_load[(road_class, seed)] = fz
                if (road_class, seed) in nominal_load:
                    corner_dm.append((fz - nominal_load[(road_class, seed)]) / GRAVITY)
                found["truth"].append(_class_of(x, raw, s["grid_m"]))
                estimates = {}
                for name in FILTERS:
                    for start, label in ((raw[0], "known"), (None, "unknown")):
                        if label == "unknown" and not variants:
                            continue
                        est = estimate_corner_road(tab, car, gd_n0=gd, corner=corner, measurement_std=sigma,
                                                   filter_name=name, initial_road_m=start)
                        if name == "MME&KF" and label == "known":
                            weights.append(est.weight)
                        zh = est.road
                        if not np.all(np.isfinite(zh)):
                            add(f"{name}|{label}|raw", np.inf)
                            continue
                        add(f"{name}|{label}|raw", error_std_percent(raw, zh))
                        add(f"{name}|{label}|enveloped", error_std_percent(env, zh))
                        zh_hp = highpass(zh, dt=dt, cutoff_hz=fc)
                        add(f"{name}|{label}|raw_hp", error_std_percent(raw_hp, zh_hp))
                        add(f"{name}|{label}|enveloped_hp", error_std_percent(env_hp, zh_hp))
                        if label == "known":
                            found[name].append(_class_of(x, zh, s["grid_m"]))
                            estimates[name] = zh
                        elif name == "KF":
                            found["KF unknown start"].append(_class_of(x, zh, s["grid_m"]))
                if example is None and len(estimates) == len(FILTERS):
                    step = 10
                    example = {"class": road_class, "delta_m_kg": dm, "seed": seed, "x_m": x[::step].tolist(),
                               "raw_m": raw[::step].tolist(), "enveloped_m": env[::step].tolist(),
                               **{f"{n}_m": z[::step].tolist() for n, z in estimates.items()}}
                if variants:  # the class a KF told class C finds (known start)
                    told = estimate_corner_road(tab, car, gd_n0=class_level("C"), corner=corner,
                                                measurement_std=sigma, initial_road_m=raw[0])
                    found["KF told C"].append(_class_of(x, told.road, s["grid_m"]))
                if variants:  # the filter's own linear quarter car (corner share of Δm) on the same road
                    qc = car.with_sprung_mass(car.sprung_mass + corner_share * dm)
                    z0 = raw - raw[0]
                    y = simulate_quarter_car(qc, z0, dt=dt).accelerations[0]
                    noise_rng = np.random.default_rng([seed, STUDY_CLASSES.index(road_class), 7])
                    y = y + sigma * noise_rng.standard_normal(y.shape)
                    road_model = iso_road_model(gd, speed=float(np.mean(tab["speed_mps"])))
                    model = discretize(car, road_model, dt=dt)
                    P0 = np.diag([1e-12] * 5 + [road_model.intensity / (2.0 * road_model.a2)])
                    zq = kalman_filter(y, model, measurement_std=sigma, state_covariance0=P0).road
                    add("quarter_car|KF|known|raw", error_std_percent(z0, zq))
                    add("quarter_car|KF|known|raw_hp", error_std_percent(highpass(z0, dt=dt, cutoff_hz=fc),
                                                                         highpass(zq, dt=dt, cutoff_hz=fc)))
                add("road_std_mm", 1e3 * np.std(raw))
                add("enveloped_minus_raw_std_mm", 1e3 * np.std(env - raw))
            paper = PAPER_TABLE2.get(road_class, {}).get(dm)
            row = {"class": road_class, "delta_m_kg": dm,
                   "paper": dict(zip(FILTERS, paper, strict=True)) if paper else None,
                   "front_left_delta_m_kg": _stats(corner_dm) if corner_dm else None,
                   "W_MME&KF": [float(f"{w:.3g}") for w in weights],
                   "classes": found}
            for key, values in acc.items():
                v = np.asarray(values)
                row[key] = _stats(v) if np.all(np.isfinite(v)) else "diverged"
            rows.append(row)
    return {
        "settings": {**STUDY_SETTINGS, "seeds": list(seeds),
                     "highpass_cycles_per_m": HIGHPASS_CUTOFF_CYCLES_PER_M,
                     "filter_car": sources,
                     "mme": "G = e2, fed through to the body acceleration; W from eq. 20 against S_k on "
                            "the first 2 s",
                     "truth": "raw: heightfield at the wheel centre; "
                              "enveloped: the tyre model's contact-patch height",
                     "error_std": "100*std(xr_hat - xr)/std(xr) per run; mean and std over seeds"},
        "table": rows,
        "example": example,
        "simulation_wall_s": round(sim_wall, 1),
    }
