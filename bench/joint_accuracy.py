"""Accuracy of the road-level-free (joint Whittle) estimator on quarter-car truth, as JSON.

Usage: ``python bench/joint_accuracy.py [seeds, comma-separated] [duration_s] [segment_s]``
(default ``2,11,7,3,5 10``; a `segment_s` runs the Bartlett-segment spectrum instead of the
whole-record periodogram).

Per batch seed: 20 runs of ``suvtwin.pipeline.quarter_car_truth.quarter_car_runs`` (linear quarter car, RK4 at
1 kHz, 60 km/h, 0.5 m/s² noise, pressure uniform 130-230 kPa, road levels inside classes
A-D); the pressure error's mean and std (kPa) at 2, 5, 10 (and 30) s, the share of samples
after 4 s with |error| <= 2 sigma, the estimator's wall time, and the Cramér-Rao bound of
the Gaussian road model at the end of the record (RMS over the runs' true pressures and
levels, from the Whittle Fisher information of (k_t, log S_v) in the estimator's band).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from suvtwin.estimators.joint import N0, LinearQuarterCar, corner_response, estimate_joint
from suvtwin.estimators.quarter_car import (
    pressure_sigma_from_stiffness_sigma,
    stiffness_from_pressure,
)
from suvtwin.pipeline.quarter_car_truth import SPEED_MPS as SPEED
from suvtwin.pipeline.quarter_car_truth import TEST_CORNER, quarter_car_runs
from suvtwin.pipeline.quarter_car_truth import TIMESTEP_S as DT

QC = LinearQuarterCar(TEST_CORNER.sprung_mass, TEST_CORNER.unsprung_mass, TEST_CORNER.spring_rate,
                      TEST_CORNER.damping)  # fmt: skip
RUNS = 20


def cramer_rao_pressure_std(pressure, level, duration, band=(0.05, 1.5), fmax=30.0, sigma=0.5):
    """Whittle Cramér-Rao bound of the pressure std (Pa) with the level free, one run."""
    f = np.arange(1, int(duration / (2 * DT))) / duration
    f = f[(f >= band[0] * SPEED) & (f <= min(band[1] * SPEED, fmax))]
    noise = 2.0 * sigma**2 * DT
    sv = 4.0 * np.pi**2 * N0**2 * SPEED * level
    kt = stiffness_from_pressure(pressure)

    def log_s(k, lsv):
        h1, h2 = corner_response(f, k, QC)
        return np.log1p(np.exp(lsv) * (np.abs(h1) ** 2 + np.abs(h2) ** 2) / noise)

    dk = 1e-4 * kt
    d_kt = (log_s(kt + dk, np.log(sv)) - log_s(kt - dk, np.log(sv))) / (2 * dk)
    d_lv = (log_s(kt, np.log(sv) + 1e-4) - log_s(kt, np.log(sv) - 1e-4)) / 2e-4
    fisher = np.array([[d_kt @ d_kt, d_kt @ d_lv], [d_lv @ d_kt, d_lv @ d_lv]])
    return float(pressure_sigma_from_stiffness_sigma(np.sqrt(np.linalg.inv(fisher)[0, 0])))


def batch(seed, duration, segment_s):
    n_steps = int(round(duration / DT))
    runs = quarter_car_runs(RUNS, n_steps, seed=seed)
    pressure, acc = runs.pressure, runs.acc
    start = time.perf_counter()
    est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED, segment_s=segment_s)
    wall = time.perf_counter() - start
    error = (est.pressure_pa - pressure[:, None]) / 1e3
    row = {}
    for t in (2.0, 5.0, 10.0, 30.0):
        if t <= duration:
            i = min(int(round(t / DT)), n_steps - 1)
            row[f"at_{t:g}s_kpa"] = {"mean": round(float(error[:, i].mean()), 1),
                                     "std": round(float(error[:, i].std()), 1)}  # fmt: skip
    after = est.t_s >= 4.0
    row["coverage_2sigma_after_4s"] = round(
        float(np.mean(np.abs(error[:, after]) <= 2 * est.pressure_sigma_pa[:, after] / 1e3)), 3
    )
    levels = runs.gd_n0
    bound = [cramer_rao_pressure_std(p, g, duration) for p, g in zip(pressure, levels, strict=True)]
    row[f"cramer_rao_std_at_{duration:g}s_kpa"] = round(float(np.sqrt(np.mean(np.square(bound)))) / 1e3, 1)
    row["wall_s"] = round(wall, 2)
    return row


def main(seeds=(2, 11, 7, 3, 5), duration=10.0, segment_s=None):
    out = {"runs_per_batch": RUNS, "duration_s": duration, "segment_s": segment_s, "batches": {}}
    for seed in seeds:
        out["batches"][str(seed)] = batch(seed, duration, segment_s)
    key = f"at_{min(duration, 10.0):g}s_kpa"
    stds = [b[key]["std"] for b in out["batches"].values()]
    means = [b[key]["mean"] for b in out["batches"].values()]
    out[f"over_batches_{key}"] = {"mean": round(float(np.mean(means)), 1), "rms_std": round(
        float(np.sqrt(np.mean(np.square(stds)))), 1)}  # fmt: skip
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    main(
        tuple(int(s) for s in args[0].split(",")) if len(args) > 0 else (2, 11, 7, 3, 5),
        float(args[1]) if len(args) > 1 else 10.0,
        float(args[2]) if len(args) > 2 else None,
    )
