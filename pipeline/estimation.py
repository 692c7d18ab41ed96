"""Running the estimators on a run file and scoring them: the glue between files and estimators.

Usual call: ``result = estimate_run("run.parquet", corner="fl", estimator="imm", params="paper",
road_input="synthetic", seed=0)``; ``metrics = score_estimate("est.parquet", "run.parquet")``.

A run file is the simulator's Parquet or any Parquet with ``t_s`` (uniform, increasing),
``speed_mps`` and the corner's ``{c}_accel_sprung_mps2`` / ``{c}_accel_unsprung_mps2``.
The corner's sprung mass is paper 000's eq. 2 with the run's extra load (from its
metadata, if any); unsprung mass and the p0/kt0 law are the SUV's.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from suvtwin import suspension_law
from suvtwin.errors import InputError
from suvtwin.estimators.full_car import FullCar, static_forces
from suvtwin.estimators.joint import LinearQuarterCar
from suvtwin.estimators.quarter_car import sprung_mass_share
from suvtwin.files import atomic_write, read_parquet_schema, read_parquet_table
from suvtwin.mjcf.tire import load_tire, tire_forces_array
from suvtwin.mjcf.vehicle import CORNERS, GRAVITY, VehicleParams, load_vehicle
from suvtwin.pipeline.estimator_registry import CornerSignals, estimate_columns, find_estimator
from suvtwin.pipeline.scoring import PRESSURE_TOLERANCE_KPA, run_metrics
from suvtwin.suspension_law import SuspensionLaw

__all__ = [
    "EstimateRun",
    "TimeAxis",
    "check_signals",
    "check_streamed_speed",
    "check_time_axis",
    "check_time_chunks",
    "corner_sprung_mass",
    "estimate_run",
    "full_car_model",
    "linear_corner_model",
    "run_accel_noise",
    "run_load_and_tire",
    "score_estimate",
    "streamed_speed",
    "write_estimate",
]

_METADATA_KEY = b"suvtwin.estimate"


@dataclass(frozen=True)
class EstimateRun:
    """An estimate's table (t_s, pressure_hat_kpa, ...) and what made it."""

    table: pd.DataFrame
    metadata: dict


def _load_run(path: str | Path, corner: str, *, gaps: bool = False) -> tuple[pd.DataFrame, dict, float]:
    """The run's time, speed and corner columns (and true pressure if there), its metadata, dt;
    `gaps`: NaN accelerometer samples are allowed (the estimator skips them)."""
    if corner not in CORNERS:
        raise InputError(f"--corner must be one of fl, fr, rl, rr, got {corner!r}")
    schema = read_parquet_schema(path, what="run file")
    needed = ["t_s", "speed_mps", f"{corner}_accel_sprung_mps2", f"{corner}_accel_unsprung_mps2"]
    missing = [c for c in needed if c not in schema.names]
    if missing:
        raise InputError(f"run file {str(path)!r} lacks column(s) {', '.join(missing)}")
    # only the columns used (a run file holds ~90)
    table = read_parquet_table(
        path, what="run file", columns=needed + [c for c in (f"{corner}_pressure_kpa",) if c in schema.names]
    )
    frame = table.to_pandas()
    # the speed's own check below (a streaming estimator takes its gaps and reversing)
    checked = needed[:1] if gaps else [needed[0], *needed[2:]]
    values = frame[checked].to_numpy(dtype=float)
    if not np.all(np.isfinite(values)):
        bad = [c for c in checked if not np.all(np.isfinite(frame[c].to_numpy(dtype=float)))]
        raise InputError(f"run file {str(path)!r}: column(s) {', '.join(bad)} hold NaN or infinite values")
    dt = check_time_axis(frame["t_s"].to_numpy(dtype=float), path)
    accelerations = {c: frame[c].to_numpy(dtype=float) for c in needed[2:]}
    frame["speed_mps"] = check_signals(
        frame["speed_mps"].to_numpy(dtype=float), accelerations, path, refuse_accel=not gaps, speed_gaps=gaps
    )
    raw = (schema.metadata or {}).get(b"suvtwin.run")
    meta = json.loads(raw) if raw else {}
    return frame, meta, dt


MIN_SAMPLE_INTERVAL_S, MAX_SAMPLE_INTERVAL_S = 1e-5, 0.05
"""Sample intervals a measurement file may have, s (100 kHz to 20 Hz): time in ms or µs falls outside."""
UNIFORM_TOLERANCE = 0.1
"""How far a run file's timestamps may lie from a uniform grid, in sample intervals (jitter, rounding)."""
MAX_SPEED_MPS = 100.0
"""Highest plausible vehicle speed in a measurement file, m/s (360 km/h)."""
STANDSTILL_MPS = 0.5
"""A standing or creeping car, m/s (1.8 km/h): its speed signal scatters about zero (the simulator's
body velocity at rest is ~1e-5 m/s either way) and it may roll back a little as it stops (the
simulator's SUV by ~5 cm/s); values down to −this are not reversing."""
MAX_IMPLAUSIBLE_SPEED_SHARE = 0.01
"""Share of a streamed run's speed samples that may lie beyond :data:`MAX_SPEED_MPS` (spikes of a
faulty signal: skipped as gaps); more is a wrong unit or a broken signal, and the file is refused."""
MAX_ACCEL_MPS2 = 1000.0
"""Largest plausible accelerometer value, m/s² (~100 g): beyond it a sample is a fault. The batch
estimators refuse such a file; the online monitor skips the windows with one (``implausible``)."""


def check_time_axis(t: np.ndarray, path: str | Path) -> float:
    """The sample interval (s) of a run file's time axis `t_s`; refuses fewer than 10 samples, a
    non-finite or non-increasing axis, one off a uniform grid by more than :data:`UNIFORM_TOLERANCE`
    of an interval anywhere, and an interval outside
    :data:`MIN_SAMPLE_INTERVAL_S`–:data:`MAX_SAMPLE_INTERVAL_S` (one message naming the file).
    The same checks as :func:`check_time_chunks` over one chunk."""
    return check_time_chunks(lambda: iter([t]), path).dt


@dataclass(frozen=True)
class TimeAxis:
    """What a run's checked time axis is: first and last stamp (s), sample count, the end-to-end mean
    interval ``dt`` (s) and the first up to ``TIME_HEAD_STEPS`` intervals (s) as they are."""

    t0: float
    t_end: float
    n: int
    dt: float
    head_steps: np.ndarray


TIME_HEAD_STEPS = 10_000
"""Intervals of a time axis kept whole by :func:`check_time_chunks` (the start of the record)."""


def check_time_chunks(chunks, path: str | Path) -> TimeAxis:
    """:func:`check_time_axis` over a time axis given in consecutive chunks: `chunks()` returns an
    iterable of 1-D arrays (it is called twice: the first pass finds the ends, the second each
    stamp's distance from the uniform grid between them), so a record larger than memory is checked
    in bounded memory. The refusals and messages are :func:`check_time_axis`'s."""
    n, t0, last, head = 0, math.nan, math.nan, []
    for chunk in chunks():
        c = np.asarray(chunk, dtype=float)
        if c.size == 0:
            continue
        if not np.all(np.isfinite(c)):
            raise InputError(f"run file {str(path)!r}: column(s) t_s hold NaN or infinite values")
        if np.any(np.diff(c) <= 0) or c[0] <= last:
            raise InputError(f"run file {str(path)!r}: t_s must be strictly increasing")
        if n == 0:
            t0 = float(c[0])
        if n < TIME_HEAD_STEPS + 1:  # the first stamps, for their intervals
            head.append(c[: TIME_HEAD_STEPS + 1 - n])
        n += c.size
        last = float(c[-1])
    if n < 10:
        raise InputError(f"run file {str(path)!r}: needs at least 10 samples, got {n}")
    # uniform to within a tenth of a sample: a logger's timestamp jitter or a float32 time column
    # (rounded to 2e-6 s at 40 s) passes, a missing sample (every later one a whole interval off) not
    dt = float((last - t0) / (n - 1))
    i, worst = 0, (0.0, 0, t0)  # the farthest stamp off the grid: its distance, index and time
    for chunk in chunks():
        c = np.asarray(chunk, dtype=float)
        if c.size == 0:
            continue
        off = np.abs(c - (t0 + (i + np.arange(c.size)) * dt))
        at = int(np.argmax(off))
        if off[at] > worst[0]:
            worst = (float(off[at]), i + at, float(c[at]))
        i += c.size
    if worst[0] > UNIFORM_TOLERANCE * dt:
        raise InputError(
            f"run file {str(path)!r}: t_s must be uniformly sampled (to within {UNIFORM_TOLERANCE:g} of "
            f"a sample interval; mark missing samples NaN), but sample {worst[1]} at {worst[2]:g} s lies "
            f"{worst[0] / dt:.3g} intervals off the grid"
        )
    if not MIN_SAMPLE_INTERVAL_S <= dt <= MAX_SAMPLE_INTERVAL_S:
        raise InputError(
            f"run file {str(path)!r}: t_s must be in seconds with a sample interval of "
            f"{MIN_SAMPLE_INTERVAL_S:g}–{MAX_SAMPLE_INTERVAL_S:g} s (100 kHz–20 Hz), got {dt:g}: "
            "time in ms or µs?"
        )
    return TimeAxis(t0=t0, t_end=last, n=n, dt=dt, head_steps=np.diff(np.concatenate(head)))


def check_signals(
    speed: np.ndarray,
    accelerations: dict[str, np.ndarray],
    path: str | Path,
    *,
    refuse_accel: bool,
    speed_gaps: bool = False,
) -> np.ndarray:
    """The run's speed as the estimators take it (m/s), or one message refusing the file.

    Batch (`speed_gaps` False): refuses a missing, infinite or implausible speed (beyond
    :data:`MAX_SPEED_MPS`) and reversing (below −:data:`STANDSTILL_MPS`: the estimators model forward
    driving); a standing or creeping car's speed about zero is kept. Streamed (`speed_gaps` True,
    the online monitor): :func:`check_streamed_speed` over the one chunk, then
    :func:`streamed_speed`. With `refuse_accel`, accelerations beyond ±:data:`MAX_ACCEL_MPS2` refuse
    the file (NaN allowed: a gap)."""
    v = np.array(speed, dtype=float)
    where = f"run file {str(path)!r}: speed_mps"
    if speed_gaps:
        check_streamed_speed([v], path)
        v = streamed_speed(v)
    else:
        bad = ~np.isfinite(v) | (v > MAX_SPEED_MPS) | (v < -STANDSTILL_MPS)
        if np.any(bad):
            raise InputError(
                f"{where} must be within 0–{MAX_SPEED_MPS:g} m/s (a standing or creeping car down to "
                f"−{STANDSTILL_MPS:g} allowed, no reversing, no gaps), got {v[bad][0]:g}"
            )
    if refuse_accel:
        for name, a in accelerations.items():
            a = np.asarray(a, dtype=float)
            big = np.abs(a) > MAX_ACCEL_MPS2
            if np.any(big):
                raise InputError(
                    f"run file {str(path)!r}: {name} holds {int(big.sum())} value(s) beyond "
                    f"±{MAX_ACCEL_MPS2:g} m/s² (e.g. {a[big][0]:g}): a faulty sensor or the wrong unit"
                )
    return v


def _wild_speed(v: np.ndarray) -> np.ndarray:
    return np.isinf(v) | (v > MAX_SPEED_MPS)


def check_streamed_speed(chunks, path: str | Path) -> None:
    """Refuse a streamed run's speed (the online monitor's; `chunks`: its consecutive 1-D arrays, m/s)
    beyond :data:`MAX_SPEED_MPS` or infinite on more than :data:`MAX_IMPLAUSIBLE_SPEED_SHARE` of the
    samples (the wrong unit) or below −:data:`STANDSTILL_MPS` on most of them (the wrong sign), one
    message each. A NaN is a gap and reversing or standing is kept (the monitor skips and counts
    those windows as ``speed``); the few wild samples become gaps (:func:`streamed_speed`)."""
    n = n_wild = n_back = 0
    wild_eg = back_eg = math.nan
    for chunk in chunks:
        v = np.asarray(chunk, dtype=float)
        wild, back = _wild_speed(v), v < -STANDSTILL_MPS
        if n_wild == 0 and np.any(wild):
            wild_eg = float(v[wild][0])
        if n_back == 0 and np.any(back):
            back_eg = float(v[back][0])
        n, n_wild, n_back = n + v.size, n_wild + int(wild.sum()), n_back + int(back.sum())
    where = f"run file {str(path)!r}: speed_mps"
    if n_wild > MAX_IMPLAUSIBLE_SPEED_SHARE * n:
        raise InputError(
            f"{where} must be within 0–{MAX_SPEED_MPS:g} m/s (reversing and gaps allowed); "
            f"{n_wild} of {n} samples are beyond (e.g. {wild_eg:g}): the wrong unit?"
        )
    if n_back > 0.5 * n:
        raise InputError(
            f"{where} must be within 0–{MAX_SPEED_MPS:g} m/s: it is negative on {n_back} of "
            f"{n} samples (e.g. {back_eg:g}): reversing for most of the run, or the wrong sign?"
        )


def streamed_speed(speed: np.ndarray) -> np.ndarray:
    """A streamed run's speed as the monitor takes it (m/s): samples beyond :data:`MAX_SPEED_MPS` or
    infinite become gaps (NaN), once :func:`check_streamed_speed` has passed the run."""
    v = np.array(speed, dtype=float)
    v[_wild_speed(v)] = np.nan
    return v


def estimate_run(
    path: str | Path, *, corner: str, estimator: str, params: str, road_input: str | None, seed: int
) -> EstimateRun:
    """Run an estimator of the registry (:data:`suvtwin.pipeline.estimator_registry.ESTIMATORS`) on one
    corner of a run: `estimator` is its family (``"imm"``: paper 000's IMM, ``"ukf"``: its single UKF,
    ``"joint"``: the road-level-free estimator on the corner's linearized physical quarter car,
    ``"online"``: the causal monitor on that corner alone) and `road_input` its road input
    (``"synthetic"`` or ``"augmented"``; ignored by ``"joint"`` and ``"online"``)."""
    entry = find_estimator(estimator, road_input)
    frame, meta, dt = _load_run(path, corner, gaps=entry.tolerates_gaps)
    vehicle = run_vehicle(meta)
    load, tire_file = run_load_and_tire(meta, path)
    ms = corner_sprung_mass(corner, load, vehicle=vehicle)
    mus = vehicle.unsprung_mass[CORNERS.index(corner)]
    static_load = corner_static_load(corner, run_loads(meta), vehicle=vehicle)
    signals = CornerSignals(
        acc_sprung=frame[f"{corner}_accel_sprung_mps2"].to_numpy()[None, :],
        acc_unsprung=frame[f"{corner}_accel_unsprung_mps2"].to_numpy()[None, :],
        dt=dt,
        speed_mps=np.array([max(float(np.nan_to_num(frame["speed_mps"].mean())), 1.0)]),
        corner=corner,
        sprung_mass=ms,
        unsprung_mass=float(mus),
        params=params,
        seeds=np.array([seed]),
        tire_file=tire_file,
        speed_series_mps=frame["speed_mps"].to_numpy(dtype=float)[None, :],
        static_travel_m=corner_static_travel(corner, run_loads(meta), vehicle=vehicle),
        vehicle=meta.get("scenario", {}).get("vehicle") or None,
        loads=run_loads(meta),
        static_load_n=static_load,
        accel_noise_mps2=run_accel_noise(meta),
    )
    batch = entry.run(signals)
    metadata = {
        "run_file": str(path),
        "corner": corner,
        "estimator": entry.family,
        "road_input": entry.road_input,
        "seed": seed,
        "tire_file": tire_file,
        "sprung_mass_kg": ms,
        "unsprung_mass_kg": float(mus),
        "static_load_n": static_load,
        **batch.info,
    }
    table = pd.DataFrame(estimate_columns(batch, 0, frame["t_s"].to_numpy()))
    return EstimateRun(table=table, metadata=metadata)


def run_load_and_tire(meta: dict, path: str | Path) -> tuple[float, str | None]:
    """The extra load (kg) and the tyre file (None: the SUV's) of a run, from its metadata.

    A run made with another tyre is estimated with its k_t(p); that file must still be there."""
    scenario = meta.get("scenario", {})
    tire_file = scenario.get("tire_file")
    if tire_file is not None and not Path(tire_file).is_file():
        raise InputError(f"run {path} was simulated with the tyre file {tire_file}, which is not there now")
    return float(sum(item.get("mass_kg", 0.0) for item in scenario.get("load", []))), tire_file


def run_accel_noise(meta: dict) -> float | None:
    """The accelerometers' white-noise σ a run was simulated with (m/s² per sample, the larger of
    the sprung and unsprung channels'), from its metadata; None where the run records none (or
    none above zero)."""
    noise = (meta.get("scenario") or {}).get("noise") or {}
    sigma = max(float(noise.get("accel_sprung_mps2", 0.0)), float(noise.get("accel_unsprung_mps2", 0.0)))
    return sigma if sigma > 0.0 else None


def run_vehicle(meta: dict) -> VehicleParams:
    """The vehicle a run was simulated with: the SUV's parameter file with the scenario's
    ``vehicle`` overrides (from the run's metadata) applied."""
    return load_vehicle(overrides=meta.get("scenario", {}).get("vehicle") or None)


def run_loads(meta: dict) -> tuple[tuple[float, tuple[float, float, float]], ...]:
    """The extra loads of a run, from its metadata: (mass in kg, position in m from the chassis CoG,
    x forward, y left, z up) each."""
    items = meta.get("scenario", {}).get("load", [])
    return tuple((float(i.get("mass_kg", 0.0)), tuple(float(x) for x in i.get("position_m", (0.0, 0.0, 0.0))))
                 for i in items)  # fmt: skip


def corner_static_travel(corner: str, loads=(), *, vehicle: VehicleParams | None = None) -> float:
    """Static suspension compression (m) of the SUV's `corner` under extra `loads` (:func:`run_loads`),
    from where the car's own weight leaves it (:func:`static_travels`)."""
    return float(static_travels(loads, vehicle=vehicle)[CORNERS.index(corner)])


def static_travels(loads=(), *, vehicle: VehicleParams | None = None) -> np.ndarray:
    """Static suspension compressions (m) of the SUV's four corners (fl, fr, rl, rr) under extra
    `loads` (:func:`run_loads`), from where the car's own weight leaves them.

    The loads' weight goes through the car's springs, anti-roll bars and tyres
    (:func:`suvtwin.estimators.full_car.static_forces` on :func:`full_car_model`: an off-centre
    load's roll moment is shared by the axles' roll stiffness); each corner's spring
    (:class:`suvtwin.suspension_law.SuspensionLaw`, progression and stops included) carries the
    extra force that gives it (:func:`suvtwin.suspension_law.static_travel`). `vehicle`: default
    the SUV's parameter file (:func:`run_vehicle` gives a run's)."""
    vehicle = vehicle or load_vehicle()
    force = _static(vehicle, loads)[1] - _static(vehicle, ())[1]
    return np.array([
        float(suspension_law.static_travel(SuspensionLaw.of(vehicle.suspension, spring_rate=float(k)), f))
        for k, f in zip(vehicle.spring_rate, force, strict=True)
    ])  # fmt: skip


def corner_static_load(corner: str, loads=(), *, vehicle: VehicleParams | None = None) -> float:
    """Static vertical force of the SUV's `corner` tyre on flat ground with extra `loads`
    (:func:`run_loads`), N (:func:`static_wheel_loads`)."""
    return float(static_wheel_loads(loads, vehicle=vehicle)[CORNERS.index(corner)])


def static_wheel_loads(loads=(), *, vehicle: VehicleParams | None = None) -> np.ndarray:
    """Static vertical forces of the SUV's four tyres (fl, fr, rl, rr) on flat ground with extra
    `loads` (:func:`run_loads`), N: the car's weight and the loads' shared through its springs, bars
    and tyres (:func:`suvtwin.estimators.full_car.static_forces` on :func:`full_car_model`). An
    off-centre load's roll moment goes to the axles by their roll stiffness, not by their share of
    its weight: 300 kg 1.2 m behind the centre of gravity and 0.5 m to its left load MuJoCo's tyres
    within 1 %, where splitting each axle's share by the lateral offset misses by up to 10 %
    (``tests/test_estimate_cli.py``)."""
    return _static(vehicle or load_vehicle(), loads)[0].copy()


def _static(vehicle: VehicleParams, loads) -> tuple[np.ndarray, np.ndarray]:
    """:func:`suvtwin.estimators.full_car.static_forces` of the SUV with `loads`: tyre, spring forces (N)."""
    return static_forces(full_car_model(vehicle, loads), GRAVITY)


def corner_sprung_mass(corner: str, load_kg: float = 0.0, *, vehicle: VehicleParams | None = None) -> float:
    """The SUV corner's sprung mass with `load_kg` of extra load, kg (paper 000 eq. 2); `vehicle`
    default the SUV's parameter file."""
    vehicle = vehicle or load_vehicle()
    front = corner.startswith("f")
    return sprung_mass_share(
        vehicle.chassis.mass,
        a_opposite=vehicle.chassis.a2 if front else vehicle.chassis.a1,
        wheelbase=vehicle.wheelbase,
        load=load_kg,
    )


def _linear_damping(s) -> float:
    """The digressive damper's equivalent linear damping at low speed: the mean of its low-speed
    compression and rebound slopes, N s/m."""
    return 0.5 * (s.damper_compression_low + s.damper_rebound_low)


def linear_corner_model(
    corner: str,
    sprung_mass: float,
    *,
    tire_file: str | Path | None = None,
    static_travel: float = 0.0,
    vehicle: VehicleParams | None = None,
    full_car: FullCar | None = None,
    static_load: float | None = None,
) -> LinearQuarterCar:
    """The SUV corner as a linear roll-plane corner model for the joint estimator.

    `sprung_mass` (kg) is the heave mode's; the unsprung mass, spring rate at the wheel, tire radial
    damping and anti-roll rate are the SUV's. The roll mode's sprung mass is the chassis roll inertia
    over twice the squared half-track of the corner's axle. The digressive damper's equivalent
    linear damping lies between the means of its high-speed and of its low-speed compression and
    rebound slopes, depending on the suspension velocity: the estimator marginalizes over that range
    (``damping`` is the low-speed mean). Leaving out the anti-roll bar or the digressive damper
    biases the pressure high; ``python bench/joint_mujoco.py`` compares this model with the plain
    quarter car on a campaign's MuJoCo runs. `tire_file`: the tyre of the run (``.tir``, its radial
    damping), default the SUV's. The corner's non-linear spring and damper laws come with it
    (``suspension``) and `static_travel` (m, :func:`corner_static_travel`), for estimators that
    linearize them at the measured travel (the online monitor), and `static_load` (N, the tyre's
    static force, :func:`corner_static_load`; None: the corner's masses times g). `vehicle`: default
    the SUV's parameter file (:func:`run_vehicle` gives a run's, its scenario overrides applied)."""
    vehicle = vehicle or load_vehicle()
    s = vehicle.suspension
    i = CORNERS.index(corner)
    front = corner.startswith("f")
    half_track = 0.5 * (vehicle.chassis.track_front if front else vehicle.chassis.track_rear)
    return LinearQuarterCar(
        sprung_mass=sprung_mass,
        unsprung_mass=float(vehicle.unsprung_mass[i]),
        spring_rate=float(vehicle.spring_rate[i]),
        damping=_linear_damping(s),
        tire_damping=float(load_tire(tire_file or vehicle.tire_file).vertical_damping),
        roll_mass=float(vehicle.chassis.inertia_roll / (2.0 * half_track**2)),
        anti_roll=float(s.anti_roll_front if front else s.anti_roll_rear),
        damping_range=(
            0.5 * (s.damper_compression_high + s.damper_rebound_high),
            _linear_damping(s),
        ),
        suspension=SuspensionLaw.of(s, spring_rate=float(vehicle.spring_rate[i])),
        static_travel=float(static_travel),
        full_car=full_car,
        corner=i,
        envelope_half_length=float(vehicle.tire.envelope_half_length),
        static_load=None if static_load is None else float(static_load),
    )


def full_car_model(
    vehicle: VehicleParams | None = None, loads=(), *, tire_file: str | Path | None = None,
    lateral: bool = False,
) -> FullCar:
    """The SUV as a linear full car (:class:`suvtwin.estimators.full_car.FullCar`) with extra `loads`
    ((kg, (x, y, z) m from the chassis CoG) each, :func:`run_loads`).

    The loads are the simulator's: 0.5 m cubes welded to the chassis (their own inertia m·0.5²/6
    about each axis); body mass, centre of gravity and pitch and roll inertias are the chassis's
    and the loads' together (parallel axes), the corners' positions taken from the new centre of
    gravity. Dampers at the mean of their low-speed compression and rebound slopes; tyres at
    their nominal stiffness (eq. 3–4 at the reference pressure) and radial damping. `vehicle`:
    default the SUV's parameter file; `tire_file`: default the vehicle's tyre.

    `lateral`: with the tyres' lateral slip (:mod:`suvtwin.estimators.full_car`): each tyre's
    cornering stiffness is the MF-Tyre slope dF_y/dα at zero slip, its static load and nominal
    pressure, a front's lowered by its lateral-force compliance steer, C/(1 + C c_f) (the rears'
    toe compliance, 1.75e-6 rad/N, is left out); the centre of gravity's height is the chassis's
    with the loads; the wheel centres at the unloaded radius less the mean static deflection;
    the yaw inertia the car's with the loads (parallel axes); the tyre's lateral relaxation
    length."""
    vehicle = vehicle or load_vehicle()
    c, s = vehicle.chassis, vehicle.suspension
    masses = np.array([c.mass] + [float(m) for m, _ in loads])
    pos = np.array([(0.0, 0.0, 0.0)] + [tuple(p) for _, p in loads], dtype=float)
    total = float(masses.sum())
    cog = masses @ pos / total
    rel = pos - cog
    own = np.array([0.0] + [m * 0.5**2 / 6.0 for m in masses[1:]])
    pitch = c.inertia_pitch + own.sum() + float(masses @ (rel[:, 0] ** 2 + rel[:, 2] ** 2))
    roll = c.inertia_roll + own.sum() + float(masses @ (rel[:, 1] ** 2 + rel[:, 2] ** 2))
    tire = load_tire(tire_file or vehicle.tire_file)
    damping = _linear_damping(s)
    extra = {}
    if lateral:
        extra = _lateral_parameters(vehicle, tire, loads, masses, rel, own, cog)
    return FullCar(
        sprung_mass=total,
        inertia_pitch=pitch,
        inertia_roll=roll,
        corner_xy=tuple((float(x - cog[0]), float(y - cog[1])) for x, y in vehicle.corner_xy),
        unsprung_mass=tuple(float(m) for m in vehicle.unsprung_mass),
        spring_rate=tuple(float(k) for k in vehicle.spring_rate),
        damping=(float(damping),) * 4,
        anti_roll=(float(s.anti_roll_front), float(s.anti_roll_rear)),
        tire_stiffness=(float(tire.vertical_stiffness_nominal),) * 4,
        tire_damping=(float(tire.vertical_damping),) * 4,
        **extra,
    )


def _lateral_parameters(vehicle: VehicleParams, tire, loads, masses, rel, own, cog) -> dict:
    """:func:`full_car_model`'s lateral-slip fields (its docstring): masses (kg), positions
    relative to the combined centre of gravity (m) and own inertias of the chassis and the loads."""
    c = vehicle.chassis
    loads_z = static_wheel_loads(loads, vehicle=vehicle)  # the tyres' static loads, N
    slip = 1e-5  # rad: the MF curve is linear there
    _, fy = tire_forces_array(loads_z, 0.0, slip, tire.nominal_pressure, tire)
    cornering = np.abs(fy) / slip
    cornering[:2] /= 1.0 + cornering[:2] * vehicle.steering.compliance_steer_front
    deflection = float(np.mean(loads_z)) / float(tire.vertical_stiffness_nominal)
    # parallel axes as for pitch and roll: the chassis's own mass too, its CoG moved by the loads
    yaw = c.inertia_yaw_total + own.sum() + float(masses @ (rel[:, 0] ** 2 + rel[:, 1] ** 2))
    return {
        "cornering_stiffness": tuple(float(k) for k in cornering),
        "cog_height": float(c.cog_height + cog[2]),
        "wheel_centre_height": float(tire.unloaded_radius - deflection),
        "inertia_yaw": float(yaw),
        "relaxation_length": float(vehicle.tire.relaxation_length_lateral),
    }


def write_estimate(result: EstimateRun, path: str | Path) -> None:
    """Write an estimate to Parquet (atomically), what made it in the metadata."""
    table = pa.Table.from_pandas(result.table, preserve_index=False)
    table = table.replace_schema_metadata(
        {_METADATA_KEY: json.dumps(result.metadata, sort_keys=True).encode()}
    )
    atomic_write(path, lambda tmp: pq.write_table(table, tmp, compression="zstd"))


def score_estimate(estimate_path: str | Path, run_path: str | Path) -> dict:
    """Metrics of an estimate file against its run's true pressure (kPa, s)."""
    est = read_parquet_table(estimate_path, what="estimate file")
    raw = (est.schema.metadata or {}).get(_METADATA_KEY)
    if raw is None:
        raise InputError(f"estimate file {str(estimate_path)!r} was not written by 'suvtwin estimate'")
    meta = json.loads(raw)
    corner = meta["corner"]
    frame, _, _ = _load_run(run_path, corner, gaps=True)
    truth_col = f"{corner}_pressure_kpa"
    if truth_col not in frame:
        raise InputError(f"run file {str(run_path)!r} lacks {truth_col}: no true pressure to score against")
    table = est.to_pandas()
    missing = [c for c in ("t_s", "pressure_hat_kpa", "pressure_sigma_kpa") if c not in table]
    if missing:
        raise InputError(f"estimate file {str(estimate_path)!r} lacks column(s) {', '.join(missing)}")
    if len(table) != len(frame) or not np.allclose(table["t_s"], frame["t_s"]):
        raise InputError(
            "estimate and run files have different time axes: was the estimate made from this run?"
        )
    m = run_metrics(
        table["t_s"].to_numpy(),
        frame[truth_col].to_numpy(),
        table["pressure_hat_kpa"].to_numpy(),
        table["pressure_sigma_kpa"].to_numpy(),
        tolerance=PRESSURE_TOLERANCE_KPA,
    )
    return {
        "corner": corner,
        "estimator": meta["estimator"],
        "road_input": meta["road_input"],
        "true_pressure_end_kpa": float(frame[truth_col].iloc[-1]),
        "estimate_end_kpa": float(table["pressure_hat_kpa"].iloc[-1]),
        "time_to_converge_s": m.time_to_converge_s,
        "mean_error_kpa": m.mean_error,
        "rmse_kpa": m.rmse,
        "inside_1sigma": m.inside_1sigma,
        "inside_2sigma": m.inside_2sigma,
    }
