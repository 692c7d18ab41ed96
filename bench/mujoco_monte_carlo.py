"""Monte Carlo of paper 000's estimators on the MuJoCo ground truth, per road class.

Run: ``python bench/mujoco_monte_carlo.py [runs_per_class] [duration_s] [paper|identified|file]``
(default 20, 10, paper) — prints JSON. For each class A–D: `runs_per_class` straight runs with pressure
uniform 130–230 kPa, speed uniform 40–80 km/h (paper 000, Table 4) and the road
level drawn log-uniformly inside the class band (not at its centre), seeded; the
front-left corner's accelerometers (0.5 m/s² noise) go to the paper's IMM (modes from
Table 3, or this SUV's identified parameters) with both road inputs, to its single UKF
(mode A), and to the road-level-free joint estimator on the corner's linear
roll-plane model (:func:`suvtwin.pipeline.estimation.linear_corner_model`). Reported per class
and estimator: the paper's indexes (eq. 23 mean error, eq. 24 error std, eq. 25
mean σ-bound) of the pressure at 2, 5 and 10 s, in kPa, and the fraction of runs
whose error is inside ±2σ at the end.
"""

from __future__ import annotations

import json
import sys

import numpy as np

from suvtwin.estimators.joint import estimate_joint
from suvtwin.estimators.quarter_car import sprung_mass_share
from suvtwin.estimators.tire_pressure import estimate_pressure, load_modes
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.estimation import linear_corner_model
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.scoring import monte_carlo_indexes
from suvtwin.pipeline.simulator import simulate
from suvtwin.roads.iso8608 import draw_level_in_class


def _runs(road_class: str, n_runs: int, duration: float, rng: np.random.Generator):
    acc_s, acc_u, pressure, speed, levels = [], [], [], [], []
    for i in range(n_runs):
        p = rng.uniform(130.0, 230.0)
        v = rng.uniform(40.0, 80.0)
        level = draw_level_in_class(road_class, rng)
        length = 10.0 + v / 3.6 * duration + 40.0
        scenario = parse_scenario(
            {
                "duration_s": duration,
                "speed_kmh": v,
                "seed": int(rng.integers(0, 2**31)),
                "road": {"segments": [{"length_m": length, "gd_n0": level}]},
                "pressure_kpa": p,
            }
        )
        table = simulate(scenario).table
        acc_s.append(table.fl_accel_sprung_mps2.to_numpy())
        acc_u.append(table.fl_accel_unsprung_mps2.to_numpy())
        pressure.append(p)
        speed.append(v / 3.6)
        levels.append(level)
        del i
    return np.array(acc_s), np.array(acc_u), np.array(pressure), np.array(speed), np.array(levels)


def _summary(est, pressure: np.ndarray, duration: float) -> dict:
    """Paper 000 eq. 23-25 (kPa) at 2 s, 5 s and the end, and the end's ±2σ coverage."""
    truth = np.broadcast_to(pressure[:, None], est.pressure_pa.shape)
    idx = monte_carlo_indexes(truth, est.pressure_pa / 1e3, est.pressure_sigma_pa / 1e3)
    out = {
        f"{t:g}s": {
            "mean_error_kpa": float(idx.mean_error[int(t / 1e-3) - 1]),
            "error_std_kpa": float(idx.error_std[int(t / 1e-3) - 1]),
            "sigma_bound_kpa": float(idx.sigma_bound[int(t / 1e-3) - 1]),
        }
        for t in (2.0, 5.0, duration)
    }
    error = est.pressure_pa[:, -1] / 1e3 - pressure
    out["inside_2sigma_at_end"] = float(np.mean(np.abs(error) <= 2 * est.pressure_sigma_pa[:, -1] / 1e3))
    return out


def main(runs_per_class: int = 20, duration: float = 10.0, params: str = "paper") -> dict:
    rng = np.random.default_rng(2022)
    vehicle = load_vehicle()
    ms = sprung_mass_share(vehicle.chassis.mass, a_opposite=vehicle.chassis.a2, wheelbase=vehicle.wheelbase)
    mus = vehicle.wheel.unsprung_mass_front
    paper = load_modes(params)
    estimators = {
        "imm_synthetic": (paper, "synthetic"),
        "imm_augmented": (paper, "augmented"),
        "ukf_synthetic": (paper.subset(("A",)), "synthetic"),
        "ukf_augmented": (paper.subset(("A",)), "augmented"),
    }
    out = {
        "runs_per_class": runs_per_class,
        "duration_s": duration,
        "corner": "fl",
        "params": params,
        "classes": {},
    }
    for road_class in "ABCD":
        acc_s, acc_u, pressure, speed, levels = _runs(road_class, runs_per_class, duration, rng)
        row = {"level_range_m3": [float(levels.min()), float(levels.max())]}
        for name, (modes, road_input) in estimators.items():
            est = estimate_pressure(acc_s, acc_u, 1e-3, modes=modes, sprung_mass=ms, unsprung_mass=mus,
                                    road_input=road_input, speed_mps=speed, seed=7)  # fmt: skip
            row[name] = _summary(est, pressure, duration)
            if est.mode_probability is not None:
                row[name]["mode_probability_at_end"] = (
                    est.mode_probability[:, -1].mean(axis=0).round(3).tolist()
                )
        est = estimate_joint(acc_s, acc_u, 1e-3, qc=linear_corner_model("fl", ms), speed_mps=speed)
        row["joint"] = _summary(est, pressure, duration)
        row["joint"]["level_over_truth_at_end"] = (est.road_level[:, -1] / levels).round(2).tolist()
        out["classes"][road_class] = row
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    main(
        int(args[0]) if len(args) > 0 else 20,
        float(args[1]) if len(args) > 1 else 10.0,
        args[2] if len(args) > 2 else "paper",
    )
