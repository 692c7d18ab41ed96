"""Wang et al. 2017, Table 2 on the MuJoCo SUV: the road under the front-left tyre from its accelerations.

Usage: ``python bench/road_estimation_mujoco.py [n_seeds]`` (default 3 seeds; ~1 min per seed
on one core).

Prints JSON. The 18 cells of the paper's Table 2 (ISO class B, C, D × Δm 0, +180, −180 kg ×
KF, MME&KF) with the SUV as the truth:

- run: 12 s at 40 km/h, lane keeping on a single-class road (``superposition``, level at the
  class centre), 250 kPa, 1 kHz, accelerometer noise σ = 0.02 m/s² on both channels (as
  ``bench/road_estimation_paper.py``); the first 2 s (the car settling from its placement)
  are dropped, the filters run over the last 10 s;
- load: +180 kg is a scenario load at the chassis CoG; −180 kg lowers the chassis mass by
  180 kg (a scenario vehicle override; loads cannot be negative). The spring preload follows
  the chassis mass, so the −180 kg car rides at the design height and the +180 kg car
  1.4 cm lower. The front-left corner's share of ±180 kg is about ±47 kg (reported as
  measured: the change of its mean tyre load / g);
- filters: the SUV's front-left corner as a quarter car (``corner_quarter_car``: nominal
  mass share, linear wheel rate, mean low-speed damper rate, kt at 250 kPa), the road model
  at the class level, Euler (eq. 7). KF (eq. 10–15); MME&KF in the estimator's default
  reading (G = e2 fed through to the measured body acceleration, eq. 16 weighted by S_k) with
  eq. 20's W against S_k from the first 2 s of the filtered record (truth-free). Known start
  (the paper's eq. 10: x̂0 from the run's state at 2 s) and, as a variant, unknown start (stationary prior);
- truth: the heightfield under the tyre, raw (at the wheel centre) and enveloped (the tyre
  model's contact-patch mean), ``road_under_wheel``;
- error STD % = 100·std(x̂_r − x_r)/std(x_r) (the paper's, each about its own mean), and the
  same after a zero-phase high-pass at 0.05 cycles/m × speed (0.56 Hz) on both, labelled
  ``hp``; mean ± std over seeds;
- reference ``quarter_car``: the same KF on a linear quarter car (the filter's own, with the
  corner's share of Δm) driven by the same raw road, same noise: what is left when the
  SUV's extra dynamics (pitch, roll, non-linear damper, anti-roll bar, enveloping) are gone;
- classification: ``classify_profile`` (w = 2, band 0.05–5 cycles/m) of the estimated and
  of the true raw track over the wheel's x, class per seed; also of the KF with an unknown
  start and of a KF told class C;
- isolation (class C, Δm = 0, KF, known start): the SUV with one feature the quarter car
  lacks removed — anti-roll bar, the damper's asymmetry and knee, the spring's progression,
  or the roll input (left and right tracks identical).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from suvtwin.estimators.road_estimation import error_std_percent
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.road_estimation import (
    HIGHPASS_CUTOFF_CYCLES_PER_M,
    corner_quarter_car,
    estimate_corner_road,
    highpass,
    mujoco_study,
    road_under_wheel,
    study_scenario,
)
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate
from suvtwin.roads.iso8608 import class_level

_LINEAR_DAMPER = {k: 2200.0 for k in ("damper_compression_low", "damper_rebound_low",
                                      "damper_compression_high", "damper_rebound_high")}
ISOLATION = {  # what of the SUV the filter's quarter car lacks, removed one at a time (class C, Δm = 0)
    "as is": ({}, "independent"),
    "no anti-roll bar": ({"suspension": {"anti_roll_front": 0.0, "anti_roll_rear": 0.0}}, "independent"),
    "linear symmetric damper (2200 N s/m)": ({"suspension": _LINEAR_DAMPER}, "independent"),
    "linear suspension, no anti-roll bar": ({"suspension": {**_LINEAR_DAMPER, "spring_progression": 0.0,
                                                           "anti_roll_front": 0.0, "anti_roll_rear": 0.0}},
                                            "independent"),
    "identical left and right tracks (no roll input)": ({}, "identical"),
}


def _isolation(seeds: list[int]) -> dict:
    """KF (known start) error on class C, Δm = 0, with one of the SUV's extra features removed."""
    vehicle = load_vehicle()
    car, _ = corner_quarter_car(vehicle, load_tire(vehicle.tire_file), corner="fl", pressure_pa=250e3)
    out = {}
    for name, (overrides, tracks) in ISOLATION.items():
        raw_err, hp_err = [], []
        for seed in seeds:
            data = study_scenario("C", 0.0, seed).model_dump(mode="json")
            data["road"]["tracks"] = tracks
            if overrides:
                data["vehicle"] = overrides
            sc = parse_scenario(data)
            table = simulate(sc).table
            raw = road_under_wheel(sc, table, corner="fl").raw[2000:]
            tab = table.iloc[2000:].reset_index(drop=True)
            est = estimate_corner_road(tab, car, gd_n0=class_level("C"), measurement_std=0.02,
                                       initial_road_m=raw[0]).road
            fc = HIGHPASS_CUTOFF_CYCLES_PER_M * float(np.mean(tab["speed_mps"]))
            raw_err.append(float(error_std_percent(raw, est)))
            hp_err.append(float(error_std_percent(highpass(raw, dt=1e-3, cutoff_hz=fc),
                                                  highpass(est, dt=1e-3, cutoff_hz=fc))))
        out[name] = {"KF_raw": [round(e, 1) for e in raw_err], "KF_raw_hp": [round(e, 1) for e in hp_err],
                     "KF_raw_hp_mean": round(float(np.mean(hp_err)), 1)}
    return out


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    seeds = list(range(int(argv[0]) if argv else 3))
    t0 = time.perf_counter()
    study = mujoco_study(seeds, variants=True)
    study.pop("example")
    study["isolation_class_C"] = _isolation(seeds)
    study["bench_wall_s"] = round(time.perf_counter() - t0, 1)
    print(json.dumps(study, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
