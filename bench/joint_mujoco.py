"""The joint (road-level-free) estimator on MuJoCo Monte Carlo runs: plain quarter car vs corner model.

Run: ``python bench/joint_mujoco.py [runs_dir]`` (default ``results/runs``, from ``suvtwin run``) — prints
JSON. Reads the ``mc_*.parquet`` runs (front-left corner, noisy accelerometers), classifies each run
by its road level (ISO 8608 class bounds) and estimates the pressure with

- ``before``: the plain linear quarter car (k_s, mean low-speed damping), the former
  ``linear_corner_model``;
- ``after``: :func:`suvtwin.pipeline.estimation.linear_corner_model` (tire damping, roll-plane model with
  the anti-roll bar, damping marginalized over the digressive damper's range).

Nothing is tuned on these runs' true pressures. Reported per class and overall: the error
(estimate − truth) mean and std at 2, 5 and 10 s, the fraction inside ±2σ at 10 s, and wall time.
"""

from __future__ import annotations

import glob
import json
import sys
import time

import numpy as np
import pyarrow.parquet as pq

from suvtwin.estimators.joint import LinearQuarterCar, estimate_joint
from suvtwin.estimators.quarter_car import sprung_mass_share
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.estimation import linear_corner_model

_CLASS_BOUNDS = (32e-6, 128e-6, 512e-6)  # m³, ISO 8608 A/B, B/C, C/D boundaries at n0 = 0.1 cycle/m


def _load(runs_dir: str) -> dict:
    files = sorted(glob.glob(f"{runs_dir}/mc_*.parquet"))
    if not files:
        raise SystemExit(f"no mc_*.parquet in {runs_dir}")
    cols = ["t_s", "speed_mps", "fl_accel_sprung_mps2", "fl_accel_unsprung_mps2", "fl_pressure_kpa"]
    out = {c: [] for c in cols}
    level = []
    for f in files:
        table = pq.read_table(f, columns=cols)
        meta = json.loads(table.schema.metadata[b"suvtwin.run"])
        level.append(meta["scenario"]["road"]["segments"][0]["gd_n0"])
        for c in cols:
            out[c].append(table[c].to_numpy())
    data = {c: np.array(v) for c, v in out.items()}
    data["road_class"] = np.array(["ABCD"[i] for i in np.searchsorted(_CLASS_BOUNDS, level)])
    return data


def _summary(t: np.ndarray, error: np.ndarray, sigma: np.ndarray) -> dict:
    out = {"runs": int(error.shape[0])}
    for at in (2.0, 5.0, 10.0):
        k = min(int(np.searchsorted(t, at)), t.size - 1)
        out[f"{at:g}s"] = {"mean_error_kpa": round(float(error[:, k].mean()), 2),
                           "error_std_kpa": round(float(error[:, k].std()), 2)}  # fmt: skip
    out["inside_2sigma_at_end"] = round(float(np.mean(np.abs(error[:, -1]) <= 2 * sigma[:, -1])), 3)
    return out


def main(runs_dir: str = "results/runs") -> dict:
    data = _load(runs_dir)
    vehicle = load_vehicle()
    ms = sprung_mass_share(vehicle.chassis.mass, a_opposite=vehicle.chassis.a2, wheelbase=vehicle.wheelbase)
    after = linear_corner_model("fl", ms)
    before = LinearQuarterCar(ms, after.unsprung_mass, after.spring_rate, after.damping)
    dt = float(np.mean(np.diff(data["t_s"][0])))
    speed = data["speed_mps"].mean(axis=1)
    truth = data["fl_pressure_kpa"]
    out = {"runs_dir": runs_dir, "runs": int(truth.shape[0]), "corner": "fl", "models": {}}
    for name, qc in (("before", before), ("after", after)):
        start = time.perf_counter()
        est = estimate_joint(
            data["fl_accel_sprung_mps2"], data["fl_accel_unsprung_mps2"], dt, qc=qc, speed_mps=speed
        )
        wall = time.perf_counter() - start
        error = est.pressure_pa / 1e3 - truth
        sigma = est.pressure_sigma_pa / 1e3
        row = {"wall_time_s": round(wall, 2), "overall": _summary(est.t_s, error, sigma)}
        for c in "ABCD":
            m = data["road_class"] == c
            if m.any():
                row[c] = _summary(est.t_s, error[m], sigma[m])
        if name == "after":
            row["damping_hat_median_at_end"] = {
                c: round(float(np.median(np.array(est.info["damping_hat_at_end"])[data["road_class"] == c])))
                for c in "ABCD"
                if np.any(data["road_class"] == c)
            }
        out["models"][name] = row
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main(*sys.argv[1:2])
