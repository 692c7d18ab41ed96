"""Vehicle parameters: the Segment-D SUV of paper 000 from its documented parameter file.

Usual call: ``vehicle = load_vehicle()`` (or ``load_vehicle(overrides={"chassis": {"mass": 1900}})``).

``mjcf/suv/parameters.toml`` holds every number with its unit, source and, where
meaningful, bounds; the tyre's MF-Tyre coefficients are in the ``.tir`` file it
names. This module reads it into frozen dataclasses (SI units) and derives what the
builder and the tests need: corner positions, static loads, sprung mass per corner
(Brancati & Tufano 2022, eq. 2).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, fields, replace
from importlib import resources
from pathlib import Path

import numpy as np

from suvtwin.errors import InputError
from suvtwin.tire_stiffness import tire_file_of

__all__ = [
    "CORNERS",
    "GRAVITY",
    "PARAMETER_FILE",
    "Chassis",
    "Driver",
    "Steering",
    "Suspension",
    "TireExtras",
    "VehicleParams",
    "Wheel",
    "load_vehicle",
    "parameter_table",
]

CORNERS: tuple[str, ...] = ("fl", "fr", "rl", "rr")
"""Corner order of every per-corner array: front-left, front-right, rear-left, rear-right."""

GRAVITY = 9.81
"""Gravitational acceleration, m/s² (the model's <option gravity>)."""

PARAMETER_FILE = Path(str(resources.files("suvtwin.mjcf") / "suv" / "parameters.toml"))


@dataclass(frozen=True)
class Chassis:
    mass: float
    a1: float
    a2: float
    track_front: float
    track_rear: float
    cog_height: float
    inertia_yaw_total: float
    inertia_roll: float
    inertia_pitch: float
    frontal_area: float
    drag_coefficient: float
    air_density: float


@dataclass(frozen=True)
class Wheel:
    unsprung_mass_front: float
    unsprung_mass_rear: float
    rotating_fraction: float
    spin_inertia: float
    width: float


@dataclass(frozen=True)
class Suspension:
    spring_rate_front: float
    spring_rate_rear: float
    spring_progression: float
    bump_stop_clearance: float
    bump_stop_linear: float
    bump_stop_quadratic: float
    rebound_stop_clearance: float
    rebound_stop_linear: float
    rebound_stop_quadratic: float
    travel_limit: float
    damper_compression_low: float
    damper_compression_high: float
    damper_rebound_low: float
    damper_rebound_high: float
    damper_knee_velocity: float
    anti_roll_front: float
    anti_roll_rear: float


@dataclass(frozen=True)
class Steering:
    max_angle: float
    servo_stiffness: float
    servo_damping: float
    compliance_steer_front: float
    bump_steer_front: float
    compliance_steer_rear: float


@dataclass(frozen=True)
class TireExtras:
    """Tire quantities of the vehicle model beside the MF-Tyre coefficients (:mod:`suvtwin.mjcf.tire`)."""

    relaxation_length_longitudinal: float
    relaxation_length_lateral: float
    rolling_resistance: float
    envelope_half_length: float
    envelope_points: float
    pressure_min: float
    pressure_max: float


@dataclass(frozen=True)
class Driver:
    speed_gain: float
    speed_integral_gain: float
    max_drive_torque: float
    max_brake_torque: float
    preview_time: float
    preview_min: float
    path_understeer: float


_SECTIONS = {
    "chassis": Chassis,
    "wheel": Wheel,
    "suspension": Suspension,
    "steering": Steering,
    "tire": TireExtras,
    "driver": Driver,
}


@dataclass(frozen=True)
class VehicleParams:
    """All parameters of the SUV, SI units. Sections mirror ``parameters.toml``."""

    chassis: Chassis
    wheel: Wheel
    suspension: Suspension
    steering: Steering
    tire: TireExtras
    driver: Driver
    tire_file: Path
    """The tyre's MF-Tyre property file (``.tir``) that the parameter file names in ``[tire.file]``."""

    @property
    def wheelbase(self) -> float:
        """a1 + a2, m."""
        return self.chassis.a1 + self.chassis.a2

    @property
    def unsprung_mass(self) -> np.ndarray:
        """Unsprung mass per corner (fl, fr, rl, rr), kg."""
        w = self.wheel
        return np.array([w.unsprung_mass_front] * 2 + [w.unsprung_mass_rear] * 2)

    @property
    def total_mass(self) -> float:
        """Chassis plus four corners, kg (no other masses)."""
        return self.chassis.mass + float(self.unsprung_mass.sum())

    @property
    def corner_xy(self) -> np.ndarray:
        """Wheel-centre (x, y) per corner relative to the chassis CoG, m, shape (4, 2); x forward, y left."""
        c = self.chassis
        return np.array(
            [
                [c.a1, c.track_front / 2],
                [c.a1, -c.track_front / 2],
                [-c.a2, c.track_rear / 2],
                [-c.a2, -c.track_rear / 2],
            ]
        )

    @property
    def sprung_mass_corner(self) -> np.ndarray:
        """Chassis mass carried by each corner at rest, kg: ½·m·a2/l front, ½·m·a1/l rear.

        Brancati & Tufano 2022, eq. 2.
        """
        m, a1, a2, lw = self.chassis.mass, self.chassis.a1, self.chassis.a2, self.wheelbase
        return np.array([0.5 * m * a2 / lw] * 2 + [0.5 * m * a1 / lw] * 2)

    @property
    def static_tire_load(self) -> np.ndarray:
        """Static vertical tire force per corner on flat ground, N."""
        return (self.sprung_mass_corner + self.unsprung_mass) * GRAVITY

    @property
    def spring_rate(self) -> np.ndarray:
        """Linear wheel rate per corner, N/m."""
        s = self.suspension
        return np.array([s.spring_rate_front] * 2 + [s.spring_rate_rear] * 2)

    def with_overrides(self, overrides: dict | None) -> VehicleParams:
        """Copy with ``{section: {name: value}}`` replaced; unknown names raise InputError."""
        if not overrides:
            return self
        updated = {}
        for section, values in overrides.items():
            if section not in _SECTIONS:
                raise InputError(
                    f"vehicle: unknown section {section!r}; expected one of {', '.join(_SECTIONS)}"
                )
            current = getattr(self, section)
            known = {f.name for f in fields(current)}
            for name, value in values.items():
                if name not in known:
                    raise InputError(f"vehicle.{section}: unknown parameter {name!r}")
                if not isinstance(value, int | float) or not np.isfinite(value):
                    raise InputError(f"vehicle.{section}.{name}: must be a finite number, got {value!r}")
            updated[section] = replace(current, **{k: float(v) for k, v in values.items()})
        return replace(self, **updated)


def parameter_table(path: str | Path = PARAMETER_FILE) -> dict[str, dict[str, dict]]:
    """The raw parameter file: ``{section: {name: {value, unit, source[, bounds]}}}``."""
    with open(path, "rb") as handle:
        return tomllib.load(handle)


def load_vehicle(path: str | Path = PARAMETER_FILE, *, overrides: dict | None = None) -> VehicleParams:
    """Read the vehicle parameter file into :class:`VehicleParams` (SI units).

    Parameters
    ----------
    path : str or Path, optional
        TOML file with one table per parameter (``value``, ``unit``, ``source``);
        default the SUV of paper 000, ``mjcf/suv/parameters.toml``. Its ``[tire.file]``
        names the tyre's ``.tir`` file, relative to the parameter file's folder
        (:attr:`VehicleParams.tire_file`; read by :func:`suvtwin.mjcf.tire.load_tire`).
    overrides : dict, optional
        ``{section: {name: value}}`` replacing file values (e.g. a scenario's).
    """
    table = parameter_table(path)
    sections = {}
    for name, cls in _SECTIONS.items():
        entries = table.get(name, {})
        wanted = [f.name for f in fields(cls)]
        missing = [w for w in wanted if w not in entries]
        if missing:
            raise InputError(f"vehicle file {path}: section [{name}] lacks {', '.join(missing)}")
        sections[name] = cls(**{w: float(entries[w]["value"]) for w in wanted})
    return VehicleParams(**sections, tire_file=tire_file_of(path, table)).with_overrides(overrides)
