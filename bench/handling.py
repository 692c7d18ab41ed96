"""Benchmark: the SUV's steady-state handling (ISO 4138, constant radius) and its settled start.

Run: ``python bench/handling.py [radius_m ...]`` (default 40 m) — prints one JSON object.

Steady-state circular test, constant-radius method (ISO 4138:2021, *Passenger cars —
Steady-state circular driving behaviour — Open-loop test methods*): the car drives left
around a circle of radius R on a flat, level road (``road: flat``: dry, μ of the ``.tir``
file) at a series of constant speeds, one simulation per speed, with the model's
circle driver (``steering: {mode: circle}``, pure pursuit on the circle from the rear axle)
holding the path and its PI speed controller the speed. Speed steps: the speeds giving a
nominal lateral acceleration a_y = v²/R of 0.5, 1.0, …, 6.0 m/s². Each run lasts 16 s; the
last 4 s are its steady state, accepted (``steady``) when speed, yaw rate and steer angle each
vary by less than 1 % (peak to peak over the window, relative to their means; 2e-4 rad
absolute on the steer angle). Quantities are window means: speed v, lateral acceleration a_y
(the chassis accelerometer, horizontal, perpendicular to the heading), yaw rate r, the
driver's road-wheel steer angle δ (the bicycle-model angle the steering servo is commanded
with, i.e. handwheel angle / steering ratio: compliance and bump steer of the knuckles are part
of the vehicle, as on a real car), body roll φ (positive: rolling out of the turn) and the
sideslip β at the chassis CoG (velocity heading minus yaw).

Reported (every gradient a least-squares line over the steps with a_y ≤ 4 m/s², ISO 4138's
linear range of passenger cars; deg/g = slope in rad per m/s² × g × 180/π):

- ``understeer_gradient_deg_per_g``: K = dδ/da_y − d(L/R_path)/da_y, L the wheelbase and
  R_path = v/r the CoG path radius (ISO 4138; Gillespie 1992, *Fundamentals of Vehicle
  Dynamics*, ch. 6; Milliken & Milliken 1995, *Race Car Vehicle Dynamics*). At
  constant radius d(L/R)/da_y ≈ 0, the second term only corrects the driver's small radius
  drift;
- ``roll_gradient_deg_per_g``: dφ/da_y;
- ``sideslip_gradient_deg_per_g``: dβ/da_y (negative: the tail swings out as speed rises);
- ``yaw_rate_gain``: r/δ per speed step (1/s), and the neutral-steer value v/L beside it;
- ``steps``: every step's numbers;
- ``start``: the settled start (issue 15): for 1 s runs at 60 km/h on a flat road, the largest
  |hub (unsprung) vertical acceleration| over the first 0.1 s, the smallest tyre load, the
  largest |body heave rate| (corner sprung points) and roll / pitch rates, and the wall time of
  building + settling the model (``prepare``), for both contacts, an asymmetric load and one
  deflated corner.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from suvtwin.mjcf.vehicle import CORNERS, GRAVITY, load_vehicle
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import prepare, simulate

QUIET = {"accel_sprung_mps2": 0.0, "accel_unsprung_mps2": 0.0}
DEG_PER_G = GRAVITY * 180.0 / np.pi
AY_STEPS = tuple(np.arange(0.5, 6.01, 0.5))
LINEAR_LIMIT = 4.0
DURATION_S, WINDOW_S = 16.0, 4.0


def circle_step(radius: float, ay_nominal: float, *, contact: str = "envelope", duration: float = DURATION_S,
                window: float = WINDOW_S, vehicle: dict | None = None) -> dict:  # fmt: skip
    """One constant-speed step of the constant-radius test: the steady window's means."""
    speed = np.sqrt(ay_nominal * radius)
    scenario = parse_scenario(
        {"duration_s": duration, "speed_kmh": speed * 3.6, "road": "flat", "noise": QUIET,
         "steering": {"mode": "circle", "radius_m": radius, "direction": "left"}, "contact": contact,
         "vehicle": vehicle or {}}
    )  # fmt: skip
    cols = simulate(scenario).columns
    t = cols["t_s"]
    keep = t > duration - window
    vx, vy = np.gradient(cols["x_m"], t), np.gradient(cols["y_m"], t)
    beta = np.unwrap(np.arctan2(vy, vx) - cols["yaw_rad"])
    beta = (beta + np.pi) % (2 * np.pi) - np.pi

    def spread(x):
        x = x[keep]
        return float((x.max() - x.min()) / max(abs(x.mean()), 1e-12))

    v = float(cols["speed_mps"][keep].mean())
    r = float(cols["yaw_rate_radps"][keep].mean())
    steer = cols["steer_rad"][keep]
    steady = (
        spread(cols["speed_mps"]) < 0.01
        and spread(cols["yaw_rate_radps"]) < 0.01
        and (np.ptp(steer) < max(0.01 * abs(steer.mean()), 2e-4))
    )
    return {
        "ay_nominal_mps2": float(ay_nominal),
        "speed_mps": v,
        "lat_accel_mps2": float(cols["lat_accel_mps2"][keep].mean()),
        "yaw_rate_radps": r,
        "path_radius_m": v / r,
        "steer_rad": float(steer.mean()),
        "roll_rad": float(cols["roll_rad"][keep].mean()),
        "sideslip_rad": float(beta[keep].mean()),
        "steady": bool(steady),
    }


def gradients(steps: list[dict], wheelbase: float, limit: float = LINEAR_LIMIT) -> dict:
    """Understeer, roll and sideslip gradients (deg/g) by linear fits over a_y ≤ `limit`."""
    sel = [s for s in steps if s["lat_accel_mps2"] <= limit]
    ay = np.array([s["lat_accel_mps2"] for s in sel])

    def slope(key):
        return float(np.polyfit(ay, [s[key] for s in sel], 1)[0])

    kinematic = float(np.polyfit(ay, [wheelbase / s["path_radius_m"] for s in sel], 1)[0])
    return {
        "understeer_gradient_deg_per_g": (slope("steer_rad") - kinematic) * DEG_PER_G,
        "steer_slope_deg_per_g": slope("steer_rad") * DEG_PER_G,
        "kinematic_slope_deg_per_g": kinematic * DEG_PER_G,
        "roll_gradient_deg_per_g": slope("roll_rad") * DEG_PER_G,
        "sideslip_gradient_deg_per_g": slope("sideslip_rad") * DEG_PER_G,
        "fitted_steps": len(sel),
    }


def circle_test(radius: float, *, contact: str = "envelope", ay_steps=AY_STEPS, **kwargs) -> dict:
    """The constant-radius test at `radius`: every step and the gradients."""
    wheelbase = load_vehicle().wheelbase
    steps = [circle_step(radius, ay, contact=contact, **kwargs) for ay in ay_steps]
    out = {"radius_m": radius, "contact": contact, **gradients(steps, wheelbase)}
    out["yaw_rate_gain"] = [
        {"speed_mps": s["speed_mps"], "yaw_rate_gain_per_s": s["yaw_rate_radps"] / s["steer_rad"],
         "neutral_per_s": s["speed_mps"] / wheelbase}
        for s in steps
    ]  # fmt: skip
    out["steps"] = steps
    return out


START_CASES = {
    "nominal": {},
    "asymmetric_load": {"load": [{"mass_kg": 300.0, "position_m": [-1.2, 0.5, 0.1]}]},
    "deflated_fr": {"pressure_kpa": {"fl": 250.0, "fr": 120.0, "rl": 250.0, "rr": 250.0}},
}


def start_check(contact: str, case: dict) -> dict:
    """Transients of the first 0.1 s of a 1 s flat-road run at 60 km/h, and the start's cost."""
    scenario = parse_scenario(
        {"duration_s": 1.0, "speed_kmh": 60.0, "road": "flat", "noise": QUIET, "contact": contact, **case}
    )
    started = time.perf_counter()
    prepare(scenario)
    prepare_s = time.perf_counter() - started
    cols = simulate(scenario).columns
    t = cols["t_s"]
    first = t < 0.1
    hub = max(float(np.abs(cols[f"{c}_accel_unsprung_true_mps2"][first]).max()) for c in CORNERS)
    fz_min = min(float(cols[f"{c}_tire_fz_n"][first].min()) for c in CORNERS)
    heave = max(float(np.abs(cols[f"{c}_v_sprung_mps"][first]).max()) for c in CORNERS)
    rates = {a: float(np.abs(np.gradient(cols[f"{a}_rad"], t)[first]).max()) for a in ("roll", "pitch")}
    return {
        "max_hub_accel_first_0.1s_mps2": hub,
        "min_tyre_load_first_0.1s_n": fz_min,
        "max_body_vertical_speed_first_0.1s_mps": heave,
        "max_roll_rate_first_0.1s_radps": rates["roll"],
        "max_pitch_rate_first_0.1s_radps": rates["pitch"],
        "prepare_wall_s": prepare_s,
    }


def main(radii=(40.0,)) -> dict:
    started = time.perf_counter()
    result = {"test": "ISO 4138 steady-state circular, constant radius, flat road, left turn"}
    result["circles"] = [circle_test(r) for r in radii]
    result["start"] = {
        f"{contact}/{name}": start_check(contact, case)
        for contact in ("envelope", "native")
        for name, case in START_CASES.items()
    }
    result["wall_s"] = time.perf_counter() - started
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main(tuple(float(a) for a in sys.argv[1:]) or (40.0,))
