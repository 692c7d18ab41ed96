r"""Per-step forces of the SUV: suspension, tire–road contact, driver; and the step log.

Usual call (inside the simulator loop)::

    mujoco.mj_step1(model, data)
    step_kernel(k, *views, *packed, state, log)
    mujoco.mj_step2(model, data)

Everything here runs once per integration step, so it is compiled with numba on
cached MjData views: per-step numpy calls would cost far more than the physics
(``docs/DESIGN.md``, "Tyre–road contact"; speed: ``python bench/simulator.py``). It writes:

- ``qfrc_applied`` on the four suspension slide joints: progressive spring with
  preload, bump and rebound stops, asymmetric digressive damper, anti-roll bars;
- ``xfrc_applied`` on the four wheels: the tire force at the contact point
  (vertical from radial deflection over the heightfield road, enveloped over the
  contact patch; longitudinal/lateral from MF-Tyre 6.1 with pressure effects and
  first-order relaxation), rolling resistance; on the chassis: aerodynamic drag;
- ``ctrl``: Ackermann steering angles from one road-wheel angle (lane keeping by
  pure pursuit, a circle, a tabulated path y(x), or an open-loop series), each front knuckle's
  plus its lateral-force compliance steer (this step's side force) and bump steer (toe-out in
  bump), and drive/brake torque from a PI speed controller (brakes as friction: they hold a
  stopped wheel, never turn it backward, :func:`_brake_or_drive`); the rear tyres' compliance
  toe (the previous step's side force, kept in the state) turns their force frame;
- one row of the log per step (:data:`LOG_COLUMNS`).

Road height under a tire (``envelope`` contact): the heightfield data are read at
``n`` points along the wheel's heading over ±``l_e`` about the wheel centre and
averaged with cos² weights; their weighted least-squares slope tilts the
effective road plane. The deflection is the unloaded radius minus the distance
from the wheel centre to that plane. This is the "effective road plane" idea of
enveloping tyre models (Schmeitz 2004; Pacejka 2012, §10.2) in its simplest form.

Frames: world z up; chassis x forward, y left. Free-joint linear velocity is in
the world frame, angular velocity in the body frame (MuJoCo convention).

References
----------
.. [1] H. B. Pacejka, *Tire and Vehicle Dynamics*, 3rd ed., Butterworth-Heinemann, 2012.
.. [2] A. J. C. Schmeitz, "A semi-empirical three-dimensional model of the pneumatic tyre
   rolling over arbitrarily uneven road surfaces", PhD thesis, TU Delft, 2004.
.. [3] R. C. Coulter, "Implementation of the pure pursuit path tracking algorithm",
   CMU-RI-TR-92-01, 1992.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from suvtwin.jit import cached_njit
from suvtwin.mjcf.tire import (
    I_UNLOADED_RADIUS,
    effective_rolling_radius,
    tire_forces,
    vertical_force,
    vertical_stiffness,
)
from suvtwin.mjcf.vehicle import CORNERS, GRAVITY

__all__ = [
    "CORNER_FIELDS",
    "GLOBAL_FIELDS",
    "HEIGHTFIELD_BLOCKS",
    "ID_BLOCKS",
    "LOG_COLUMNS",
    "MODE_BLOCKS",
    "MODE_CIRCLE",
    "MODE_LANE",
    "MODE_OPEN_LOOP",
    "MODE_PATH",
    "N_MODE",
    "N_STATE",
    "STATE_BLOCKS",
    "VEHICLE_BLOCKS",
    "finish_log",
    "pack_heightfield",
    "pack_ids",
    "pack_vehicle",
    "road_height",
    "step_kernel",
]

MODE_LANE, MODE_CIRCLE, MODE_OPEN_LOOP, MODE_PATH = 0, 1, 2, 3
"""Steering modes (``mode[M_KIND]``): lane keeping, a circle, an open-loop angle series, a
tabulated reference path y(x) (pure pursuit; the table follows the fixed blocks of ``mode``)."""


def _layout(typename: str, blocks: tuple[tuple[str, int], ...]) -> tuple[tuple, int]:
    """First index of each block of a packed array, by name, and the array's length.

    `blocks` lists ``(name, width)`` in array order; the first index of a block is the sum
    of the widths before it. Returns a named tuple of first indices and the total width.
    """
    first, size = {}, 0
    for name, width in blocks:
        first[name] = size
        size += width
    return namedtuple(typename, first)(**first), size


GLOBAL_FIELDS = (
    "t_s",
    "speed_mps",
    "steer_rad",
    "lat_accel_mps2",
    "long_accel_mps2",
    "yaw_rate_radps",
    "heave_m",
    "pitch_rad",
    "roll_rad",
    "yaw_rad",
    "x_m",
    "y_m",
)
CORNER_FIELDS = (
    "accel_sprung_true_mps2",
    "accel_unsprung_true_mps2",
    "z_sprung_m",
    "z_unsprung_m",
    "v_sprung_mps",
    "v_unsprung_mps",
    "road_z_m",
    "pressure_pa",
    "tire_stiffness_npm",
    "tire_fz_n",
    "tire_fx_n",
    "tire_fy_n",
    "tire_slip_ratio",
    "tire_slip_angle_rad",
    "tire_deflection_m",
    "susp_force_n",
    "susp_travel_m",
    "wheel_speed_radps",
)
LOG_COLUMNS = GLOBAL_FIELDS + tuple(f"{c}_{f}" for f in CORNER_FIELDS for c in CORNERS)
"""Column names of the raw step log: globals, then each corner field for fl, fr, rl, rr."""

# ---- slots of the packed arrays. The compiled functions index them with the module-level
# ints below, which numba compiles in as constants; every number is derived from a field list.

_NG = len(GLOBAL_FIELDS)
G_T, G_SPEED, G_STEER = (GLOBAL_FIELDS.index(f) for f in ("t_s", "speed_mps", "steer_rad"))
G_LAT_ACCEL, G_LONG_ACCEL = (GLOBAL_FIELDS.index(f) for f in ("lat_accel_mps2", "long_accel_mps2"))
G_YAW_RATE, G_HEAVE = (GLOBAL_FIELDS.index(f) for f in ("yaw_rate_radps", "heave_m"))
G_PITCH, G_ROLL, G_YAW = (GLOBAL_FIELDS.index(f) for f in ("pitch_rad", "roll_rad", "yaw_rad"))
G_X, G_Y = (GLOBAL_FIELDS.index(f) for f in ("x_m", "y_m"))


def _corner_column(field: str) -> int:
    """Log column of `field` at the front-left corner; corner i (fl, fr, rl, rr) adds i."""
    return _NG + len(CORNERS) * CORNER_FIELDS.index(field)


C_ACC_SPRUNG = _corner_column("accel_sprung_true_mps2")
C_ACC_UNSPRUNG = _corner_column("accel_unsprung_true_mps2")
C_Z_SPRUNG = _corner_column("z_sprung_m")
C_Z_UNSPRUNG = _corner_column("z_unsprung_m")
C_V_SPRUNG = _corner_column("v_sprung_mps")
C_V_UNSPRUNG = _corner_column("v_unsprung_mps")
C_ROAD_Z = _corner_column("road_z_m")
C_PRESSURE = _corner_column("pressure_pa")
C_KT = _corner_column("tire_stiffness_npm")
C_FZ = _corner_column("tire_fz_n")
C_FX = _corner_column("tire_fx_n")
C_FY = _corner_column("tire_fy_n")
C_KAPPA = _corner_column("tire_slip_ratio")
C_ALPHA = _corner_column("tire_slip_angle_rad")
C_DEFLECTION = _corner_column("tire_deflection_m")
C_SUSP_FORCE = _corner_column("susp_force_n")
C_SUSP_TRAVEL = _corner_column("susp_travel_m")
C_WHEEL_SPEED = _corner_column("wheel_speed_radps")

ID_BLOCKS = (
    ("chassis_body", 1),
    ("chassis_qpos", 1),
    ("chassis_dof", 1),
    ("carrier_body", 4),
    ("knuckle_body", 4),
    ("wheel_body", 4),
    ("susp_qpos", 4),
    ("susp_dof", 4),
    ("spin_dof", 4),
    ("steer_act", 2),
    ("drive_act", 4),
    ("acc_sprung", 4),
    ("acc_unsprung", 4),
    ("acc_imu", 1),
    ("ring_qpos", 4),  # native contact only (-1 otherwise)
    ("ring_dof", 4),  # native contact only (-1 otherwise)
)
"""Blocks of the packed integer ids (:func:`pack_ids`): the builder's id names and their widths."""
IDS, N_IDS = _layout("IdSlots", ID_BLOCKS)
I_CHASSIS_BODY, I_CHASSIS_QPOS, I_CHASSIS_DOF = IDS.chassis_body, IDS.chassis_qpos, IDS.chassis_dof
I_CARRIER, I_KNUCKLE, I_WHEEL = IDS.carrier_body, IDS.knuckle_body, IDS.wheel_body
I_SUSP_QPOS, I_SUSP_DOF, I_SPIN_DOF = IDS.susp_qpos, IDS.susp_dof, IDS.spin_dof
I_STEER_ACT, I_DRIVE_ACT = IDS.steer_act, IDS.drive_act
I_ACC_SPRUNG, I_ACC_UNSPRUNG, I_ACC_IMU = IDS.acc_sprung, IDS.acc_unsprung, IDS.acc_imu
I_RING_QPOS, I_RING_DOF = IDS.ring_qpos, IDS.ring_dof

VEHICLE_BLOCKS = (
    ("preload", 4),  # per corner: spring preload, N
    ("spring", 4),  # per corner: spring rate, N/m
    ("wheel_z", 4),  # per corner: design wheel-centre z relative to chassis CoG, m
    ("progression", 1),
    ("bump_clear", 1),
    ("bump_lin", 1),
    ("bump_quad", 1),
    ("reb_clear", 1),
    ("reb_lin", 1),
    ("reb_quad", 1),
    ("c_comp_low", 1),
    ("c_comp_high", 1),
    ("c_reb_low", 1),
    ("c_reb_high", 1),
    ("v_knee", 1),
    ("arb_f", 1),
    ("arb_r", 1),
    ("wheelbase", 1),
    ("track_f", 1),
    ("a2", 1),
    ("max_steer", 1),
    ("compliance_steer_f", 1),  # front toe per N of the wheel's own side force, rad/N
    ("bump_steer_f", 1),  # front toe-out per m of compression, rad/m
    ("compliance_steer_r", 1),  # rear toe toward the side force per N, rad/N
    ("sigma_x", 1),
    ("sigma_y", 1),
    ("roll_res", 1),
    ("env_half", 1),
    ("env_n", 1),
    ("drag", 1),
    ("kp_speed", 1),
    ("ki_speed", 1),
    ("max_drive", 1),
    ("max_brake", 1),
    ("preview_t", 1),
    ("preview_min", 1),
    ("path_understeer", 1),
    ("cog_height", 1),
    ("contact_native", 1),
    ("spin_inertia", 1),
)
"""Blocks of the packed vehicle and driver parameters (:func:`pack_vehicle`), SI units."""
VEHICLE, N_VEHICLE = _layout("VehicleSlots", VEHICLE_BLOCKS)
V_PRELOAD, V_SPRING, V_WHEEL_Z = VEHICLE.preload, VEHICLE.spring, VEHICLE.wheel_z
V_PROGRESSION = VEHICLE.progression
V_BUMP_CLEAR, V_BUMP_LIN, V_BUMP_QUAD = VEHICLE.bump_clear, VEHICLE.bump_lin, VEHICLE.bump_quad
V_REB_CLEAR, V_REB_LIN, V_REB_QUAD = VEHICLE.reb_clear, VEHICLE.reb_lin, VEHICLE.reb_quad
V_C_COMP_LOW, V_C_COMP_HIGH = VEHICLE.c_comp_low, VEHICLE.c_comp_high
V_C_REB_LOW, V_C_REB_HIGH = VEHICLE.c_reb_low, VEHICLE.c_reb_high
V_V_KNEE = VEHICLE.v_knee
V_ARB_F, V_ARB_R = VEHICLE.arb_f, VEHICLE.arb_r
V_WHEELBASE, V_TRACK_F, V_A2 = VEHICLE.wheelbase, VEHICLE.track_f, VEHICLE.a2
V_MAX_STEER = VEHICLE.max_steer
V_COMPLIANCE_F, V_BUMP_STEER_F = VEHICLE.compliance_steer_f, VEHICLE.bump_steer_f
V_COMPLIANCE_R = VEHICLE.compliance_steer_r
V_SIGMA_X, V_SIGMA_Y = VEHICLE.sigma_x, VEHICLE.sigma_y
V_ROLL_RES = VEHICLE.roll_res
V_ENV_HALF, V_ENV_N = VEHICLE.env_half, VEHICLE.env_n
V_DRAG = VEHICLE.drag
V_KP_SPEED, V_KI_SPEED = VEHICLE.kp_speed, VEHICLE.ki_speed
V_MAX_DRIVE, V_MAX_BRAKE = VEHICLE.max_drive, VEHICLE.max_brake
V_SPIN_INERTIA = VEHICLE.spin_inertia
V_PREVIEW_T, V_PREVIEW_MIN = VEHICLE.preview_t, VEHICLE.preview_min
V_PATH_UNDERSTEER = VEHICLE.path_understeer
V_COG_HEIGHT = VEHICLE.cog_height
V_CONTACT_NATIVE = VEHICLE.contact_native

STATE_BLOCKS = (
    ("integral", 1),  # integral of the speed error, m
    ("slip_u", 4),  # per corner: longitudinal tyre deflection (relaxation), m
    ("slip_v", 4),  # per corner: lateral tyre deflection (relaxation), m
    ("r_prev", 9),  # chassis rotation matrix of the previous step, row-major
    ("steer", 1),  # road-wheel angle of the bicycle model, rad
    ("fy_prev", 4),  # per corner: tyre side force of the previous step (rear compliance steer), N
)
"""Blocks of the kernel's scratch state, carried from step to step."""
STATE, N_STATE = _layout("StateSlots", STATE_BLOCKS)
S_INTEGRAL, S_SLIP_U, S_SLIP_V = STATE.integral, STATE.slip_u, STATE.slip_v
S_R_PREV, S_STEER = STATE.r_prev, STATE.steer
S_FY_PREV = STATE.fy_prev

MODE_BLOCKS = (
    ("kind", 1),  # MODE_LANE, MODE_CIRCLE or MODE_OPEN_LOOP
    ("lane_y_or_centre_x", 1),  # lane: y of the lane, m; circle: x of its centre, m
    ("centre_y", 1),  # circle: y of its centre, m
    ("radius", 1),  # circle: radius, m
    ("direction", 1),  # circle: +1 left (counter-clockwise), -1 right
    ("path_x0", 1),  # path: world x of the table's first point, m
    ("path_dx", 1),  # path: spacing of the table's points in x, m (> 0)
    ("path_n", 1),  # path: number of points of the table (>= 2)
)
"""Blocks of the steering-mode array (``mode``) the simulator packs. In :data:`MODE_PATH` the
array continues after these blocks with the path's ``path_n`` lateral positions y, m, at
x = path_x0 + j·path_dx (linear in between, held beyond the ends)."""
MODE, N_MODE = _layout("ModeSlots", MODE_BLOCKS)
M_KIND, M_LANE_Y, M_CENTRE_X = MODE.kind, MODE.lane_y_or_centre_x, MODE.lane_y_or_centre_x
M_CENTRE_Y, M_RADIUS, M_DIRECTION = MODE.centre_y, MODE.radius, MODE.direction
M_PATH_X0, M_PATH_DX, M_PATH_N = MODE.path_x0, MODE.path_dx, MODE.path_n


HEIGHTFIELD_BLOCKS = (
    ("x0", 1),  # world x of the grid's column 0, m
    ("dx", 1),  # column spacing, m
    ("y0", 1),  # world y of the grid's row 0, m
    ("dy", 1),  # row spacing, m
    ("nrow", 1),  # rows
    ("ncol", 1),  # columns
    ("z_base", 1),  # height of data value 0, m
    ("z_scale", 1),  # metres per data unit
)
"""Blocks of the heightfield description ``hf`` (:attr:`suvtwin.mjcf.builder.VehicleModel.hfield`)."""
HEIGHTFIELD, N_HEIGHTFIELD = _layout("HeightfieldSlots", HEIGHTFIELD_BLOCKS)
H_X0, H_DX, H_Y0, H_DY = HEIGHTFIELD.x0, HEIGHTFIELD.dx, HEIGHTFIELD.y0, HEIGHTFIELD.dy
H_NROW, H_NCOL = HEIGHTFIELD.nrow, HEIGHTFIELD.ncol
H_Z_BASE, H_Z_SCALE = HEIGHTFIELD.z_base, HEIGHTFIELD.z_scale


def pack_heightfield(**values: float) -> np.ndarray:
    """Pack the heightfield description (:data:`HEIGHTFIELD_BLOCKS` names, SI units) into ``hf``."""
    missing = sorted(set(HEIGHTFIELD._fields) - set(values))
    unknown = sorted(set(values) - set(HEIGHTFIELD._fields))
    if missing or unknown:
        raise ValueError(f"pack_heightfield: missing {missing}, unknown {unknown}")
    out = np.empty(N_HEIGHTFIELD)
    for name, value in values.items():
        out[getattr(HEIGHTFIELD, name)] = value
    return out


def pack_ids(ids: dict) -> np.ndarray:
    """Pack the builder's id dict (:data:`ID_BLOCKS` names) into the int64 layout above."""
    out = np.zeros(N_IDS, dtype=np.int64)
    for name, width in ID_BLOCKS:
        first = getattr(IDS, name)
        out[first : first + width] = ids[name]
    return out


def pack_vehicle(vm) -> np.ndarray:
    """Pack a :class:`suvtwin.mjcf.builder.VehicleModel`'s suspension, tire-extra and driver values."""
    v = vm.vehicle
    s, t, d, c = v.suspension, v.tire, v.driver, v.chassis
    out = np.zeros(N_VEHICLE)
    out[V_PRELOAD : V_PRELOAD + 4] = vm.spring_preload
    out[V_SPRING : V_SPRING + 4] = v.spring_rate
    out[V_WHEEL_Z : V_WHEEL_Z + 4] = vm.wheel_center_z
    out[V_PROGRESSION] = s.spring_progression
    out[V_BUMP_CLEAR], out[V_BUMP_LIN], out[V_BUMP_QUAD] = (
        s.bump_stop_clearance,
        s.bump_stop_linear,
        s.bump_stop_quadratic,
    )
    out[V_REB_CLEAR], out[V_REB_LIN], out[V_REB_QUAD] = (
        s.rebound_stop_clearance,
        s.rebound_stop_linear,
        s.rebound_stop_quadratic,
    )
    out[V_C_COMP_LOW], out[V_C_COMP_HIGH] = s.damper_compression_low, s.damper_compression_high
    out[V_C_REB_LOW], out[V_C_REB_HIGH] = s.damper_rebound_low, s.damper_rebound_high
    out[V_V_KNEE] = s.damper_knee_velocity
    out[V_ARB_F], out[V_ARB_R] = s.anti_roll_front, s.anti_roll_rear
    out[V_WHEELBASE], out[V_TRACK_F], out[V_A2] = v.wheelbase, c.track_front, c.a2
    out[V_MAX_STEER] = v.steering.max_angle
    out[V_COMPLIANCE_F] = v.steering.compliance_steer_front
    out[V_BUMP_STEER_F] = v.steering.bump_steer_front
    out[V_COMPLIANCE_R] = v.steering.compliance_steer_rear
    out[V_SIGMA_X], out[V_SIGMA_Y] = t.relaxation_length_longitudinal, t.relaxation_length_lateral
    out[V_ROLL_RES] = t.rolling_resistance
    out[V_ENV_HALF], out[V_ENV_N] = t.envelope_half_length, t.envelope_points
    out[V_DRAG] = 0.5 * c.air_density * c.drag_coefficient * c.frontal_area
    out[V_KP_SPEED], out[V_KI_SPEED] = d.speed_gain, d.speed_integral_gain
    out[V_MAX_DRIVE], out[V_MAX_BRAKE] = d.max_drive_torque, d.max_brake_torque
    out[V_PREVIEW_T], out[V_PREVIEW_MIN] = d.preview_time, d.preview_min
    out[V_PATH_UNDERSTEER] = d.path_understeer
    out[V_COG_HEIGHT] = c.cog_height
    out[V_CONTACT_NATIVE] = 1.0 if vm.contact == "native" else 0.0
    out[V_SPIN_INERTIA] = v.wheel.spin_inertia
    return out


@cached_njit
def road_height(x, y, hf, hdata):
    """Heightfield elevation at world (x, y), m: bilinear in the grid, clamped at its edges.

    `hf`: the heightfield description (:data:`HEIGHTFIELD_BLOCKS`) from
    :class:`suvtwin.mjcf.builder.VehicleModel`; `hdata` the (nrow, ncol) data,
    height = z_base + data·z_scale.
    """
    nrow, ncol = int(hf[H_NROW]), int(hf[H_NCOL])
    fx = (x - hf[H_X0]) / hf[H_DX]
    fy = (y - hf[H_Y0]) / hf[H_DY]
    fx = min(max(fx, 0.0), ncol - 1.000001)
    fy = min(max(fy, 0.0), nrow - 1.000001)
    i, j = int(fy), int(fx)
    ty, tx = fy - i, fx - j
    h00, h01 = hdata[i, j], hdata[i, j + 1]
    h10, h11 = hdata[i + 1, j], hdata[i + 1, j + 1]
    h = (1 - ty) * ((1 - tx) * h00 + tx * h01) + ty * ((1 - tx) * h10 + tx * h11)
    return hf[H_Z_BASE] + h * hf[H_Z_SCALE]


@cached_njit
def _envelope(cx, cy, fx, fy, half, npts, hf, hdata):
    """cos²-weighted mean road height and slope along (fx, fy) over ±half about (cx, cy)."""
    wsum, zsum, szs, sss = 0.0, 0.0, 0.0, 0.0
    n = int(npts)
    zs = np.empty(n)
    ss = np.empty(n)
    ws = np.empty(n)
    for j in range(n):
        s = half * (2.0 * (j + 0.5) / n - 1.0)
        w = np.cos(0.5 * np.pi * s / half) ** 2
        z = road_height(cx + s * fx, cy + s * fy, hf, hdata)
        zs[j], ss[j], ws[j] = z, s, w
        wsum += w
        zsum += w * z
    zmean = zsum / wsum
    for j in range(n):
        szs += ws[j] * ss[j] * (zs[j] - zmean)
        sss += ws[j] * ss[j] * ss[j]
    return zmean, szs / sss


@cached_njit
def _path_y(x, mode):
    """Lateral position of the tabulated path (:data:`MODE_PATH`) at world x, m: linear, held at the ends."""
    n = int(mode[M_PATH_N])
    f = (x - mode[M_PATH_X0]) / mode[M_PATH_DX]
    if f <= 0.0:
        return mode[N_MODE]
    if f >= n - 1:
        return mode[N_MODE + n - 1]
    j = int(f)
    w = f - j
    return (1.0 - w) * mode[N_MODE + j] + w * mode[N_MODE + j + 1]


@cached_njit
def _damper(v, vp):
    """Damper force for compression velocity v (m/s, > 0 in bump), N; digressive, asymmetric."""
    knee = vp[V_V_KNEE]
    if v >= 0.0:
        lo, hi = vp[V_C_COMP_LOW], vp[V_C_COMP_HIGH]
    else:
        lo, hi = vp[V_C_REB_LOW], vp[V_C_REB_HIGH]
    a = abs(v)
    f = lo * a if a <= knee else lo * knee + hi * (a - knee)
    return f if v >= 0.0 else -f


@cached_njit
def _spring(i, s, vp):
    """Spring + stop force for compression s (m) at corner i, N (> 0 pushes the wheel down)."""
    k = vp[V_SPRING + i]
    f = vp[V_PRELOAD + i] + k * s
    if s > 0.0:
        f += k * vp[V_PROGRESSION] * s**3
    e = s - vp[V_BUMP_CLEAR]
    if e > 0.0:
        f += vp[V_BUMP_LIN] * e + vp[V_BUMP_QUAD] * e * e
    e = -s - vp[V_REB_CLEAR]
    if e > 0.0:
        f -= vp[V_REB_LIN] * e + vp[V_REB_QUAD] * e * e
    return f


@cached_njit
def _brake_or_drive(torque, omega, spin_inertia, dt):
    """The torque on a wheel's spin joint, N m, from the speed controller's `torque` (N m; < 0 brakes).

    A drive torque (≥ 0) is applied as it is. A brake is friction between disc and pads: it opposes
    the wheel's spin `omega` (rad/s) with up to ``|torque|`` and never drives the wheel the other
    way. Near standstill it takes only what stops the wheel within this step,
    ``spin_inertia · |omega| / dt`` (the wheel's inertia alone, kg m², the least it could be: so it
    cannot overshoot), which holds a stopped car instead of reversing it (as a signed torque did: the
    SUV braked to rest from 80 km/h rolled back 1.5 m at up to 0.64 m/s). Above
    ``|torque| · dt / spin_inertia`` (about 2 rad/s, 0.8 m/s, at full braking) a brake torque is applied
    exactly as asked.
    """
    if torque >= 0.0:
        return torque
    hold = spin_inertia * abs(omega) / dt
    if omega >= 0.0:
        return max(torque, -hold)
    return min(-torque, hold)


@cached_njit
def step_kernel(
    k,
    dt,
    qpos,
    qvel,
    xpos,
    xmat,
    sensordata,
    qfrc_applied,
    xfrc_applied,
    ctrl,
    ids,
    hf,
    hdata,
    vp,
    tp,
    pressure,
    speed_ref,
    steer_cmd,
    mode,
    state,
    log,
):
    """Apply the forces of step `k` (state at t_k after ``mj_step1``) and log row `k`.

    Also completes row k-1 with the accelerations MuJoCo computed in the previous
    ``mj_step2``. Shapes: `pressure` (nstep, 4) Pa, `speed_ref` (nstep,) m/s,
    `steer_cmd` (nstep,) rad, `mode` (N_MODE,) laid out as :data:`MODE_BLOCKS`,
    `log` (nstep, len(LOG_COLUMNS)).
    """
    cb = ids[I_CHASSIS_BODY]
    cq = ids[I_CHASSIS_QPOS]
    cd = ids[I_CHASSIS_DOF]
    px, py, pz = qpos[cq], qpos[cq + 1], qpos[cq + 2]
    R = xmat[cb].reshape(3, 3)
    vx, vy, vz = qvel[cd], qvel[cd + 1], qvel[cd + 2]
    wl0, wl1, wl2 = qvel[cd + 3], qvel[cd + 4], qvel[cd + 5]
    wx = R[0, 0] * wl0 + R[0, 1] * wl1 + R[0, 2] * wl2
    wy = R[1, 0] * wl0 + R[1, 1] * wl1 + R[1, 2] * wl2
    wz = R[2, 0] * wl0 + R[2, 1] * wl1 + R[2, 2] * wl2
    yaw = np.arctan2(R[1, 0], R[0, 0])
    hx, hy = np.cos(yaw), np.sin(yaw)
    speed = vx * hx + vy * hy

    # ---- accelerations of the previous step (computed by the last mj_step2) ----
    if k > 0:
        _log_accelerations(k - 1, sensordata, ids, state, log)
    for j in range(9):
        state[S_R_PREV + j] = R.ravel()[j]

    # ---- driver: speed ----
    err = speed_ref[k] - speed
    integral = state[S_INTEGRAL] + err * dt
    torque = vp[V_KP_SPEED] * err + vp[V_KI_SPEED] * integral
    per_wheel = torque / 4.0
    if per_wheel > vp[V_MAX_DRIVE] or per_wheel < -vp[V_MAX_BRAKE]:
        integral = state[S_INTEGRAL]  # anti-windup: hold the integral while saturated
        per_wheel = min(max(per_wheel, -vp[V_MAX_BRAKE]), vp[V_MAX_DRIVE])
    state[S_INTEGRAL] = integral
    for i in range(4):
        omega = qvel[ids[I_SPIN_DOF + i]]
        ctrl[ids[I_DRIVE_ACT + i]] = _brake_or_drive(per_wheel, omega, vp[V_SPIN_INERTIA], dt)

    # ---- driver: steering (road-wheel angle of the bicycle model) ----
    wb = vp[V_WHEELBASE]
    if mode[M_KIND] == MODE_OPEN_LOOP:
        delta = steer_cmd[k]
    else:
        rx, ry = px - vp[V_A2] * hx, py - vp[V_A2] * hy  # rear-axle centre
        look = max(vp[V_PREVIEW_MIN], abs(speed) * vp[V_PREVIEW_T])
        if mode[M_KIND] == MODE_LANE:
            tx, ty = rx + look, mode[M_LANE_Y]
        elif mode[M_KIND] == MODE_PATH:
            tx = rx + look  # the path runs along +x with small slopes: target one look-ahead ahead in x
            ty = _path_y(tx, mode)
        else:
            ocx, ocy, radius = mode[M_CENTRE_X], mode[M_CENTRE_Y], mode[M_RADIUS]
            theta = np.arctan2(ry - ocy, rx - ocx) + mode[M_DIRECTION] * look / radius
            tx, ty = ocx + radius * np.cos(theta), ocy + radius * np.sin(theta)
        eta = np.arctan2(ty - ry, tx - rx) - yaw
        eta = np.arctan2(np.sin(eta), np.cos(eta))
        dist = np.hypot(tx - rx, ty - ry)
        kappa = 2.0 * np.sin(eta) / dist  # curvature of the arc through the target point
        delta = np.arctan(wb * kappa)
        if mode[M_KIND] == MODE_PATH:  # the lane-change driver also steers for the car's understeer
            delta += vp[V_PATH_UNDERSTEER] * speed * speed * kappa
    delta = min(max(delta, -vp[V_MAX_STEER]), vp[V_MAX_STEER])
    state[S_STEER] = delta

    # ---- suspension ----
    travel = np.empty(4)
    rate = np.empty(4)
    for i in range(4):
        travel[i] = qpos[ids[I_SUSP_QPOS + i]]  # compression: wheel up relative to the body
        rate[i] = qvel[ids[I_SUSP_DOF + i]]
    for i in range(4):
        arb = vp[V_ARB_F] if i < 2 else vp[V_ARB_R]
        other = i + 1 if i % 2 == 0 else i - 1
        force = _spring(i, travel[i], vp) + _damper(rate[i], vp) + arb * (travel[i] - travel[other])
        qfrc_applied[ids[I_SUSP_DOF + i]] = -force
        log[k, C_SUSP_FORCE + i] = force
        log[k, C_SUSP_TRAVEL + i] = travel[i]

    # ---- tires ----
    native = vp[V_CONTACT_NATIVE] > 0.5
    for i in range(4):
        wbody = ids[I_WHEEL + i]
        kn = xmat[ids[I_KNUCKLE + i]].reshape(3, 3)
        cx, cy, cz = xpos[wbody, 0], xpos[wbody, 1], xpos[wbody, 2]
        # wheel-centre velocity: chassis point velocity + slide along the chassis z axis
        rx_, ry_, rz_ = cx - px, cy - py, cz - pz
        qd = qvel[ids[I_SUSP_DOF + i]]
        ux = vx + wy * rz_ - wz * ry_ + R[0, 2] * qd
        uy = vy + wz * rx_ - wx * rz_ + R[1, 2] * qd
        uz = vz + wx * ry_ - wy * rx_ + R[2, 2] * qd
        # sprung point above the wheel (slide anchor) and its vertical velocity
        log[k, C_Z_SPRUNG + i] = cz + R[2, 2] * qpos[ids[I_SUSP_QPOS + i]] * -1.0
        log[k, C_V_SPRUNG + i] = uz - R[2, 2] * qd
        log[k, C_Z_UNSPRUNG + i] = cz
        log[k, C_V_UNSPRUNG + i] = uz
        # heading of the wheel in the ground plane
        sx, sy = kn[0, 1], kn[1, 1]
        norm = np.hypot(sx, sy)
        fx, fy = sy / norm, -sx / norm
        if i >= 2:  # rear lateral-force compliance: toe toward the last step's side force
            toe = vp[V_COMPLIANCE_R] * state[S_FY_PREV + i]
            ct_, st_ = np.cos(toe), np.sin(toe)
            fx, fy = ct_ * fx - st_ * fy, st_ * fx + ct_ * fy
        zr, slope = _envelope(cx, cy, fx, fy, vp[V_ENV_HALF], vp[V_ENV_N], hf, hdata)
        inv = 1.0 / np.sqrt(1.0 + slope * slope)
        nx, ny, nz = -slope * fx * inv, -slope * fy * inv, inv
        dist = (cz - zr) * inv
        deflection = tp[I_UNLOADED_RADIUS] - dist
        vfwd = ux * fx + uy * fy
        deflection_rate = -(uz - slope * vfwd) * inv
        p = pressure[k, i]
        log[k, C_ROAD_Z + i] = zr
        log[k, C_PRESSURE + i] = p
        log[k, C_KT + i] = vertical_stiffness(p, tp)
        log[k, C_DEFLECTION + i] = deflection
        omega = qvel[ids[I_SPIN_DOF + i]]
        log[k, C_WHEEL_SPEED + i] = omega
        if native:
            # MuJoCo's contact holds the ring sphere on the road; the tyre spring acts on its slide
            deflection = qpos[ids[I_RING_QPOS + i]]
            deflection_rate = qvel[ids[I_RING_DOF + i]]
            dist = tp[I_UNLOADED_RADIUS] - deflection
            slope, inv = 0.0, 1.0
            nx, ny, nz = 0.0, 0.0, 1.0
            log[k, C_DEFLECTION + i] = deflection
        fz = vertical_force(deflection, deflection_rate, p, tp)
        if native:
            qfrc_applied[ids[I_RING_DOF + i]] = -fz
        # tangent directions of the effective road plane
        tx_, ty_, tz_ = fx * inv, fy * inv, slope * inv
        lx, ly, lz = ny * tz_ - nz * ty_, nz * tx_ - nx * tz_, nx * ty_ - ny * tx_
        v_long = ux * tx_ + uy * ty_ + uz * tz_
        v_lat = ux * lx + uy * ly + uz * lz
        re = effective_rolling_radius(fz, p, tp)
        slip_x = v_long - omega * re
        gain = dt * abs(v_long)
        u = (state[S_SLIP_U + i] - dt * slip_x) / (1.0 + gain / vp[V_SIGMA_X])
        w = (state[S_SLIP_V + i] - dt * v_lat) / (1.0 + gain / vp[V_SIGMA_Y])
        state[S_SLIP_U + i] = u
        state[S_SLIP_V + i] = w
        kappa = u / vp[V_SIGMA_X]
        alpha = np.arctan(-w / vp[V_SIGMA_Y])
        f_long, f_lat = tire_forces(fz, kappa, alpha, p, tp)
        Fx = fz * nx + f_long * tx_ + f_lat * lx
        Fy = fz * ny + f_long * ty_ + f_lat * ly
        Fz = fz * nz + f_long * tz_ + f_lat * lz
        # contact point relative to the wheel centre
        ox, oy, oz = -dist * nx, -dist * ny, -dist * nz
        roll_torque = -vp[V_ROLL_RES] * fz * dist * np.tanh(omega)
        if native:  # the vertical force already reaches the wheel through the ring's slide
            Fx, Fy, Fz = Fx - fz * nx, Fy - fz * ny, Fz - fz * nz
        xfrc_applied[wbody, 0] = Fx
        xfrc_applied[wbody, 1] = Fy
        xfrc_applied[wbody, 2] = Fz
        xfrc_applied[wbody, 3] = oy * Fz - oz * Fy + roll_torque * kn[0, 1]
        xfrc_applied[wbody, 4] = oz * Fx - ox * Fz + roll_torque * kn[1, 1]
        xfrc_applied[wbody, 5] = ox * Fy - oy * Fx + roll_torque * kn[2, 1]
        log[k, C_FZ + i] = fz
        log[k, C_FX + i] = f_long
        log[k, C_FY + i] = f_lat
        log[k, C_KAPPA + i] = kappa
        log[k, C_ALPHA + i] = alpha
        state[S_FY_PREV + i] = f_lat

    # ---- steering: Ackermann angles of the two knuckles, plus each front wheel's compliance steer
    # (toe out of the turn per N of its side force, this step's) and bump steer (toe-out in bump) ----
    tan_d = np.tan(delta)
    half_t = 0.5 * vp[V_TRACK_F]
    toe_l = vp[V_BUMP_STEER_F] * travel[0] - vp[V_COMPLIANCE_F] * log[k, C_FY]
    toe_r = -vp[V_BUMP_STEER_F] * travel[1] - vp[V_COMPLIANCE_F] * log[k, C_FY + 1]
    ctrl[ids[I_STEER_ACT]] = np.arctan(wb * tan_d / (wb - half_t * tan_d)) + toe_l  # left: inner if delta > 0
    ctrl[ids[I_STEER_ACT + 1]] = np.arctan(wb * tan_d / (wb + half_t * tan_d)) + toe_r

    # ---- aerodynamic drag on the chassis (horizontal, opposite the velocity) ----
    vh = np.hypot(vx, vy)
    xfrc_applied[cb, 0] = -vp[V_DRAG] * vh * vx
    xfrc_applied[cb, 1] = -vp[V_DRAG] * vh * vy

    # ---- globals ----
    log[k, G_T] = k * dt
    log[k, G_SPEED] = speed
    log[k, G_STEER] = delta
    log[k, G_YAW_RATE] = wz
    log[k, G_HEAVE] = pz - vp[V_COG_HEIGHT]
    log[k, G_PITCH] = np.arcsin(min(max(-R[2, 0], -1.0), 1.0))
    log[k, G_ROLL] = np.arctan2(R[2, 1], R[2, 2])
    log[k, G_YAW] = yaw
    log[k, G_X] = px
    log[k, G_Y] = py


def finish_log(
    k_last: int, sensordata: np.ndarray, ids: np.ndarray, state: np.ndarray, log: np.ndarray
) -> None:
    """Write the accelerations of the last step (after the final ``mj_step2``) into its row."""
    _log_accelerations(k_last, sensordata, ids, state, log)


@cached_njit
def _log_accelerations(row, sensordata, ids, state, log):
    """World-frame accelerations, gravity removed, from the accelerometers of step `row`.

    MuJoCo's accelerometers read proper acceleration in the site frame; the sites
    are aligned with the chassis, whose rotation at that step is kept in `state`.
    """
    Rp = state[S_R_PREV : S_R_PREV + 9].reshape(3, 3)
    for i in range(4):
        for which in range(2):
            adr = ids[I_ACC_SPRUNG + i] if which == 0 else ids[I_ACC_UNSPRUNG + i]
            a0, a1, a2 = sensordata[adr], sensordata[adr + 1], sensordata[adr + 2]
            az = Rp[2, 0] * a0 + Rp[2, 1] * a1 + Rp[2, 2] * a2 - GRAVITY
            col = C_ACC_SPRUNG if which == 0 else C_ACC_UNSPRUNG
            log[row, col + i] = az
    adr = ids[I_ACC_IMU]
    a0, a1, a2 = sensordata[adr], sensordata[adr + 1], sensordata[adr + 2]
    ax = Rp[0, 0] * a0 + Rp[0, 1] * a1 + Rp[0, 2] * a2
    ay = Rp[1, 0] * a0 + Rp[1, 1] * a1 + Rp[1, 2] * a2
    pyaw = np.arctan2(Rp[1, 0], Rp[0, 0])
    log[row, G_LAT_ACCEL] = -np.sin(pyaw) * ax + np.cos(pyaw) * ay
    log[row, G_LONG_ACCEL] = np.cos(pyaw) * ax + np.sin(pyaw) * ay
