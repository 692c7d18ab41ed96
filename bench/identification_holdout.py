"""Held-out check of identified quarter-car parameters against new MuJoCo runs.

Run: ``python bench/identification_holdout.py params.json [n_seeds]`` — prints JSON: for each
road class A–D, `n_seeds` (default 5) new runs (70 km/h, 200 kPa, new road seeds, levels
drawn inside the class band), the normalized RMSE (RMSE / RMS of the MuJoCo signal) of
the sprung and unsprung acceleration reproduced by each class's identified QC, averaged
over the runs: the 4 × 4 matrix of class parameters × road class; the own class's value
per run; and ``best_qc_for_these_runs``, the quarter car fitted to the held-out runs
themselves (Nelder–Mead), i.e. the best this model structure can do on them.
Targets (issue 5): own-class unsprung NRMSE ≤ 0.30, sprung ≤ 0.35. Paper 000's premise is
that each road class is best fitted by its own parameters (the diagonal is the row minimum).

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
import scipy.optimize
import scipy.signal

from suvtwin.estimators.tire_pressure import load_modes
from suvtwin.identification.quarter_car_fit import FitData, objectives
from suvtwin.pipeline.identification_runs import corner_masses, corner_run
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate
from suvtwin.roads.iso8608 import draw_level_in_class


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
        level = draw_level_in_class(road_class, rng)
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


def _held_out(road_class: str, seeds: list[int]) -> FitData:
    """Held-out runs of one class: 70 km/h, 200 kPa, new road seeds, levels drawn in the band."""
    ms, mus = corner_masses("fl")
    runs = []
    for seed in seeds:
        rng = np.random.default_rng([seed, "ABCD".index(road_class)])
        level = draw_level_in_class(road_class, rng)
        runs.append(corner_run((road_class, level, 70.0, 200.0, 10.0, int(rng.integers(0, 2**31)), "fl")))
    return FitData(*(np.array([r[i] for r in runs]) for i in range(4)), ms, mus, 1e-3)


def _nrmse(params: np.ndarray, data: FitData) -> tuple[np.ndarray, np.ndarray]:
    """(P, runs) normalized RMSE of sprung and unsprung acceleration."""
    rmse = objectives(params, data)
    n = data.road.shape[0]
    rms_s = np.sqrt(np.mean(data.accel_sprung**2, axis=1))
    rms_u = np.sqrt(np.mean(data.accel_unsprung**2, axis=1))
    return rmse[:, :n] / rms_s, rmse[:, n:] / rms_u


def _oracle(data: FitData, start: np.ndarray, which: int) -> tuple[float, list]:
    """The best quarter car for these very runs (Nelder–Mead on the mean NRMSE of one signal)."""

    def loss(x):
        params = np.array([[max(x[0], 1.0), max(x[1], 0.0), max(x[2], 1.0), max(x[3], 0.0)]])
        return float(_nrmse(params, data)[which].mean())

    options = {"maxiter": 600, "fatol": 1e-4}
    result = scipy.optimize.minimize(loss, start, method="Nelder-Mead", options=options)
    return round(float(result.fun), 3), np.round(result.x, 1).tolist()


def main(params_path: str, n_seeds: int = 5) -> dict:
    modes = load_modes(params_path)
    params = np.column_stack([modes.cs, modes.csnl, modes.ks, modes.ksnl])
    seeds = [1000 + s for s in range(n_seeds)]
    out = {"params": params_path, "seeds": seeds, "classes_of_params": list(modes.classes), "road": {}}
    for road_class in "ABCD":
        data = _held_out(road_class, seeds)
        nr_s, nr_u = _nrmse(params, data)
        own = list(modes.classes).index(road_class) if road_class in modes.classes else 0
        out["road"][road_class] = {
            "road_std_m": data.road.std(axis=1).round(4).tolist(),
            "nrmse_sprung_mean": dict(zip(modes.classes, nr_s.mean(axis=1).round(3).tolist(), strict=True)),
            "nrmse_unsprung_mean": dict(zip(modes.classes, nr_u.mean(axis=1).round(3).tolist(), strict=True)),
            "own_class_unsprung_per_run": nr_u[own].round(3).tolist(),
            "own_class_sprung_per_run": nr_s[own].round(3).tolist(),
            "best_qc_for_these_runs": {
                "unsprung": _oracle(data, params[own], 1),
                "sprung": _oracle(data, params[own], 0),
            },
        }
    out["structural_floor"] = structural_floor(seeds[0])
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 5)
