"""Why the radius analysis's blocks are off on rough roads: the wheels' longitudinal slip, not their radii.

Run: ``python bench/radius_slip.py [--set constant] [--runs-dir bench/_runs/<set>] [--runs 100]``;
prints JSON.
One process; the cached runs of ``bench/monitor_mujoco.py``'s set (``constant`` by default) are read
(simulated first if missing).

Per run, 4 s block and wheel (the blocks after the first 8 s): the block's mean log-radius excess
as the radius analysis reads it from the wheel speeds
(:meth:`suvtwin.estimators.rolling_radius.RollingRadius.sample_excess`) against

- (a) MF-Tyre 6.1's effective rolling radius at the tyre's pressure and its mean load over the block
  (the simulator's true ``{c}_tire_fz_n``): what the analysis assumes;
- (b) the same, with the excess of the block's true mean longitudinal slip ratio
  (``{c}_tire_slip_ratio``, κ = (ω R_e − v)/v) taken out: the part of (a) that is the
  wheel slipping under its drive torque, not its radius;
- (c) MF-Tyre's log radius averaged over the block's samples of the true load (the radius's
  dynamic mean; ln R_e is concave in F_z);
- (d) as (a), with the samples left out where a wheel carries under ``min_load_share`` of its static
  load by its two accelerometers (:func:`suvtwin.pipeline.monitoring.tyre_load_share`), as the
  radius analysis does: the wheels off the ground;
- (e) against MF-Tyre's radius at the wheels' STATIC loads (what the monitor's fusion assumes), split
  into the slip's part (b's correction) and the part of the load the car's motion moves between
  the wheels (drag and pitch: (a)'s reference less (e)'s).

Printed: the RMS of each error (‰) by the block's largest per-sample scatter of the wheels' excess
(‰, the analysis's roughness measure; its ``max_scatter_permille`` skips blocks beyond 10) and by
road class, with the blocks' median share of samples with a wheel off the ground. A car measures
neither κ nor F_z: (b) says how much of the error a model of the slip (drive torque over slip
stiffness, which varies with the load) could remove, (c) whether the radius's own nonlinearity
explains it, (d) what is left with the measured gate. Blocks with under half their samples
counted are left out, and of (d) those where under ``RadiusConfig.min_valid_share`` pass the gate
(``blocks_gated``), as the analysis skips them; ``gated_by_counted_share`` gives (d) by the share
of the block's samples the gate keeps; ``smooth_by_speed`` the mean of (e), its slip part and its
load part per wheel (‰) over the smooth blocks (sample scatter under 4 ‰) by speed. ``--set``:
another cached set's runs (``warning``, ``drop``, ``slow_leak``; the truth is each block's mean
pressure, so the changing sets are scored too).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from suvtwin.estimators.rolling_radius import RadiusConfig, RollingRadius, excess_of
from suvtwin.mjcf.tire import effective_rolling_radius, load_tire
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.estimation import run_loads, static_wheel_loads
from suvtwin.pipeline.monitor_scenarios import scenario_set, simulate_cached
from suvtwin.pipeline.monitoring import tyre_load_share, wheel_positions

BLOCK_S, SKIP_S = 4.0, 8.0
SCATTER_EDGES = (0.0, 2.0, 4.0, 7.0, 10.0, 20.0, np.inf)
COUNTED_EDGES = (0.05, 0.15, 0.25, 0.35, 0.5, 0.75, 1.01)
SPEED_EDGES = (10.0, 15.0, 20.0, 25.0, 30.0, 35.0)


def block_errors(path: Path, tire) -> dict[str, np.ndarray]:
    """Per block (after `SKIP_S`): the excess errors (a), (b), (c), (d) of the module docstring (B, C;
    (d) NaN where no sample passes the gate), the share of samples that pass it (B,), the wheels'
    largest sample scatter (B,) and the share of samples with a wheel off the ground (B,)."""
    names = ("wheel_speed_radps", "tire_fz_n", "pressure_kpa", "tire_slip_ratio", "accel_sprung_mps2",
             "accel_unsprung_mps2")  # fmt: skip
    columns = ["t_s", "yaw_rate_radps", "speed_mps"] + [f"{c}_{k}" for c in CORNERS for k in names]
    tab = pq.read_table(path, columns=columns)
    col = {k: tab[k].to_numpy() for k in columns}
    vehicle = load_vehicle()
    loads = run_loads(json.loads(tab.schema.metadata[b"suvtwin.run"]))
    share = tyre_load_share(
        np.stack([col[f"{c}_accel_sprung_mps2"] for c in CORNERS], axis=1),
        np.stack([col[f"{c}_accel_unsprung_mps2"] for c in CORNERS], axis=1), loads=loads, vehicle=vehicle,
    )  # fmt: skip
    with np.errstate(invalid="ignore"):
        carried = np.all(share >= RadiusConfig().min_load_share, axis=1)
    t = col["t_s"]
    dt = float(np.median(np.diff(t)))
    analysis = RollingRadius(wheel_positions(load_vehicle()), dt, tire.unloaded_radius)
    w = np.stack([col[f"{c}_wheel_speed_radps"] for c in CORNERS], axis=1)
    e, ok = analysis.sample_excess(w, col["yaw_rate_radps"])
    fz = np.stack([col[f"{c}_tire_fz_n"] for c in CORNERS], axis=1)
    p_pa = 1e3 * np.stack([col[f"{c}_pressure_kpa"] for c in CORNERS], axis=1)
    kappa = np.stack([col[f"{c}_tire_slip_ratio"] for c in CORNERS], axis=1)
    tp = tire.to_array()
    static_fz = static_wheel_loads(loads, vehicle=vehicle)
    n = int(round(BLOCK_S / dt))
    out: dict[str, list] = {"a": [], "b": [], "c": [], "d": [], "scatter": [], "airborne": [], "counted": [],
                            "speed": [], "static": [], "slip": [], "load": []}  # fmt: skip
    for start in range(int(round(SKIP_S / dt)), t.size - n + 1, n):
        s = slice(start, start + n)
        if ok[s].mean() < 0.5:
            continue
        meas = e[s][ok[s]].mean(axis=0)
        scatter = e[s][ok[s]].std(axis=0).max()
        mean_fz, mean_p = fz[s].mean(axis=0), p_pa[s].mean(axis=0)
        static = np.log([effective_rolling_radius(f, q, tp) for f, q in zip(mean_fz, mean_p, strict=True)])
        sub = slice(start, start + n, 10)  # the radius's dynamic mean from every 10th sample
        dyn = np.mean([[np.log(effective_rolling_radius(f, q, tp)) for f, q in zip(fr, pr, strict=True)]
                       for fr, pr in zip(fz[sub], p_pa[sub], strict=True)], axis=0)  # fmt: skip
        err_a = meas - excess_of(static)
        out["a"].append(err_a)
        # (e) against MF-Tyre at the static loads (what the monitor's fusion assumes), split into the
        # slip's part and the part of the load the car's motion moves between the wheels (drag, pitch)
        at_static = excess_of(
            np.log([effective_rolling_radius(f, q, tp) for f, q in zip(static_fz, mean_p, strict=True)])
        )
        # ω R_e = v (1 + κ): −ln ω = ln R_e − ln v − ln(1 + κ), so the slip moves the excess by −excess(κ)
        slip = -excess_of(np.log1p(kappa[s].mean(axis=0)))
        out["static"].append(meas - at_static)
        out["slip"].append(slip)
        out["load"].append(excess_of(static) - at_static)
        out["speed"].append(float(np.mean(col["speed_mps"][s])))
        out["b"].append(err_a - slip)
        out["c"].append(meas - excess_of(dyn))
        gate = ok[s] & carried[s]
        nan = np.full(len(CORNERS), np.nan)
        out["d"].append(e[s][gate].mean(axis=0) - excess_of(static) if gate.any() else nan)
        out["counted"].append(float(gate.mean()))
        out["scatter"].append(scatter)
        out["airborne"].append(float(np.mean(np.any(fz[s] <= 1.0, axis=1))))
    return {k: np.array(v) for k, v in out.items()}


def _rms(x: np.ndarray) -> float | None:
    x = x[np.all(np.isfinite(x), axis=-1)] if x.ndim > 1 else x
    return float(1e3 * np.sqrt(np.mean(x**2))) if x.size else None


def _summary(blocks: dict[str, np.ndarray], mask: np.ndarray) -> dict:
    gated = mask & (blocks["counted"] >= RadiusConfig().min_valid_share)
    return {
        "blocks": int(mask.sum()),
        "rms_permille": {k: _rms(blocks[k][gated if k == "d" else mask]) for k in ("a", "b", "c", "d")},
        "blocks_gated": int(gated.sum()),
        "airborne_share_median": float(np.median(blocks["airborne"][mask])) if mask.any() else None,
    }


def _by_speed(blocks: dict[str, np.ndarray], scatter_permille: np.ndarray) -> dict:
    """Smooth blocks (wheels' sample scatter under 4 ‰) by mean speed: per wheel (fl, fr, rl, rr) the
    mean error (e) against MF-Tyre at the static loads, its slip part and its load-transfer part, ‰."""
    out = {}
    for lo, hi in zip(SPEED_EDGES[:-1], SPEED_EDGES[1:], strict=True):
        sel = (scatter_permille < 4.0) & (blocks["speed"] >= lo) & (blocks["speed"] < hi)
        out[f"{lo:g}-{hi:g} m/s"] = {
            "blocks": int(sel.sum()),
            **{k: [round(float(x), 3) for x in 1e3 * blocks[k][sel].mean(axis=0)] if sel.any() else None
               for k in ("static", "slip", "load")},  # fmt: skip
        }
    return out


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", default="constant", choices=["constant", "slow_leak", "drop", "warning"])
    parser.add_argument("--runs-dir", type=Path, default=None)
    parser.add_argument("--runs", type=int, default=100)
    args = parser.parse_args(argv)
    runs = scenario_set(args.set, args.runs)
    runs_dir = args.runs_dir or Path(__file__).resolve().parent / "_runs" / args.set
    paths, _ = simulate_cached(runs, runs_dir, jobs=1)
    tire = load_tire(None)
    per_run = [(r.info["road_class"], block_errors(p, tire)) for r, p in zip(runs, paths, strict=True) if p]
    keys = ("a", "b", "c", "d", "scatter", "airborne", "counted", "speed", "static", "slip", "load")
    blocks = {k: np.concatenate([b[k] for _, b in per_run]) for k in keys}
    road = np.concatenate([[cls] * len(b["scatter"]) for cls, b in per_run])
    scatter = 1e3 * blocks["scatter"]
    by_scatter = {}
    for lo, hi in zip(SCATTER_EDGES[:-1], SCATTER_EDGES[1:], strict=True):
        by_scatter[f"{lo:g}-{hi:g}"] = _summary(blocks, (scatter >= lo) & (scatter < hi))
    out = {
        "bench": "radius_slip",
        "set": args.set,
        "runs": len(per_run),
        "block_s": BLOCK_S,
        "errors": {"a": "against MF-Tyre R_e at the mean load", "b": "(a) with the true mean slip taken out",
                   "c": "against MF-Tyre ln R_e averaged over the true load",
                   "d": "(a) without the samples where a wheel is (nearly) off the ground"},  # fmt: skip
        "all": _summary(blocks, np.ones(scatter.size, bool)),
        "by_scatter_permille": by_scatter,
        "by_class": {c: _summary(blocks, road == c) for c in sorted(set(road))},
        "smooth_by_speed": _by_speed(blocks, scatter),
        "gated_by_counted_share": {
            f"{lo:g}-{hi:g}": {
                "blocks": int(sel.sum()),
                "rms_permille": _rms(blocks["d"][sel]),
                "by_class": {c: {"blocks": int((sel & (road == c)).sum()),
                                 "rms_permille": _rms(blocks["d"][sel & (road == c)])}
                             for c in sorted(set(road))},  # fmt: skip
            }
            for lo, hi in zip(COUNTED_EDGES[:-1], COUNTED_EDGES[1:], strict=True)
            for sel in [(blocks["counted"] >= lo) & (blocks["counted"] < hi)]
        },
    }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
