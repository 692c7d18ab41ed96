"""Held-out check of identified quarter-car parameters against new MuJoCo runs.

Run: ``python bench/identification_holdout.py params.json [seed]`` — prints JSON: for each
road class A–D a new run (70 km/h, 200 kPa, new road seed, level drawn inside the class
band), the normalized RMSE (RMSE / RMS of the MuJoCo signal) of the sprung and
unsprung acceleration reproduced by each class's identified QC: the 4 × 4 matrix of
class parameters × road class. Targets (issue 5): own-class unsprung NRMSE ≤ 0.30,
sprung ≤ 0.35. Paper 000's premise is that each road class is best fitted by its own
parameters (the diagonal is the row minimum).

``structural_floor`` answers whether *any* quarter car could meet those targets: on a
longer held-out run (60 s, same speed and pressure, per class) it gives the normalized
RMSE of the best linear time-invariant predictor of each acceleration (non-causal
Wiener filter, from Welch cross-spectra: unexplained PSD S_yy − S_yx S_xx⁻¹ S_xy) from
(a) the road under the corner's own tire — all a quarter car sees — and (b) the roads
of both wheel tracks — what the full car responds to (rear wheels follow the front
ones on the same track; a non-causal predictor has those delays already). A linear QC driven by its own
road cannot beat (a); the QC's non-linear terms are small corrections.
"""

from __future__ import annotations

import json
import sys

import numpy as np
import scipy.signal

from estimators.tire_pressure import load_modes
from identification.quarter_car_fit import FitData, objectives
from pipeline.identification_runs import corner_masses, corner_run
from pipeline.iso8608 import class_bounds
from pipeline.scenario import parse_scenario
from pipeline.simulator import simulate


def linear_floor(y: np.ndarray, inputs: list[np.ndarray], fs: float, nperseg: int) -> float:
    """NRMSE of the best LTI predictor of `y` from `inputs` (multiple coherence, Welch)."""
    m = len(inputs)
    f, s_yy = scipy.signal.welch(y, fs, nperseg=nperseg)
    s_xx = np.empty((f.size, m, m), dtype=complex)
    s_xy = np.empty((f.size, m), dtype=complex)
    for i, xi in enumerate(inputs):
        s_xy[:, i] = scipy.signal.csd(xi, y, fs, nperseg=nperseg)[1]
        for j, xj in enumerate(inputs):
            s_xx[:, i, j] = scipy.signal.csd(xi, xj, fs, nperseg=nperseg)[1]
    explained = np.real(np.einsum("fi,fi->f", np.conj(s_xy), np.linalg.solve(s_xx, s_xy[..., None])[..., 0]))
    return float(np.sqrt(np.sum(np.clip(s_yy - explained, 0.0, None)) / np.sum(s_yy)))


def structural_floor(seed: int = 99, duration: float = 60.0) -> dict:
    """Best-possible NRMSE from the corner's own road vs from both tracks, per class (fl corner)."""
    out = {}
    for i, road_class in enumerate("ABCD"):
        rng = np.random.default_rng([seed, i, 1])
        lower, upper = class_bounds(road_class)
        level = float(np.exp(rng.uniform(np.log(lower), np.log(upper))))
        scenario = parse_scenario(
            {
                "duration_s": duration,
                "speed_kmh": 70.0,
                "seed": int(rng.integers(0, 2**31)),
                "road": {"segments": [{"length_m": 70 / 3.6 * duration + 60.0, "gd_n0": level}]},
                "pressure_kpa": 200.0,
                "noise": {"accel_sprung_mps2": 0.0, "accel_unsprung_mps2": 0.0},
            }
        )
        table = simulate(scenario).table.iloc[2000:]  # drop the start transient
        # the rear wheels roll over the front wheels' tracks (delayed copies, which a non-causal
        # predictor already has): the left and right front roads are all the inputs there are
        roads = [table[f"{c}_road_z_m"].to_numpy() for c in ("fl", "fr")]
        row = {"gd_n0_m3": level}
        for name in ("sprung", "unsprung"):
            y = table[f"fl_accel_{name}_true_mps2"].to_numpy()
            row[name] = {
                "own_road": round(linear_floor(y, roads[:1], 1000.0, 4096), 3),
                "both_tracks": round(linear_floor(y, roads, 1000.0, 4096), 3),
            }
        out[road_class] = row
    return out


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
    out["structural_floor"] = structural_floor(seed)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 99)
