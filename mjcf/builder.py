"""Build the SUV on a road into a MuJoCo model whose heightfield *is* the road.

Usual call: ``vm = build_model(load_vehicle(), road, contact="envelope")`` → ``vm.model`` (MjModel).

Bodies (names with a corner suffix ``fl fr rl rr``):

``chassis``
    free body, mass and inertia of the paper-000 chassis, origin at its CoG;
    carries the sprung-mass accelerometer site ``sprung_{c}`` above each wheel.
``carrier_{c}``
    vertical slide joint ``susp_{c}`` (suspension travel, +z up relative to the
    body: compression s = q); non-rotating unsprung mass; site ``unsprung_{c}``.
``knuckle_{fl,fr}``
    front only: steering hinge ``steer_{c}`` about the vertical through the wheel
    centre (no scrub, no trail), driven by a position servo.
``wheel_{c}``
    spin hinge ``spin_{c}`` about the lateral axis, driven by a motor (drive and
    brake torque).

The suspension forces (progressive spring, stops, digressive asymmetric damper,
anti-roll bars) and the tire forces are not MJCF elements: the step kernel
(:mod:`suvtwin.mjcf.kernel`) computes them each step and applies them through
``qfrc_applied`` (suspension, on the slide joints) and ``xfrc_applied`` (tires,
at the contact point). The heightfield ``road`` spans the road's x range and
±2 m in y; the left track's profile lies on y > 0, the right on y < 0, each flat
across ±0.25 m about its track line, blended linearly between the tracks.

With ``contact="native"`` (for cross-validation) MuJoCo's own collision finds
the road: each corner gets a non-spinning ``ring_{c}`` body on a vertical slide
``tire_{c}`` at the wheel centre, carrying a sphere of the unloaded radius that
collides with the heightfield through a stiff, frictionless contact; the kernel
applies the same radial tire law Fz = kt(p)·δ + ct·δ̇ on that slide (δ = its
travel) and the same MF-Tyre forces at the wheel. Only the road geometry then
comes from MuJoCo instead of the enveloped heightfield reading. (MuJoCo's soft
contact alone cannot stand for the tire spring: on a heightfield a sphere makes a
varying number of contacts whose combined stiffness changes with the road under it;
``docs/DESIGN.md``, "Tyre–road contact".)
With ``"envelope"`` (default) nothing collides.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from suvtwin.errors import InputError
from suvtwin.mjcf.kernel import pack_heightfield
from suvtwin.mjcf.tire import TireParams, load_tire
from suvtwin.mjcf.vehicle import CORNERS, GRAVITY, VehicleParams
from suvtwin.roads.profile import Road

__all__ = [
    "HALF_WIDTH_Y",
    "TRACK_PLATEAU",
    "VehicleModel",
    "build_model",
    "flat_road_xml",
    "road_grid",
    "vehicle_xml",
]

HALF_WIDTH_Y = 2.0
"""Half-width of the heightfield across the road, m."""

TRACK_PLATEAU = 0.25
"""Half-width about each track line over which the heightfield holds that track's profile, m."""

_ROW_SPACING = 0.05  # m, heightfield row spacing across the road


@dataclass(frozen=True)
class VehicleModel:
    """A compiled SUV-on-road model and where things are in it.

    Attributes
    ----------
    model : mujoco.MjModel
    vehicle : VehicleParams
    tire : TireParams
    contact : str
        ``"envelope"`` or ``"native"``.
    wheel_center_z : numpy.ndarray, shape (4,)
        Wheel-centre height below/above the chassis CoG at design, m (negative: below).
    static_radius : numpy.ndarray, shape (4,)
        Loaded radius at static load and nominal pressure on flat ground, m.
    spring_preload : numpy.ndarray, shape (4,)
        Spring force at the design position, N (holds the static sprung load).
    ids : dict[str, numpy.ndarray]
        Index arrays: ``chassis_body``, ``carrier_body``, ``knuckle_body``, ``wheel_body``
        (body ids); ``susp_qpos``, ``susp_dof``, ``spin_qpos``, ``spin_dof``; ``steer_act``,
        ``drive_act`` (actuator ids); ``acc_sprung``, ``acc_unsprung`` (sensor adr).
    hfield : numpy.ndarray, shape (8,)
        The heightfield description, laid out by :data:`suvtwin.mjcf.kernel.HEIGHTFIELD_BLOCKS`
        (world x of column 0, column spacing, world y of row 0, row spacing, rows, columns,
        height of data 0 and metres per data unit).
    """

    model: mujoco.MjModel
    vehicle: VehicleParams
    tire: TireParams
    contact: str
    wheel_center_z: np.ndarray
    static_radius: np.ndarray
    spring_preload: np.ndarray
    ids: dict
    hfield: np.ndarray


def road_grid(
    road: Road, *, track_y: float, half_width: float = HALF_WIDTH_Y, n_rows: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Heightfield rows across the road: y of each row (m) and elevation grid (rows, cols), m.

    Row r at y_r holds the left profile for y_r ≥ track_y - plateau, the right profile
    for y_r ≤ -(track_y - plateau), and a linear blend between. Rows are 0.05 m apart
    unless `n_rows` is given.
    """
    if n_rows is None:
        n_rows = int(round(2 * half_width / _ROW_SPACING)) + 1
    y = np.linspace(-half_width, half_width, n_rows)
    edge = track_y - TRACK_PLATEAU
    weight_left = np.clip((y + edge) / (2 * edge), 0.0, 1.0)
    grid = weight_left[:, None] * road.z[0][None, :] + (1.0 - weight_left[:, None]) * road.z[1][None, :]
    return y, grid


def _corner_geometry(vehicle: VehicleParams, tire: TireParams) -> tuple[np.ndarray, np.ndarray]:
    static_radius = tire.unloaded_radius - vehicle.static_tire_load / tire.vertical_stiffness_nominal
    return static_radius - vehicle.chassis.cog_height, static_radius


def vehicle_xml(
    vehicle: VehicleParams,
    tire: TireParams,
    *,
    hfield_shape: tuple[int, int],
    hfield_size: tuple[float, float, float, float],
    hfield_pos: tuple[float, float, float],
    contact: str = "envelope",
    timestep: float = 1e-3,
    loads: tuple[tuple[float, tuple[float, float, float]], ...] = (),
) -> str:
    """MJCF text of the SUV on a heightfield of the given shape (rows, cols), size and position.

    `loads` are extra masses (kg) welded to the chassis at (x, y, z) from its CoG (m),
    each a 0.5 m cube of uniform density.
    """
    c, w, st = vehicle.chassis, vehicle.wheel, vehicle.steering
    wheel_z, _ = _corner_geometry(vehicle, tire)
    xy = vehicle.corner_xy
    m_us = vehicle.unsprung_mass
    radius = tire.unloaded_radius
    m_wheel = m_us * w.rotating_fraction
    knuckle_mass = 1.0
    m_carrier = m_us - m_wheel - np.array([knuckle_mass, knuckle_mass, 0.0, 0.0])
    wheel_transverse = 0.5 * w.spin_inertia + m_wheel * w.width**2 / 12  # per corner, kg m^2
    carrier_inertia = 0.3
    # chassis yaw inertia: the whole vehicle's Jz (about the chassis CoG) minus the corners' share
    knuckle_inertia = 0.05
    corner_izz = (
        np.sum(m_us * (xy[:, 0] ** 2 + xy[:, 1] ** 2))
        + np.sum(wheel_transverse + carrier_inertia)
        + 2 * knuckle_inertia
    )
    native = contact == "native"
    ring_mass, ring_inertia = (2.0, 0.01) if native else (0.0, 0.0)  # tyre belt on the native slide
    corner_izz += 4 * ring_inertia
    izz_chassis = c.inertia_yaw_total - corner_izz
    if izz_chassis <= 0:
        raise InputError("vehicle: inertia_yaw_total is smaller than the wheels' own share")
    m_carrier = m_carrier - ring_mass
    hz = c.cog_height
    lim = vehicle.suspension.travel_limit
    corners_xml = []
    for i, name in enumerate(CORNERS):
        x, y, z = xy[i, 0], xy[i, 1], wheel_z[i]
        wheel = f"""
          <body name="wheel_{name}">
            <joint name="spin_{name}" type="hinge" axis="0 1 0" damping="0"/>
            <inertial pos="0 0 0" mass="{m_wheel[i]:.6g}" diaginertia="{wheel_transverse[i]:.6g} {w.spin_inertia:.6g} {wheel_transverse[i]:.6g}"/>
            <geom name="tire_{name}" class="tire_visual" size="{radius:.6g} {w.width / 2:.6g}"/>
            <geom name="rim_{name}" class="rim_visual" size="{0.6 * radius:.6g} {w.width / 2 + 0.005:.6g}"/>
          </body>"""
        if name in ("fl", "fr"):
            wheel = f"""
        <body name="knuckle_{name}">
          <joint name="steer_{name}" type="hinge" axis="0 0 1" range="{-st.max_angle:.6g} {st.max_angle:.6g}"/>
          <inertial pos="0 0 0" mass="{knuckle_mass}" diaginertia="{knuckle_inertia} {knuckle_inertia} {knuckle_inertia}"/>{wheel}
        </body>"""
        if native:
            wheel += f"""
          <body name="ring_{name}">
            <joint name="tire_{name}" type="slide" axis="0 0 1" range="-0.1 0.2"/>
            <inertial pos="0 0 0" mass="{ring_mass}" diaginertia="{ring_inertia} {ring_inertia} {ring_inertia}"/>
            <geom name="contact_{name}" type="sphere" size="{radius:.6g}" contype="1" conaffinity="1" condim="1"
                  group="3" rgba="0 0 0 0" solref="{2 * timestep:.6g} 1" solimp="0.99 0.999 0.0005"/>
          </body>"""
        corners_xml.append(f"""
      <site name="sprung_{name}" pos="{x:.6g} {y:.6g} {z + 0.35:.6g}" size="0.03" rgba="0.9 0.2 0.2 1"/>
      <body name="carrier_{name}" pos="{x:.6g} {y:.6g} {z:.6g}">
        <joint name="susp_{name}" type="slide" axis="0 0 1" range="{-lim:.6g} {lim:.6g}"/>
        <inertial pos="0 0 0" mass="{m_carrier[i]:.6g}" diaginertia="{carrier_inertia} {carrier_inertia} {carrier_inertia}"/>
        <site name="unsprung_{name}" pos="0 0 0" size="0.02" rgba="0.2 0.2 0.9 1"/>
        <geom class="strut" fromto="0 0 0 0 0 0.35"/>{wheel}
      </body>""")
    actuators = []
    for name in ("fl", "fr"):
        actuators.append(
            f'<position name="steer_{name}" joint="steer_{name}" kp="{st.servo_stiffness:.6g}" '
            f'kv="{st.servo_damping:.6g}" ctrlrange="{-st.max_angle:.6g} {st.max_angle:.6g}"/>'
        )
    for name in CORNERS:
        actuators.append(f'<motor name="drive_{name}" joint="spin_{name}" gear="1"/>')
    sensors = ['<accelerometer name="acc_imu" site="imu"/>']
    sensors += [f'<accelerometer name="acc_sprung_{n}" site="sprung_{n}"/>' for n in CORNERS]
    sensors += [f'<accelerometer name="acc_unsprung_{n}" site="unsprung_{n}"/>' for n in CORNERS]
    load_xml = []
    for j, (mass, (lx, ly, lz)) in enumerate(loads):
        inertia = mass * 0.5**2 / 6.0
        load_xml.append(f"""
      <body name="load_{j}" pos="{lx:.6g} {ly:.6g} {lz:.6g}">
        <inertial pos="0 0 0" mass="{mass:.6g}" diaginertia="{inertia:.6g} {inertia:.6g} {inertia:.6g}"/>
        <geom type="box" size="0.25 0.25 0.25" rgba="0.8 0.5 0.1 0.6"/>
      </body>""")
    rows, cols = hfield_shape
    body_len = c.a1 + c.a2 + 0.9
    return f"""<mujoco model="suvtwin_suv">
  <!-- Generated by suvtwin.mjcf.builder from mjcf/suv/parameters.toml: Segment-D SUV of
       Brancati & Tufano 2022, Table 1. Do not edit; change the parameter file. -->
  <compiler angle="radian" autolimits="true" inertiafromgeom="false"/>
  <option timestep="{timestep:.6g}" integrator="implicitfast" gravity="0 0 {-GRAVITY}"/>
  <size memory="64M"/>
  <visual>
    <global offwidth="1280" offheight="720"/>
    <headlight ambient="0.4 0.4 0.4" diffuse="0.6 0.6 0.6"/>
    <map znear="0.05" zfar="500"/>
  </visual>
  <default>
    <geom contype="0" conaffinity="0" group="1" friction="1 0.005 0.0001" solref="0.005 1" solimp="0.95 0.99 0.001"/>
    <default class="tire_visual">
      <geom type="cylinder" euler="1.5708 0 0" rgba="0.1 0.1 0.1 1"/>
    </default>
    <default class="rim_visual">
      <geom type="cylinder" euler="1.5708 0 0" rgba="0.7 0.7 0.75 1"/>
    </default>
    <default class="strut">
      <geom type="capsule" size="0.03" rgba="0.5 0.5 0.5 1"/>
    </default>
  </default>
  <asset>
    <hfield name="road" nrow="{rows}" ncol="{cols}" size="{hfield_size[0]:.9g} {hfield_size[1]:.9g} {hfield_size[2]:.9g} {hfield_size[3]:.9g}"/>
    <texture name="asphalt" type="2d" builtin="checker" rgb1="0.32 0.32 0.34" rgb2="0.36 0.36 0.38" width="256" height="256"/>
    <material name="asphalt" texture="asphalt" texrepeat="{max(1, int(hfield_size[0]))} {max(1, int(hfield_size[1]))}"/>
    <material name="body" rgba="0.15 0.35 0.6 0.55"/>
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 50" dir="0 0 -1" directional="true"/>
    <geom name="road" type="hfield" hfield="road" pos="{hfield_pos[0]:.9g} {hfield_pos[1]:.9g} {hfield_pos[2]:.9g}" material="asphalt" contype="1" conaffinity="1" condim="{1 if native else 3}" group="0"/>
    <body name="chassis" pos="0 0 {hz:.6g}">
      <freejoint name="chassis"/>
      <inertial pos="0 0 0" mass="{c.mass:.6g}" diaginertia="{c.inertia_roll:.6g} {c.inertia_pitch:.6g} {izz_chassis:.6g}"/>
      <site name="imu" pos="0 0 0" size="0.04" rgba="0.9 0.9 0.1 1"/>
      <geom name="body" type="box" pos="{(c.a1 - c.a2) / 2:.6g} 0 0.25" size="{body_len / 2:.6g} {c.track_front / 2 + 0.05:.6g} 0.45" material="body"/>
      <camera name="chase" pos="-9 -3 3.2" xyaxes="0.32 -0.95 0 0.25 0.08 0.96" mode="trackcom"/>
      <camera name="side" pos="0 -7 0.4" xyaxes="1 0 0 0 0 1" mode="trackcom"/>{"".join(load_xml)}{"".join(corners_xml)}
    </body>
  </worldbody>
  <actuator>
    {chr(10).join("    " + a for a in actuators).strip()}
  </actuator>
  <sensor>
    {chr(10).join("    " + s for s in sensors).strip()}
  </sensor>
</mujoco>
"""


def build_model(
    vehicle: VehicleParams,
    road: Road,
    *,
    tire: TireParams | None = None,
    contact: str = "envelope",
    timestep: float = 1e-3,
    loads: tuple[tuple[float, tuple[float, float, float]], ...] = (),
    half_width: float = HALF_WIDTH_Y,
) -> VehicleModel:
    """Compile the SUV on `road` into a :class:`VehicleModel`.

    Parameters
    ----------
    vehicle : VehicleParams
    road : Road
        Two-track road; its x grid (≤ 0.05 m) becomes the heightfield columns.
    tire : TireParams, optional
        MF-Tyre and vertical tire parameters (default: the ``.tir`` file the vehicle's
        parameter file names, :attr:`~suvtwin.mjcf.vehicle.VehicleParams.tire_file`).
    contact : {"envelope", "native"}
        Tire-road contact: the tire model reading the heightfield (default) or
        MuJoCo's sphere-heightfield contact.
    timestep : float
        Integration step, s.
    loads : sequence of (mass, (x, y, z)), optional
        Extra masses on the chassis, kg at m from its CoG.
    half_width : float, optional
        Half-width of the heightfield across the road, m (default 2). A flat road
        (all elevations zero) may be coarse and wide, e.g. for a steady circle.
    """
    if contact not in ("envelope", "native"):
        raise InputError(f"contact must be 'envelope' or 'native', got {contact!r}")
    flat = not np.any(road.z)
    if road.spacing_m > 0.05 + 1e-12 and not flat:
        raise InputError(f"road spacing must be ≤ 0.05 m for the heightfield, got {road.spacing_m:g}")
    tire = tire or load_tire(vehicle.tire_file)
    track_y = 0.25 * (vehicle.chassis.track_front + vehicle.chassis.track_rear)
    y, grid = road_grid(road, track_y=track_y, half_width=half_width, n_rows=3 if flat else None)
    z_min, z_max = float(grid.min()), float(grid.max())
    z_scale = max(z_max - z_min, 1e-6)
    half_x = 0.5 * (road.x[-1] - road.x[0])
    xml = vehicle_xml(
        vehicle,
        tire,
        hfield_shape=grid.shape,
        hfield_size=(half_x, half_width, z_scale, 0.5),
        hfield_pos=(road.x[0] + half_x, 0.0, z_min),
        contact=contact,
        timestep=timestep,
        loads=tuple(loads),
    )
    model = mujoco.MjModel.from_xml_string(xml)
    # Written after compiling, the data keep their raw values: height = pos_z + data * size[2].
    model.hfield_data[:] = ((grid - z_min) / z_scale).ravel().astype(np.float32)
    wheel_z, static_radius = _corner_geometry(vehicle, tire)

    def body(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)

    def joint(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

    def actuator(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)

    def sensor(name: str) -> int:
        return int(model.sensor_adr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, name)])

    knuckles = ["knuckle_fl", "knuckle_fr", "carrier_rl", "carrier_rr"]
    ids = {
        "chassis_body": np.array([body("chassis")]),
        "chassis_qpos": np.array([model.jnt_qposadr[joint("chassis")]]),
        "chassis_dof": np.array([model.jnt_dofadr[joint("chassis")]]),
        "carrier_body": np.array([body(f"carrier_{c}") for c in CORNERS]),
        "knuckle_body": np.array([body(k) for k in knuckles]),
        "wheel_body": np.array([body(f"wheel_{c}") for c in CORNERS]),
        "susp_qpos": np.array([model.jnt_qposadr[joint(f"susp_{c}")] for c in CORNERS]),
        "susp_dof": np.array([model.jnt_dofadr[joint(f"susp_{c}")] for c in CORNERS]),
        "spin_qpos": np.array([model.jnt_qposadr[joint(f"spin_{c}")] for c in CORNERS]),
        "spin_dof": np.array([model.jnt_dofadr[joint(f"spin_{c}")] for c in CORNERS]),
        "steer_qpos": np.array([model.jnt_qposadr[joint(f"steer_{c}")] for c in ("fl", "fr")]),
        "steer_act": np.array([actuator(f"steer_{c}") for c in ("fl", "fr")]),
        "drive_act": np.array([actuator(f"drive_{c}") for c in CORNERS]),
        "acc_sprung": np.array([sensor(f"acc_sprung_{c}") for c in CORNERS]),
        "acc_unsprung": np.array([sensor(f"acc_unsprung_{c}") for c in CORNERS]),
        "acc_imu": np.array([sensor("acc_imu")]),
        "ring_qpos": np.array(
            [model.jnt_qposadr[joint(f"tire_{c}")] if contact == "native" else -1 for c in CORNERS]
        ),
        "ring_dof": np.array(
            [model.jnt_dofadr[joint(f"tire_{c}")] if contact == "native" else -1 for c in CORNERS]
        ),
    }
    ids = {k: v.astype(np.int64) for k, v in ids.items()}
    hfield = pack_heightfield(
        x0=road.x[0], dx=road.spacing_m, y0=y[0], dy=y[1] - y[0], nrow=grid.shape[0], ncol=grid.shape[1],
        z_base=z_min, z_scale=z_scale,
    )  # fmt: skip
    return VehicleModel(
        model=model,
        vehicle=vehicle,
        tire=tire,
        contact=contact,
        wheel_center_z=wheel_z,
        static_radius=static_radius,
        spring_preload=vehicle.sprung_mass_corner * GRAVITY,
        ids=ids,
        hfield=hfield,
    )


def flat_road_xml(
    vehicle: VehicleParams | None = None, tire: TireParams | None = None, *, contact: str = "envelope"
) -> str:
    """MJCF of the SUV on a flat 200 m road (``contact="envelope"``: ``mjcf/suv/suv.xml``)."""
    from suvtwin.mjcf.vehicle import load_vehicle

    vehicle = vehicle or load_vehicle()
    return vehicle_xml(
        vehicle,
        tire or load_tire(vehicle.tire_file),
        hfield_shape=(3, 3),
        hfield_size=(100.0, 5.0, 0.001, 0.5),
        hfield_pos=(80.0, 0.0, 0.0),
        contact=contact,
    )


if __name__ == "__main__":  # regenerate mjcf/suv/suv.xml after changing parameters.toml
    from pathlib import Path

    (Path(__file__).with_name("suv") / "suv.xml").write_text(flat_road_xml())
