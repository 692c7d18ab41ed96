"""Benchmark: speed of the paper's 4-mode IMM of UKFs against filterpy's IMMEstimator.

Run: ``python bench/estimator_speed.py`` — prints one JSON object: steps per second of
the IMM (synthetic road input) for one run and for 100 runs batched (run-steps/s),
filterpy 2.0's ``IMMEstimator`` with four ``UnscentedKalmanFilter`` on the same
data (single thread), their ratios, and the wall time of a 100-run × 10 s × 1 kHz
Monte Carlo in one process and split over two (2 cores). Targets (issue 4): ≥ 10×
filterpy for one run, ≥ 80× batched, the Monte Carlo in ≤ 10 s on 2 cores. Also the joint
estimator's run-steps per second (10 s runs at 1 kHz, one and 100 runs; its cost grows with
the record length, since every update uses the whole record so far).

The top-level keys are for the default backend (``EstimatorSettings().backend``, the
compiled numba loop); ``backends`` holds both backends' speeds ("numba" and the numpy
reference) and their ratios to filterpy, and ``numba_first_call_s`` the wall time of the
first call in this process (numba compilation, or loading its on-disk cache).
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import json  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from suvtwin.estimators.imm import PAPER_TRANSITION  # noqa: E402
from suvtwin.estimators.quarter_car import QuarterCar, accelerations, process_semi_implicit  # noqa: E402
from suvtwin.estimators.tire_pressure import EstimatorSettings, estimate_pressure, load_modes  # noqa: E402

DT, SPEED, MS, MUS = 1e-3, 60 / 3.6, 466.7, 61.14


def _data(n_runs: int, n_steps: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(0)
    t = np.arange(n_steps) * DT
    acc_s = 0.8 * np.sin(2 * np.pi * 1.3 * t) + rng.normal(0, 0.5, (n_runs, n_steps))
    acc_u = 6.0 * np.sin(2 * np.pi * 11.0 * t) + rng.normal(0, 0.5, (n_runs, n_steps))
    return acc_s, acc_u


def _ours(n_runs: int, n_steps: int, repeats: int = 1, backend: str | None = None) -> float:
    """Best wall time of `repeats` runs (the machine is shared; the best is the least disturbed)."""
    acc_s, acc_u = _data(n_runs, n_steps)
    settings = EstimatorSettings() if backend is None else EstimatorSettings(backend=backend)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        estimate_pressure(acc_s, acc_u, DT, modes=load_modes("paper"), sprung_mass=MS, unsprung_mass=MUS,
                          road_input="synthetic", speed_mps=SPEED, seed=1, settings=settings)  # fmt: skip
        times.append(time.perf_counter() - start)
    return min(times)


def _joint(n_runs: int, n_steps: int) -> float:
    """Wall time of the joint (road-level-free) estimator on the SUV corner model, s."""
    from suvtwin.estimators.joint import estimate_joint
    from suvtwin.pipeline.estimation import linear_corner_model

    acc_s, acc_u = _data(n_runs, n_steps)
    start = time.perf_counter()
    estimate_joint(acc_s, acc_u, DT, qc=linear_corner_model("fl", MS), speed_mps=SPEED)
    return time.perf_counter() - start


def _filterpy(n_steps: int) -> float:
    from filterpy.kalman import IMMEstimator, MerweScaledSigmaPoints, UnscentedKalmanFilter

    acc_s, acc_u = _data(1, n_steps)
    modes = load_modes("paper")
    settings = EstimatorSettings()
    roads = np.random.default_rng(1).normal(0, 0.01, (4, n_steps))
    state = {"k": 0}
    filters = []
    for s in range(4):
        qc = QuarterCar(MS, MUS, modes.ks[s], modes.ksnl[s], modes.cs[s], modes.csnl[s])
        f = UnscentedKalmanFilter(
            dim_x=5, dim_z=2, dt=DT,
            fx=lambda x, dt, qc=qc, s=s: process_semi_implicit(x, roads[s, state["k"]], qc, dt),
            hx=lambda x, qc=qc, s=s: np.array(accelerations(x, roads[s, state["k"]], qc)),
            points=MerweScaledSigmaPoints(5, alpha=settings.alpha, beta=settings.beta, kappa=settings.kappa),
        )  # fmt: skip
        f.x = np.array([0, 0, 0, 0, 264700.0])
        f.P = np.diag([2.5e-3, 2.5e-3, 1e-2, 9e-2, 2e9])
        f.Q = np.diag(np.array(settings.q) * DT**3)
        f.R = np.diag([0.25, 0.25])
        filters.append(f)
    times = []
    for _ in range(3):
        imm = IMMEstimator(filters, np.full(4, 0.25), PAPER_TRANSITION)
        start = time.perf_counter()
        for k in range(1, n_steps):
            state["k"] = k
            imm.predict()
            imm.update(np.array([acc_s[0, k], acc_u[0, k]]))
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> dict:
    first = _ours(1, 200, backend="numba")  # warm-up: compiles, or loads numba's cache
    _ours(1, 200, backend="numpy")
    ref = _filterpy(1000)
    filterpy_rate = 999 / ref
    backends = {}
    for backend in ("numba", "numpy"):
        rate_one = 5000 / _ours(1, 5000, repeats=3, backend=backend)
        rate_batch = 100 * 2000 / _ours(100, 2000, repeats=3, backend=backend)
        backends[backend] = {
            "imm_steps_per_s_one_run": rate_one,
            "imm_run_steps_per_s_100_runs": rate_batch,
            "ratio_one_run": rate_one / filterpy_rate,
            "ratio_batched": rate_batch / filterpy_rate,
        }
    default = backends[EstimatorSettings().backend]
    mc = _ours(100, 10000)
    from concurrent.futures import ProcessPoolExecutor

    start = time.perf_counter()
    with ProcessPoolExecutor(max_workers=2) as pool:  # 2 cores: two halves of the campaign
        list(pool.map(_ours, [50, 50], [10000, 10000]))
    mc_two = time.perf_counter() - start
    result = {
        "backend": EstimatorSettings().backend,
        "imm_steps_per_s_one_run": default["imm_steps_per_s_one_run"],
        "imm_run_steps_per_s_100_runs": default["imm_run_steps_per_s_100_runs"],
        "filterpy_imm_steps_per_s": filterpy_rate,
        "ratio_one_run": default["ratio_one_run"],
        "ratio_batched": default["ratio_batched"],
        "monte_carlo_100x10s_1kHz_wall_s_one_process": mc,
        "monte_carlo_100x10s_1kHz_wall_s_two_processes": mc_two,
        "threads": os.environ.get("OMP_NUM_THREADS"),
        "numba_first_call_s": first,
        "backends": backends,
        "joint_run_steps_per_s_one_run_10s": 10000 / _joint(1, 10000),
        "joint_run_steps_per_s_100_runs_10s": 100 * 10000 / _joint(100, 10000),
    }
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
