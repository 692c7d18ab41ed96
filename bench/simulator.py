"""Benchmark: speed of the ground-truth simulator and its sensitivity to the time step.

Run: ``python bench/simulator.py`` — prints one JSON object:

- ``realtime_factor``: simulated / wall time of a 10 s class C run at 60 km/h,
  1 ms steps, one core (envelope contact, compiled kernel, Python step loop);
- ``baseline_realtime_factor``: the same multibody with MuJoCo's native sphere
  contact on a flat plane, linear joint springs/dampers in place of the kernel, and
  no Python callback (``mujoco.rollout``); ``ratio`` = ours / baseline. Targets
  (issue 3): ≥ 60× real time and ratio ≥ 0.8;
- ``timestep_sensitivity``: hub (unsprung) and body (sprung) acceleration RMS at
  the front-left corner for 1, 0.5 and 0.25 ms steps on the same road, and their
  change relative to 0.25 ms.
"""

from __future__ import annotations

import json
import os
import platform
import time

import mujoco
import numpy as np
from mujoco import rollout

from mjcf.builder import flat_road_xml
from mjcf.vehicle import load_vehicle
from pipeline.scenario import parse_scenario
from pipeline.simulator import simulate


def _scenario(timestep: float) -> object:
    return parse_scenario(
        {
            "duration_s": 10.0,
            "timestep_s": timestep,
            "speed_kmh": 60.0,
            "seed": 1,
            "road": {"segments": [{"length_m": 200.0, "road_class": "C"}]},
            "noise": {"accel_sprung_mps2": 0.0, "accel_unsprung_mps2": 0.0},
        }
    )


def _baseline_model() -> mujoco.MjModel:
    """The SUV multibody on a plane with MuJoCo's own sphere contact and joint springs."""
    vehicle = load_vehicle()
    xml = flat_road_xml(vehicle)
    start = xml.index('<geom name="road"')
    end = xml.index("/>", start) + 2
    xml = (
        xml[:start]
        + '<geom name="road" type="plane" size="500 500 0.1" contype="1" conaffinity="1"/>'
        + xml[end:]
    )
    xml = xml.replace('contype="0" conaffinity="0" group="3"', 'contype="1" conaffinity="1" group="3"')
    k_front, k_rear = vehicle.suspension.spring_rate_front, vehicle.suspension.spring_rate_rear
    c = 0.5 * (vehicle.suspension.damper_compression_low + vehicle.suspension.damper_rebound_low)
    for corner, k in (("fl", k_front), ("fr", k_front), ("rl", k_rear), ("rr", k_rear)):
        xml = xml.replace(
            f'<joint name="susp_{corner}" type="slide"',
            f'<joint name="susp_{corner}" type="slide" stiffness="{k}" damping="{c}" springref="0.1"',
        )
    return mujoco.MjModel.from_xml_string(xml)


def _baseline_factor(duration: float = 10.0) -> float:
    model = _baseline_model()
    model.opt.timestep = 1e-3
    data = mujoco.MjData(model)
    data.qpos[2] = 0.62
    data.qvel[0] = 60 / 3.6
    n = int(duration / model.opt.timestep)
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    rollout.rollout(model, data, state, nstep=100)  # warm-up
    start = time.perf_counter()
    rollout.rollout(model, data, state, nstep=n)
    return duration / (time.perf_counter() - start)


def main() -> dict:
    simulate(_scenario(1e-3))  # compile / load the kernel cache
    walls = []
    for _ in range(3):
        walls.append(simulate(_scenario(1e-3)).metadata["wall_time_s"])
    factor = 10.0 / float(np.median(walls))
    baseline = _baseline_factor()
    sensitivity = {}
    for dt in (1e-3, 5e-4, 2.5e-4):
        table = simulate(_scenario(dt)).table
        keep = table.t_s > 1.0
        sensitivity[f"{dt * 1e3:g}ms"] = {
            "hub_accel_rms_mps2": float(np.sqrt(np.mean(table.fl_accel_unsprung_true_mps2[keep] ** 2))),
            "body_accel_rms_mps2": float(np.sqrt(np.mean(table.fl_accel_sprung_true_mps2[keep] ** 2))),
        }
    ref = sensitivity["0.25ms"]
    for entry in sensitivity.values():
        entry["hub_change_vs_0.25ms"] = entry["hub_accel_rms_mps2"] / ref["hub_accel_rms_mps2"] - 1
        entry["body_change_vs_0.25ms"] = entry["body_accel_rms_mps2"] / ref["body_accel_rms_mps2"] - 1
    result = {
        "run": "10 s, class C, 60 km/h, 1 ms steps, envelope contact",
        "wall_time_s": walls,
        "realtime_factor": factor,
        "baseline_realtime_factor": baseline,
        "ratio": factor / baseline,
        "timestep_sensitivity": sensitivity,
        "python": platform.python_version(),
        "mujoco": mujoco.__version__,
        "cpu_count": os.cpu_count(),
    }
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
