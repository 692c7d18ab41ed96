"""Held-out check of identified quarter-car parameters against new MuJoCo runs.

Run: ``python bench/identification_holdout.py params.json [seed]`` — prints JSON: for each
road class A–D a new run (70 km/h, 200 kPa, new road seed, level drawn inside the class
band), the normalized RMSE (RMSE / RMS of the MuJoCo signal) of the sprung and
unsprung acceleration reproduced by each class's identified QC: the 4 × 4 matrix of
class parameters × road class. Targets (issue 5): own-class unsprung NRMSE ≤ 0.30,
sprung ≤ 0.35. Paper 000's premise is that each road class is best fitted by its own
parameters (the diagonal is the row minimum).
"""

from __future__ import annotations

import json
import sys

import numpy as np

from estimators.tire_pressure import load_modes
from identification.quarter_car_fit import FitData, objectives
from pipeline.identification_runs import corner_masses, corner_run
from pipeline.iso8608 import class_bounds


def main(params_path: str, seed: int = 99) -> dict:
    modes = load_modes(params_path)
    params = np.column_stack([modes.cs, modes.csnl, modes.ks, modes.ksnl])
    ms, mus = corner_masses("fl")
    out = {"params": params_path, "seed": seed, "classes_of_params": list(modes.classes), "road": {}}
    for i, road_class in enumerate("ABCD"):
        rng = np.random.default_rng([seed, i])
        lower, upper = class_bounds(road_class)
        level = float(np.exp(rng.uniform(np.log(lower), np.log(upper))))
        road, acc_s, acc_u, kt = corner_run(
            (road_class, level, 70.0, 200.0, 10.0, int(rng.integers(0, 2**31)), "fl")
        )
        data = FitData(road[None], acc_s[None], acc_u[None], np.array([kt]), ms, mus, 1e-3)
        rmse = objectives(params, data)  # (n_params, 2): sprung, unsprung
        out["road"][road_class] = {
            "gd_n0_m3": level,
            "nrmse_sprung": dict(
                zip(modes.classes, (rmse[:, 0] / np.sqrt(np.mean(acc_s**2))).round(3).tolist(), strict=True)
            ),
            "nrmse_unsprung": dict(
                zip(modes.classes, (rmse[:, 1] / np.sqrt(np.mean(acc_u**2))).round(3).tolist(), strict=True)
            ),
        }
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 99)
