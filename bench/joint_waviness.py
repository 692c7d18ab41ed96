"""The joint estimator on roads whose waviness is not 2: the road's slope fixed at w = 2 vs estimated.

Usage: ``python bench/joint_waviness.py [parts, comma-separated] [seeds, comma-separated]`` — prints JSON.
Parts: ``qc`` (quarter-car truth, default seeds 2,11,7), ``mujoco_non_iso`` (the campaign's
``non_iso_road`` scenario, simulated), ``mujoco_mc [runs_dir]`` (the campaign's Monte Carlo runs on w = 2
roads; first existing of ``results/runs``, ``/tmp/final/results_full/runs``). Default: all three.

Quarter-car truth: per batch seed 20 runs of ``quarter_car_runs``
(:mod:`suvtwin.pipeline.quarter_car_truth`: linear quarter car, RK4 5 substeps at 1 kHz, 60 km/h,
0.5 m/s² noise, pressure uniform 130-230 kPa, level log-uniform in classes A-D cycling), on roads of
waviness drawn uniform in [1.5, 3.0] (``w_uniform``) and on w = 2 roads (``w2``). Estimators:
``before`` = ``waviness=2.0`` (the former model, equal to it bit for bit), ``after`` = the default
(w = 2 with prior probability 0.8, else uniform in 1.5-3),
``slope_uniform`` = w uniform in 1.5-3 (``waviness_iso_weight=0``). Reported: the pressure error
(estimate − truth) mean and std at 5 and 10 s, the share of samples after 4 s within ±2σ, wall time.
"""

from __future__ import annotations

import glob
import json
import sys
import time
from pathlib import Path

import numpy as np

from suvtwin.estimators.joint import LinearQuarterCar, estimate_joint
from suvtwin.pipeline.quarter_car_truth import SPEED_MPS as SPEED
from suvtwin.pipeline.quarter_car_truth import TEST_CORNER, quarter_car_runs
from suvtwin.pipeline.quarter_car_truth import TIMESTEP_S as DT

QC = LinearQuarterCar(TEST_CORNER.sprung_mass, TEST_CORNER.unsprung_mass, TEST_CORNER.spring_rate,
                      TEST_CORNER.damping)  # fmt: skip
RUNS = 20
VARIANTS = {"before": {"waviness": 2.0}, "after": {}, "slope_uniform": {"waviness_iso_weight": 0.0}}


def _score(est, pressure_kpa, times=(5.0, 10.0)):
    error = est.pressure_pa / 1e3 - np.asarray(pressure_kpa)[:, None]
    row = {}
    for t in times:
        i = min(int(round(t / (est.t_s[1] - est.t_s[0]))), est.t_s.size - 1)
        row[f"at_{t:g}s_kpa"] = {"mean": round(float(error[:, i].mean()), 1),
                                 "std": round(float(error[:, i].std()), 1)}  # fmt: skip
    after = est.t_s >= 4.0
    row["coverage_2sigma_after_4s"] = round(
        float(np.mean(np.abs(error[:, after]) <= 2 * est.pressure_sigma_pa[:, after] / 1e3)), 3
    )
    return row, error[:, -1]


def quarter_car(seeds=(2, 11, 7), duration=10.0):
    n = int(round(duration / DT))
    out = {"runs_per_batch": RUNS, "duration_s": duration, "roads": {}}
    for road in ("w_uniform", "w2"):
        errors = {v: [] for v in VARIANTS}
        batches = {}
        for seed in seeds:
            runs = quarter_car_runs(RUNS, n, seed=seed, waviness=2.0 if road == "w2" else (1.5, 3.0))
            pressure, acc = runs.pressure, runs.acc
            rows = {}
            for name, kwargs in VARIANTS.items():
                start = time.perf_counter()
                est = estimate_joint(acc[..., 0], acc[..., 1], DT, qc=QC, speed_mps=SPEED, **kwargs)
                rows[name], err = _score(est, pressure / 1e3)
                rows[name]["wall_s"] = round(time.perf_counter() - start, 2)
                if "waviness_hat_at_end" in est.info:
                    rows[name]["waviness_hat_at_end_mean"] = round(
                        float(np.mean(est.info["waviness_hat_at_end"])), 2
                    )
                errors[name].append(err)
            batches[str(seed)] = rows
        pooled = {
            name: {"mean": round(float(np.mean(e)), 1), "std": round(float(np.std(np.concatenate(e))), 1),
                   "rms_batch_std": round(float(np.sqrt(np.mean([np.var(x) for x in e]))), 1)}
            for name, e in errors.items()
        }  # fmt: skip
        out["roads"][road] = {"batches": batches, "pooled_at_10s_kpa": pooled}
    return out


def _corner_model():
    from suvtwin.pipeline.estimation import linear_corner_model
    from suvtwin.pipeline.identification_runs import corner_masses

    return linear_corner_model("fl", corner_masses("fl")[0])


def mujoco_non_iso():
    from suvtwin.pipeline.campaign import campaign_specs, preset
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import simulate

    spec = {s.name: s for s in campaign_specs(preset("quick", monte_carlo_runs=0))}["non_iso_road"]
    table = simulate(parse_scenario(spec.scenario)).table
    qc = _corner_model()
    t = table.t_s.to_numpy()
    dt = float(np.mean(np.diff(t)))
    out = {"scenario": spec.info, "duration_s": round(float(t[-1] + dt), 2), "estimators": {}}
    truth = table.fl_pressure_kpa.to_numpy()
    for name, kwargs in VARIANTS.items():
        start = time.perf_counter()
        est = estimate_joint(table.fl_accel_sprung_mps2.to_numpy(), table.fl_accel_unsprung_mps2.to_numpy(),
                             dt, qc=qc, speed_mps=float(table.speed_mps.mean()), **kwargs)  # fmt: skip
        wall = time.perf_counter() - start
        row = {"wall_s": round(wall, 2)}
        for at in (5.0, 10.0):
            i = min(int(round(at / dt)), t.size - 1)
            row[f"error_at_{at:g}s_kpa"] = round(float(est.pressure_pa[0, i] / 1e3 - truth[i]), 1)
            row[f"sigma_at_{at:g}s_kpa"] = round(float(est.pressure_sigma_pa[0, i] / 1e3), 1)
        if "waviness_hat_at_end" in est.info:
            row["waviness_hat_at_end"] = [round(w, 2) for w in est.info["waviness_hat_at_end"]]
        out["estimators"][name] = row
    return out


def mujoco_mc(runs_dir=None):
    import pyarrow.parquet as pq

    dirs = [runs_dir] if runs_dir else ["results/runs", "/tmp/final/results_full/runs"]
    files = []
    for d in dirs:
        files = sorted(glob.glob(f"{d}/mc_*.parquet"))
        if files:
            break
    if not files:
        return {"skipped": f"no mc_*.parquet in {dirs}"}
    cols = ["t_s", "speed_mps", "fl_accel_sprung_mps2", "fl_accel_unsprung_mps2", "fl_pressure_kpa"]
    tables = [pq.read_table(f, columns=cols) for f in files]
    data = {c: np.array([tb[c].to_numpy() for tb in tables]) for c in cols}
    dt = float(np.mean(np.diff(data["t_s"][0])))
    qc = _corner_model()
    out = {"runs_dir": str(Path(files[0]).parent), "runs": len(files), "estimators": {}}
    for name, kwargs in VARIANTS.items():
        start = time.perf_counter()
        est = estimate_joint(data["fl_accel_sprung_mps2"], data["fl_accel_unsprung_mps2"], dt, qc=qc,
                             speed_mps=data["speed_mps"].mean(axis=1), **kwargs)  # fmt: skip
        wall = time.perf_counter() - start
        error = est.pressure_pa / 1e3 - data["fl_pressure_kpa"]
        row = {"wall_s": round(wall, 2)}
        for at in (5.0, 10.0):
            i = min(int(round(at / dt)), error.shape[1] - 1)
            row[f"at_{at:g}s_kpa"] = {"mean": round(float(error[:, i].mean()), 2),
                                      "std": round(float(error[:, i].std()), 2)}  # fmt: skip
        after = est.t_s >= 4.0
        sig = est.pressure_sigma_pa[:, after] / 1e3
        row["coverage_2sigma_after_4s"] = round(float(np.mean(np.abs(error[:, after]) <= 2 * sig)), 3)
        if "waviness_hat_at_end" in est.info:
            w = np.array(est.info["waviness_hat_at_end"])
            row["waviness_hat_at_end"] = {"mean": round(float(w.mean()), 2), "std": round(float(w.std()), 2)}
        out["estimators"][name] = row
    return out


def main(parts=("qc", "mujoco_non_iso", "mujoco_mc"), seeds=(2, 11, 7), runs_dir=None):
    out = {}
    if "qc" in parts:
        out["quarter_car"] = quarter_car(seeds)
    if "mujoco_non_iso" in parts:
        out["mujoco_non_iso_road"] = mujoco_non_iso()
    if "mujoco_mc" in parts:
        out["mujoco_monte_carlo"] = mujoco_mc(runs_dir)
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    args = sys.argv[1:]
    main(
        tuple(args[0].split(",")) if args else ("qc", "mujoco_non_iso", "mujoco_mc"),
        tuple(int(s) for s in args[1].split(",")) if len(args) > 1 else (2, 11, 7),
        args[2] if len(args) > 2 else None,
    )
