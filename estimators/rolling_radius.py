r"""Radius analysis: each wheel's effective rolling radius against the other three, from wheel speeds.

Usual call::

    ra = RollingRadius(positions_m, RadiusConfig())
    rows = ra.update(t_s, wheel_speed_radps, yaw_rate_radps, lat_accel_mps2, long_accel_mps2)

An under-inflated tyre deflects more under its load, so its effective rolling radius
:math:`R_e` is smaller and its wheel turns faster than the others at the same road speed: the
principle of the wheel-speed ("indirect") TPMS (e.g. EP 0 863 028: wheel speeds calibrated after a
reset, filtered for slip, rough road and cornering, compared between wheels). On the MuJoCo SUV
(MF-Tyre 6.1's :math:`R_e = R_0 - (F_{z0}/C_z)(D\,\arctan(B F_z/F_{z0}) + F F_z/F_{z0})`, with
:math:`C_z` the pressure's vertical stiffness) a tyre 20 % below the others turns 3.4–4.3 ‰ faster.

What is estimated, per wheel i and from wheel speeds, yaw rate and the body's accelerations
only (no vehicle speed: a car's speed comes from these wheels):

- the kinematic speed ratio of the wheel centre: in a turn of yaw rate :math:`\dot\psi` at speed v
  (taken at the rear axle, whose centre has no lateral slip in the kinematic model), a wheel at
  (x_i, y_i) from the rear axle's centre (x forward, y left) moves at
  :math:`u_i = v\sqrt{(1 - \rho y_i)^2 + (\rho x_i)^2}`, :math:`\rho = \dot\psi/v`: the outer
  wheels and the fronts run further (Gillespie 1992, ch. 6, low-speed turning); v is the wheels'
  mean speed times ``nominal_radius_m`` over their mean ratio (a fixed-point step);
- its log radius :math:`\delta_i = \ln(u_i/v) - \ln\omega_i` (+ ln v, common to all wheels), and its
  **excess** over the other three, :math:`e_i = \delta_i - \frac{1}{3}\sum_{j\ne i}\delta_j`
  (dimensionless; 1e-3 = 1 ‰): v cancels, so no speed is needed beyond ρ's.

A sample counts only when every wheel speed is finite and positive, the speed is at least
``min_speed_mps`` and, where each sample's tyre loads are given (:func:`load_share`, from the
corners' accelerometers), every wheel carries at least ``min_load_share`` of its static load: a
wheel in the air does not roll on its radius (on the MuJoCo ``constant`` runs' class D blocks this
took the excess's error against MF-Tyre's R_e from 0.91 to 0.21 ‰ RMS, ``bench/radius_slip.py``);
the samples are averaged in blocks of ``block_s`` seconds, and a block is skipped where fewer than
``min_valid_share`` of its samples count (35 %: on a class D road at 110 km/h the gate keeps 35–60 %
of a block, and at half, as before the gate, a drop of pressure there went unseen by the radii for
28 s), where its mean longitudinal acceleration exceeds
``max_long_accel_mps2`` (traction or braking: the driven or braked wheels slip, each by its own
share of the force) or its RMS lateral acceleration ``max_lat_accel_mps2`` (hard cornering moves the
load across the car, and R_e depends on the load). Block means, not samples, because on a rough road
the accelerometers' samples scatter by several m/s² about a steady value: gated per sample, a class
D road's braking from 104 to 33 km/h (1.3 m/s²) let half of each block through. Where the lateral
or longitudinal accelerometer is missing (a gap, a dead sensor), the gates take the wheels'
kinematics instead: a_y = v ψ̇, a_x = dv/dt from the wheels' mean speed (a block's mean of it is
exactly its speed change over its duration); a missing yaw rate is taken as a_y/v, a few per cent
off (the accelerometer reads the body's roll, v is the wheels' speed at the nominal radius), so such
a block counts only while its mean |a_y| stays within ``max_lat_accel_no_yaw_mps2`` (0.5 m/s²: the
turn's correction of the excess is then ≤ 3 ‰ at 58 km/h, its error ≤ 0.2 ‰). A wheel-speed
sensor that reads nothing (NaN or ≤ 0) over a whole block while the other wheels turn (one at
least at ``TURNING_MPS``, 1 m/s: a stopped car's wheels rock about zero) is taken for
dead: that block and those after it are analysed over the other wheels (v from their mean, each excess
over the others read, the dead wheel's NaN), every memory starting afresh (an excess over three
wheels is another quantity than one over four); the sensor is taken back with a block where it read
on every sample the others did. Its silent samples are counted (:attr:`RollingRadius.silent_wheel_samples`).
Each wheel's estimate is the mean of its recent blocks — since the last
change, at most ``memory_blocks`` — with

.. math:: \sigma^2 = \frac{s^2}{n} + \sigma_{floor}^2, \qquad
          s^2 = \frac{\nu_0 s_0^2 + \sum_b (e_b - \bar e)^2}{\nu_0 + n - 1},

the blocks' scatter shrunk towards a prior ``prior_block_permille`` (s_0, ν_0 = ``prior_weight``
blocks; a few blocks alone give a poor variance), and σ_floor² = ``floor_permille``² +
(``roughness_share`` × the blocks' mean sample scatter)² for what their mean does not average
away: on a rough road at speed the wheels hop and their dynamic radii depart from the static one,
the same way block after block. On the MuJoCo ``warning`` runs (100 runs, 4 s blocks, each wheel)
a block's error against MF-Tyre's R_e at the static loads had an RMS of 0.17 ‰ where its samples
scattered less than 2 ‰ (classes A–C), 0.25 at 2–4 ‰, 0.50 at 4–7, 0.92 at 7–10, 2.0 at 10–20 and
3.9 beyond (class D at speed): the floor and about 0.1 of the scatter beyond it; blocks scattering
more than ``max_scatter_permille`` are skipped. A block more than ``change_z`` predictive σ from
the mean is held aside; if the next used block lies within ``change_z`` σ of it, the two start
every wheel's memory afresh (a change of pressure, the road or the load; one tyre's change moves
every wheel's excess, by a third of its own on the others, so restarting the changed wheel alone
left the others' memories averaging across it: after a 230→180 kPa drop the four excesses summed
to −1.3 ‰ instead of 0 for 20 s), else it is dropped as an outlier (a wheel hopping or spinning on a
rough stretch read a class D run's front 11 ‰ small for one block). So a drop in pressure is
followed within two blocks, with the estimate never averaging across the change. A slow leak
moves the blocks a little each time, none far enough to be a change, and the memory's mean would
trail the ramp by half its length: where a ramp through a wheel's blocks has a slope beyond
``trend_z`` σ, every wheel's estimate is the ramp's value at the newest block, with its σ there (a
ramp of 0.12 ‰/s is followed within 0.5 ‰ instead of 1.4 ‰ behind, and the fused ``slow_leak``
runs' ±2σ coverage went from 88 % to 98.5 %). The ramp is the straight line or, where it fits the
blocks better, a line that began from a flat stretch or ended in one (a two-phase regression, joined
at a block): the straight line alone carried a leak on past its end by a block's worth (0.25 ‰) and
took a block longer to take up its start. No ramp is taken while a block is held as a possible
change (a step inside a block reads as the start of a ramp for one block). The state is the last
``memory_blocks`` block means per wheel, a held block, the last block and the current block's
samples: fixed in size, so the cost per second of data does not grow.

The excess tells which tyre differs from the others, not by how much all four have lost:
a loss shared by all four leaves it unchanged (that is the vibration monitor's, :mod:`.monitor`).
Every value at a block uses that block and earlier ones only (causal). No MuJoCo here.

References: EP 0 863 028 A3 (indirect tyre pressure monitoring from calibrated wheel speeds); T. D.
Gillespie, Fundamentals of Vehicle Dynamics, SAE 1992, ch. 6; TNO MF-Tyre 6.1 equation manual
(the effective rolling radius).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit

__all__ = ["TURNING_MPS", "RadiusConfig", "RadiusUpdate", "RollingRadius", "excess_of", "load_share"]


@dataclass(frozen=True)
class RadiusConfig:
    """Settings of :class:`RollingRadius` (units in the names).

    Attributes
    ----------
    block_s : float
        Length of the blocks the samples are averaged over, s.
    min_speed_mps : float
        Slowest speed a sample counts at, m/s (the wheels' mean speed times the nominal radius).
    max_lat_accel_mps2, max_long_accel_mps2 : float
        Largest RMS lateral and |mean| longitudinal acceleration of a used block, m/s².
    max_lat_accel_no_yaw_mps2 : float
        Largest |mean| lateral acceleration of a used block whose yaw rate was guessed from it (a
        dead yaw-rate sensor: ψ̇ = a_y/v, a few per cent off, :meth:`RollingRadius._body_motion`):
        the turn's correction of the excess is ~2ρy, ρ = a_y/v², 3 ‰ at 0.5 m/s² and 58 km/h.
    min_valid_share : float
        Share of a block's samples that must count for the block to be used. On rough roads at speed
        the load gate (`min_load_share`) leaves out half a block or more; the gated blocks' error
        against MF-Tyre's R_e at the mean loads grows as fewer samples count (``bench/radius_slip.py
        --set S``, RMS over the four wheels, ‰; ``constant`` / ``warning`` / ``drop`` / ``slow_leak``
        runs, 100 each): 0.11 / 0.10 / 0.10 / 0.11 with ≥ 75 % counted, 0.29 / 0.24 / 0.26 / 0.26 with
        50–75 %, 0.48 / 0.42 / 0.30 / 0.44 with 35–50 % (18, 40, 19, 22 blocks, all class D, within
        the σ the roughness term gives them), 1.39 / 0.41 / 1.16 / 0.93 with 25–35 % (1, 4, 6, 1
        blocks), none below: hence 0.35. At 0.5 the ``drop`` runs' class D run
        at 112 km/h had no block for 28 s after the drop (settled within 12.5 kPa ≤ 15 s: 85 % of the
        runs with 0.5, 95 % with 0.35).
    memory_blocks : int
        Most blocks a wheel's estimate averages (its memory: memory_blocks × block_s seconds).
    change_z : float
        A block this many predictive σ from the current mean is held; confirmed by the next, the
        two start every wheel's memory afresh.
    prior_block_permille, prior_weight : float
        Prior of a block's scatter, ‰, and its weight in blocks.
    floor_permille : float
        σ the mean cannot go below, ‰.
    roughness_share : float
        Systematic error of a block's mean per ‰ of its samples' scatter (the road's roughness at
        the speed), added to σ over the memory's mean scatter.
    max_scatter_permille : float
        A block whose samples scatter more than this (any wheel), ‰, is skipped.
    trend_z : float or None
        A wheel's ramp through its memory's blocks (a straight line, or one that began or ended at a
        block) whose slope is this many σ from 0 (a slow leak) makes every wheel's estimate the
        ramp's value at the newest block instead of the memory's mean (None: never).
    trend_min_blocks : int
        Fewest blocks a significant slope needs.
    min_load_share : float
        Where each sample's tyre loads are given (`load_share` of :meth:`RollingRadius.update`), the
        smallest share of its static load every wheel must carry for the sample to count: a wheel
        off the ground, or nearly, does not roll on its radius. The accelerometers' estimate
        scatters about the true force by a fifth or so of the static load on rough roads; at 0.3 it
        keeps over 90 % of the samples with a wheel in the air out (on the ``constant`` runs' class D
        blocks: 0.2 left 0.25 ‰ RMS error, 0.3 0.21 ‰, 0.5 0.19 ‰ but a third of the blocks with
        under half their samples).
    """

    block_s: float = 4.0
    min_speed_mps: float = 8.0
    max_lat_accel_mps2: float = 2.0
    max_long_accel_mps2: float = 0.5
    max_lat_accel_no_yaw_mps2: float = 0.5
    min_valid_share: float = 0.35
    memory_blocks: int = 6
    change_z: float = 5.0
    prior_block_permille: float = 0.5
    prior_weight: float = 2.0
    floor_permille: float = 0.17
    roughness_share: float = 0.10
    max_scatter_permille: float = 10.0
    trend_z: float | None = 3.0
    trend_min_blocks: int = 4
    min_load_share: float = 0.3

    def __post_init__(self) -> None:
        checks = [
            ("block_s", 0.1 <= self.block_s <= 60.0, "0.1–60 s"),
            ("min_speed_mps", 0.0 < self.min_speed_mps <= 50.0, "(0, 50] m/s"),
            ("max_lat_accel_mps2", self.max_lat_accel_mps2 > 0.0, "> 0"),
            ("max_long_accel_mps2", self.max_long_accel_mps2 > 0.0, "> 0"),
            ("max_lat_accel_no_yaw_mps2", self.max_lat_accel_no_yaw_mps2 > 0.0, "> 0"),
            ("min_valid_share", 0.0 < self.min_valid_share <= 1.0, "(0, 1]"),
            ("memory_blocks", 1 <= self.memory_blocks <= 10_000, "1–10000"),
            ("change_z", self.change_z > 0.0, "> 0"),
            ("prior_block_permille", self.prior_block_permille > 0.0, "> 0"),
            ("prior_weight", self.prior_weight > 0.0, "> 0"),
            ("floor_permille", self.floor_permille >= 0.0, "≥ 0"),
            ("roughness_share", 0.0 <= self.roughness_share <= 1.0, "0–1"),
            ("max_scatter_permille", self.max_scatter_permille > 0.0, "> 0"),
            ("trend_z", self.trend_z is None or self.trend_z > 0.0, "> 0 or None"),
            ("trend_min_blocks", 3 <= self.trend_min_blocks <= 10_000, "3–10000"),
            ("min_load_share", 0.0 <= self.min_load_share < 1.0, "[0, 1)"),
        ]
        for name, ok, allowed in checks:
            if not ok:
                raise InputError(f"radius setting {name} must be {allowed}, got {getattr(self, name)!r}")


@dataclass(frozen=True)
class RadiusUpdate:
    """Rows of finished blocks (K): `t_s` (K,) the block's last sample, s; `excess`, `sigma` (K, C)
    each wheel's log-radius excess over the other wheels read (:attr:`RollingRadius.alive`) and its σ
    (dimensionless, 1e-3 = 1 ‰; NaN before a first used block and for a wheel not read); `blocks`
    (K, C) the blocks the estimate averages; `used` (K,) whether the block was used; `changes` (K, C)
    whether the block confirmed a change of the wheel (with the block held before it; every wheel's
    memory then starts afresh); `held` (K, C) a block held aside as a possible change minus the
    wheel's mean (0: none), as a change it would move the excess by that much; `trend` (K, C) the
    excess's slope, 1/s, where the estimate follows a significant ramp (0 elsewhere)."""

    t_s: np.ndarray
    excess: np.ndarray
    sigma: np.ndarray
    blocks: np.ndarray
    used: np.ndarray
    changes: np.ndarray
    held: np.ndarray
    trend: np.ndarray

    @staticmethod
    def concatenate(parts: list[RadiusUpdate], n_c: int) -> RadiusUpdate:
        """Rows of several updates, in order (`n_c` wheels, for an empty list)."""
        if not parts:
            e = np.empty((0, n_c))
            return RadiusUpdate(np.empty(0), e, e.copy(), np.empty((0, n_c), int), np.empty(0, bool),
                                np.empty((0, n_c), bool), e.copy(), e.copy())  # fmt: skip
        return RadiusUpdate(**{
            name: np.concatenate([getattr(p, name) for p in parts], axis=0)
            for name in RadiusUpdate.__dataclass_fields__
        })  # fmt: skip


def load_share(
    accel_sprung_mps2, accel_unsprung_mps2, sprung_mass_kg, unsprung_mass_kg, static_load_n
) -> np.ndarray:
    r"""Each sample's tyre load over its static load from the corner's two vertical accelerations:
    :math:`(W + m_s \ddot z_s + m_{us} \ddot z_{us}) / W` — the quarter car's two equations of motion
    summed (paper 000 eq. 1: :math:`m_s \ddot z_s + m_{us} \ddot z_{us} = k_t (z_r - z_{us})`, the
    tyre's force beyond the static load W). Accelerations (n, C) m/s² about the static state, masses
    (C,) kg, static loads (C,) N; NaN where an acceleration is. On MuJoCo class D runs at 100 km/h
    the estimate's RMS error against the simulator's tyre force is 0.3–0.6 of that force's own
    standard deviation (the corners' coupling through the body, the tyre's damping, the sensors'
    noise), and it reads under 30 % of the static load in over 90 % of the samples with the wheel in
    the air (`tests/test_rolling_radius.py`)."""
    w = np.asarray(static_load_n, dtype=float)
    return (w + np.asarray(sprung_mass_kg, dtype=float) * np.asarray(accel_sprung_mps2, dtype=float)
            + np.asarray(unsprung_mass_kg, dtype=float) * np.asarray(accel_unsprung_mps2, dtype=float)) / w


TURNING_MPS = 1.0
"""Slowest wheel speed, at the nominal radius (m/s), at which the car counts as moving for the
wheel-speed sensors' check: a wheel that reads nothing while another turns at least this fast is
silent (a gap or a dead sensor); below it the wheels of a stopped car rock about zero."""


def excess_of(log_radius: npt.ArrayLike) -> np.ndarray:
    r"""Each wheel's excess over the others' mean along the last axis of `log_radius` (..., C):
    :math:`e_i = \delta_i - \frac{1}{C-1}\sum_{j\ne i}\delta_j`."""
    d = np.asarray(log_radius, dtype=float)
    n_c = d.shape[-1]
    total = d.sum(axis=-1, keepdims=True)
    return d - (total - d) / (n_c - 1)


@dataclass
class _State:
    part: np.ndarray  # (k, C + 5) the current block's samples so far: ω, ψ̇, grounded, a_x, a_y, ψ̇ guessed
    pending: np.ndarray  # (C,) a block held as a possible change (NaN: none)
    pending_sd: np.ndarray  # (C,) its samples' scatter
    last: np.ndarray  # (C,) the last used block's means (NaN: none yet)
    last_sd: np.ndarray  # (C,) their samples' scatter
    memory: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))  # (M, C) ring of block means
    scatter: np.ndarray = field(default_factory=lambda: np.empty((0, 0)))  # (M, C) their samples' sd
    filled: np.ndarray = field(default_factory=lambda: np.empty(0, int))  # (C,) blocks in memory
    head: np.ndarray = field(default_factory=lambda: np.empty(0, int))  # (C,) next slot
    last_t: float = math.nan
    last_speed: float = math.nan  # the wheels' speed at the last sample, m/s
    substituted: np.ndarray = field(default_factory=lambda: np.zeros(3, int))  # samples: a_y, a_x, ψ̇
    silent: np.ndarray = field(default_factory=lambda: np.zeros(0, int))  # (C,) samples a wheel read nothing
    alive: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))  # (C,) the wheels read now


class RollingRadius:
    """Streaming radius analysis of C wheels (see the module docstring).

    Parameters
    ----------
    positions_m : (C, 2) array
        Each wheel centre's (x, y) from the rear axle's centre, m (x forward, y left).
    dt : float
        Sampling interval of the stream, s.
    nominal_radius_m : float
        A wheel's rolling radius, m: only for the speed in ρ = ψ̇/v (1 % off there is 1 % of a
        correction of a few ‰).
    config : RadiusConfig, optional
    """

    def __init__(self, positions_m: npt.ArrayLike, dt: float, nominal_radius_m: float,
                 config: RadiusConfig | None = None) -> None:  # fmt: skip
        pos = np.asarray(positions_m, dtype=float)
        if pos.ndim != 2 or pos.shape[1] != 2 or pos.shape[0] < 2 or not np.all(np.isfinite(pos)):
            raise InputError(f"positions_m must be finite (C, 2) with C ≥ 2, got shape {pos.shape}")
        if not (np.isfinite(dt) and dt > 0):
            raise InputError(f"dt must be > 0 s, got {dt!r}")
        if not (np.isfinite(nominal_radius_m) and 0.1 <= nominal_radius_m <= 1.0):
            raise InputError(f"nominal_radius_m must be 0.1–1 m, got {nominal_radius_m!r}")
        self.config = config or RadiusConfig()
        self.positions = pos
        self.dt = float(dt)
        self.radius = float(nominal_radius_m)
        self.block = max(int(round(self.config.block_s / self.dt)), 1)
        self.reset()

    def reset(self) -> None:
        """Forget everything."""
        n_c = self.positions.shape[0]
        self._s = _State(
            part=np.empty((0, n_c + 5)),
            pending=np.full(n_c, np.nan),
            pending_sd=np.full(n_c, np.nan),
            last=np.full(n_c, np.nan),
            last_sd=np.full(n_c, np.nan),
            memory=np.zeros((self.config.memory_blocks, n_c)),
            scatter=np.zeros((self.config.memory_blocks, n_c)),
            filled=np.zeros(n_c, dtype=int),
            head=np.zeros(n_c, dtype=int),
            silent=np.zeros(n_c, dtype=int),
            alive=np.ones(n_c, dtype=bool),
        )

    @property
    def state_nbytes(self) -> int:
        """Bytes of state carried between updates (bounded)."""
        s = self._s
        arrays = (s.part, s.pending, s.pending_sd, s.last, s.last_sd, s.memory, s.scatter, s.filled, s.head,
                  s.silent, s.alive)
        return int(sum(a.nbytes for a in arrays))

    def sample_excess(self, wheel_speed_radps, yaw_rate_radps, alive=None):
        """Per sample: each wheel's log-radius excess (n, C) over the wheels `alive` (C,) bool (default
        the analysis's current ones, :attr:`alive`; 0 for the others) and whether the sample counts (n,)."""
        w = np.ascontiguousarray(wheel_speed_radps, dtype=float)
        psi = np.ascontiguousarray(yaw_rate_radps, dtype=float)
        alive = self._s.alive if alive is None else np.asarray(alive, dtype=np.bool_)
        e = np.zeros(w.shape)
        ok = np.zeros(w.shape[0], dtype=np.bool_)
        x, y = (np.ascontiguousarray(self.positions[:, k]) for k in (0, 1))
        _sample_excess(w, psi, x, y, self.radius, self.config.min_speed_mps, alive, e, ok)
        return e, ok

    @property
    def alive(self) -> np.ndarray:
        """The wheels (C,) bool whose speeds the analysis reads now: all but those whose sensor read
        nothing over a whole block while the others turned (and not yet read again over a whole one)."""
        return self._s.alive.copy()

    def update(
        self, t_s, wheel_speed_radps, yaw_rate_radps, lat_accel_mps2, long_accel_mps2, load_share=None
    ) -> RadiusUpdate:
        """Consume samples in time order (`t_s` (n,) s, continuing the stream; `wheel_speed_radps`
        (n, C) rad/s; the others (n,), rad/s and m/s², NaN where missing: a missing acceleration is
        taken from the kinematics, :meth:`_body_motion`); one row per finished block.
        `load_share` (n, C), optional: each wheel's tyre load over its static load per sample
        (:func:`load_share`); a sample where a wheel's is below ``min_load_share`` does not count. A
        NaN share (that corner's accelerometer missing) is no evidence of a wheel off the ground: the
        sample counts on its wheel speeds (one dead accelerometer would otherwise stop all four
        wheels' analysis)."""
        t = np.asarray(t_s, dtype=float).reshape(-1)
        n_c = self.positions.shape[0]
        w = np.asarray(wheel_speed_radps, dtype=float).reshape(t.size, -1) if t.size else np.empty((0, n_c))
        others = [np.asarray(a, dtype=float).reshape(-1)
                  for a in (yaw_rate_radps, lat_accel_mps2, long_accel_mps2)]  # fmt: skip
        if w.shape != (t.size, n_c) or any(a.shape != t.shape for a in others):
            raise InputError(
                f"update needs t_s, yaw rate and accelerations of shape (n,) and wheel speeds (n, {n_c})")
        if load_share is not None:
            load_share = np.asarray(load_share, dtype=float)
            if load_share.shape != (t.size, n_c):
                raise InputError(
                    f"load_share must have shape (n, {n_c}) like the wheel speeds, got {load_share.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise InputError("t_s must be finite and strictly increasing")
        s = self._s
        if t.size and np.isfinite(s.last_t) and t[0] <= s.last_t:
            raise InputError(f"t_s must continue the stream: got {t[0]} s after {s.last_t} s")
        others[0], others[1], others[2], guessed = self._body_motion(t, w, *others)
        reads = np.isfinite(w) & (w > 0.0)
        if not reads.all():  # a wheel reading nothing (NaN or ≤ 0) while another turns: counted
            s.silent += np.sum(~reads & self._turning(w, reads)[:, None], axis=0)
        grounded = np.ones(t.size, dtype=bool)
        if load_share is not None:  # a wheel off the ground does not roll on its radius
            for c in range(n_c):  # wheel by wheel: numpy's any over the rows' four is 5 times slower
                grounded &= ~(load_share[:, c] < self.config.min_load_share)  # NaN < x is False
        # the raw inputs: the excesses are taken per block, over the wheels read then (:meth:`_finish_block`)
        samples = np.column_stack([w, others[0], grounded, others[2], others[1], guessed])
        rows = []
        i = 0
        while i < t.size:
            take = min(self.block - s.part.shape[0], t.size - i)
            s.part = np.concatenate([s.part, samples[i : i + take]])
            i += take
            if s.part.shape[0] == self.block:  # statistics of whole blocks: chunking changes no bit
                rows.append(self._finish_block(float(t[i - 1]), s.part))
                s.part = s.part[:0]
        if t.size:
            s.last_t = float(t[-1])
        return RadiusUpdate.concatenate(rows, n_c)

    def _body_motion(self, t, w, yaw, lat, lon) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The yaw rate (rad/s) and the lateral and longitudinal accelerations (m/s²) the analysis
        uses, (n,) each, and where the yaw rate was guessed (n,) bool: the sensors', and where one
        is missing (a gap, a dead sensor) the wheels' kinematics instead: a_y = v ψ̇ (steady
        turning; from the yaw-rate sensor), a_x = dv/dt (the wheels' mean speed times
        ``nominal_radius_m``, differenced sample to sample: a block's mean is its speed change over
        its duration, whatever the noise between) and ψ̇ = a_y/v (the lateral accelerometer
        reads the body's roll too, and v here is a few per cent off: a block with a guessed yaw
        rate counts only while its mean |a_y| stays within ``max_lat_accel_no_yaw_mps2``). Counted
        in :attr:`substituted_samples`."""
        s = self._s
        yaw_gap, lat_gap, lon_gap = ~np.isfinite(yaw), ~np.isfinite(lat), ~np.isfinite(lon)
        guessed = np.zeros(t.size, dtype=bool)
        if not (yaw_gap.any() or lat_gap.any() or lon_gap.any()):  # every sensor there: as they are
            if t.size:
                s.last_speed = float(self._wheel_speed(w[-1:])[0])
            return yaw, lat, lon, guessed
        speed = self._wheel_speed(w)
        if lat_gap.any():
            new_lat = np.where(lat_gap, speed * yaw, lat)
            s.substituted[0] += int(np.sum(lat_gap & np.isfinite(new_lat)))
        else:
            new_lat = lat
        if yaw_gap.any():
            moving = speed >= self.config.min_speed_mps  # below it no sample counts anyway
            yaw = np.where(yaw_gap & moving, lat / np.where(moving, speed, 1.0), yaw)
            guessed = yaw_gap & np.isfinite(yaw)
            s.substituted[2] += int(guessed.sum())
        if lon_gap.any():
            before, t_before = np.r_[s.last_speed, speed[:-1]], np.r_[s.last_t, t[:-1]]
            lon = np.where(lon_gap, (speed - before) / (t - t_before), lon)
            s.substituted[1] += int(np.sum(lon_gap & np.isfinite(lon)))
        if t.size:
            s.last_speed = float(speed[-1])
        return yaw, new_lat, lon, guessed

    def _wheel_speed(self, w: np.ndarray) -> np.ndarray:
        """The wheels' mean speed times ``nominal_radius_m`` per sample (n,), m/s, over the wheels
        with a finite positive speed (NaN where none)."""
        finite = np.isfinite(w) & (w > 0)
        count = finite.sum(axis=1)
        speed = self.radius * np.where(finite, w, 0.0).sum(axis=1) / np.maximum(count, 1)
        return np.where(count > 0, speed, np.nan)

    @property
    def silent_wheel_samples(self) -> np.ndarray:
        """Per wheel (C,), the samples since the last reset where its speed was missing (NaN) or not
        positive while another wheel's was: a gap or a dead wheel-speed sensor. Such a sample does not
        count; over a whole block the wheel is left out and the others analysed without it (:attr:`alive`)."""
        return self._s.silent.copy()

    @property
    def substituted_samples(self) -> dict:
        """Samples whose lateral / longitudinal acceleration or yaw rate came from the kinematics
        (:meth:`_body_motion`) since the last reset."""
        sub = self._s.substituted
        return {"lat_accel": int(sub[0]), "long_accel": int(sub[1]), "yaw_rate": int(sub[2])}

    def _finish_block(self, t_end: float, block: np.ndarray) -> RadiusUpdate:
        cfg = self.config
        s = self._s
        n_c = self.positions.shape[0]
        w, psi, grounded = block[:, :n_c], block[:, n_c], block[:, n_c + 1] > 0
        ax, ay, guessed = block[:, n_c + 2], block[:, n_c + 3], bool(np.any(block[:, n_c + 4] > 0))
        self._check_wheels(w)
        e, ok = self.sample_excess(w, psi)
        ok &= grounded
        e[~ok] = 0.0
        live = s.alive
        counted = int(ok.sum())
        total, total_sq = _column_sums(e)
        x = total / max(counted, 1)
        sd = np.sqrt(np.maximum(total_sq / max(counted, 1) - x**2, 0.0))
        ax, ay = ax[np.isfinite(ax)], ay[np.isfinite(ay)]
        used = (
            counted >= cfg.min_valid_share * self.block and ax.size > 0 and ay.size > 0
            and float(sd[live].max()) <= cfg.max_scatter_permille * 1e-3
            and abs(float(ax.mean())) <= cfg.max_long_accel_mps2
            and math.sqrt(float(np.mean(ay**2))) <= cfg.max_lat_accel_mps2
            and (not guessed or abs(float(ay.mean())) <= cfg.max_lat_accel_no_yaw_mps2)
        )  # fmt: skip
        changed = np.zeros(n_c, dtype=bool)
        if used:
            # tested against the memory without its newest block: a block the change fell within
            # (partly before, partly after) would otherwise widen the prediction it is tested against
            mean, var, n, rough = self._moments(skip_newest=True)
            model2 = (cfg.floor_permille * 1e-3) ** 2 + (cfg.roughness_share * np.maximum(rough, sd)) ** 2
            pred = np.sqrt(var * (1.0 + 1.0 / np.maximum(n, 1)) + model2)
            out = live & (n > 0) & (np.abs(x - mean) > cfg.change_z * pred)
            # a second block beside the one held: a change (both start the memory); else held
            changed = out & (np.abs(x - s.pending) <= cfg.change_z * np.sqrt(2.0 * var + model2))
            if changed.any():
                # one wheel's change moves every wheel's excess (the others' mean holds it): every
                # memory starts afresh from the two blocks since
                s.filled[:] = 0
                for c in np.flatnonzero(live):
                    if np.isfinite(s.last[c]):
                        self._add(c, s.last[c], s.last_sd[c])
                    self._add(c, x[c], sd[c])
                s.pending = np.full(n_c, np.nan)
                s.pending_sd = np.full(n_c, np.nan)
            else:
                for c in np.flatnonzero(live & ~out):
                    self._add(c, x[c], sd[c])
                s.pending = np.where(out, x, np.nan)
                s.pending_sd = np.where(out, sd, np.nan)
            s.last, s.last_sd = x.copy(), sd.copy()
        mean, var, n, rough = self._moments()
        model2 = (cfg.floor_permille * 1e-3) ** 2 + (cfg.roughness_share * rough) ** 2
        held = np.where(np.isfinite(s.pending) & (n > 0), s.pending - mean, 0.0)
        value, spread = mean, var / np.maximum(n, 1)
        slope = np.zeros(n_c)
        if cfg.trend_z is not None and not np.isfinite(s.pending).any():  # a step pending: no ramp
            level, level_var, rate, significant = self._trend()
            if significant.any():  # one wheel's ramp moves every excess: all extrapolated, or none
                fit = n >= 3
                value = np.where(fit, level, mean)
                spread = np.where(fit, level_var, spread)
                slope = np.where(fit, rate / cfg.block_s, 0.0)
        sigma = np.where(n > 0, np.sqrt(spread + model2), np.nan)
        return RadiusUpdate(
            t_s=np.array([t_end]), excess=np.where(n > 0, value, np.nan)[None], sigma=sigma[None],
            blocks=n[None].copy(), used=np.array([used]), changes=changed[None], held=held[None],
            trend=slope[None],
        )  # fmt: skip

    def _turning(self, w: np.ndarray, reads: np.ndarray) -> np.ndarray:
        """Per sample (n,), whether some wheel turns: reads (`reads`, (n, C)) at least
        :data:`TURNING_MPS` at the nominal radius. Below it a stopped car's wheels rock about zero
        (the brakes' hold, the suspension settling): a wheel reading 0 or less then is not silent."""
        return np.any(np.where(reads, w, 0.0) >= TURNING_MPS / self.radius, axis=1)

    def _check_wheels(self, w: np.ndarray) -> None:
        """Which wheels the block `w` (n, C) of wheel speeds is analysed over: a wheel read now that
        read nothing (NaN or ≤ 0) over the whole block while the others turned (:meth:`_turning`, on at least
        ``min_valid_share`` of its samples) is left out, and one left out that read on every sample
        where another turned is taken back; at least two wheels stay. Where the set changes, every
        wheel's memory starts afresh (an excess over other wheels is another quantity)."""
        s = self._s
        if s.alive.all() and _all_read(w):  # every wheel read throughout: nothing to change
            return
        reads = np.isfinite(w) & (w > 0.0)
        turning = self._turning(w, reads)
        if turning.sum() < self.config.min_valid_share * self.block:
            return
        alive = s.alive.copy()
        alive[alive & ~reads[turning].any(axis=0)] = False
        alive[~s.alive & reads[turning].all(axis=0)] = True
        if alive.sum() < 2 or np.array_equal(alive, s.alive):
            return
        n_c = alive.size
        s.alive = alive
        s.filled[:] = 0
        s.head[:] = 0
        s.pending, s.pending_sd = np.full(n_c, np.nan), np.full(n_c, np.nan)
        s.last, s.last_sd = np.full(n_c, np.nan), np.full(n_c, np.nan)

    def _add(self, c: int, value: float, scatter: float) -> None:
        """Put one block's mean and its samples' scatter into wheel `c`'s memory."""
        s = self._s
        s.memory[s.head[c], c] = value
        s.scatter[s.head[c], c] = scatter
        s.head[c] = (s.head[c] + 1) % self.config.memory_blocks
        s.filled[c] = min(s.filled[c] + 1, self.config.memory_blocks)

    def _trend(self):
        r"""Each wheel's ramp through its memory's block means against their order (one per used block,
        the newest at age 0): its value at the newest block and the variance of that value, the current
        slope per block (> 0: rising) and whether the memory holds a ramp.

        The shapes: the straight line (:math:`g = a`, the age), a ramp that ended k blocks ago and is
        flat since (:math:`g = \max(a - k, 0)`, at least three blocks on the ramp) and one that began
        k blocks ago from a flat stretch (:math:`g = \min(a, k)`, at least ``trend_min_blocks`` blocks
        on it), each fitted as :math:`x = \alpha + \beta g` by least squares (a two-phase regression
        joined at a block, Hinkley 1971). A shape counts where its slope is significant,
        :math:`|\beta| > z\,\sigma_\beta` with n ≥ ``trend_min_blocks``; of those, the one with the
        least residual sum of squares over the wheels is taken, the same for every wheel (one tyre's
        ramp moves every excess, and they start and end together). Residual variance shrunk towards the
        prior as the mean's (n − 2 degrees of freedom): :math:`\sigma_\beta^2 = s_r^2/S_{gg}`, the
        value's :math:`s_r^2(1/n + \bar g^2/S_{gg})`.

        Reference: D. V. Hinkley, "Inference in two-phase regression", JASA 66(336), 736–743, 1971."""
        cfg = self.config
        m = cfg.memory_blocks
        n = self._s.filled
        age, mask = self._ages()
        wheels = n >= cfg.trend_min_blocks
        first = cfg.trend_min_blocks - 1  # a ramp that began: at least trend_min_blocks blocks on it
        ended, began = np.arange(1, m - 2), np.arange(first, m - 1)
        # every shape at once (S, M, C): the line, the ramps that ended k blocks ago, those that began
        g = np.concatenate([age[None], np.maximum(age[None] - ended[:, None, None], 0.0),
                            np.minimum(age[None], began[:, None, None])])  # fmt: skip
        now = np.concatenate([[1.0], np.zeros(ended.size), np.ones(began.size)])
        enough = np.concatenate([(n >= 3)[None], n[None] - 1 - ended[:, None] >= 2,
                                 n[None] - 1 - began[:, None] >= 1])  # fmt: skip
        alpha, alpha_var, beta, sigma_beta, ok, rss = self._fit(g, mask, n)
        ok &= enough
        sig = ok & wheels & (np.abs(beta) > cfg.trend_z * sigma_beta)
        candidate = sig.any(axis=1) & ok[:, wheels].all(axis=1)
        if not candidate.any():
            return np.zeros(n.size), np.zeros(n.size), np.zeros(n.size), np.zeros(n.size, dtype=bool)
        # the least residual sum of squares over the wheels (the first such shape on a tie)
        j = int(np.argmin(np.where(candidate, rss[:, wheels].sum(axis=1), np.inf)))
        return alpha[j], alpha_var[j], -beta[j] * now[j], sig[j]

    def _fit(self, g: np.ndarray, mask: np.ndarray, n: np.ndarray):
        """Least squares x = α + β g of each wheel's memory on the regressor `g` (…, M, C) over `mask`:
        α (the value where g = 0, the newest block), its variance, β, σ_β, whether it could be fitted
        (n ≥ 3, g not constant) and the residual sum of squares (:meth:`_trend`), each (…, C)."""
        cfg = self.config
        shape = g.shape[:-2] + (g.shape[-1],)
        g3 = np.ascontiguousarray(g.reshape((-1,) + g.shape[-2:]), dtype=float)
        out = np.empty((5, g3.shape[0], g3.shape[2]))
        ok = np.empty((g3.shape[0], g3.shape[2]), dtype=np.bool_)
        _least_squares(g3, np.ascontiguousarray(mask), self._s.memory, n.astype(np.int64), cfg.prior_weight,
                       cfg.prior_block_permille * 1e-3, out, ok)  # fmt: skip
        alpha, alpha_var, beta, sigma_beta, rss = (a.reshape(shape) for a in out)
        return alpha, alpha_var, beta, sigma_beta, ok.reshape(shape), rss

    def _ages(self) -> tuple[np.ndarray, np.ndarray]:
        """Each memory slot's age in blocks (M, C; the newest 0) and whether it holds one of the
        wheel's blocks: slot j of the ring is (head − 1 − j) mod M blocks old."""
        s = self._s
        m = self.config.memory_blocks
        age = ((s.head[None, :] - 1 - np.arange(m)[:, None]) % m).astype(float)
        return age, age < s.filled[None, :]

    def _moments(self, skip_newest: bool = False):
        """Each wheel's mean over its memory, the blocks' shrunk variance s², the count n and the
        blocks' mean sample scatter (`skip_newest`: without the newest block where it holds two or
        more)."""
        cfg = self.config
        s = self._s
        n_c = s.memory.shape[1]
        mean, var, rough = np.empty(n_c), np.empty(n_c), np.empty(n_c)
        n = np.empty(n_c, dtype=s.filled.dtype)
        _memory_moments(s.memory, s.scatter, s.head.astype(np.int64), s.filled.astype(np.int64), skip_newest,
                        cfg.prior_weight, cfg.prior_block_permille * 1e-3, mean, var, n, rough)  # fmt: skip
        return mean, var, n, rough


@cached_njit
def _memory_moments(memory, scatter, head, filled, skip_newest, prior_weight, s0, mean, var, n_out, rough):
    """:meth:`RollingRadius._moments` of the ring `memory` / `scatter` (M, C), slot j holding the
    block (head − 1 − j) mod M old where that age is below `filled`; the newest left out with
    `skip_newest` where a wheel holds two or more. Sums over the slots in order (numpy's over axis 0)."""
    m, n_c = memory.shape
    for c in range(n_c):
        n = filled[c]
        skip = skip_newest and n >= 2
        count = n - 1 if skip else n
        total = 0.0
        scat = 0.0
        for j in range(m):
            age = (head[c] - 1 - j) % m
            if age < n and not (skip and age == 0):
                total += memory[j, c]
                scat += scatter[j, c]
        mu = total / max(count, 1)
        ss = 0.0
        for j in range(m):
            age = (head[c] - 1 - j) % m
            if age < n and not (skip and age == 0):
                ss += (memory[j, c] - mu) ** 2
        mean[c] = mu
        var[c] = (prior_weight * s0**2 + ss) / (prior_weight + max(count - 1, 0))
        n_out[c] = count
        rough[c] = scat / max(count, 1)


@cached_njit
def _least_squares(g, mask, memory, n, prior_weight, s0, out, ok):
    """:meth:`RollingRadius._fit` for regressors `g` (S, M, C) over `mask` (M, C): into `out` (5, S, C)
    α, its variance, β, σ_β and the residual sum of squares, and `ok` (S, C). Sums over the slots in
    order."""
    n_s, m, n_c = g.shape
    for k in range(n_s):
        for c in range(n_c):
            count = max(n[c], 1)
            g_sum = 0.0
            x_sum = 0.0
            for j in range(m):
                if mask[j, c]:
                    g_sum += g[k, j, c]
                    x_sum += memory[j, c]
            g_bar = g_sum / count
            x_bar = x_sum / count
            s_gg = 0.0
            s_gx = 0.0
            for j in range(m):
                if mask[j, c]:
                    dg = g[k, j, c] - g_bar
                    s_gg += dg * dg
                    s_gx += dg * (memory[j, c] - x_bar)
            good = n[c] >= 3 and s_gg > 1e-12
            s_gg_safe = s_gg if good else 1.0
            beta = s_gx / s_gg_safe if good else 0.0
            rss = 0.0
            for j in range(m):
                if mask[j, c]:
                    r = memory[j, c] - x_bar - beta * (g[k, j, c] - g_bar)
                    rss += r * r
            s_r2 = (prior_weight * s0**2 + rss) / (prior_weight + max(n[c] - 2, 0))
            out[0, k, c] = x_bar - beta * g_bar
            out[1, k, c] = s_r2 * (1.0 / count + g_bar**2 / s_gg_safe)
            out[2, k, c] = beta
            out[3, k, c] = np.sqrt(s_r2 / s_gg_safe)
            out[4, k, c] = rss
            ok[k, c] = good


@cached_njit
def _sample_excess(w, psi, x, y, radius, min_speed, alive, out_e, out_ok):
    """Each sample's log-radius excess per wheel (the module docstring's kinematics, δ_i = ln(u_i/v) −
    ln ω_i, e_i = δ_i − mean of the other wheels') over the wheels `alive` (C,) bool into `out_e`
    (n, C), 0 where the sample does not count and for the other wheels, and whether it counts into
    `out_ok` (n,): every alive wheel's ω finite and positive, ψ̇ finite, v ≥ `min_speed`. A compiled
    loop: numpy's reductions over four wheels cost about ten times more."""
    n, n_c = w.shape
    kin = np.empty(n_c)
    m = 0
    for c in range(n_c):
        m += 1 if alive[c] else 0
    for k in range(n):
        good = np.isfinite(psi[k]) and m >= 2
        total = 0.0
        for c in range(n_c):
            if alive[c]:
                good = good and np.isfinite(w[k, c]) and w[k, c] > 0.0
                total += w[k, c]
        if not good:
            continue
        rim = total / m * radius
        v = rim
        for _ in range(2):  # v at the rear axle: the mean speed over the mean kinematic ratio
            rho = psi[k] / v
            mean_kin = 0.0
            for c in range(n_c):
                a = 1.0 - rho * y[c]
                b = rho * x[c]
                kin[c] = math.sqrt(a * a + b * b)
                if alive[c]:
                    mean_kin += kin[c]
            v = rim / (mean_kin / m)
        if v < min_speed:
            continue
        out_ok[k] = True
        delta_sum = 0.0
        for c in range(n_c):
            if alive[c]:
                kin[c] = math.log(kin[c] / w[k, c])
                delta_sum += kin[c]
        for c in range(n_c):
            if alive[c]:
                out_e[k, c] = kin[c] - (delta_sum - kin[c]) / (m - 1)


@cached_njit
def _column_sums(e):
    """Each column's sum and sum of squares of `e` (n, C), the rows added in order: what numpy's
    ``e.sum(axis=0)`` and ``(e**2).sum(axis=0)`` give, bit for bit, without their passes over the block
    in narrow rows (10 times the time)."""
    total, total_sq = np.zeros(e.shape[1]), np.zeros(e.shape[1])
    for k in range(e.shape[0]):
        for c in range(e.shape[1]):
            total[c] += e[k, c]
            total_sq[c] += e[k, c] * e[k, c]
    return total, total_sq


@cached_njit
def _all_read(w):
    """Whether every wheel speed in `w` (n, C) is finite and positive (:meth:`RollingRadius._check_wheels`;
    numpy's test takes a pass per operation)."""
    for k in range(w.shape[0]):
        for c in range(w.shape[1]):
            if not (np.isfinite(w[k, c]) and w[k, c] > 0.0):
                return False
    return True
