"""The front→rear preview (:mod:`suvtwin.estimators.preview`) on the cached MuJoCo runs: accuracy and cost.

Run: ``python bench/preview_mujoco.py [--runs-dir bench/_runs/constant] [--runs 100] [--no-monitor]``
— prints JSON. One process; the run files are only read.

Per run and track (fl→rl, fr→rr) a :class:`~suvtwin.estimators.preview.PreviewTrack` (the run's
corner models and tyre) is fed the measured unsprung and sprung accelerations and the
speed in 1 s chunks (``--memory-s``: the statistics forgotten with that time constant before each);
at each time T of ``--times`` it gives the rear pressure (i) given the TRUE front
pressure (σ_f = 0), (ii) given the monitor's front estimate and σ at its last update at or before T
(:func:`suvtwin.pipeline.monitoring.monitor_run`, columns ``{c}_vibration_pressure_kpa``,
``{c}_vibration_sigma_kpa``: without the radii), beside (iii) the monitor's own rear estimate, and (iv)
both pressures fused (:func:`~suvtwin.estimators.preview.fuse_track`: the monitor's front and rear and
the preview, their errors correlated by ``--correlation``, default the monitor's).
Errors (estimate − truth, kPa): mean ± std and the share within ±2σ, over all tracks and split by
the track's dynamic load coefficient (≤ / > ``rough_dlc``, the preview's own, accumulated up to T);
the preview's rows only where it says it is informative (counted). Cost: wall time of ``add`` per
1 s chunk and of ``conditional`` per call (one track, one core).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from suvtwin.estimators.monitor import MonitorConfig
from suvtwin.estimators.preview import PreviewConfig, PreviewTrack, fuse_track
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.estimation import run_load_and_tire, run_loads
from suvtwin.pipeline.monitoring import corner_models, monitor_run
from suvtwin.tire_stiffness import tire_stiffness_of

TRACKS = (("fl", "rl"), ("fr", "rr"))


def read_run(path: Path) -> dict:
    cols = ["t_s", "speed_mps"]
    cols += [f"{c}_accel_{w}_mps2" for w in ("sprung", "unsprung") for c in CORNERS]
    cols += [f"{c}_pressure_kpa" for c in CORNERS]
    table = pq.read_table(path, columns=cols)
    meta = json.loads(table.schema.metadata[b"suvtwin.run"])
    col = {c: table[c].to_numpy() for c in cols}
    return {"col": col, "meta": meta}


def summary(errors, sigmas) -> dict:
    e, s = np.asarray(errors, dtype=float), np.asarray(sigmas, dtype=float)
    if e.size == 0:
        return {"n": 0}
    return {
        "n": int(e.size),
        "mean_kpa": round(float(e.mean()), 2),
        "std_kpa": round(float(e.std()), 2),
        "within_2sigma": round(float(np.mean(np.abs(e) <= 2 * s)), 3),
        "median_sigma_kpa": round(float(np.median(s)), 2),
    }


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs-dir", default="bench/_runs/constant")
    ap.add_argument("--runs", type=int, default=100)
    ap.add_argument("--times", default="10,30", help="evaluation times, s")
    ap.add_argument("--no-monitor", action="store_true", help="only the preview at the true front")
    ap.add_argument(
        "--memory-s", type=float, default=None, help="forgetting time constant τ, s (default none)"
    )
    ap.add_argument("--sigma-scale", type=float, default=PreviewConfig.sigma_scale)
    ap.add_argument(
        "--correlation", type=float, default=MonitorConfig.preview_correlation,
        help="correlation of the front's and rear's own errors in the fusion (default the monitor's)",
    )  # fmt: skip
    a = ap.parse_args()
    times = [float(x) for x in a.times.split(",")]
    paths = sorted(Path(a.runs_dir).glob("*.parquet"))[: a.runs]
    config = PreviewConfig(sigma_scale=a.sigma_scale)
    wheelbase = float(load_vehicle().wheelbase)
    rows = []
    t_add, t_cond = [], []
    t0 = time.perf_counter()
    for path in paths:
        run = read_run(path)
        col, meta = run["col"], run["meta"]
        load_kg, tire_file = run_load_and_tire(meta, path)
        models = corner_models(CORNERS, loads=run_loads(meta), tire_file=tire_file)
        models = dict(zip(CORNERS, models, strict=True))
        tire = tire_stiffness_of(tire_file)
        dt = float(np.mean(np.diff(col["t_s"])))
        p_true = {c: float(np.mean(col[f"{c}_pressure_kpa"])) for c in CORNERS}
        mon = None if a.no_monitor else monitor_run(path, preview=False).table  # the rear on its own
        step = int(round(1.0 / dt))
        for front, rear in TRACKS:
            track = PreviewTrack(models[front], models[rear], tire, tire, dt, wheelbase, config)
            fed = 0
            for T in times:
                end = int(round(T / dt))
                while fed < end:
                    sl = slice(fed, min(fed + step, end))
                    c0 = time.perf_counter()
                    if a.memory_s is not None:
                        track.decay(np.exp(-(sl.stop - sl.start) * dt / a.memory_s))
                    track.add(
                        col[f"{front}_accel_unsprung_mps2"][sl], col[f"{rear}_accel_unsprung_mps2"][sl],
                        col["speed_mps"][sl], acc_s_front=col[f"{front}_accel_sprung_mps2"][sl],
                        acc_s_rear=col[f"{rear}_accel_sprung_mps2"][sl],
                    )  # fmt: skip
                    t_add.append(time.perf_counter() - c0)
                    fed = sl.stop
                c0 = time.perf_counter()
                true_front = track.conditional(p_true[front], 0.0)
                t_cond.append(time.perf_counter() - c0)
                row = {
                    "run": path.stem, "track": f"{front}-{rear}", "t_s": T, "load_kg": load_kg,
                    "p_front_kpa": p_true[front], "p_rear_kpa": p_true[rear], "dlc": track.dlc(),
                    "true_front": {"mean": true_front.mean_kpa, "sigma": true_front.sigma_kpa,
                                   "sigma_lik": true_front.sigma_likelihood_kpa,
                                   "informative": true_front.informative, "reason": true_front.reason},
                }  # fmt: skip
                if mon is not None:
                    last = mon[mon["t_s"] <= T + 1e-9]
                    if len(last):
                        r = last.iloc[-1]
                        pf = float(r[f"{front}_vibration_pressure_kpa"])
                        sf = float(r[f"{front}_vibration_sigma_kpa"])
                        lo, hi = config.pressure_range_kpa
                        given = track.conditional(min(max(pf, lo), hi), sf)
                        row["monitor_front"] = {
                            "mean": given.mean_kpa, "sigma": given.sigma_kpa,
                            "informative": given.informative, "slope": given.ridge_slope,
                        }  # fmt: skip
                        row["monitor_rear"] = {"mean": float(r[f"{rear}_vibration_pressure_kpa"]),
                                               "sigma": float(r[f"{rear}_vibration_sigma_kpa"])}  # fmt: skip
                        row["monitor_front_own"] = {"mean": pf, "sigma": sf}
                        pr, sr = row["monitor_rear"]["mean"], row["monitor_rear"]["sigma"]
                        if given.informative and sr > 0:
                            pf_in = min(max(pf, lo), hi)
                            m, cv = fuse_track(pf_in, sf, pr, sr, given, correlation=a.correlation)
                            row["fused_front"] = {"mean": float(m[0]), "sigma": float(np.sqrt(cv[0, 0]))}
                            row["fused_rear"] = {"mean": float(m[1]), "sigma": float(np.sqrt(cv[1, 1]))}
                rows.append(row)
    wall = time.perf_counter() - t0

    def table(key: str, T: float, cond=lambda r: True) -> dict:
        sel = [r for r in rows if r["t_s"] == T and key in r and cond(r)]
        used = [r for r in sel if r[key].get("informative", True) and np.isfinite(r[key]["mean"])]
        truth = "p_front_kpa" if key in ("monitor_front_own", "fused_front") else "p_rear_kpa"
        out = summary([r[key]["mean"] - r[truth] for r in used], [r[key]["sigma"] for r in used])
        out["not_informative"] = len(sel) - len(used)
        return out

    rough = config.rough_dlc
    splits = {
        "all": lambda r: True,
        "dlc_le": lambda r: np.isfinite(r["dlc"]) and r["dlc"] <= rough,
        "dlc_gt": lambda r: not (np.isfinite(r["dlc"]) and r["dlc"] <= rough),
    }
    keys = ["true_front"]
    if not a.no_monitor:
        keys += ["monitor_front", "monitor_rear", "monitor_front_own", "fused_rear", "fused_front"]
    result = {
        "runs": len(paths),
        "tracks": 2 * len(paths),
        "config": {k: getattr(config, k) for k in config.__dataclass_fields__},
        "memory_s": a.memory_s,
        "correlation": a.correlation,
        "rows": {
            f"{key}@{T:g}s": {name: table(key, T, c) for name, c in splits.items()}
            for key in keys
            for T in times
        },
        "cost": {
            "add_per_1s_chunk_ms": {
                "median": round(1e3 * float(np.median(t_add)), 4),
                "p95": round(1e3 * float(np.percentile(t_add, 95)), 4),
            },
            "conditional_ms": {
                "median": round(1e3 * float(np.median(t_cond)), 4),
                "p95": round(1e3 * float(np.percentile(t_cond, 95)), 4),
            },
            "state_bytes_per_track": track.state_nbytes,
        },  # fmt: skip
        "wall_s": round(wall, 1),
        "notes": "errors estimate − truth, kPa; 'dlc_le'/'dlc_gt': the track's DLC up to T ≤ / > rough_dlc; "
        "monitor_front_own: the monitor's front estimate itself; fused_front/fused_rear: fuse_track of the "
        "monitor's two and the preview; preview rows only where informative",
    }
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
