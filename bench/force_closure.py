"""The force closure (:mod:`suvtwin.estimators.force_closure`) on MuJoCo runs: each track's two tyres.

Run: ``python bench/force_closure.py [--set constant] [--runs 30] [--at 10,30] [--window 4] [--no-lag]``
— prints JSON.

The first `--runs` runs of a monitor bench set (:mod:`suvtwin.pipeline.monitor_scenarios`: Gaussian
roads, levels anywhere in the class band, 0–300 kg; the runs cached in ``bench/_runs/<set>/``,
simulated there if missing), each read from 5 s on (the start's transient left out) to 5 s + each
`--at` value. Per track the closure's objective over a grid of the two tyres' pressures (60–400 kPa,
1 kPa steps, through eq. 3–4 of the run's tyre file), its minimum taken as the estimate; the corner
parts from the SUV's parameter file with the run's loads (static travels and tyre loads), the
accelerometers' noise the run records, the delay the wheelbase over the window's mean speed (the
run's true speed), the damper's timing per track the one of 0–1 ms (quarter steps) with the least J
(``--no-lag``: 0). Printed per road class group (A–C, D): the error (estimate − truth, kPa) mean,
std, median of its magnitude over the tyres with a usable window, how many tyres had one, and (a
probe of a σ for it) the share of them within ±2σ of a posterior exp(−(J − J_min)/2s), s = J_min over
its degrees of freedom.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from suvtwin.estimators.force_closure import CornerParts, closure_objective, corner_signals
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.estimation import run_loads, static_travels, static_wheel_loads
from suvtwin.pipeline.monitor_scenarios import scenario_set, simulate_cached
from suvtwin.suspension_law import SuspensionLaw
from suvtwin.tire_stiffness import stiffness_at_pressure_array, tire_stiffness_of

START_S = 5.0
OTHER = {"fl": "fr", "fr": "fl", "rl": "rr", "rr": "rl"}


LAGS_S = (0.0, 0.25e-3, 0.5e-3, 0.75e-3, 1.0e-3)
"""The damper timings tried per track (s); the one with the least J is taken."""


def run_errors(path: Path, at_s: list[float], window_s: float, jacking: bool = True,
               lags_s: tuple[float, ...] = LAGS_S) -> dict:  # fmt: skip
    """Estimate − truth (kPa) of each tyre at each record length, NaN where no window was usable."""
    table = pq.read_table(path)
    meta = json.loads(table.schema.metadata[b"suvtwin.run"])
    frame = table.to_pandas()
    vehicle = load_vehicle(overrides=meta["scenario"].get("vehicle") or None)
    tire_file = meta["scenario"].get("tire_file")
    stiff = tire_stiffness_of(tire_file)
    damping = float(load_tire(tire_file or vehicle.tire_file).vertical_damping)
    loads = run_loads(meta)
    travel0, wheel_load = static_travels(loads, vehicle=vehicle), static_wheel_loads(loads, vehicle=vehicle)
    s = vehicle.suspension
    parts = {}
    for i, c in enumerate(CORNERS):
        front = c[0] == "f"
        law = SuspensionLaw.of(s, spring_rate=s.spring_rate_front if front else s.spring_rate_rear)
        parts[c] = CornerParts(
            unsprung_mass=vehicle.wheel.unsprung_mass_front if front else vehicle.wheel.unsprung_mass_rear,
            law=law, anti_roll=s.anti_roll_front if front else s.anti_roll_rear,
            static_travel=float(travel0[i]), static_load=float(wheel_load[i]))  # fmt: skip
    noise = max(float(meta["scenario"]["noise"]["accel_unsprung_mps2"]), 0.05)
    pressures = np.arange(60.0, 400.5, 1.0)
    grid = stiffness_at_pressure_array(pressures * 1e3, stiff.kt0, stiff.p0, stiff.pfz1)
    t = frame["t_s"].to_numpy()
    dt = float(np.median(np.diff(t[:1000])))
    out = {}
    for at in at_s:
        keep = (t >= START_S) & (t < START_S + at)
        col = {name: frame[name].to_numpy()[keep] for name in frame.columns
               if "accel" in name and "true" not in name}  # fmt: skip
        delay = vehicle.wheelbase / float(frame["speed_mps"].to_numpy()[keep].mean())
        fits = {}
        for lag in lags_s:
            acc = {c: (col[f"{c}_accel_unsprung_mps2"], col[f"{c}_accel_sprung_mps2"]) for c in CORNERS}
            sig = {c: corner_signals(*acc[c], *acc[OTHER[c]], parts[c], dt=dt, jacking=jacking,
                                     damper_lag_s=lag) for c in CORNERS}  # fmt: skip
            for f, r in (("fl", "rl"), ("fr", "rr")):
                fit = closure_objective(sig[f], sig[r], delay_s=delay, dt=dt, stiffness_grid=grid,
                                        tyre_damping=damping, noise_sigma=noise, window_s=window_s)
                if f not in fits or (fit.windows_used and fit.objective.min() < fits[f][0].objective.min()):
                    fits[f] = (fit, lag)
        errors, used, z, lags = {}, {}, {}, {}
        for f, r in (("fl", "rl"), ("fr", "rr")):
            fit, lags[f + r] = fits[f]
            for j, c in enumerate((f, r)):
                truth = float(frame[f"{c}_pressure_kpa"].to_numpy()[keep][-1])
                errors[c] = float(pressures[fit.best[j]] - truth) if fit.best else float("nan")
                used[c] = [fit.windows_used, fit.windows]
                z[c] = _z_score(fit, j, pressures, truth, window_s, dt) if fit.best else float("nan")
        out[f"{at:g}s"] = {"error_kpa": errors, "windows": used, "z": z, "damper_lag_s": lags}
    return out


def _z_score(fit, j: int, pressures: np.ndarray, truth: float, window_s: float, dt: float) -> float:
    """(estimate − truth)/σ with σ from exp(−(J − J_min)/(2 s)), s = J_min over its degrees of freedom
    (2 per frequency and window, over 1.5 for the Hann window's overlap of neighbouring bins): J
    scaled as if the model's error were white like the noise (a quasi-likelihood; a probe)."""
    freq = np.fft.rfftfreq(int(round(window_s / dt)), dt)
    dof = 2.0 * np.count_nonzero((freq > 0.5) & (freq < 20.0)) * fit.windows_used / 1.5
    scale = max(fit.objective.min() / dof, 1.0)
    post = np.exp(-(fit.objective - fit.objective.min()) / (2.0 * scale))
    marginal = post.sum(axis=1 - j)
    marginal /= marginal.sum()
    mean = float(np.sum(marginal * pressures))
    sigma = float(np.sqrt(np.sum(marginal * (pressures - mean) ** 2)))
    return (mean - truth) / max(sigma, 0.5)


def _summary(errors: np.ndarray) -> dict:
    e = errors[np.isfinite(errors)]
    if not e.size:
        return {"tyres_with_a_window": 0, "tyres": int(errors.size)}
    return {"tyres_with_a_window": int(e.size), "tyres": int(errors.size),
            "mean_kpa": round(float(e.mean()), 2), "std_kpa": round(float(e.std()), 2),
            "median_abs_kpa": round(float(np.median(np.abs(e))), 2)}  # fmt: skip


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--set", default="constant", help="monitor bench set (default constant)")
    parser.add_argument("--runs", type=int, default=30, help="runs of the set (default 30)")
    parser.add_argument("--at", default="10,30", help="record lengths after the first 5 s, s (default 10,30)")
    parser.add_argument("--window", type=float, default=4.0, help="window length, s (default 4)")
    parser.add_argument("--no-lag", action="store_true", help="the damper's timing taken as 0 (default: "
                        "per track the least J of 0, 0.25, 0.5, 0.75, 1 ms)")
    parser.add_argument("--static-travel", action="store_true",
                        help="the travel's mean at the loads' static travel (default: less the jacking)")
    args = parser.parse_args(argv)
    at_s = [float(a) for a in args.at.split(",")]
    runs = scenario_set(args.set, args.runs)
    folder = Path(__file__).resolve().parent / "_runs" / args.set
    paths, _ = simulate_cached(runs, folder, jobs=2)
    per_run = []
    for run, path in zip(runs, paths, strict=True):
        if path is None:
            continue
        lags = (0.0,) if args.no_lag else LAGS_S
        per_run.append((run, run_errors(path, at_s, args.window, not args.static_travel, lags)))
        print(f"force_closure: {run.name}", file=sys.stderr, flush=True)
    out: dict = {"bench": "force_closure", "set": args.set, "runs": len(per_run), "window_s": args.window,
                 "travel_mean": "static" if args.static_travel else "jacking",
                 "damper_lags_s": [0.0] if args.no_lag else list(LAGS_S), "results": {}}  # fmt: skip
    for at in at_s:
        key = f"{at:g}s"
        groups: dict[str, list] = {"A-C": [], "D": []}
        zs: dict[str, list] = {"A-C": [], "D": []}
        for run, result in per_run:
            group = "D" if run.info["road_class"] == "D" else "A-C"
            groups[group] += [result[key]["error_kpa"][c] for c in CORNERS]
            zs[group] += [result[key]["z"][c] for c in CORNERS]
        out["results"][key] = {g: _summary(np.array(v, dtype=float)) for g, v in groups.items()}
        for g, v in zs.items():
            z = np.array(v, dtype=float)
            z = z[np.isfinite(z)]
            if z.size:
                out["results"][key][g]["inside_2sigma"] = round(float(np.mean(np.abs(z) <= 2.0)), 3)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main()
