"""Headless video of a finished run: the SUV replayed from its Parquet file.

Usual call: ``render_run("run.parquet", "run.mp4")`` (``suvtwin render``).

The run's scenario (in the file's metadata) rebuilds the same road and model; each
video frame sets the logged pose (position, yaw/pitch/roll, suspension travel,
steering, wheel spin integrated from wheel speed) and renders it offscreen with
MuJoCo. Needs an OpenGL context without a display: EGL (``MUJOCO_GL=egl``, the
default here) or OSMesa; where neither works, :class:`RenderUnavailable` says so.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from suvtwin.errors import InputError, RunError

__all__ = ["RenderUnavailable", "render_run"]


class RenderUnavailable(RunError):
    """No offscreen OpenGL context (or no video writer) is available on this machine."""


def _quat_from_euler(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of intrinsic z-y-x (yaw, pitch, roll) rotations."""
    cy, sy = np.cos(yaw / 2), np.sin(yaw / 2)
    cp, sp = np.cos(pitch / 2), np.sin(pitch / 2)
    cr, sr = np.cos(roll / 2), np.sin(roll / 2)
    return np.array(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ]
    )


def render_run(
    run_path: str | os.PathLike,
    out_path: str | os.PathLike,
    *,
    fps: int = 30,
    width: int = 1024,
    height: int = 576,
    camera: str = "chase",
) -> int:
    """Render the run in `run_path` to the MP4 `out_path`; return the number of frames.

    Raises
    ------
    InputError
        If the run file is missing, has no scenario metadata, or `camera` is unknown.
    RenderUnavailable
        If no offscreen OpenGL context or MP4 writer can be had.
    """
    os.environ.setdefault("MUJOCO_GL", "egl")
    import mujoco

    if not hasattr(mujoco, "GLContext"):  # imported earlier in this process with its GL backends off
        raise RenderUnavailable(
            "MuJoCo was imported in this process without OpenGL (as `suvtwin simulate`, `identify` and "
            "`run` do); render in a fresh process (`suvtwin render`)"
        )

    from suvtwin.files import atomic_write
    from suvtwin.mjcf.vehicle import CORNERS
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.pipeline.simulator import prepare, read_run

    table, meta = read_run(run_path)
    if "scenario" not in meta:
        raise InputError(
            f"run file {str(run_path)!r} carries no scenario metadata: it was not written by suvtwin"
        )
    scenario = parse_scenario(meta["scenario"], source="run metadata")
    prep = prepare(scenario)
    model, data = prep.vm.model, prep.data
    if mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
        raise InputError(f"--camera must be 'chase' or 'side', got {camera!r}")
    try:
        import imageio.v2 as imageio
    except ImportError as error:
        raise RenderUnavailable(f"writing MP4 needs imageio and imageio-ffmpeg ({error})") from None
    try:
        renderer = mujoco.Renderer(model, height=height, width=width)
    except Exception as error:  # noqa: BLE001 - any GL failure means: no offscreen context here
        raise RenderUnavailable(
            f"no offscreen OpenGL context (MUJOCO_GL={os.environ.get('MUJOCO_GL')}): {error}. "
            "Install EGL (e.g. libegl1) or OSMesa and set MUJOCO_GL=egl or osmesa."
        ) from None
    ids, vehicle = prep.vm.ids, prep.vm.vehicle
    t = table["t_s"].to_numpy()
    dt_out = t[1] - t[0] if t.size > 1 else 1.0
    spin = {c: np.cumsum(table[f"{c}_wheel_speed_radps"].to_numpy()) * dt_out for c in CORNERS}
    frame_times = np.arange(t[0], t[-1] + 1e-9, 1.0 / fps)
    rows = np.searchsorted(t, frame_times).clip(0, t.size - 1)
    wheelbase, half_track = vehicle.wheelbase, vehicle.chassis.track_front / 2
    cq = ids["chassis_qpos"][0]

    def frames():
        for r in rows:
            row = table.iloc[r]
            data.qpos[cq : cq + 3] = row.x_m, row.y_m, row.heave_m + vehicle.chassis.cog_height
            data.qpos[cq + 3 : cq + 7] = _quat_from_euler(row.yaw_rad, row.pitch_rad, row.roll_rad)
            for i, c in enumerate(CORNERS):
                data.qpos[ids["susp_qpos"][i]] = row[f"{c}_susp_travel_m"]
                data.qpos[ids["spin_qpos"][i]] = spin[c][r]
            tan_d = np.tan(row.steer_rad)
            data.qpos[ids["steer_qpos"][0]] = np.arctan(wheelbase * tan_d / (wheelbase - half_track * tan_d))
            data.qpos[ids["steer_qpos"][1]] = np.arctan(wheelbase * tan_d / (wheelbase + half_track * tan_d))
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)  # subtree centre of mass, for the tracking cameras
            mujoco.mj_camlight(model, data)
            renderer.update_scene(data, camera=camera)
            yield renderer.render()

    def write(tmp: str) -> None:
        try:
            writer = imageio.get_writer(tmp, format="FFMPEG", fps=fps, codec="libx264", quality=7)
        except Exception as error:  # noqa: BLE001
            raise RenderUnavailable(f"no MP4 writer (imageio-ffmpeg): {error}") from None
        with writer:
            for image in frames():
                writer.append_data(image)

    out_path = Path(out_path)
    atomic_write(out_path, write)
    renderer.close()
    return int(rows.size)
