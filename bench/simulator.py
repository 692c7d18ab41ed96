"""Benchmark: speed of the ground-truth simulator and its sensitivity to the time step.

Run: ``python bench/simulator.py`` — prints one JSON object:

- ``realtime_factor``: simulated / wall time of a 10 s class C run at 60 km/h,
  1 ms steps, one core (envelope contact, compiled kernel, Python step loop);
- ``baseline_realtime_factor``: the same multibody (its native-contact variant, with
  the tyre-belt slides) with MuJoCo's own sphere contact on a flat plane, linear joint
  springs/dampers in place of the kernel, and no Python callback
  (``mujoco.rollout``); ``baseline_contacts`` checks it really rolls on its four
  spheres; ``ratio`` = ours / baseline. Targets
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

from suvtwin.mjcf.builder import flat_road_xml
from suvtwin.mjcf.tire import load_tire
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate


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
    """The SUV multibody (native-contact variant) on a plane, MuJoCo's own sphere contact with
    friction, and linear joint springs/dampers in place of the kernel's suspension and tyre laws."""
    vehicle = load_vehicle()
    tire = load_tire(vehicle.tire_file)
    xml = flat_road_xml(vehicle, tire, contact="native")
    start = xml.index('<geom name="road"')
    end = xml.index("/>", start) + 2
    xml = (
        xml[:start]
        + '<geom name="road" type="plane" size="500 500 0.1" contype="1" conaffinity="1"/>'
        + xml[end:]
    )
    xml = xml.replace('condim="1"', 'condim="3"')
    s = vehicle.suspension
    c = 0.5 * (s.damper_compression_low + s.damper_rebound_low)
    preload = vehicle.sprung_mass_corner * 9.81
    for i, corner in enumerate(("fl", "fr", "rl", "rr")):
        k = vehicle.spring_rate[i]
        xml = xml.replace(
            f'<joint name="susp_{corner}" type="slide"',
            f'<joint name="susp_{corner}" type="slide" stiffness="{k}" damping="{c}" '
            f'springref="{-preload[i] / k}"',
        )
        xml = xml.replace(
            f'<joint name="tire_{corner}" type="slide"',
            f'<joint name="tire_{corner}" type="slide" stiffness="{tire.vertical_stiffness_nominal}" '
            f'damping="{tire.vertical_damping}"',
        )
    return mujoco.MjModel.from_xml_string(xml)


def _baseline_factor(duration: float = 10.0) -> tuple[float, int, float]:
    model = _baseline_model()
    model.opt.timestep = 1e-3
    data = mujoco.MjData(model)
    data.qpos[2] = load_vehicle().chassis.cog_height
    data.qvel[0] = 60 / 3.6
    mujoco.mj_forward(model, data)
    n = int(duration / model.opt.timestep)
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    rollout.rollout(model, data, state, nstep=100)  # warm-up
    start = time.perf_counter()
    rollout.rollout(model, data, state, nstep=n)
    wall = time.perf_counter() - start
    mujoco.mj_setState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_step(model, data, nstep=n)
    return duration / wall, int(data.ncon), float(data.qpos[2])


def main() -> dict:
    simulate(_scenario(1e-3))  # compile / load the kernel cache
    walls = []
    for _ in range(3):
        walls.append(simulate(_scenario(1e-3)).metadata["wall_time_s"])
    factor = 10.0 / float(np.median(walls))
    baseline, contacts, height = _baseline_factor()
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
        "baseline_contacts": contacts,
        "baseline_chassis_height_m": height,
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
