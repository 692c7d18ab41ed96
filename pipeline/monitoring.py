"""Running the online tyre-pressure monitor on a run file: the glue between files and the monitor.

Usual call: ``result = monitor_run("run.parquet", placard_kpa=230)``; ``write_monitor(result, path)``.

A run file is the simulator's Parquet or any Parquet with ``t_s`` (uniform, increasing),
``speed_mps`` and each corner's ``{c}_accel_sprung_mps2`` / ``{c}_accel_unsprung_mps2``
(NaN where a sample is missing: such segments are skipped, not refused). The file is fed to
:class:`suvtwin.estimators.monitor.TyreMonitor` in chunks of ``chunk_s`` seconds, as a car
would stream it; the result does not depend on the chunk length. Each corner's model is
:func:`suvtwin.pipeline.estimation.linear_corner_model` with the run's extra load (from its
metadata, if any) and the run's tyre.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import norm

from suvtwin.errors import InputError
from suvtwin.estimators.deflation import DeflationRule, RadiusEvidence, deflation_warnings
from suvtwin.estimators.force_closure import ClosureConfig
from suvtwin.estimators.monitor import SKIP_REASONS, TAIL_LEVELS, MonitorConfig, MonitorUpdate, TyreMonitor
from suvtwin.estimators.radius_fusion import RadiusModel, vibration_lag_kpa
from suvtwin.estimators.rolling_radius import RadiusConfig, RadiusUpdate, RollingRadius, load_share
from suvtwin.files import atomic_write, iter_parquet_batches, read_parquet_schema
from suvtwin.mjcf.tire import effective_rolling_radius, load_tire
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.estimation import (
    TIME_HEAD_STEPS,
    check_streamed_speed,
    check_time_chunks,
    corner_sprung_mass,
    full_car_model,
    linear_corner_model,
    run_accel_noise,
    run_load_and_tire,
    run_loads,
    run_vehicle,
    static_travels,
    static_wheel_loads,
    streamed_speed,
)
from suvtwin.tire_stiffness import tire_stiffness_of

__all__ = [
    "CORNER_MODELS", "BestEstimate", "MonitorResult", "RADIUS_COLUMNS", "RADIUS_OPTIONAL_COLUMNS",
    "RADIUS_WHEEL_COLUMNS", "ROAD_WAVINESS",
    "best_estimate", "corner_models", "monitor_run", "monitor_signals", "radius_evidence", "tyre_load_share",
    "wheel_positions", "write_monitor",
]  # fmt: skip

RADIUS_COLUMNS = ("yaw_rate_radps", "lat_accel_mps2", "long_accel_mps2")
"""Besides each wheel's ``{c}_wheel_speed_radps``, the columns the radius analysis reads."""

RADIUS_WHEEL_COLUMNS = tuple(f"{c}_wheel_speed_radps" for c in CORNERS) + RADIUS_COLUMNS
"""Every column the radius analysis reads: the four wheel speeds, then :data:`RADIUS_COLUMNS`. It needs
the wheel speeds and the yaw rate; the lateral and longitudinal accelerations, where a file lacks
them, come from the wheels' kinematics (:class:`~suvtwin.estimators.rolling_radius.RollingRadius`)."""

RADIUS_OPTIONAL_COLUMNS = ("lat_accel_mps2", "long_accel_mps2")
"""The columns of :data:`RADIUS_WHEEL_COLUMNS` a run file may lack (the analysis is then gated on the
wheels' kinematics)."""

RADIUS_MODEL_GRID_KPA = np.arange(50.0, 452.0, 2.0)
"""Pressures at which the tyre model's effective rolling radius is tabulated for the radius fusion, kPa."""

_METADATA_KEY = b"suvtwin.monitor"


@dataclass(frozen=True)
class MonitorResult:
    """The monitor's table (one row per update; see :func:`monitor_run`) and what made it."""

    table: pd.DataFrame
    metadata: dict
    update: MonitorUpdate


CORNER_MODELS = ("full_car", "roll_plane")
"""How the monitor models each corner's spectrum: ``full_car`` (the corner in the linear full car on two
tracks, :mod:`suvtwin.estimators.full_car`; default) or ``roll_plane`` (half a heave and half a roll
quarter car, :class:`suvtwin.estimators.joint.LinearQuarterCar`; the model before, kept to compare)."""


def corner_models(
    corners: tuple[str, ...], *, loads=(), tire_file: str | Path | None = None, vehicle=None,
    corner_model: str = "full_car",
):  # fmt: skip
    """The SUV's linear corner models of `corners` with extra `loads` on the chassis ((kg, (x, y, z) m)
    each, :func:`suvtwin.pipeline.estimation.run_loads`): their total mass shared as in paper 000
    eq. 2, each corner's static travel and tyre load under them; each placed in the car as a linear full car
    (:func:`suvtwin.pipeline.estimation.full_car_model`, loads included). `vehicle`: default the
    SUV's parameter file (:func:`suvtwin.pipeline.estimation.run_vehicle` gives a run's).
    `corner_model`: one of :data:`CORNER_MODELS` (``roll_plane``: not placed in the full car)."""
    if corner_model not in CORNER_MODELS:
        raise InputError(f"corner model must be one of {', '.join(CORNER_MODELS)}, got {corner_model!r}")
    load_kg = float(sum(m for m, _ in loads))
    car = full_car_model(vehicle, loads, tire_file=tire_file) if corner_model == "full_car" else None
    travel, wheel_loads = static_travels(loads, vehicle=vehicle), static_wheel_loads(loads, vehicle=vehicle)
    return [
        linear_corner_model(c, corner_sprung_mass(c, load_kg, vehicle=vehicle), tire_file=tire_file,
                            static_travel=float(travel[CORNERS.index(c)]), vehicle=vehicle, full_car=car,
                            static_load=float(wheel_loads[CORNERS.index(c)]))
        for c in corners
    ]  # fmt: skip


def assumed_accel_noise(
    config: MonitorConfig, recorded: float | None, given: float | None = None
) -> tuple[MonitorConfig, str]:
    """`config` with the accelerometer noise σ (m/s² per sample) the monitor assumes, and where it
    comes from: `given` if not None; else the noise the run `recorded` for its sensors
    (:func:`~suvtwin.pipeline.estimation.run_accel_noise`), never below `config`'s ``sigma_accel``
    (the figure the monitor was validated with: below it the likelihood would count at a precision
    the linear corner model does not have); `config`'s where nothing is recorded."""
    if given is not None:
        return replace(config, sigma_accel=float(given)), "given"
    if recorded is not None and recorded >= config.sigma_accel:
        return replace(config, sigma_accel=float(recorded)), "the run's sensors"
    return config, ("the monitor's floor (above the run's)" if recorded else "the monitor's default")


def stream_dt(t_s: np.ndarray) -> float:
    """The sampling interval of a record's time stamps `t_s` (s), the same whatever the record's length
    (the estimate at t must not depend on what follows t): 1/f for a whole rate f in Hz that the stamps'
    end-to-end mean interval gives to within 1e-4 (loggers sample at 100, 500, 1000 Hz; the end-to-end
    mean averages a stamp's jitter or float32 rounding out, ~2e-5 of an interval after 4 s at 1 kHz
    with ±5 % jitter), else the median of the first :data:`~suvtwin.pipeline.estimation.TIME_HEAD_STEPS`
    intervals to 12 significant digits (float stamps give medians that differ in the last bits with
    the record's length)."""
    t = np.asarray(t_s, dtype=float)
    if t.size < 2:
        raise InputError("a record needs at least two time stamps for its sampling interval")
    return _stream_interval(t.size, float(t[0]), float(t[-1]), np.diff(t[: TIME_HEAD_STEPS + 1]))


def _stream_interval(n: int, t0: float, t_end: float, head_steps: np.ndarray) -> float:
    """:func:`stream_dt` of a record of `n` stamps from `t0` to `t_end` (s) whose first intervals are
    `head_steps` (s)."""
    if t_end > t0:
        rate = (n - 1) / (t_end - t0)
        nominal = round(rate)
        if nominal >= 1 and abs(rate - nominal) <= 1e-4 * rate:
            return 1.0 / nominal
    return float(f"{np.median(head_steps):.12g}")


def monitor_signals(
    t_s: np.ndarray,
    speed_mps: np.ndarray,
    acc_sprung: np.ndarray,
    acc_unsprung: np.ndarray,
    *,
    corners: tuple[str, ...] = CORNERS,
    loads=(),
    tire_file: str | Path | None = None,
    config: MonitorConfig | None = None,
    chunk_s: float = 10.0,
    preview: bool = True,
    vehicle=None,
    corner_model: str = "full_car",
) -> tuple[TyreMonitor, MonitorUpdate]:
    """Stream arrays through a new monitor in chunks of `chunk_s` s; the monitor and all its rows.

    `acc_sprung`, `acc_unsprung`: (T, C) in the order of `corners`; `loads`: the extra loads on the
    chassis, (kg, (x, y, z) m from the CoG) each (:func:`corner_models`); `preview`: fuse each track's
    two tyres through its front→rear preview (when both its corners are monitored; default on,
    False: each corner on its own); `vehicle`:
    the car's parameters (default the SUV's parameter file); `corner_model`: :data:`CORNER_MODELS`."""
    t = np.asarray(t_s, dtype=float)
    if t.size < 2:
        raise InputError("a run needs at least two samples")
    dt = stream_dt(t)
    monitor = _new_monitor(dt, corners, loads=loads, tire_file=tire_file, config=config, preview=preview,
                           vehicle=vehicle or load_vehicle(), corner_model=corner_model)  # fmt: skip
    step = max(int(round(chunk_s / dt)), 1)
    parts = [
        monitor.update(
            t[i : i + step], speed_mps[i : i + step], acc_sprung[i : i + step], acc_unsprung[i : i + step]
        )
        for i in range(0, t.size, step)
    ]
    return monitor, MonitorUpdate.concatenate(parts)


def run_damper_lag(meta: dict) -> float:
    """The damper's timing against the accelerometers in a run of this simulator, s: half its step.

    MuJoCo integrates with semi-implicit Euler: a step's damper force is taken at the velocity the
    step starts with, while the accelerations the sensors report are the step's, whose velocity lies
    half a step later on average. The force closure (:mod:`suvtwin.estimators.force_closure`) reads
    the damper's force at the rate it is given, so it is told this lag; with none it read the tyres
    +4.7 ± 4.3 kPa high after 30 s on the ``constant`` runs, with the lag read from the data (the
    least J of 0–1 ms) −0.0 ± 3.1. 0 for a record without the simulator's scenario (a measured car's
    damper timing is its own, not known here)."""
    step = (meta.get("scenario") or {}).get("timestep_s")
    return 0.5 * float(step) if isinstance(step, (int, float)) and step > 0 else 0.0


def _new_monitor(dt, corners, *, loads, tire_file, config, preview, vehicle, corner_model,
                 damper_lag_s: float = 0.0) -> TyreMonitor:  # fmt: skip
    """A monitor that has seen nothing, of `corners` with each track's preview (and the force closure)
    if `preview`; the closure told the damper's timing `damper_lag_s` (s, :func:`run_damper_lag`)."""
    tracks = [(corners.index(f), corners.index(r)) for f, r in (("fl", "rl"), ("fr", "rr"))
              if f in corners and r in corners]  # fmt: skip
    return TyreMonitor(
        corner_models(corners, loads=loads, tire_file=tire_file, vehicle=vehicle, corner_model=corner_model),
        dt=dt, config=config,
        tire=[tire_stiffness_of(tire_file)] * len(corners), names=corners,
        tracks=tracks if preview else (), wheelbase_m=vehicle.wheelbase,
        closure_config=ClosureConfig(damper_lag_s=damper_lag_s),
    )  # fmt: skip


def wheel_positions(vehicle) -> np.ndarray:
    """The wheel centres fl, fr, rl, rr from the rear axle's centre, (4, 2) m (x forward, y left):
    what :class:`~suvtwin.estimators.rolling_radius.RollingRadius` takes."""
    front, rear = vehicle.chassis.track_front / 2, vehicle.chassis.track_rear / 2
    return np.array([[vehicle.wheelbase, front], [vehicle.wheelbase, -front], [0.0, rear], [0.0, -rear]])


def tyre_load_share(
    acc_sprung: np.ndarray, acc_unsprung: np.ndarray, *, loads=(), vehicle, static_loads=None
) -> np.ndarray:
    """Each sample's tyre load over its static load at the four corners (n, 4), from their sprung and
    unsprung accelerations (n, 4) m/s² (:func:`~suvtwin.estimators.rolling_radius.load_share`): the
    corners' sprung masses with the extra `loads` (paper 000 eq. 2), the vehicle's unsprung masses,
    the static loads with the loads where they sit (`static_loads`, N, (4,): given by a caller that
    feeds chunks; default :func:`~suvtwin.pipeline.estimation.static_wheel_loads`, ~1 ms)."""
    load_kg = float(sum(m for m, _ in loads))
    static = static_wheel_loads(loads, vehicle=vehicle) if static_loads is None else static_loads
    return load_share(
        acc_sprung, acc_unsprung, [corner_sprung_mass(c, load_kg, vehicle=vehicle) for c in CORNERS],
        vehicle.unsprung_mass, static,
    )  # fmt: skip


def radius_evidence(
    frame: pd.DataFrame,
    update_t_s: np.ndarray,
    *,
    loads=(),
    vehicle,
    tire_file: str | Path | None,
    placard_kpa: float | None,
    rule: DeflationRule,
    config: RadiusConfig | None = None,
) -> tuple[RadiusEvidence, RollingRadius]:
    """The radius analysis of a run's four wheels (:class:`~suvtwin.estimators.rolling_radius.RollingRadius`)
    at the monitor's update times `update_t_s` (the last block ending at or before each), and what the
    tyre model says of it: each tyre's log radius per kPa (MF-Tyre 6.1's effective rolling radius at
    the corner's static load, the secant from the reference to the detection threshold; the
    reference the placard, else the tyre's nominal pressure; for the learned references' route) and
    each tyre's log radius at its load on :data:`RADIUS_MODEL_GRID_KPA` (the model the estimates are
    fused against, :func:`~suvtwin.estimators.radius_fusion.fuse_with_radii`). `frame`: ``t_s``,
    ``{c}_wheel_speed_radps`` and :data:`RADIUS_COLUMNS`, and where it has every corner's
    ``{c}_accel_sprung_mps2`` and ``{c}_accel_unsprung_mps2``, each sample's tyre loads from them
    (:func:`tyre_load_share`): a sample where a wheel is (nearly) off the ground does not count;
    `loads`: the extra loads on the chassis (their positions share them among the wheels,
    :func:`~suvtwin.pipeline.estimation.corner_static_load`)."""
    t = frame["t_s"].to_numpy(dtype=float)
    tire = load_tire(tire_file)
    dt = stream_dt(t)
    analysis = RollingRadius(wheel_positions(vehicle), dt, tire.unloaded_radius, config)
    accels = [[f"{c}_accel_{w}_mps2" for c in CORNERS] for w in ("sprung", "unsprung")]
    acc_s = acc_u = None
    if all(k in frame.columns for k in accels[0] + accels[1]):  # each sample's tyre loads
        acc_s, acc_u = (frame[names].to_numpy(dtype=float) for names in accels)
    values = {k: frame[k].to_numpy(dtype=float) for k in RADIUS_WHEEL_COLUMNS if k in frame.columns}
    rows = _feed_radius(analysis, t, values, acc_s, acc_u, loads=loads, vehicle=vehicle,
                        static=static_wheel_loads(loads, vehicle=vehicle))  # fmt: skip
    evidence = _evidence_of_rows(rows, dt, update_t_s, loads=loads, vehicle=vehicle, tire=tire,
                                 placard_kpa=placard_kpa, rule=rule)  # fmt: skip
    return evidence, analysis


@dataclass(frozen=True)
class BestEstimate:
    """Each tyre's pressure as the monitor reports it (K updates × C corners, kPa): `pressure_kpa`,
    `sigma_kpa`, the 5 % / 95 % quantiles `lower_kpa` / `upper_kpa`, `observable` (σ within the
    monitor's ``observable_sigma_kpa``) and `with_radii` (bool: the wheels' radii are fused in)."""

    pressure_kpa: np.ndarray
    sigma_kpa: np.ndarray
    lower_kpa: np.ndarray
    upper_kpa: np.ndarray
    observable: np.ndarray
    with_radii: np.ndarray


def best_estimate(update: MonitorUpdate, warnings=None, observable_sigma_kpa: float = 25.0) -> BestEstimate:
    """The best pressure estimate the monitor has per update and tyre: the vibration estimate fused with
    the wheels' radii (`warnings`' ``fused_kpa`` and ``fused_sigma_kpa``,
    :func:`~suvtwin.estimators.deflation.deflation_warnings` with radius evidence) where there is one,
    else the vibration's own (`update`: its posterior's mean, σ and quantiles; with the force closure
    where the monitor has it). The fusion is Gaussian (a generalized least-squares estimate), so its
    quantiles at :data:`~suvtwin.estimators.monitor.TAIL_LEVELS` are the normal's. On the
    ``bench/monitor_mujoco.py`` sets the fused estimate meets every accuracy and coverage target and
    the vibration's own does not (e.g. 100 ``constant`` runs: ±6.5 / 3.3 kPa at 10 / 30 s against
    ±10.5 / 6.7; a slow leak's ±2σ coverage 96 % against 69 %), hence the default."""
    own = update.pressure_pa / 1e3
    own_sigma = update.pressure_sigma_pa / 1e3
    lower, upper = update.pressure_lower_pa / 1e3, update.pressure_upper_pa / 1e3
    here = np.zeros(own.shape, dtype=bool)
    p, sigma = own, own_sigma
    if warnings is not None:
        fused, fused_sigma = np.asarray(warnings.fused_kpa), np.asarray(warnings.fused_sigma_kpa)
        here = np.isfinite(fused) & np.isfinite(fused_sigma)
        p, sigma = np.where(here, fused, own), np.where(here, fused_sigma, own_sigma)
        lo, hi = (norm.ppf(q) for q in TAIL_LEVELS)
        lower = np.where(here, fused + lo * fused_sigma, lower)
        upper = np.where(here, fused + hi * fused_sigma, upper)
    observable = np.where(here, sigma <= observable_sigma_kpa, update.observable)
    return BestEstimate(pressure_kpa=p, sigma_kpa=sigma, lower_kpa=lower, upper_kpa=upper,
                        observable=observable, with_radii=here)  # fmt: skip


def _feed_radius(analysis, t, values, acc_s, acc_u, *, loads, vehicle, static) -> RadiusUpdate:
    """The radius analysis `analysis` fed one chunk: time `t`, the columns of
    :data:`RADIUS_WHEEL_COLUMNS` in `values`, and where the four corners' accelerations (n, 4) are
    given, each sample's tyre loads from them (:func:`tyre_load_share`, static loads `static`, N)."""
    share = None
    if acc_s is not None and acc_u is not None:
        share = tyre_load_share(acc_s, acc_u, loads=loads, vehicle=vehicle, static_loads=static)
    return analysis.update(
        t, np.column_stack([values[f"{c}_wheel_speed_radps"] for c in CORNERS]),
        *(values.get(k, np.full(t.size, np.nan)) for k in RADIUS_COLUMNS), load_share=share,
    )  # fmt: skip


def _evidence_of_rows(rows, dt, update_t_s, *, loads, vehicle, tire, placard_kpa, rule) -> RadiusEvidence:
    """What the tyre model says of the radius analysis's rows `rows` at the update times
    (:func:`radius_evidence`)."""
    at = np.searchsorted(rows.t_s, np.asarray(update_t_s) + 0.5 * dt, side="right") - 1
    excess = np.where(at[:, None] >= 0, rows.excess[np.maximum(at, 0)], np.nan)
    # a block held aside as a possible change: that wheel's estimate may be its mean or the block, and
    # the others' memories, which took the same block in, may hold 1/(m − 1) of its step (m the wheels
    # the excesses are over: all, or all but a dead sensor's)
    held = np.abs(np.where(at[:, None] >= 0, rows.held[np.maximum(at, 0)], 0.0))
    m = np.maximum(np.isfinite(excess).sum(axis=1, keepdims=True), 2)
    held = held + (held.sum(axis=1, keepdims=True) - held) / (m - 1)
    sigma = np.hypot(np.where(at[:, None] >= 0, rows.sigma[np.maximum(at, 0)], np.nan), held)
    tp = tire.to_array()
    wheel_loads = static_wheel_loads(loads, vehicle=vehicle)
    ref_pa = (placard_kpa * 1e3) if placard_kpa is not None else tire.nominal_pressure
    low_pa = (1.0 - rule.detect_fraction) * ref_pa
    log_re = np.log([[effective_rolling_radius(fz, q, tp) for q in (ref_pa, low_pa)] for fz in wheel_loads])
    gain = (log_re[:, 0] - log_re[:, 1]) / ((ref_pa - low_pa) / 1e3)
    grid = RADIUS_MODEL_GRID_KPA
    model = RadiusModel(
        pressure_kpa=grid,
        log_radius=np.log([[effective_rolling_radius(fz, 1e3 * q, tp) for q in grid] for fz in wheel_loads]),
    )
    lag = vibration_lag_kpa(rows.t_s - 0.5 * dt, rows.excess, rows.changes, gain, update_t_s, held=rows.held,
                            trend=rows.trend)  # fmt: skip
    return RadiusEvidence(excess=excess, sigma=sigma, gain_per_kpa=gain, model=model, lag_kpa=lag)


ROAD_WAVINESS = {"iso": {}, "free": {"waviness_iso_weight": 0.0, "waviness_points": 7}}
"""The monitor's prior on the road's waviness w (the exponent of its PSD), by name: ``iso`` (the
:class:`~suvtwin.estimators.monitor.MonitorConfig` default: w = 2, ISO 8608's classes, with
probability 0.8, else uniform on 1.5–3 at 5 points) or ``free`` (uniform on 1.5–3 at 7 points, no
weight at 2). Within 10–30 s of data a corner's spectrum barely tells w from k_t, so the prior
decides: ``iso`` is sharper on ISO roads and biased, its σ too small, where w differs (bench
``monitor_waviness.py``)."""


def monitor_run(
    path: str | Path,
    *,
    corners: tuple[str, ...] = CORNERS,
    placard_kpa: float | None = None,
    reset_at_s: float | None = None,
    config: MonitorConfig | None = None,
    rule: DeflationRule | None = None,
    chunk_s: float = 10.0,
    preview: bool = True,
    corner_model: str = "full_car",
    radius: bool = True,
    accel_noise_mps2: float | None = None,
    road_waviness: str = "iso",
    force_closure: bool = True,
) -> MonitorResult:
    """Run the monitor and the deflation warning on a run file.

    The warning's reference is `placard_kpa` (the same for every tyre) if given, else what the
    monitor learns after a driver reset at `reset_at_s` (default the run's start). The table has
    one row per update: ``t_s``, ``speed_mps``, per corner ``{c}_pressure_hat_kpa``,
    ``{c}_pressure_sigma_kpa``, ``{c}_pressure_lower_kpa`` and ``{c}_pressure_upper_kpa`` (the 5 % and
    95 % quantiles), ``{c}_observable`` and ``{c}_with_radii``: the monitor's best estimate
    (:func:`best_estimate`: fused with the wheels' radii where they are, else the vibration's own);
    ``{c}_vibration_pressure_kpa``, ``{c}_vibration_sigma_kpa``, ``{c}_vibration_lower_kpa``,
    ``{c}_vibration_upper_kpa`` and ``{c}_vibration_observable``: the vibration's own (the corners'
    spectra, the previews and the force closure, without the radii), ``{c}_status`` (what became of
    the segment:
    ``used`` or why skipped), ``{c}_reference_kpa``, ``{c}_loss_probability``, ``{c}_warning``
    (latched), ``{c}_spring_rate_npm`` and ``{c}_tyre_contact`` (the suspension rate and tyre contact
    share the window was analysed with: :class:`~suvtwin.estimators.monitor.MonitorUpdate`), and the
    shared ``road_level_hat_m3``, ``waviness_hat``, ``track_coherence_hat`` (the left and right
    tracks' road coherence the monitor estimated) and ``common_loss_probability`` (the observable
    tyres' shared loss, :func:`~suvtwin.estimators.deflation.deflation_warnings`). `preview`: fuse
    each rear tyre with the front→rear preview of its track (:func:`monitor_signals`).
    `corner_model`: how each corner's spectrum is modelled, :data:`CORNER_MODELS`. `radius`: with all
    four corners and the run's wheel speeds and yaw rate (its accelerations where it has them, else
    the wheels' kinematics: :data:`RADIUS_WHEEL_COLUMNS`), fuse
    the radius analysis with the pressures (:func:`radius_evidence`; columns
    ``{c}_radius_excess_permille``, ``{c}_radius_sigma_permille``, ``{c}_fused_pressure_kpa`` and
    ``{c}_fused_sigma_kpa``: the pressure with the radii, against the tyre model within the tyres'
    spread, or once learned references are known against the radii when they were learned; the
    warning decides on it; and with a learned reference ``{c}_relative_loss_probability``: the
    tyre against the others since the radii's calibration after the reset). `accel_noise_mps2`: the
    accelerometers' white-noise σ per sample (m/s², 0.05–50) the monitor and its previews assume;
    None: the noise the run records for its sensors (:func:`~suvtwin.pipeline.estimation.run_accel_noise`,
    the simulator's scenario), never below `config`'s ``sigma_accel`` (the figure the monitor was
    validated with, 0.5 m/s² by default: below it the bands where the road's signal is weak would
    count at a precision the linear corner model does not have); `config`'s where the run records none.
    `road_waviness`: the prior on the road's waviness, :data:`ROAD_WAVINESS` (applied over `config`).
    `force_closure`: each track's two tyres also from the wheels' force balance and the road they share
    (:mod:`suvtwin.estimators.force_closure`; with `preview` and all four corners; applied over `config`).
    """
    unknown = [c for c in corners if c not in CORNERS]
    if unknown or not corners:
        raise InputError(f"corners must be among fl, fr, rl, rr, got {', '.join(corners) or 'none'}")
    if placard_kpa is not None and not (np.isfinite(placard_kpa) and 50.0 <= placard_kpa <= 500.0):
        raise InputError(f"--placard must be a pressure within 50–500 kPa, got {placard_kpa}")
    schema = read_parquet_schema(path, what="run file")
    needed = ["t_s", "speed_mps"] + [f"{c}_accel_{w}_mps2" for c in corners for w in ("sprung", "unsprung")]
    missing = [c for c in needed if c not in schema.names]
    if missing:
        raise InputError(f"run file {str(path)!r} lacks column(s) {', '.join(missing)}")
    wheel = [k for k in RADIUS_WHEEL_COLUMNS if k in schema.names]
    needed_radius = [k for k in RADIUS_WHEEL_COLUMNS if k not in RADIUS_OPTIONAL_COLUMNS]
    use_radius = radius and tuple(corners) == CORNERS and all(c in schema.names for c in needed_radius)
    # the time axis and the speed checked in chunks first (a record larger than memory; nothing is
    # run on a file that would be refused); a NaN speed is a gap the monitor skips, as is reversing;
    # an accelerometer beyond range is flagged per window
    def column(name: str):
        batches = iter_parquet_batches(path, what="run file", columns=[name], rows=1 << 16)
        return (batch.column(name).to_numpy(zero_copy_only=False).astype(float) for batch in batches)

    axis = check_time_chunks(lambda: column("t_s"), path)
    check_streamed_speed(column("speed_mps"), path)
    t0, t_end = axis.t0, axis.t_end
    if reset_at_s is not None and not (np.isfinite(reset_at_s) and t0 <= reset_at_s <= t_end):
        raise InputError(f"--reset-at must lie within the run, {t0:g}–{t_end:g} s, got {reset_at_s}")
    noise = accel_noise_mps2
    if noise is not None and not (np.isfinite(noise) and 0.05 <= noise <= 50.0):
        raise InputError(f"--accel-noise must be an accelerometer noise σ within 0.05–50 m/s², got {noise}")
    if road_waviness not in ROAD_WAVINESS:
        raise InputError(f"--road-waviness must be one of {', '.join(ROAD_WAVINESS)}, got {road_waviness!r}")
    raw = (schema.metadata or {}).get(b"suvtwin.run")
    meta = json.loads(raw) if raw else {}
    config = replace(config or MonitorConfig(), **ROAD_WAVINESS[road_waviness])
    if not force_closure:
        config = replace(config, force_closure=False)
    recorded = run_accel_noise(meta)
    config, noise_source = assumed_accel_noise(config, recorded, accel_noise_mps2)
    load, tire_file = run_load_and_tire(meta, path)
    loads = run_loads(meta)
    vehicle = run_vehicle(meta)
    dt = _stream_interval(axis.n, t0, t_end, axis.head_steps)
    monitor = _new_monitor(dt, corners, loads=loads, tire_file=tire_file, config=config, preview=preview,
                           vehicle=vehicle, corner_model=corner_model,
                           damper_lag_s=run_damper_lag(meta))  # fmt: skip
    tire = load_tire(tire_file)
    analysis = RollingRadius(wheel_positions(vehicle), dt, tire.unloaded_radius) if use_radius else None
    static = static_wheel_loads(loads, vehicle=vehicle)
    # streamed as a car would, in chunks of chunk_s (a Parquet batch ends early at a row group's end):
    # memory bounded by a chunk whatever the drive's length; neither the monitor's nor the radius
    # analysis's result depends on the chunks
    names_s = [f"{c}_accel_sprung_mps2" for c in corners]
    names_u = [f"{c}_accel_unsprung_mps2" for c in corners]
    columns = ["t_s", "speed_mps"] + names_s + names_u + (wheel if use_radius else [])
    parts, radius_rows, i = [], [], 0
    step = max(int(round(chunk_s / dt)), 1)
    # read in batches of 2^16 rows or more (a fifth less time than batches of a chunk: 0.8 against 1.0 s
    # for an hour's columns), fed a chunk at a time
    for batch in iter_parquet_batches(path, what="run file", columns=columns, rows=max(step, 1 << 16)):
        read = {name: np.asarray(batch.column(name).to_numpy(zero_copy_only=False), dtype=float)
                for name in columns}  # fmt: skip
        batch_s = np.column_stack([read[k] for k in names_s])  # (rows, C), a chunk's rows a view of it
        batch_u = np.column_stack([read[k] for k in names_u])
        for a in range(0, batch.num_rows, step):
            values = {name: column[a : a + step] for name, column in read.items()}
            t = values["t_s"]
            acc_s, acc_u = batch_s[a : a + step], batch_u[a : a + step]
            parts.append(monitor.update(t, streamed_speed(values["speed_mps"]), acc_s, acc_u))
            if analysis is not None:  # corners are CORNERS: each sample's tyre loads from its accelerometers
                radius_rows.append(_feed_radius(analysis, t, values, acc_s, acc_u, loads=loads,
                                                vehicle=vehicle, static=static))  # fmt: skip
        i += batch.num_rows
    if i != axis.n:
        raise InputError(f"run file {str(path)!r}: its columns hold {i} rows against {axis.n} of t_s")
    update = MonitorUpdate.concatenate(parts)
    rule = rule or DeflationRule(informed_sigma_kpa=config.observable_sigma_kpa)
    evidence = None
    if analysis is not None:
        rows = RadiusUpdate.concatenate(radius_rows, len(CORNERS))
        evidence = _evidence_of_rows(rows, dt, update.t_s, loads=loads, vehicle=vehicle, tire=tire,
                                     placard_kpa=placard_kpa, rule=rule)  # fmt: skip
    warn = deflation_warnings(
        update.t_s, update.pressure_pa / 1e3, update.pressure_sigma_pa / 1e3, update.observable,
        update.speed_mps,
        placard_kpa=placard_kpa, reset_at_s=t0 if reset_at_s is None else reset_at_s, rule=rule,
        upper_kpa=update.pressure_upper_pa / 1e3, upper_level=TAIL_LEVELS[1],
        tracks=[(corners.index(f), corners.index(r)) for f, r in (("fl", "rl"), ("fr", "rr"))
                if f in corners and r in corners],
        radius=evidence, track_coherence=update.track_coherence,
    )  # fmt: skip
    best = best_estimate(update, warn if evidence is not None else None, config.observable_sigma_kpa)
    columns: dict[str, np.ndarray] = {"t_s": update.t_s, "speed_mps": update.speed_mps}
    per_tyre = {  # (K, C) each: the estimate reported, then the vibration's own
        "pressure_hat_kpa": best.pressure_kpa, "pressure_sigma_kpa": best.sigma_kpa,
        "pressure_lower_kpa": best.lower_kpa, "pressure_upper_kpa": best.upper_kpa,
        "observable": best.observable, "with_radii": best.with_radii,
        "vibration_pressure_kpa": update.pressure_pa / 1e3,
        "vibration_sigma_kpa": update.pressure_sigma_pa / 1e3,
        "vibration_lower_kpa": update.pressure_lower_pa / 1e3,
        "vibration_upper_kpa": update.pressure_upper_pa / 1e3,
        "vibration_observable": update.observable,
    }  # fmt: skip
    for i, c in enumerate(corners):
        for name, values in per_tyre.items():
            columns[f"{c}_{name}"] = values[:, i]
        columns[f"{c}_status"] = np.array(SKIP_REASONS)[update.status[:, i]]
        columns[f"{c}_reference_kpa"] = warn.reference_kpa[:, i]
        columns[f"{c}_loss_probability"] = warn.probability[:, i]
        columns[f"{c}_warning"] = warn.warning[:, i]
        columns[f"{c}_spring_rate_npm"] = update.spring_rate[:, i]
        columns[f"{c}_tyre_contact"] = update.tyre_contact[:, i]
        columns[f"{c}_change_probability"] = update.change_probability[:, i]
        if evidence is not None:
            columns[f"{c}_radius_excess_permille"] = 1e3 * evidence.excess[:, i]
            columns[f"{c}_radius_sigma_permille"] = 1e3 * evidence.sigma[:, i]
            columns[f"{c}_fused_pressure_kpa"] = warn.fused_kpa[:, i]
            columns[f"{c}_fused_sigma_kpa"] = warn.fused_sigma_kpa[:, i]
            columns[f"{c}_relative_loss_probability"] = warn.relative_probability[:, i]
    columns["common_loss_probability"] = warn.common_probability
    columns["road_level_hat_m3"] = update.road_level
    columns["waviness_hat"] = update.waviness
    columns["track_coherence_hat"] = update.track_coherence
    counts = monitor.counts
    metadata = {
        "run_file": str(path),
        "run_off_road_share": meta.get("off_road_share"),  # wheels beyond the road strip (the simulator's)
        "corners": list(corners),
        "tire_file": tire_file,
        "load_kg": load,
        "corner_model": corner_model,
        "static_travel_mm": dict(zip(corners, [1e3 * m.static_travel for m in monitor.models], strict=True)),
        "placard_kpa": placard_kpa,
        "reset_at_s": None if placard_kpa is not None else float(t0 if reset_at_s is None else reset_at_s),
        "config": asdict(monitor.config),
        "road_waviness": road_waviness,
        "accel_noise": {"sigma_mps2": monitor.config.sigma_accel, "source": noise_source,
                        "recorded_mps2": recorded},
        "rule": asdict(rule),
        "segments": counts["segments"],
        "segment_status": {r: dict(zip(corners, counts[r].tolist(), strict=True)) for r in SKIP_REASONS},
        "changes": dict(zip(corners, counts["changes"].tolist(), strict=True)),
        # the force closure: its settings and, per tyre, its track's windows used and passed over
        "force_closure": None if monitor.closure_config is None else {
            "config": asdict(monitor.closure_config),
            "windows": dict(zip(corners, counts["closure_windows"].tolist(), strict=True)),
            "skipped": dict(zip(corners, counts["closure_skipped"].tolist(), strict=True)),
            # the short windows read where a span's windows were mostly not clear (a rough road)
            "short_windows": dict(zip(corners, counts["closure_short_windows"].tolist(), strict=True)),
        },
        "radius": None if evidence is None else {
            "config": asdict(analysis.config),
            "calibration": "tyre model at the placard" if placard_kpa is not None else "learned at the reset",
            "gain_per_kpa": dict(zip(corners, evidence.gain_per_kpa.tolist(), strict=True)),
            "substituted_samples": analysis.substituted_samples,
            # samples a wheel's speed was missing while another's was not: the radius analysis stops there
            "silent_wheel_samples": dict(zip(corners, analysis.silent_wheel_samples.tolist(), strict=True)),
        },
        "warnings": {
            c: (
                None
                if np.isnan(warn.warning_time_s[i])
                else {
                    "t_s": float(warn.warning_time_s[i]),
                    "loss_probability": float(warn.warning_probability[i]),
                    "pressure_hat_kpa": float(warn.warning_pressure_kpa[i]),
                    # None: warned by the radii before the vibration had learned a reference
                    "reference_kpa": None if np.isnan(warn.warning_reference_kpa[i])
                    else float(warn.warning_reference_kpa[i]),
                    "by": ("common loss" if warn.warning_common[i]
                           else "radii against the others" if warn.warning_relative[i] else "own"),
                }
            )
            for i, c in enumerate(corners)
        },  # fmt: skip
    }
    return MonitorResult(table=pd.DataFrame(columns), metadata=metadata, update=update)


def write_monitor(result: MonitorResult, path: str | Path) -> None:
    """Write a monitor's table to Parquet (atomically), what made it in the metadata."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    table = pa.Table.from_pandas(result.table, preserve_index=False)
    table = table.replace_schema_metadata(
        {_METADATA_KEY: json.dumps(result.metadata, sort_keys=True).encode()}
    )
    atomic_write(path, lambda tmp: pq.write_table(table, tmp, compression="zstd"))
