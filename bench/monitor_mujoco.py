"""The four-corner tyre-pressure monitor (issue 12) on MuJoCo ground truth, one scenario set at a time.

Run: ``python bench/monitor_mujoco.py --set constant --runs 100 [--first 0] [--jobs 2]
[--corner-model roll_plane] [--no-preview] [--road-waviness free] [--dead-sensor COLUMN]
[--road-method shape-filter]`` — prints
JSON (``--first``: the set's runs from that one on, e.g. 5000 for runs no default call draws, to see
a score is not the draw's; ``--corner-model``: the
monitor's corner model, default the full car; ``--road-waviness``: its prior on the road's
waviness, default ``iso``; ``--no-preview``: each tyre on its own, without the front→rear preview
that ``suvtwin monitor`` uses by default; ``--dead-sensor``: a column of each run file NaN
throughout, e.g. ``rl_wheel_speed_radps``; ``--road-method``: every run's road drawn by that
generator instead of the set's ``gaussian``, e.g. ``superposition``, the simulator's default
random-phase roads the sets drew before 2026-12-04, which flatter the monitor, or ``shape-filter``).
Sets (:mod:`suvtwin.pipeline.monitor_scenarios`): ``constant``, ``slow_leak``, ``drop``,
``low_speed``, ``warning``, ``nominal_long``, ``reset_leak`` (ours: UN R141's procedure, the
references learned after a reset and a 20 % leak later), ``warning_multi`` (ours: two or three tyres
low, FMVSS 138's any number); every road level drawn anywhere in its class
band, seeds from 900000 on (none a test uses). Default 4 runs per set (the issue asks for
≥ 100 for ``constant`` and ``warning``, and ≥ 500 simulated minutes for ``nominal_long``:
``--runs 130``, 98 lane-kept runs of 300 s and 32 weaves of 30 s).

The runs are simulated in ``--jobs`` processes into ``--runs-dir`` (default
``bench/_runs/<set>/``, one Parquet file per run named by the hash of its scenario and the
simulator's code, so a second call reuses them); ``--discard-runs`` deletes each batch's files
once monitored (a run takes ~0.8 MB per simulated second). The monitor
(:func:`suvtwin.pipeline.monitoring.monitor_run`) gets each run file and, for the ``warning``,
``warning_multi`` and ``nominal_long`` sets, the run's placard pressure (``--reset-at S``: a driver
reset at S s instead). Scored (:func:`suvtwin.pipeline.monitor_scoring.score_set`) against the run's true
pressures, beside the issue's targets: the estimate the monitor reports (with the wheels' radii where
fused) and, in ``vibration_only``, the vibration's own; also the simulation and monitor throughput (driving s
per wall s; the monitor's includes reading the file and, on its first run per process, JIT
compilation), runs whose simulation diverged (left out of the scores), and what the car went
through: runs that left their lane or lost wheel contact, and how far the weave runs of
``nominal_long`` swung.
``--simulate-only`` fills the cache without a monitor.
"""

from __future__ import annotations

import argparse
import json
import sys
from functools import partial
from pathlib import Path

import numpy as np

from suvtwin.pipeline.monitor_scenarios import SETS, BenchRun, monitor_traces, scenario_set, simulate_cached
from suvtwin.pipeline.monitor_scoring import issue_targets, score_set

ISSUE_SIZE = {"constant": 100, "slow_leak": 20, "drop": 20, "low_speed": 20, "warning": 100,
              "nominal_long": 130, "reset_leak": 40, "warning_multi": 100}  # fmt: skip
"""Runs the issue asks for (``constant``, ``warning``: ≥ 100; ``nominal_long``: ≥ 500 simulated min, which
130 runs give: 98 of 300 s and 32 weaves of 30 s); the change and low-speed sets have no stated size;
``warning_multi`` is ours, sized as ``warning``."""


def run_conditions(path: Path) -> dict:
    """What the car went through in a run: max |y| of the chassis from the lane's line (m), the
    share of samples with a wheel beyond the 4 m road strip (there the road is the strip's edge
    row, extended; the simulator's ``off_road_share``, :func:`suvtwin.pipeline.simulator.off_road_share`)
    and the share with a wheel off the ground (tyre load ≤ 1 N)."""
    import pyarrow.parquet as pq

    from suvtwin.mjcf.vehicle import CORNERS
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import off_road_share

    columns = ["y_m", "yaw_rad"] + [f"{c}_tire_fz_n" for c in CORNERS]
    table = pq.read_table(path, columns=columns)
    y = table["y_m"].to_numpy()
    fz = np.stack([table[f"{c}_tire_fz_n"].to_numpy() for c in CORNERS], axis=1)
    meta = json.loads(pq.read_schema(path).metadata[b"suvtwin.run"])
    off = meta.get("off_road_share")
    if off is None:  # a run file written before the simulator measured it
        off = off_road_share({"y_m": y, "yaw_rad": table["yaw_rad"].to_numpy()},
                             parse_scenario(meta["scenario"], source=str(path)))  # fmt: skip
    return {
        "max_abs_y_m": float(np.abs(y).max()),
        "share_off_strip": float(off),
        "share_wheel_airborne": float(np.mean(np.any(fz <= 1.0, axis=1))),
    }


def _conditions_summary(conditions: dict) -> dict:
    """Runs that left their lane (|y| > 1 m; lane-kept runs only) or lost wheel contact (> 1 % of
    samples), and the weave runs' lateral swing next to how far they went."""
    lane = {n: c for n, c in conditions.items() if not c.get("weave")}
    airborne = np.array([c["share_wheel_airborne"] for c in conditions.values()])
    return {
        "max_abs_y_m_lane_kept": max((c["max_abs_y_m"] for c in lane.values()), default=None),
        "left_lane_over_1m": {n: c["max_abs_y_m"] for n, c in lane.items() if c["max_abs_y_m"] > 1.0},
        "share_wheel_airborne_median": float(np.median(airborne)) if airborne.size else None,
        "share_wheel_airborne_max": float(airborne.max()) if airborne.size else None,
        "runs_wheel_airborne_over_1pct": {
            n: c["share_wheel_airborne"] for n, c in conditions.items() if c["share_wheel_airborne"] > 0.01
        },
        "weaves": {n: c for n, c in conditions.items() if c.get("weave")},
    }


def _level_ratio(runs, extras) -> dict | None:
    ratio = [
        e["road_level_hat_m3_at_end"] / r.info["gd_n0_m3"]
        for r, e in zip(runs, extras, strict=True)
        if isinstance(r.info.get("gd_n0_m3"), float) and "road_level_hat_m3_at_end" in e
    ]
    if not ratio:
        return None
    ratio = [x for x in ratio if np.isfinite(x)]  # NaN: the last window unused
    if not ratio:
        return None
    q = np.percentile(ratio, [10, 50, 90])
    return {"runs": len(ratio), "p10": float(q[0]), "median": float(q[1]), "p90": float(q[2])}


def monitor_without(path, *, silent: str, **options):
    """:func:`suvtwin.pipeline.monitoring.monitor_run` on the run file `path` with the column `silent` NaN
    throughout (a dead sensor; the copy in a temporary folder, removed after)."""
    import shutil
    import tempfile

    import pyarrow as pa
    import pyarrow.parquet as pq

    from suvtwin.pipeline.monitoring import monitor_run

    table = pq.read_table(path)
    table = table.set_column(table.column_names.index(silent), silent,
                             pa.array(np.full(table.num_rows, np.nan)))  # fmt: skip
    folder = tempfile.mkdtemp()
    try:
        copy = Path(folder) / Path(path).name
        pq.write_table(table, copy)
        return monitor_run(copy, **options)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _round(obj, digits: int = 4):
    if isinstance(obj, float):  # inf (e.g. a settle time never reached) and NaN print as null
        return float(f"{obj:.{digits}g}") if np.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _round(v, digits) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_round(v, digits) for v in obj]
    return obj


def _with_road_method(run: BenchRun, method: str) -> BenchRun:
    """The run with its road drawn by `method` (:class:`suvtwin.roads.spec.RoadSpec`'s ``method``)."""
    from suvtwin.pipeline.scenario import parse_scenario

    data = run.scenario.model_dump(mode="json", exclude_none=True)
    data["road"]["method"] = method
    return BenchRun(run.name, run.set, parse_scenario(data, source=f"bench run {run.name}, {method}"),
                    {**run.info, "road_method": method})  # fmt: skip


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add = parser.add_argument
    add("--set", default="constant", choices=SETS)
    add("--runs", type=int, default=4, help="runs of the set (default 4)")
    add("--first", type=int, default=0,
        help="the set's first run taken (default 0; e.g. 5000: fresh runs no default call draws)")
    add("--duration", type=float, default=None, help="run length, s (default: the set's)")
    add("--jobs", type=int, default=2, help="processes (default 2)")
    add("--runs-dir", type=Path, default=None, help="run cache (default bench/_runs/<set>)")
    add("--loss", type=float, default=0.20, help="warning set: loss below placard (0.20)")
    add("--weave-every", type=int, default=4, help="nominal_long: every n-th run weaves (0: none)")
    add("--weave-duration", type=float, default=30.0, help="nominal_long: weave run length, s")
    add(
        "--reset-at",
        type=float,
        default=None,
        help="driver reset at S s instead of the placard "
        "(meant for nominal_long: the warning set is low from t = 0)",
    )
    add("--corner-model", default="full_car", choices=("full_car", "roll_plane"),
        help="how the monitor models each corner (default full_car; roll_plane: the model before)")
    add("--road-waviness", default="iso", choices=("iso", "free"),
        help="the monitor's prior on the road's waviness (suvtwin.pipeline.monitoring.ROAD_WAVINESS)")
    add("--no-preview", dest="preview", action="store_false",
        help="each tyre on its own (default: each track's two tyres fused through its front→rear preview)")
    add("--no-closure", dest="closure", action="store_false",
        help="without the force closure (suvtwin.estimators.force_closure; default with it)")
    add("--dead-sensor", default=None, metavar="COLUMN",
        help="monitor with this column of each run file NaN throughout (e.g. rl_wheel_speed_radps)")
    add("--road-method", default=None, choices=("superposition", "shape-filter", "gaussian"),
        help="every run's road drawn by this generator (default: the set's, gaussian)")
    add("--discard-runs", action="store_true", help="delete run files once monitored")
    add("--simulate-only", action="store_true", help="fill the run cache, run no monitor")
    args = parser.parse_args(argv)

    runs = scenario_set(args.set, args.runs, duration_s=args.duration, loss=args.loss, first=args.first,
                        weave_every=args.weave_every, weave_duration_s=args.weave_duration)  # fmt: skip
    if args.road_method is not None:
        runs = [_with_road_method(r, args.road_method) for r in runs]
    if args.reset_at is not None:
        for r in runs:
            r.info.pop("placard_kpa", None)
    folder = args.runs_dir or Path(__file__).resolve().parent / "_runs" / args.set
    out: dict = {
        "bench": "monitor_mujoco",
        "set": args.set,
        "runs": len(runs),
        "first_run": args.first,
        "issue_size": ISSUE_SIZE[args.set],
        "simulated_min": sum(r.scenario.duration_s for r in runs) / 60.0,
        "options": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
    }
    monitor_ok = True
    if not args.simulate_only:
        try:
            from suvtwin.pipeline.monitoring import monitor_run
        except ImportError as error:
            monitor_ok = False
            out["monitor_error"] = f"suvtwin.pipeline.monitoring.monitor_run is not available: {error}"
    batch = max(2 * args.jobs, 2) if args.discard_runs else len(runs)
    sim_costs, mon_costs, traces, extras, conditions, scored = [], [], [], [], {}, []
    for start in range(0, len(runs), batch):
        part = runs[start : start + batch]
        label = f"monitor_mujoco: {args.set} runs {args.first + start}–{args.first + start + len(part) - 1}"
        print(f"{label}: simulating", file=sys.stderr)
        paths, cost = simulate_cached(part, folder, jobs=args.jobs)
        sim_costs.append(cost)
        good = [i for i, p in enumerate(paths) if p is not None]  # failed (diverged) runs are left out
        part, paths = [part[i] for i in good], [paths[i] for i in good]
        for r, p in zip(part, paths, strict=True):
            conditions[r.name] = {
                **run_conditions(p),
                **({"weave": r.info["weave"]} if r.info.get("weave") else {}),
            }
        if monitor_ok and not args.simulate_only and part:
            print(f"{label}: monitoring", file=sys.stderr)
            run_monitor = monitor_run if args.dead_sensor is None else partial(monitor_without,
                                                                                silent=args.dead_sensor)
            monitor = partial(run_monitor, corner_model=args.corner_model, preview=args.preview,
                              road_waviness=args.road_waviness, force_closure=args.closure)  # fmt: skip
            t, e, cost = monitor_traces(part, paths, monitor=monitor, jobs=args.jobs,
                                        reset_at_s=args.reset_at)  # fmt: skip
            ok = [i for i, trace in enumerate(t) if trace is not None]  # the monitor raised on the others
            traces += [t[i] for i in ok]
            extras += [e[i] for i in ok]
            scored += [part[i] for i in ok]
            mon_costs.append(cost)
        if args.discard_runs:
            for p in paths:
                p.unlink(missing_ok=True)
    sim_s = sum(c["simulated_s"] for c in sim_costs)
    wall = sum(c["wall_s"] for c in sim_costs)
    run_wall = sum(c["run_wall_s"] for c in sim_costs)
    size = sum(p.stat().st_size for p in folder.glob("*.parquet")) if folder.is_dir() else 0
    files = len(list(folder.glob("*.parquet"))) if folder.is_dir() else 0
    out["simulation"] = {
        "runs_dir": str(folder),
        "simulated": sum(c["simulated"] for c in sim_costs),
        "reused": sum(c["reused"] for c in sim_costs),
        "failed": {k: v for c in sim_costs for k, v in c["failed"].items()},
        "simulated_s": sim_s,
        "wall_s": wall,
        "jobs": args.jobs,
        "realtime_factor": sim_s / wall if sim_s else None,
        "realtime_factor_per_process": sim_s / run_wall if sim_s else None,
        "cache_files": files,
        "cache_mb": size / 1e6,
    }
    if traces:
        driving = sum(c["driving_s"] for c in mon_costs)
        monitor_s = sum(c["monitor_s"] for c in mon_costs)
        out["monitor"] = {
            "driving_s": driving,
            "monitor_s": monitor_s,
            "realtime_factor": driving / monitor_s if monitor_s else None,
            "updates_per_run_median": float(np.median([e["updates"] for e in extras])),
        }
    if mon_costs:
        out.setdefault("monitor", {})["failed"] = {k: v for c in mon_costs for k, v in c["failed"].items()}
        scores = score_set(args.set, traces, [{**r.info, "name": r.name} for r in scored])
        out["targets"] = issue_targets(args.set, scores)
        out["scores"] = scores
        out["road_level_hat_over_truth_at_end"] = _level_ratio(scored, extras)
    out["conditions"] = _conditions_summary(conditions)
    out = _round(out)
    print(json.dumps(out, indent=1))
    if not monitor_ok:
        sys.exit(2)
    return out


if __name__ == "__main__":
    main()
