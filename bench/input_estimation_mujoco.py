"""Lin et al. 2021's CIE and AWIE on the MuJoCo SUV: sine bump, cleat, random road at 30/60/90 km/h.

Usage: ``python bench/input_estimation_mujoco.py [n_seeds] [realistic_std]`` (default 10 seeds,
realistic noise 1e-4 m and rad).

Prints JSON. One MuJoCo run per road and speed (:func:`obstacle_scenario`: 1.5 s, the front
wheel reaches the 0.1 m × 1 m obstacle at 0.3 s; the random road is ISO class C, scenario
seed 0). The half car is the SUV's (:func:`half_car_from_vehicle`). The measured heave and
pitch get ``n_seeds`` white-noise draws (``numpy.random.default_rng(seed)``); the estimator
runs with the paper's Q = 1e2 and R = σ². For each cell, method and channel (vertical force,
pitch torque), mean and standard deviation over the seeds of:

- ``input``: û against the model's true input u* = [F_s, T_s] + Kx + Cẋ;
- ``suspension``: the loads û implies (û − K X̄ − C Ẋ̄) against what the suspensions put on the
  body, [F_s, T_s];

- ``body`` (diagnostic): û against Mẍ + Cẋ + Kx from the noise-free heave and pitch, the input
  that moves the linear half car exactly as the body moved (u* without the joints' share);

each in three readings: ``aligned`` (100‖u(k−1) − û(k)‖/‖u‖), ``same_index``
(100‖u(k) − û(k)‖/‖u‖) and ``eq32`` (100(‖u‖ − ‖û‖)/‖u‖, eq. 32 made dimensionless). Noise
levels: the paper's σ = 1e-8 m and rad, ``realistic_std``, and ``none`` (noise-free data,
the filter tuned for σ = 1e-8: the method's own floor). ``closure`` is how far the
body's Mẍ is from the suspension loads (%); ``paper`` holds Tables 2–3.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from suvtwin.pipeline.input_estimation import (
    METHODS,
    PAPER_TABLE2,
    PAPER_TABLE3,
    ROADS,
    SPEEDS_KMH,
    body_input,
    closure_error,
    estimate_run,
    half_car_from_vehicle,
    model_input,
    obstacle_scenario,
    scores,
    suspension_loads,
)
from suvtwin.pipeline.simulator import simulate

SIGMA_PAPER = 1e-8
CHANNELS = ("vertical_force", "pitch_torque")


def _stats(values: np.ndarray) -> dict:
    """Mean and std over seeds (axis 0) per channel, 4 significant digits."""
    mean, std = values.mean(axis=0), values.std(axis=0)
    return {
        ch: {"mean": float(f"{mean[i]:.4g}"), "std": float(f"{std[i]:.4g}")} for i, ch in enumerate(CHANNELS)
    }


def rms(values: np.ndarray) -> np.ndarray:
    """Root mean square over time (axis 0) per channel."""
    return np.sqrt(np.mean(values**2, axis=0))


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    n_seeds = int(argv[0]) if argv else 10
    realistic = float(argv[1]) if len(argv) > 1 else 1e-4
    car = half_car_from_vehicle()
    started = time.perf_counter()
    sim_time = 0.0
    cells = []
    for road in ROADS:
        for speed in SPEEDS_KMH:
            t0 = time.perf_counter()
            table = simulate(obstacle_scenario(road, speed_kmh=speed)).table
            sim_time += time.perf_counter() - t0
            closure = closure_error(table, car)
            body = body_input(table, car)
            cell = {
                "road": road,
                "speed_kmh": speed,
                "closure_percent": {ch: float(f"{closure[i]:.4g}") for i, ch in enumerate(CHANNELS)},
                "truth_rms": {
                    "suspension": [float(f"{v:.4g}") for v in rms(suspension_loads(table))],
                    "input": [float(f"{v:.4g}") for v in rms(model_input(table, car))],
                },
                "noise": {},
            }
            for label, sigma in (
                ("paper_1e-8", SIGMA_PAPER),
                (f"realistic_{realistic:g}", realistic),
                ("none", 0.0),
            ):
                per_method = {}
                for name in METHODS:
                    runs = 1 if sigma == 0.0 else n_seeds
                    r = estimate_run(
                        table,
                        method=name,
                        measurement_std=sigma,
                        filter_std=sigma or SIGMA_PAPER,
                        seed=0,
                        runs=runs,
                    )
                    entry = {}
                    for truth_name, truth, est in (
                        ("input", r.truth_input, r.estimate),
                        ("suspension", r.truth_suspension, r.estimate_suspension),
                        ("body", body, r.estimate),
                    ):
                        s = scores(truth, est)
                        entry[truth_name] = {reading: _stats(v) for reading, v in s.items()}
                    per_method[name] = entry
                cell["noise"][label] = per_method
            cells.append(cell)
    out = {
        "what": "Lin et al. 2021 CIE/AWIE on the MuJoCo SUV (half car from the SUV's parameters)",
        "n_seeds": n_seeds,
        "q": 1e2,
        "half_car": car.__dict__,
        "cells": cells,
        "paper": {
            "table2": PAPER_TABLE2,
            "table3": {r: {str(v): m for v, m in d.items()} for r, d in PAPER_TABLE3.items()},
        },
        "simulation_seconds": round(sim_time, 2),
        "total_seconds": round(time.perf_counter() - started, 2),
    }
    print(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
