"""The ground-truth simulator: the MuJoCo SUV driven through a scenario, with its sensors.

Usual call: ``result = simulate(load_scenario("s.yaml")); write_run(result, "run.parquet")``.

One run: build the road (seeded from the scenario), compile the SUV on it
(:func:`suvtwin.mjcf.builder.build_model`), settle the car into static equilibrium on the
road under its wheels for its loads and pressures and set it rolling steadily at the start
speed (:mod:`suvtwin.mjcf.statics`), then step MuJoCo with the compiled force kernel
(:func:`suvtwin.mjcf.kernel.step_kernel`) between ``mj_step1`` and ``mj_step2``. The
step log is decimated to the output rate; the accelerometer signals get white
noise from the scenario's noise stream. Output: one row per output sample, SI
units (pressure also in kPa), see :data:`OUTPUT_COLUMNS`.

Accelerations ``{c}_accel_sprung_mps2`` / ``{c}_accel_unsprung_mps2`` are vertical
(world z), gravity removed, at the chassis point above the wheel centre and at the
wheel centre; ``_true`` columns are the same without noise.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from suvtwin.errors import InputError, RunError
from suvtwin.files import atomic_write, package_versions, read_parquet_table
from suvtwin.mjcf.builder import HALF_WIDTH_Y, VehicleModel, build_model
from suvtwin.mjcf.kernel import (
    CORNER_FIELDS,
    GLOBAL_FIELDS,
    H_NCOL,
    H_NROW,
    LOG_COLUMNS,
    M_CENTRE_X,
    M_CENTRE_Y,
    M_DIRECTION,
    M_KIND,
    M_LANE_Y,
    M_PATH_DX,
    M_PATH_N,
    M_PATH_X0,
    M_RADIUS,
    MODE_CIRCLE,
    MODE_LANE,
    MODE_OPEN_LOOP,
    MODE_PATH,
    N_MODE,
    finish_log,
    pack_ids,
    pack_vehicle,
    step_kernel,
)
from suvtwin.mjcf.statics import settle, start_rolling
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.scenario import END_MARGIN_M, START_MARGIN_M, Scenario
from suvtwin.roads.profile import Road, generate_road

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["OUTPUT_COLUMNS", "SimResult", "SimulationError", "prepare", "read_run", "simulate", "write_run"]

_METADATA_KEY = b"suvtwin.run"


class SimulationError(RunError):
    """The simulation diverged (non-finite state) or MuJoCo raised warnings."""


def _mujoco_warning(message: str) -> None:
    """MuJoCo's warnings as Python warnings: without a handler of the user's, MuJoCo appends them to
    ``MUJOCO_LOG.TXT`` in the working folder (the user's). A diverging state is caught from the
    warning counters (:func:`simulate`), not from here."""
    import warnings

    warnings.warn(f"MuJoCo: {message}", RuntimeWarning, stacklevel=2)


mujoco.set_mju_user_warning(_mujoco_warning)


def _output_columns() -> tuple[str, ...]:
    cols = list(GLOBAL_FIELDS)
    for c in CORNERS:
        cols += [f"{c}_accel_sprung_mps2", f"{c}_accel_unsprung_mps2"]
        for field in CORNER_FIELDS:
            cols.append(f"{c}_{field.replace('pressure_pa', 'pressure_kpa')}")
    return tuple(cols)


OUTPUT_COLUMNS = _output_columns()
"""Columns of a run's table, in order."""


@dataclass(frozen=True)
class SimResult:
    """A finished run: its output columns (:data:`OUTPUT_COLUMNS`, one value per output sample),
    its scenario and its metadata; :attr:`table` holds the same columns as a DataFrame."""

    columns: dict[str, np.ndarray]
    scenario: Scenario
    metadata: dict

    @property
    def n_samples(self) -> int:
        """Number of output samples (rows of :attr:`table`)."""
        return len(self.columns[OUTPUT_COLUMNS[0]])

    @cached_property
    def table(self) -> pd.DataFrame:
        """The run as a pandas DataFrame, one row per output sample, columns :data:`OUTPUT_COLUMNS`.

        Built on first use: writing a run needs no pandas (a 10 s ``suvtwin simulate`` is
        faster without importing it).
        """
        import pandas as pd

        return pd.DataFrame(self.columns)


@dataclass
class _Prepared:
    vm: VehicleModel
    data: mujoco.MjData
    road: Road
    inputs: dict


def _road_for(scenario: Scenario) -> tuple[Road, float]:
    """The scenario's road and the heightfield half-width it needs."""
    vehicle_reach = 5.0
    if scenario.road == "flat":
        x_min, x_max, half = -50.0, scenario.distance_m() + 200.0, HALF_WIDTH_Y
        if scenario.steering.mode == "circle":
            radius = scenario.steering.radius_m
            x_min, x_max, half = -radius - 50.0, radius + 50.0, 2 * radius + 50.0
        path = scenario.steering.reference_path()
        if path is not None:  # the road must reach the path's widest point
            half = max(half, abs(scenario.steering.lane_y_m) + float(np.max(np.abs(path[1]))) + 10.0)
        x = np.linspace(x_min, x_max, 3)
        return Road(x=x, z=np.zeros((2, 3))), half
    road = generate_road(scenario.road, seed=scenario.road_seed())
    needed = START_MARGIN_M + scenario.distance_m() + vehicle_reach + END_MARGIN_M
    if road.length_m < needed:
        raise InputError(
            f"road is {road.length_m:g} m long but the run needs ≥ {needed:.1f} m "
            f"(start {START_MARGIN_M:g} m + {scenario.distance_m():.1f} m driven + vehicle and margin)"
        )
    return road, HALF_WIDTH_Y


def prepare(scenario: Scenario) -> _Prepared:
    """Build road, model and inputs, and place the car; nothing is stepped yet."""
    vehicle = load_vehicle(overrides=scenario.vehicle or None)
    tire = load_tire(scenario.tire_file or vehicle.tire_file)
    road, half_width = _road_for(scenario)
    loads = tuple((ld.mass_kg, tuple(ld.position_m)) for ld in scenario.load)
    vm = build_model(
        vehicle,
        road,
        tire=tire,
        contact=scenario.contact,
        timestep=scenario.timestep_s,
        loads=loads,
        half_width=half_width,
    )
    model = vm.model
    data = mujoco.MjData(model)
    t = np.arange(scenario.n_steps) * scenario.timestep_s
    pressure = np.ascontiguousarray(scenario.pressure_schedule(t))
    speed_ref = np.ascontiguousarray(scenario.speed_profile(t))
    steer_cmd = np.ascontiguousarray(scenario.steer_series(t))
    mode = np.zeros(N_MODE)
    x0 = START_MARGIN_M + vehicle.chassis.a2
    y0 = scenario.steering.lane_y_m
    if scenario.steering.mode == "lane":
        mode[M_KIND], mode[M_LANE_Y] = MODE_LANE, y0
    elif scenario.steering.mode == "circle":
        sign = 1.0 if scenario.steering.direction == "left" else -1.0
        x0 = 0.0
        mode[M_KIND], mode[M_DIRECTION], mode[M_RADIUS] = MODE_CIRCLE, sign, scenario.steering.radius_m
        mode[M_CENTRE_X], mode[M_CENTRE_Y] = x0, y0 + sign * scenario.steering.radius_m
    elif scenario.steering.mode in ("path", "iso3888"):
        px, py = scenario.steering.reference_path()
        mode = np.zeros(N_MODE + px.size)
        mode[M_KIND], mode[M_PATH_X0], mode[M_PATH_N] = MODE_PATH, x0 + px[0], px.size
        mode[M_PATH_DX] = px[1] - px[0]
        mode[N_MODE:] = y0 + py
    else:
        mode[M_KIND] = MODE_OPEN_LOOP
    hdata = model.hfield_data.reshape(int(vm.hfield[H_NROW]), int(vm.hfield[H_NCOL]))
    # start: static equilibrium for the run's loads, pressures and the road under the wheels,
    # rolling steadily at the start speed (suvtwin.mjcf.statics: Newton on the model's own forces)
    cq = vm.ids["chassis_qpos"][0]
    data.qpos[cq : cq + 2] = x0, y0
    data.qpos[cq + 3 : cq + 7] = 1.0, 0.0, 0.0, 0.0
    settled = settle(vm, data, pressure[0], hdata)
    if not settled.converged:
        import warnings

        warnings.warn(
            f"the start is not fully settled: {settled.residual_n:.3g} N of force left unbalanced",
            RuntimeWarning,
            stacklevel=2,
        )
    state0 = start_rolling(vm, data, pressure[0], float(speed_ref[0]), settled)
    inputs = {
        "pressure": pressure,
        "speed_ref": speed_ref,
        "steer_cmd": steer_cmd,
        "mode": mode,
        "tp": vm.tire.to_array(),
        "vp": pack_vehicle(vm),
        "ids": pack_ids(vm.ids),
        "hdata": hdata,
        "state": state0,
    }
    return _Prepared(vm=vm, data=data, road=road, inputs=inputs)


def simulate(scenario: Scenario, *, progress: bool = False) -> SimResult:
    """Run `scenario` and return its table and metadata.

    Parameters
    ----------
    scenario : Scenario
    progress : bool, optional
        Show a progress bar (stderr).

    Raises
    ------
    InputError
        If the scenario cannot be run (e.g. its road is too short).
    SimulationError
        If the state diverges.
    """
    prep = prepare(scenario)
    vm, data, inp = prep.vm, prep.data, prep.inputs
    model = vm.model
    n = scenario.n_steps
    dt = scenario.timestep_s
    log = np.zeros((n, len(LOG_COLUMNS)))
    state = inp["state"].copy()
    qpos, qvel, xpos, xmat = data.qpos, data.qvel, data.xpos, data.xmat
    sensordata, qfrc, xfrc, ctrl = data.sensordata, data.qfrc_applied, data.xfrc_applied, data.ctrl
    ids, hf, hdata, vp, tp = inp["ids"], vm.hfield, inp["hdata"], inp["vp"], inp["tp"]
    pressure, speed_ref, steer_cmd, mode = inp["pressure"], inp["speed_ref"], inp["steer_cmd"], inp["mode"]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=n, unit="step", unit_scale=True, desc="simulate", leave=False)
    chunk = 2000
    started = time.perf_counter()
    step1, step2 = mujoco.mj_step1, mujoco.mj_step2
    for start in range(0, n, chunk):
        for k in range(start, min(start + chunk, n)):
            step1(model, data)
            step_kernel(
                k, dt, qpos, qvel, xpos, xmat, sensordata, qfrc, xfrc, ctrl,
                ids, hf, hdata, vp, tp, pressure, speed_ref, steer_cmd, mode, state, log,
            )  # fmt: skip
            step2(model, data)
        unstable = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0
        if unstable or not (np.all(np.isfinite(qpos)) and np.all(np.isfinite(qvel))):
            raise SimulationError(f"simulation diverged before t = {(k + 1) * dt:.3f} s (MuJoCo: bad qacc)")
        if bar is not None:
            bar.update(min(chunk, n - start))
    finish_log(n - 1, sensordata, ids, state, log)
    wall = time.perf_counter() - started
    if bar is not None:
        bar.close()
    columns = _output_arrays(log[:: scenario.decimation], scenario)
    off_road = off_road_share(columns, scenario, vm.vehicle)
    meta = {
        "scenario": scenario.model_dump(mode="json"),
        "road_seed": scenario.road_seed(),
        "noise_seed": scenario.noise_seed(),
        "contact": scenario.contact,
        "versions": package_versions(("suvtwin", "mujoco", "numpy", "numba", "scipy", "pyarrow")),
        "wall_time_s": wall,
        "total_mass_kg": float(np.sum(model.body_mass)),
        "off_road_share": off_road,
    }
    return SimResult(columns=columns, scenario=scenario, metadata=meta)


def off_road_share(columns: dict[str, np.ndarray], scenario: Scenario, vehicle=None) -> float:
    """Share of the output samples with a wheel centre beyond the road strip (|y| > ``HALF_WIDTH_Y``,
    2 m; 0 on a flat road, which is flat everywhere): a road with segments is a straight heightfield
    strip, and beyond it the road under the wheel is the strip's edge row extended, not the road asked
    for. Steering modes checked before the run (:meth:`~suvtwin.pipeline.scenario.Scenario._check_on_road`)
    stay on it; an open-loop ``series`` may not. From the chassis position ``y_m`` and ``yaw_rad``
    and the wheels' places on the chassis (`vehicle`'s, default the scenario's)."""
    if scenario.road == "flat":
        return 0.0
    x_w, y_w = (vehicle or load_vehicle(overrides=scenario.vehicle or None)).corner_xy.T
    yaw = columns["yaw_rad"][:, None]
    y = columns["y_m"][:, None] + x_w * np.sin(yaw) + y_w * np.cos(yaw)
    return float(np.mean(np.any(np.abs(y) > HALF_WIDTH_Y, axis=1)))


def _output_arrays(log: np.ndarray, scenario: Scenario) -> dict[str, np.ndarray]:
    raw = dict(zip(LOG_COLUMNS, np.ascontiguousarray(log.T), strict=True))
    rng = np.random.default_rng(scenario.noise_seed())
    out = {}
    for name in GLOBAL_FIELDS:
        out[name] = raw[name]
    n = log.shape[0]
    noise_s = rng.standard_normal((4, n)) * scenario.noise.accel_sprung_mps2
    noise_u = rng.standard_normal((4, n)) * scenario.noise.accel_unsprung_mps2
    for i, c in enumerate(CORNERS):
        out[f"{c}_accel_sprung_mps2"] = raw[f"{c}_accel_sprung_true_mps2"] + noise_s[i]
        out[f"{c}_accel_unsprung_mps2"] = raw[f"{c}_accel_unsprung_true_mps2"] + noise_u[i]
        for field in CORNER_FIELDS:
            if field == "pressure_pa":
                out[f"{c}_pressure_kpa"] = raw[f"{c}_pressure_pa"] / 1e3
            else:
                out[f"{c}_{field}"] = raw[f"{c}_{field}"]
    return {name: out[name] for name in OUTPUT_COLUMNS}


def write_run(result: SimResult, path: str | Path) -> None:
    """Write a run to Parquet: the table, with scenario and versions in the metadata.

    Atomic (no partial file on failure). The wall time is not stored, so the same
    scenario and seed give the same bytes. Compressed with LZ4: noisy float64 samples barely
    compress, and LZ4 reads fastest (the 17 columns ``suvtwin monitor`` reads of an hour's run,
    2026-12-05: ZSTD 454 MB read in 0.81 s, LZ4 496 MB in 0.31 s, Snappy 494 MB in 0.39 s, none
    508 MB in 0.29 s; until then ZSTD, a fifth of the monitor's wall time on the file).
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    meta = {k: v for k, v in result.metadata.items() if k != "wall_time_s"}
    arrays = [_arrow_float64(result.columns[name]) for name in OUTPUT_COLUMNS]
    table = pa.Table.from_arrays(arrays, names=list(OUTPUT_COLUMNS))
    table = table.replace_schema_metadata({_METADATA_KEY: json.dumps(meta, sort_keys=True).encode()})
    atomic_write(path, lambda tmp: pq.write_table(table, tmp, compression="lz4"))


def _arrow_float64(values: np.ndarray):
    """`values` as a float64 Arrow array, NaN as null (as pyarrow's pandas conversion stores it).

    Built from its buffers: ``pyarrow.array`` imports pandas on its first call, and writing
    a run needs no pandas.
    """
    import pyarrow as pa

    values = np.ascontiguousarray(values, dtype=np.float64)
    nan = np.isnan(values)
    validity = pa.py_buffer(np.packbits(~nan, bitorder="little")) if nan.any() else None
    return pa.Array.from_buffers(
        pa.float64(), values.size, [validity, pa.py_buffer(values)], null_count=int(nan.sum())
    )


def read_run(path: str | Path) -> tuple[pd.DataFrame, dict]:
    """Read a run's table and metadata (empty dict if the file carries none)."""
    table = read_parquet_table(path, what="run file")
    raw = (table.schema.metadata or {}).get(_METADATA_KEY)
    return table.to_pandas(), (json.loads(raw) if raw else {})
