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
  at the class level, Euler (eq. 7). KF (eq. 10–15); MME&KF with G = I and eq. 20's W from
  the first 2 s of the filtered record (truth-free). Known start (the paper's eq. 10: x̂0 from
  the run's state at 2 s) and, as a variant, unknown start (stationary prior);
- truth: the heightfield under the tyre, raw (at the wheel centre) and enveloped (the tyre
  model's contact-patch mean), ``road_under_wheel``;
- error STD % = 100·std(x̂_r − x_r)/std(x_r) (the paper's, each about its own mean), and the
  same after a zero-phase high-pass at 0.05 cycles/m × speed (0.56 Hz) on both, labelled
  ``hp``; mean ± std over seeds;
- reference ``quarter_car``: the same KF on a linear quarter car (the filter's own, with the
  corner's share of Δm) driven by the same raw road, same noise: what is left when the
  SUV's extra dynamics (pitch, roll, non-linear damper, anti-roll bar, enveloping) are gone;
- classification: ``classify_profile`` (w = 2, band 0.05–5 cycles/m) of the estimated and
  of the true raw track over the wheel's x, class per seed.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from suvtwin.estimators.road_estimation import (
    discretize,
    error_std_percent,
    iso_road_model,
    kalman_filter,
    simulate_quarter_car,
)
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import GRAVITY, load_vehicle
from suvtwin.pipeline.road_estimation import (
    FILTERS,
    HIGHPASS_CUTOFF_CYCLES_PER_M,
    corner_quarter_car,
    estimate_corner_road,
    highpass,
    road_under_wheel,
)
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate
from suvtwin.roads.iso8608 import class_level
from suvtwin.roads.roughness import classify_profile

CLASSES = ("B", "C", "D")
MASS_CHANGES = (0.0, 180.0, -180.0)
SPEED_KMH = 40.0
DURATION_S = 12.0
SETTLE_S = 2.0
SIGMA = 0.02
PRESSURE_KPA = 250.0
CORNER = "fl"
GRID_M = 0.05  # spacing of the track classified, m

PAPER_TABLE2 = {  # Wang et al. 2017, Table 2 (simulation), error STD %: (KF, MME&KF)
    "B": {0.0: (7.3, 3.3), 180.0: (7.6, 3.7), -180.0: (10.3, 5.5)},
    "C": {0.0: (8.1, 4.6), 180.0: (9.5, 5.2), -180.0: (12.1, 8.3)},
    "D": {0.0: (10.5, 6.5), 180.0: (12.8, 7.9), -180.0: (16.4, 11.5)},
}


def scenario_for(road_class: str, delta_m: float, seed: int):
    """The run of one cell and seed."""
    vehicle = load_vehicle()
    data = {
        "duration_s": DURATION_S, "seed": seed, "speed_kmh": SPEED_KMH, "pressure_kpa": PRESSURE_KPA,
        "road": {"segments": [{"length_m": 200.0, "road_class": road_class}]},
        "noise": {"accel_sprung_mps2": SIGMA, "accel_unsprung_mps2": SIGMA},
    }
    if delta_m > 0:
        data["load"] = [{"mass_kg": delta_m, "position_m": [0.0, 0.0, 0.0]}]
    elif delta_m < 0:
        data["vehicle"] = {"chassis": {"mass": vehicle.chassis.mass + delta_m}}
    return parse_scenario(data)


def _stats(values) -> dict:
    v = np.asarray(values, dtype=float)
    spread = np.std(v, ddof=1) if v.size > 1 else 0.0
    return {"mean": float(f"{np.mean(v):.4g}"), "std": float(f"{spread:.3g}")}


def _class_of(x: np.ndarray, z: np.ndarray) -> str:
    grid = np.arange(x[0], x[-1], GRID_M)
    return classify_profile(np.interp(grid, x, z), GRID_M).road_class


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    seeds = list(range(int(argv[0]) if argv else 3))
    vehicle = load_vehicle()
    tire = load_tire(vehicle.tire_file)
    car, sources = corner_quarter_car(vehicle, tire, corner=CORNER, pressure_pa=PRESSURE_KPA * 1e3)
    corner_share = vehicle.sprung_mass_corner[0] / vehicle.chassis.mass
    t0 = time.perf_counter()
    sim_wall = 0.0
    rows = []
    nominal_load = {}
    for road_class in CLASSES:
        gd = class_level(road_class)
        for dm in MASS_CHANGES:
            acc: dict[str, list] = {}
            classes = {"truth": [], "KF": [], "MME&KF": []}
            weights, corner_dm = [], []

            def add(key, value, acc=acc):
                acc.setdefault(key, []).append(float(value))

            for seed in seeds:
                sc = scenario_for(road_class, dm, seed)
                ts = time.perf_counter()
                table = simulate(sc).table
                sim_wall += time.perf_counter() - ts
                truth = road_under_wheel(sc, table, corner=CORNER)
                keep = int(round(SETTLE_S * sc.output_rate_hz))
                tab = table.iloc[keep:].reset_index(drop=True)
                raw, env, x = truth.raw[keep:], truth.enveloped[keep:], truth.x[keep:]
                dt = 1.0 / sc.output_rate_hz
                fc = HIGHPASS_CUTOFF_CYCLES_PER_M * float(np.mean(tab["speed_mps"]))
                raw_hp, env_hp = highpass(raw, dt=dt, cutoff_hz=fc), highpass(env, dt=dt, cutoff_hz=fc)
                fz = float(np.mean(tab[f"{CORNER}_tire_fz_n"]))
                if dm == 0.0:
                    nominal_load[(road_class, seed)] = fz
                corner_dm.append((fz - nominal_load[(road_class, seed)]) / GRAVITY)
                classes["truth"].append(_class_of(x, raw))
                for name in FILTERS:
                    for start, label in ((raw[0], "known"), (None, "unknown")):
                        est = estimate_corner_road(tab, car, gd_n0=gd, corner=CORNER, measurement_std=SIGMA,
                                                   filter_name=name, initial_road_m=start)
                        if name == "MME&KF" and label == "known":
                            weights.append(est.weight)
                        zh = est.road
                        if not np.all(np.isfinite(zh)):
                            add(f"{name}|{label}|raw", np.inf)
                            continue
                        add(f"{name}|{label}|raw", error_std_percent(raw, zh))
                        add(f"{name}|{label}|enveloped", error_std_percent(env, zh))
                        zh_hp = highpass(zh, dt=dt, cutoff_hz=fc)
                        add(f"{name}|{label}|raw_hp", error_std_percent(raw_hp, zh_hp))
                        add(f"{name}|{label}|enveloped_hp", error_std_percent(env_hp, zh_hp))
                        if label == "known":
                            classes[name].append(_class_of(x, zh))
                # reference: the filter's own linear quarter car (corner share of Δm) on the same road
                qc = car.with_sprung_mass(car.sprung_mass + corner_share * dm)
                z0 = raw - raw[0]
                y = simulate_quarter_car(qc, z0, dt=dt).accelerations[0]
                noise_rng = np.random.default_rng([seed, CLASSES.index(road_class), 7])
                y = y + SIGMA * noise_rng.standard_normal(y.shape)
                road_model = iso_road_model(gd, speed=float(np.mean(tab["speed_mps"])))
                model = discretize(car, road_model, dt=dt)
                P0 = np.diag([1e-12] * 5 + [road_model.intensity / (2.0 * road_model.a2)])
                zq = kalman_filter(y, model, measurement_std=SIGMA, state_covariance0=P0).road
                add("quarter_car|KF|known|raw", error_std_percent(z0, zq))
                add("quarter_car|KF|known|raw_hp", error_std_percent(highpass(z0, dt=dt, cutoff_hz=fc),
                                                                     highpass(zq, dt=dt, cutoff_hz=fc)))
                add("road_std_mm", 1e3 * np.std(raw))
                add("enveloped_minus_raw_std_mm", 1e3 * np.std(env - raw))
            row = {"class": road_class, "delta_m_kg": dm,
                   "paper": dict(zip(FILTERS, PAPER_TABLE2[road_class][dm], strict=True)),
                   "front_left_delta_m_kg": _stats(corner_dm),
                   "W_MME&KF": [float(f"{w:.3g}") for w in weights],
                   "classes": classes}
            for key, values in acc.items():
                v = np.asarray(values)
                row[key] = _stats(v) if np.all(np.isfinite(v)) else "diverged"
            rows.append(row)
    print(json.dumps({
        "settings": {"speed_kmh": SPEED_KMH, "duration_s": DURATION_S, "settle_dropped_s": SETTLE_S,
                     "sigma_mps2": SIGMA, "pressure_kpa": PRESSURE_KPA, "corner": CORNER, "seeds": seeds,
                     "highpass_cycles_per_m": HIGHPASS_CUTOFF_CYCLES_PER_M, "filter_car": sources,
                     "mme": "G = I, W from eq. 20 on the first 2 s",
                     "error_std": "100*std(xr_hat - xr)/std(xr) per run; mean and std over seeds"},
        "table": rows,
        "simulation_wall_s": round(sim_wall, 1),
        "bench_wall_s": round(time.perf_counter() - t0, 1),
    }, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
