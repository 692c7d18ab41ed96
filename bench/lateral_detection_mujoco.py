"""Solmaz's 16-model deflation detector on the MuJoCo SUV: ISO 3888-1 double lane changes, Monte Carlo.

Run: ``python bench/lateral_detection_mujoco.py [--runs 120] [--jobs 2] [--runs-dir DIR]`` — prints JSON.

Two tyre cases: ``shipped`` (the SUV's .tir, whose cornering stiffness *rises* at low pressure,
PPY1 < 0) and ``softer_deflated`` (``mjcf/suv/suv_235_60R18_softer_deflated.tir``, a labelled
sensitivity case whose cornering stiffness falls 20 % from 250 to 150 kPa: paper 004's premise).
Per case the bank's arctan tyres are fitted from simulator runs
(:func:`suvtwin.pipeline.lateral_detection.fit_bank`: nominal 250 kPa, deflated 155 kPa), then
``--runs`` lane changes are drawn with ``numpy.random.default_rng(900000 + i)`` (the same draws in
both cases): speed uniform 80–120 km/h, direction left or right, the deflated tyre FL, FR, RL, RR
or none in turn (run i: ``i % 5``, so exactly 20 % have none), its pressure uniform 130–180 kPa,
an extra load uniform 0–300 kg at x ∈ [−1.8, 0.5] m, y ∈ [−0.5, 0.5] m, z ∈ [−0.2, 0.2] m from the
chassis CoG (boot to front seats). The detector knows the load (its vehicle includes it).
Runs are simulated in ``--jobs`` processes into ``bench/_runs/lateral_detection/<case>/`` (one
Parquet file per run, named by the hash of its scenario and the simulator's code: reused on a
second call).

Detector variants (paper cost: α 0, γ 1, λ 0; ESC noise σ 0.05 m/s², 0.2 °/s, seeded per run):
``esc_body`` — a_y as a body-fixed sensor reads it (roll's gravity component included), sideslip
by eq. 10; ``roll_compensated`` — the horizontal a_y, eq. 10; ``ideal_sideslip`` — the horizontal
a_y and the true sideslip. Scored per variant: confusion matrix (true model vs final pick; 1 RR,
2 RL, 4 FR, 8 FL, 16 none), the correct rate, the detection delay (steering onset — |δ| first at
10 % of its peak — to the first sample from which the true model is selected to the end), and
the false-alarm rate (share of no-deflation runs ending on a deflated model).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import sys
import time
from pathlib import Path

import numpy as np

CASES = {"shipped": None, "softer_deflated": "softer_deflated"}
VARIANTS = {  # name: (accel frame, true sideslip)
    "esc_body": ("body", False),
    "roll_compensated": ("horizontal", False),
    "ideal_sideslip": ("horizontal", True),
}
CHOICES = ("fl", "fr", "rl", "rr", None)
SEED0 = 900000


def tire_file(case: str) -> str | None:
    """The .tir of a case (None: the SUV's)."""
    from suvtwin.mjcf.vehicle import load_vehicle

    if CASES[case] is None:
        return None
    return str(load_vehicle().tire_file.with_name("suv_235_60R18_softer_deflated.tir"))


def draw(i: int, case: str) -> dict:
    """Run i's draws (independent of the case)."""
    rng = np.random.default_rng(SEED0 + i)
    speed = float(rng.uniform(80.0, 120.0))
    direction = "left" if rng.random() < 0.5 else "right"
    pressure = float(rng.uniform(130.0, 180.0))
    load = float(rng.uniform(0.0, 300.0))
    position = (float(rng.uniform(-1.8, 0.5)), float(rng.uniform(-0.5, 0.5)), float(rng.uniform(-0.2, 0.2)))
    tyre = CHOICES[i % 5]
    return {"i": i, "speed_kmh": round(speed, 2), "direction": direction, "tyre": tyre,
            "pressure_kpa": round(pressure, 1), "load_kg": round(load, 1),
            "load_position_m": [round(p, 3) for p in position], "case": case}  # fmt: skip


def scenario_of(d: dict):
    from suvtwin.pipeline.lateral_detection import CORNERS, NOMINAL_KPA, lane_change_scenario

    p = {c: (d["pressure_kpa"] if c == d["tyre"] else NOMINAL_KPA) for c in CORNERS}
    return lane_change_scenario(speed_kmh=d["speed_kmh"], pressure_kpa=p, direction=d["direction"],
                                load_kg=d["load_kg"], load_position_m=tuple(d["load_position_m"]),
                                tire_file=tire_file(d["case"]), seed=d["i"])  # fmt: skip


def _detect_one(item: tuple) -> dict:
    path, d, bank = item
    from suvtwin.pipeline.lateral_detection import ESC_NOISE, detect_run, two_track_vehicle
    from suvtwin.pipeline.simulator import read_run

    table, _ = read_run(path)
    vehicle = two_track_vehicle(scenario_of(d))
    out = {"draw": d, "peak_ay_mps2": float(np.abs(table["lat_accel_mps2"]).max()),
           "peak_roll_deg": float(np.degrees(np.abs(table["roll_rad"]).max()))}  # fmt: skip
    for name, (accel, beta) in VARIANTS.items():
        det = detect_run(table, vehicle, bank, accel=accel, noise=ESC_NOISE, seed=d["i"], true_sideslip=beta)
        out[name] = {"truth": det.truth, "final": det.final, "delay_s": det.delay_s, "onset_s": det.onset_s}
    return out


def score(rows: list[dict], variant: str) -> dict:
    """Confusion matrix, correct rate, delay distribution and false alarms of one variant."""
    truths = sorted({r[variant]["truth"] for r in rows})
    picks = sorted({r[variant]["final"] for r in rows} | set(truths))
    matrix = {str(t): {str(p): sum(1 for r in rows if r[variant]["truth"] == t and r[variant]["final"] == p)
                       for p in picks} for t in truths}  # fmt: skip
    correct = [r[variant]["final"] == r[variant]["truth"] for r in rows]
    delays = np.array([r[variant]["delay_s"] for r in rows if r[variant]["truth"] != 16], dtype=float)
    delays = delays[np.isfinite(delays)]
    nominal = [r for r in rows if r[variant]["truth"] == 16]
    per_truth = {str(t): float(np.mean([r[variant]["final"] == t for r in rows if r[variant]["truth"] == t]))
                 for t in truths}  # fmt: skip
    return {
        "runs": len(rows),
        "correct_rate": float(np.mean(correct)),
        "correct_rate_per_truth": per_truth,
        "confusion_truth_vs_final": matrix,
        "delay_s_deflated_runs_found": {
            "n": int(delays.size),
            "quantiles_0_25_50_75_90_100": [float(q) for q in np.quantile(delays, [0, .25, .5, .75, .9, 1])]
            if delays.size else None,
            "histogram_edges_s": [0, 0.5, 1, 1.5, 2, 3, 4, 6, 10],
            "histogram_counts": np.histogram(delays, bins=[0, 0.5, 1, 1.5, 2, 3, 4, 6, 10])[0].tolist(),
        },
        "false_alarm_rate_no_deflation": (float(np.mean([r[variant]["final"] != 16 for r in nominal]))
                                          if nominal else None),  # fmt: skip
    }


def run_case(case: str, n_runs: int, jobs: int, runs_dir: Path) -> dict:
    from suvtwin.pipeline.lateral_detection import fit_bank
    from suvtwin.pipeline.monitor_scenarios import BenchRun, simulate_cached

    started = time.perf_counter()
    bank = fit_bank(tire_file(case))
    fit_s = time.perf_counter() - started
    draws = [draw(i, case) for i in range(n_runs)]
    runs = [BenchRun(name=f"{case}-{d['i']}", set="lateral_detection", scenario=scenario_of(d))
            for d in draws]  # fmt: skip
    paths, cost = simulate_cached(runs, runs_dir / case, jobs=jobs)
    items = [(str(p), d, bank) for p, d in zip(paths, draws, strict=True) if p is not None]
    started = time.perf_counter()
    if jobs > 1:
        ctx = multiprocessing.get_context("spawn" if os.name == "nt" else "forkserver")
        with ctx.Pool(jobs) as pool:
            rows = pool.map(_detect_one, items)
    else:
        rows = [_detect_one(it) for it in items]
    detect_s = time.perf_counter() - started
    return {
        "bank": bank.as_dict(),
        "bank_fit_s": round(fit_s, 2),
        "simulation": cost,
        "detection_wall_s": round(detect_s, 2),
        "peak_ay_mps2_quantiles_0_50_100": [float(q) for q in np.quantile([r["peak_ay_mps2"] for r in rows],
                                                                           [0, .5, 1])],  # fmt: skip
        "peak_roll_deg_quantiles_0_50_100": [float(q) for q in np.quantile([r["peak_roll_deg"] for r in rows],
                                                                            [0, .5, 1])],  # fmt: skip
        "variants": {v: score(rows, v) for v in VARIANTS},
    }


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=120, help="lane changes per tyre case (default 120)")
    parser.add_argument("--jobs", type=int, default=2, help="processes (default 2)")
    default_dir = Path(__file__).parent / "_runs" / "lateral_detection"
    parser.add_argument("--runs-dir", type=Path, default=default_dir)
    parser.add_argument("--case", choices=sorted(CASES), action="append", help="default: both")
    args = parser.parse_args(argv)
    if args.runs < 1 or args.jobs < 1:
        parser.error("--runs and --jobs must be >= 1")
    report = {"runs_per_case": args.runs, "cases": {}}
    for case in args.case or list(CASES):
        report["cases"][case] = run_case(case, args.runs, args.jobs, args.runs_dir)
    return report


if __name__ == "__main__":
    json.dump(main(sys.argv[1:]), sys.stdout, indent=1)
    print()
