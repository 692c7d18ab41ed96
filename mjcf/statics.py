"""The settled start: the SUV in static equilibrium on its road at t = 0, rolling at the start speed.

Usual call (the simulator's ``prepare``, with the car's x, y and yaw set)::

    settled = settle(vm, data, pressure0, hdata)       # heave, roll, pitch, travels, tyre rings
    state = start_rolling(vm, data, pressure0, speed0, settled)  # speed, wheel spin, kernel state

Method: Newton's method on the model itself. The unknowns are the chassis height, roll and
pitch, the four suspension travels and, with ``native`` contact, the four tyre-ring slides (x,
y and yaw held where the scenario puts the car; wheels and knuckles at rest). The residual is
the generalized force M·q̈ on those degrees of freedom at zero velocity, with every force the
run will see: the step kernel's (:func:`suvtwin.mjcf.kernel.step_kernel`: spring with preload,
stops, anti-roll bars, the tyre's radial force over the enveloped heightfield at each corner's
own pressure) and MuJoCo's (gravity on the chassis, the corners and any load bodies wherever
they sit; the native sphere–heightfield contact). The first guess lays the chassis parallel
to the plane through the road under the four wheels, each wheel at its design deflection over
its own road height (native: each ring just into the road, found by collision detection). The
Jacobian is taken by forward differences (7 or 11 evaluations, each one ``mj_kinematics`` +
kernel + ``mj_forward``, tens of µs) and kept while full steps cut the residual tenfold; steps
are limited to 20 mm / 0.02 rad and backtracked until the residual falls. On a flat road 2
iterations (native 5), on rough roads with offset loads and unequal pressures 3–6, leave
< 1e-3 N (N m). Cost, measured on the 2-core machine: 0.5–1 ms per run with ``envelope``
contact, 1–8 ms with ``native`` (its collisions with a rough heightfield), against ~0.09 s for
the 10 s of a class C run it starts. A wheel over a dip may hang (zero tyre force).

Why not a short pre-settling simulation with x, y and yaw held: the body's own damping ratio
is ~0.3 at 1.2–1.5 Hz, so reaching hub accelerations below 1 m/s² takes seconds of simulated
time (or artificial damping whose end state still has to be checked), ~10–100× the cost of the
Newton solve, and it stops wherever the damping leaves it instead of at the equilibrium.

:func:`start_rolling` then gives the chassis the start speed along its heading and each wheel
the spin of steady rolling at its settled load and pressure, ω = v(1 + κ)/R_e (MF-Tyre 6.1
effective rolling radius), with the longitudinal slip κ that carries the wheel's share of the
steady drive force (drag and rolling resistance at that speed), the kernel's relaxation state
u = σ_x·κ and the speed controller's integral preset to that drive torque: t = 0 is steady
straight rolling, not a car dropped onto the road or braked by an idle controller.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from suvtwin.mjcf.kernel import (
    C_DEFLECTION,
    C_FZ,
    LOG_COLUMNS,
    M_KIND,
    MODE_OPEN_LOOP,
    N_MODE,
    N_STATE,
    S_INTEGRAL,
    S_SLIP_U,
    V_DRAG,
    V_KI_SPEED,
    V_ROLL_RES,
    V_SIGMA_X,
    pack_ids,
    pack_vehicle,
    road_height,
    step_kernel,
)
from suvtwin.mjcf.tire import I_UNLOADED_RADIUS, effective_rolling_radius, tire_forces, vertical_stiffness
from suvtwin.mjcf.vehicle import CORNERS

__all__ = ["SettleInfo", "settle", "start_rolling"]

_MAX_STEP_M = 0.02  # largest Newton step of a height or travel, m
_MAX_STEP_RAD = 0.02  # of roll or pitch, rad


@dataclass(frozen=True)
class SettleInfo:
    """How the static solve went: Newton iterations, residual evaluations, the largest
    remaining |q̈| on the solved degrees of freedom (m/s², rad/s²; the knuckles' and wheels'
    own small accelerations couple into it), and each corner's tyre
    load (N) and radial deflection (m) at the solution."""

    iterations: int
    evaluations: int
    max_qacc: float
    tyre_load_n: np.ndarray
    tyre_deflection_m: np.ndarray
    residual_n: float
    """Largest generalized force left on the solved degrees of freedom, N (N m)."""
    converged: bool
    """Whether the residual fell below the tolerance (else `data` holds the best point found)."""


def _quat(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Unit quaternion of the z-y-x (yaw, pitch, roll) rotation, MuJoCo's (w, x, y, z) order."""
    cr, sr = np.cos(0.5 * roll), np.sin(0.5 * roll)
    cp, sp = np.cos(0.5 * pitch), np.sin(0.5 * pitch)
    cy, sy = np.cos(0.5 * yaw), np.sin(0.5 * yaw)
    return np.array(
        [
            cy * cp * cr + sy * sp * sr,
            cy * cp * sr - sy * sp * cr,
            cy * sp * cr + sy * cp * sr,
            sy * cp * cr - cy * sp * sr,
        ]
    )


class _Statics:
    """Residual of the static equilibrium as a function of the unknowns (see the module docstring)."""

    def __init__(self, vm, data, pressure0, hdata):
        self.vm, self.model, self.data = vm, vm.model, data
        ids = vm.ids
        self.cq, self.cd = int(ids["chassis_qpos"][0]), int(ids["chassis_dof"][0])
        self.native = vm.contact == "native"
        self.qadr = list(ids["susp_qpos"]) + (list(ids["ring_qpos"]) if self.native else [])
        dofs = list(ids["susp_dof"]) + (list(ids["ring_dof"]) if self.native else [])
        self.dofs = np.array([self.cd + 2, self.cd + 3, self.cd + 4, *dofs])
        q = data.qpos[self.cq + 3 : self.cq + 7]
        self.yaw = float(np.arctan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2)))
        self.packed = (
            pack_ids(ids), vm.hfield, hdata, pack_vehicle(vm), vm.tire.to_array(),
            np.ascontiguousarray(np.asarray(pressure0, dtype=float).reshape(1, 4)),
            np.zeros(1), np.zeros(1),
        )  # fmt: skip
        self.mode = np.zeros(N_MODE)
        self.mode[M_KIND] = MODE_OPEN_LOOP  # wheels straight ahead: zero steer command
        self.log = np.zeros((1, len(LOG_COLUMNS)))
        self.mqacc = np.zeros(self.model.nv)
        self.evaluations = 0

    def first_guess(self, pressure0) -> np.ndarray:
        """The unknowns of a car whose chassis lies parallel to the plane fitted through the road
        under its four wheels, each wheel at its design static deflection over its own road
        height (loads and pressure differences are left to Newton's method); with native contact
        each tyre ring 0.2 mm into the road (MuJoCo's soft contact pushes once it penetrates)."""
        vm, d, cq = self.vm, self.data, self.cq
        v, tp = vm.vehicle, self.packed[4]
        xy = v.corner_xy
        c, sn = np.cos(self.yaw), np.sin(self.yaw)
        x0, y0 = d.qpos[cq], d.qpos[cq + 1]
        wx, wy = x0 + c * xy[:, 0] - sn * xy[:, 1], y0 + sn * xy[:, 0] + c * xy[:, 1]
        hf, hdata = self.packed[1], self.packed[2]
        road = np.array([road_height(wx[i], wy[i], hf, hdata) for i in range(4)])
        kt = np.array([vertical_stiffness(p, tp) for p in pressure0])
        centre = road + tp[I_UNLOADED_RADIUS] - v.static_tire_load / kt  # wheel-centre heights wanted
        a, b, slope_y = np.linalg.lstsq(np.column_stack([np.ones(4), xy]), centre, rcond=None)[0]
        pitch, roll = -np.arctan(b), np.arctan(slope_y)
        z = a - vm.wheel_center_z.mean()  # chassis CoG over the fitted wheel-centre plane
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, _quat(roll, pitch, self.yaw))
        rot = rot.reshape(3, 3)
        body = np.column_stack([xy, vm.wheel_center_z])
        travel = (centre - z - body @ rot[2]) / rot[2, 2]
        u = np.array([z, roll, pitch, *travel, *(v.static_tire_load / kt if self.native else [])])
        if self.native:
            u[7:] -= 0.02
            self.seat_rings(u)
        return u

    def seat_rings(self, u: np.ndarray) -> None:
        """Move each native tyre ring (in `u`) along its slide to 0.2 mm of penetration into the
        road: a few passes of collision detection, from wherever the rings are."""
        m, d = self.model, self.data
        rings = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"contact_{c}") for c in CORNERS]
        for _ in range(4):
            self.place(u)
            mujoco.mj_kinematics(m, d)
            mujoco.mj_collision(m, d)
            depth = np.full(4, -np.inf)
            for j in range(d.ncon):
                for i, geom in enumerate(rings):
                    if geom in (d.contact.geom1[j], d.contact.geom2[j]):
                        depth[i] = max(depth[i], -d.contact.dist[j])
            # a ring above the road (no contact) goes down 10 mm, one in it up to 0.2 mm deep
            u[7:] += np.where(np.isfinite(depth), depth - 2e-4, -0.01)

    def unknowns(self) -> np.ndarray:
        d, cq = self.data, self.cq
        q = d.qpos[cq + 3 : cq + 7]
        roll = np.arctan2(2 * (q[0] * q[1] + q[2] * q[3]), 1 - 2 * (q[1] ** 2 + q[2] ** 2))
        pitch = np.arcsin(np.clip(2 * (q[0] * q[2] - q[3] * q[1]), -1.0, 1.0))
        return np.array([d.qpos[cq + 2], roll, pitch, *d.qpos[self.qadr]])

    def place(self, u: np.ndarray) -> None:
        d, cq = self.data, self.cq
        d.qpos[cq + 2] = u[0]
        d.qpos[cq + 3 : cq + 7] = _quat(u[1], u[2], self.yaw)
        d.qpos[self.qadr] = u[3:]

    def residual(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """Generalized force M·q̈ on the unknowns' degrees of freedom at rest, and max |q̈| there."""
        m, d = self.model, self.data
        self.place(u)
        d.qvel[:] = 0.0
        mujoco.mj_kinematics(m, d)
        ids, hf, hdata, vp, tp, pressure, speed_ref, steer_cmd = self.packed
        state = np.zeros(N_STATE)
        step_kernel(
            0, m.opt.timestep, d.qpos, d.qvel, d.xpos, d.xmat, d.sensordata, d.qfrc_applied,
            d.xfrc_applied, d.ctrl, ids, hf, hdata, vp, tp, pressure, speed_ref, steer_cmd, self.mode,
            state, self.log,
        )  # fmt: skip
        mujoco.mj_forward(m, d)
        mujoco.mj_mulM(m, d, self.mqacc, d.qacc)
        self.evaluations += 1
        return self.mqacc[self.dofs].copy(), float(np.abs(d.qacc[self.dofs]).max())

    def jacobian(self, u: np.ndarray, r0: np.ndarray, step: float = 1e-7) -> np.ndarray:
        jac = np.empty((r0.size, u.size))
        for j in range(u.size):
            du = u.copy()
            du[j] += step
            jac[:, j] = (self.residual(du)[0] - r0) / step
        return jac


def settle(vm, data, pressure0, hdata, *, tol: float = 1e-3, max_iter: int = 60) -> SettleInfo:
    """Put the car of `data` into static equilibrium on its road (in place) and return how it went.

    Parameters
    ----------
    vm : suvtwin.mjcf.builder.VehicleModel
    data : mujoco.MjData
        Holds the car's x, y and yaw (kept); everything else is set here (the first guess:
        :meth:`_Statics.first_guess`), velocities to zero.
    pressure0 : array_like, shape (4,)
        Each tyre's pressure at t = 0, Pa.
    hdata : numpy.ndarray
        The heightfield data, (rows, cols), as the kernel reads them.
    tol : float
        Largest generalized force left on the solved degrees of freedom, N (N m): the
        equilibrium's error (a hub of ~50 kg then starts with |q̈| ≲ 2e-5 m/s²).

    Where Newton's method cannot reach `tol` (seen once in 60 random starts: native contact on
    a class F road with 550 kg on one side), `data` is left at the best point found and the
    returned :class:`SettleInfo` says so (``converged`` False, ``residual_n``).
    """
    statics = _Statics(vm, data, pressure0, hdata)
    u = statics.first_guess(pressure0)
    r, worst = statics.residual(u)
    limit = np.full(u.size, _MAX_STEP_M)
    limit[1:3] = _MAX_STEP_RAD
    jac, fresh, iterations, fd_step, reseated = None, False, 0, 1e-7, not statics.native
    while np.abs(r).max() > tol and iterations < max_iter:
        if jac is None:
            jac, fresh = statics.jacobian(u, r, fd_step), True
        step = np.linalg.lstsq(jac, -r, rcond=None)[0]
        step *= min(1.0, float(np.min(limit / np.maximum(np.abs(step), 1e-300))))  # trust region
        norm, scale, accepted = float(np.linalg.norm(r)), 1.0, False
        for _ in range(12):  # backtrack until the residual falls
            trial = u + scale * step
            r_new, worst_new = statics.residual(trial)
            if np.linalg.norm(r_new) < norm:
                accepted = True
                break
            scale *= 0.5
        if not accepted:
            if not fresh or fd_step < 1e-5:  # an old Jacobian, or one too local where native
                jac = None  # contacts come and go: renew it (with a wider difference) and retry
                fd_step = fd_step if not fresh else 1e-5
                continue
            if not reseated:  # a native ring lifted off the road: put it back on, once
                statics.seat_rings(u)
                r, worst = statics.residual(u)
                jac, fd_step, reseated = None, 1e-7, True
                continue
            break
        # keep the Jacobian while full steps shrink the residual tenfold (chord steps)
        if not (scale == 1.0 and np.linalg.norm(r_new) < 0.1 * norm):
            jac = None
        fresh, fd_step = False, 1e-7
        u, r, worst = trial, r_new, worst_new
        iterations += 1
    statics.place(u)
    statics.residual(u)  # leave data at the solution, forces and all
    loads = np.array([statics.log[0, C_FZ + i] for i in range(4)])
    deflections = np.array([statics.log[0, C_DEFLECTION + i] for i in range(4)])
    steer_qpos = vm.ids.get("steer_qpos")
    if steer_qpos is not None:  # knuckles at their commanded (bump-steer) toe, so the servo starts still
        data.qpos[steer_qpos] = data.ctrl[vm.ids["steer_act"]]
        mujoco.mj_forward(vm.model, data)
    left = float(np.abs(r).max())
    return SettleInfo(iterations, statics.evaluations, worst, loads, deflections, left, left <= tol)


def start_rolling(vm, data, pressure0, speed0: float, settled: SettleInfo) -> np.ndarray:
    """Set the start speed and steady rolling on the settled car; return the kernel's initial state.

    The chassis gets `speed0` (m/s) along its heading; each wheel the spin of steady rolling at
    its `settled` load and deflection and `pressure0` (Pa) carrying an equal share of the drive torque that
    balances drag and rolling resistance at that speed; the kernel state the matching slip
    deflections u = σ_x·κ and speed-controller integral (module docstring).
    """
    vp, tp = pack_vehicle(vm), vm.tire.to_array()
    ids = vm.ids
    cd, cq = int(ids["chassis_dof"][0]), int(ids["chassis_qpos"][0])
    q = data.qpos[cq + 3 : cq + 7]
    yaw = float(np.arctan2(2 * (q[0] * q[3] + q[1] * q[2]), 1 - 2 * (q[2] ** 2 + q[3] ** 2)))
    state = np.zeros(N_STATE)
    data.qvel[:] = 0.0
    data.qvel[cd], data.qvel[cd + 1] = speed0 * np.cos(yaw), speed0 * np.sin(yaw)
    loads = np.maximum(settled.tyre_load_n, 0.0)
    radius = tp[I_UNLOADED_RADIUS] - np.maximum(settled.tyre_deflection_m, 0.0)  # centre to contact
    rolling = vp[V_ROLL_RES] * loads * np.tanh(speed0 / np.maximum(radius, 1e-3))
    drag = vp[V_DRAG] * speed0 * speed0
    torque = (drag + rolling.sum()) / np.sum(1.0 / radius)  # per wheel, equal on all four
    state[S_INTEGRAL] = 4.0 * torque / vp[V_KI_SPEED]
    for i in range(4):
        force = (torque - rolling[i] * radius[i]) / radius[i]
        kappa = 0.0
        if loads[i] > 0.0 and force != 0.0:
            h = 1e-5
            stiffness = tire_forces(loads[i], h, 0.0, pressure0[i], tp)[0] / h
            kappa = force / stiffness
        state[S_SLIP_U + i] = vp[V_SIGMA_X] * kappa
        re = effective_rolling_radius(loads[i], pressure0[i], tp)
        data.qvel[ids["spin_dof"][i]] = speed0 * (1.0 + kappa) / re
    mujoco.mj_forward(vm.model, data)
    return state

