"""Wang et al. 2017, eq. 16–21: the readings of the MME&KF tried, on Table 2's simulation.

Usage: ``python bench/road_estimation_mme_readings.py [n_seeds]`` (default 10 seeds).

Prints JSON. Same simulation and settings as ``bench/road_estimation_paper.py`` (Table 1
car, ISO B/C/D at 40 km/h, Δm = 0, +180, −180 kg, the filters keeping 410 kg; T = 1 ms,
10 s, σ = 0.02 and 0.005 m/s², known start, Euler). Each reading is one choice of

- ``error_input`` G: ``all`` (G = I), ``body`` (e₂), ``mass`` (e₂ scaled by the model's body
  acceleration, d = −Δm/(m_b + Δm)), ``printed`` (eq. 7's G times its six equal d);
- ``feedthrough``: whether the measured accelerations contain d (y = Cx + Ed + v);
- ``order``: d_k corrects the prediction of x_k (``same-step``, eq. 21) or of x_{k+1};
- ``fit``: eq. 16's residual weight R⁻¹ (as printed) or S_k⁻¹;
- the W rule: eq. 20 against R (as printed) or against the KF's innovation covariance
  S_k = CP_{k|k-1}Cᵀ + R, on each cell's first 2 s of measurements (truth-free); or the
  prior W = 1/σ_d², σ_d = (180/410)·RMS of the measured body acceleration.

Also per cell: the KF's normalized innovation (NIS, mean eᵀS⁻¹e; 2 if the model is
consistent with the data) and per-channel innovation variance / R, the evidence for the
W rule; the mean d of the ``mass`` reading with W from eq. 20 against S_k.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from road_estimation_paper import (
    BAND,
    CAR,
    CLASSES,
    CONSTRAINT_WINDOW,
    DT,
    MASS_CHANGES,
    N_STEPS,
    PAPER_TABLE2,
    SIGMA_MAIN,
    SPEED,
    _known_start,
    _roads,
)

from suvtwin.estimators.road_estimation import (
    covariance_constraint_weight,
    discretize,
    error_std_percent,
    iso_road_model,
    kalman_filter,
    mme_kalman_filter,
    simulate_quarter_car,
)
from suvtwin.roads.iso8608 import class_level

SIGMAS = (SIGMA_MAIN, 0.005)  # m/s^2: the main table's and the sweep's lowest

# name: (error_input, feedthrough, order, fit, W rule)
READINGS = {
    "G=I, R (eq. 16-21 as printed, old default)": ("all", False, "same-step", "R", "R"),
    "G=e2, R": ("body", False, "same-step", "R", "R"),
    "G=e2, prior W": ("body", False, "same-step", "R", "prior"),
    "G=eq.7 printed, R": ("printed", False, "same-step", "R", "R"),
    "G=I, S": ("all", False, "same-step", "R", "innovation"),
    "G=I, fit S, S": ("all", False, "same-step", "innovation", "innovation"),
    "G=I, fed through, fit S, S": ("all", True, "same-step", "innovation", "innovation"),
    "G=e2, fed through, R": ("body", True, "same-step", "R", "R"),
    "G=e2, fed through, S": ("body", True, "same-step", "R", "innovation"),
    "G=e2, fed through, fit S, S all channels": ("body", True, "same-step", "innovation", "innovation-all"),
    "G=e2, fed through, fit S, S (default)": ("body", True, "same-step", "innovation", "innovation"),
    "G=e2, fed through, fit S, S, delayed": ("body", True, "delayed", "innovation", "innovation"),
    "G=[e2 e4], fed through, fit S, S": ("accelerations", True, "same-step", "innovation", "innovation"),
    "mass, fed through, fit S, S": ("mass", True, "same-step", "innovation", "innovation"),
}


def _stats(e: np.ndarray) -> dict | str:
    if not np.all(np.isfinite(e)) or np.mean(e) > 1e4:
        return "diverged"
    return {"mean": float(f"{np.mean(e):.4g}"), "std": float(f"{np.std(e, ddof=1):.3g}")}


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    seeds = list(range(int(argv[0]) if argv else 10))
    t0 = time.perf_counter()
    rows = []
    for sigma, road_class in [(sg, c) for sg in SIGMAS for c in CLASSES]:
        gd, tag = class_level(road_class), CLASSES.index(road_class)
        z = _roads(gd, seeds, tag)
        road = iso_road_model(gd, speed=SPEED, n_low=BAND[0], n_high=BAND[1])
        model = discretize(CAR, road, dt=DT)
        P0 = _known_start(road)
        for j, dm in enumerate(MASS_CHANGES):
            acc = simulate_quarter_car(CAR.with_sprung_mass(CAR.sprung_mass + dm), z, dt=DT).accelerations
            noise = np.stack([np.random.default_rng([s, tag, j, 2]).standard_normal((N_STEPS, 2))
                              for s in seeds])
            y = acc + sigma * noise  # the same data as bench/road_estimation_paper.py
            kf = kalman_filter(y, model, measurement_std=sigma, state_covariance0=P0)
            e, S = kf.innovations[:, 1:], kf.innovation_covariance[1:]
            row = {"class": road_class, "delta_m_kg": dm, "sigma_mps2": sigma,
                   "paper": dict(zip(("KF", "MME&KF"), PAPER_TABLE2[road_class][dm], strict=True)),
                   "KF": _stats(error_std_percent(z, kf.road)),
                   "KF_NIS": round(float(np.mean(np.einsum("rki,kij,rkj->rk", e, np.linalg.inv(S), e))), 3),
                   "KF_innovation_var_over_R": [round(float(v), 2) for v in e.var(axis=(0, 1)) / sigma**2],
                   "KF_S_over_R": [round(float(v), 2) for v in np.diag(S[-1]) / sigma**2],
                   "readings": {}}
            body_rms = float(np.sqrt(np.mean(y[..., 0] ** 2)))
            for name, (ei, ft, order, fit, rule) in READINGS.items():
                opts = {"error_input": ei, "feedthrough": ft, "order": order, "fit": fit}
                with np.errstate(all="ignore"):
                    if rule == "prior":
                        w = 1.0 / ((180.0 / CAR.sprung_mass) * body_rms) ** 2
                    else:
                        w = covariance_constraint_weight(
                            y[:, :CONSTRAINT_WINDOW], model, measurement_std=sigma, target=rule,
                            state_covariance0=P0, bounds=(1e-8, 1e12), iterations=16, **opts)
                    est = mme_kalman_filter(y, model, measurement_std=sigma, weight=w, state_covariance0=P0,
                                            **opts)
                    r = {"W": float(f"{w:.3g}"), "error": _stats(error_std_percent(z, est.road))}
                if ei == "mass":
                    r["mean_d"] = round(float(np.nanmean(est.model_errors)), 4)
                    r["true_d"] = round(-dm / (CAR.sprung_mass + dm), 4)
                row["readings"][name] = r
            rows.append(row)
            print(f"{sigma} {road_class} {dm:+.0f} done {time.perf_counter() - t0:.0f}s", file=sys.stderr,
                  flush=True)
    print(json.dumps({"settings": {"sigma_mps2": SIGMAS, "seeds": seeds, "dt_s": DT, "euler": True,
                                   "known_start": True, "W_window_samples": CONSTRAINT_WINDOW},
                      "readings": {k: dict(zip(("error_input", "feedthrough", "order", "fit", "W_rule"), v,
                                               strict=True)) for k, v in READINGS.items()},
                      "cells": rows, "bench_wall_s": round(time.perf_counter() - t0, 1)}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
