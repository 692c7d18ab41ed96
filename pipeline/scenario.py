"""What one ground-truth run is: the validated scenario a simulation is made from.

Usual call: ``scenario = load_scenario("s.yaml")`` or
``scenario = quick_scenario(road_class="C", speed_kmh=60, pressure_kpa=180, duration_s=10, seed=1)``.

A scenario file (YAML, TOML or JSON) holds the run's duration, integration step,
output rate, seed, speed (constant or a profile), road (a :class:`RoadSpec` or
``"flat"``), tire pressures and pressure events, extra loads, steering, sensor
noise, the tire–road contact and, optionally, the tyre as a TNO MF-Tyre 6.1 property
file (``tire_file``, relative to the scenario file's folder; default the SUV's ``.tir``
named by ``mjcf/suv/parameters.toml``). Units in files are the user's: km/h, kPa, kg, s,
m, rad; :mod:`suvtwin.pipeline.simulator` converts to SI at the edge. Every problem is
reported with its field path and allowed range.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from suvtwin.errors import InputError
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.roads.spec import RoadSpec, format_validation_error

__all__ = [
    "ISO3888_OFFSET_M",
    "ISO3888_SECTIONS_M",
    "LoadSpec",
    "NoiseSpec",
    "PressureEvent",
    "Scenario",
    "SteeringSpec",
    "iso3888_centreline",
    "load_scenario",
    "parse_scenario",
    "quick_scenario",
]

_MODEL = ConfigDict(frozen=True, extra="forbid", str_strip_whitespace=True, allow_inf_nan=False)
_DEFAULT_TIRE = load_vehicle().tire
PRESSURE_MIN_KPA = _DEFAULT_TIRE.pressure_min / 1e3
PRESSURE_MAX_KPA = _DEFAULT_TIRE.pressure_max / 1e3
MAX_SPEED_KMH = 200.0
START_MARGIN_M = 10.0
"""Distance from the road's start to the rear axle at t = 0, m."""
END_MARGIN_M = 10.0
"""Road left beyond the front axle at the end of the run, m."""

Corner = Literal["fl", "fr", "rl", "rr"]


class PressureEvent(BaseModel):
    """Pressure of one tire ramps linearly to `target_kpa` between `start_s` and `end_s`."""

    model_config = _MODEL
    tire: Corner
    start_s: float = Field(ge=0.0)
    end_s: float = Field(ge=0.0)
    target_kpa: float = Field(ge=PRESSURE_MIN_KPA, le=PRESSURE_MAX_KPA)

    @model_validator(mode="after")
    def _ordered(self) -> PressureEvent:
        if self.end_s < self.start_s:
            raise ValueError(f"end_s ({self.end_s}) must not precede start_s ({self.start_s})")
        return self


class LoadSpec(BaseModel):
    """Extra mass fixed to the chassis at `position_m` (x fwd, y left, z up from the chassis CoG)."""

    model_config = _MODEL
    mass_kg: float = Field(gt=0.0, le=1500.0)
    position_m: tuple[float, float, float] = (0.0, 0.0, 0.0)


ISO3888_SECTIONS_M = (15.0, 30.0, 25.0, 25.0, 15.0, 15.0)
"""Lengths of the six sections of the ISO 3888-1:2018 double lane change, m: entry lane,
lane change, offset lane, change back, exit lane (two sections of 15 m)."""
WHEEL_MARGIN_M = 0.25
"""How far beyond half its track a wheel may reach from the car's centre line, m: half a 235 mm tyre
and about 0.1 m of the path driver's tracking error (the road strip's check,
:meth:`Scenario._check_on_road`)."""
ISO3888_OFFSET_M = 3.5
"""Lateral offset of the ISO 3888-1 offset lane (section 3), m."""


def _smoothstep(s: np.ndarray) -> np.ndarray:
    """Quintic 0 → 1 on [0, 1] with zero slope and curvature at both ends (C² transitions)."""
    s = np.clip(s, 0.0, 1.0)
    return s**3 * (10.0 - 15.0 * s + 6.0 * s * s)


def iso3888_centreline(x: np.ndarray, *, start_m: float, offset_m: float, sign: float) -> np.ndarray:
    """Centreline y(x) of the ISO 3888-1 double lane change, m, as a smooth curve.

    ``x`` in m from the car's start (chassis centre of gravity at t = 0); section 1 (entry,
    15 m) begins at `start_m`; sections 2 and 4 (30 m and 25 m) move the centreline by
    ``sign·offset_m`` and back with a quintic smoothstep; section 3 (25 m) holds the offset;
    sections 5–6 (exit, 30 m) and beyond are at y = 0. The standard fixes the sections'
    lengths and lane widths (1.1, 1.2 and 1.3 × vehicle width + 0.25 m) and dimensions the
    3.5 m offset between cone lines; here it is taken between lane centrelines (the two differ
    by half the difference of the lane widths, 0.05 × vehicle width ≈ 0.1 m on the SUV).
    """
    l1, l2, l3, l4, _, _ = ISO3888_SECTIONS_M
    a = start_m + l1
    b = a + l2 + l3
    up = _smoothstep((np.asarray(x, dtype=float) - a) / l2)
    down = _smoothstep((np.asarray(x, dtype=float) - b) / l4)
    return sign * offset_m * (up - down)


class SteeringSpec(BaseModel):
    """How the driver steers.

    ``lane``: keep the straight line y = `lane_y_m` (pure pursuit); ``circle``: follow a
    circle of `radius_m` turning `direction` from the start; ``series``: road-wheel angle
    (bicycle model, rad) from `series` = [[t_s, angle_rad], …], linear in between;
    ``path``: follow the reference path `path` = [[x_m, y_m], …] (pure pursuit; x from the
    car's start, strictly increasing, linear in between, y held beyond the ends; lateral
    positions relative to `lane_y_m`); ``iso3888``: the ISO 3888-1 double lane change
    (:func:`iso3888_centreline`) towards `direction`, section 1 beginning `iso3888_start_m`
    ahead of the car's start, offset `iso3888_offset_m`.
    """

    model_config = _MODEL
    mode: Literal["lane", "circle", "series", "path", "iso3888"] = "lane"
    lane_y_m: float = 0.0
    radius_m: float = Field(default=50.0, ge=5.0, le=2000.0)
    direction: Literal["left", "right"] = "left"
    series: list[tuple[float, float]] = Field(default_factory=list)
    path: list[tuple[float, float]] = Field(default_factory=list)
    iso3888_start_m: float = Field(default=50.0, ge=0.0, le=10000.0)
    iso3888_offset_m: float = Field(default=ISO3888_OFFSET_M, gt=0.0, le=10.0)

    @model_validator(mode="after")
    def _series_given(self) -> SteeringSpec:
        if self.mode == "series":
            if len(self.series) < 1:
                raise ValueError("mode 'series' needs series = [[t_s, angle_rad], ...]")
            times = [t for t, _ in self.series]
            if any(b <= a for a, b in zip(times, times[1:], strict=False)):
                raise ValueError("series times must be strictly increasing")
            if any(abs(a) > 0.6 for _, a in self.series):
                raise ValueError("series angles must lie within ±0.6 rad (the steering lock)")
        if self.mode == "path":
            if len(self.path) < 2:
                raise ValueError("mode 'path' needs path = [[x_m, y_m], ...] with at least 2 points")
            xs = [x for x, _ in self.path]
            if any(b <= a for a, b in zip(xs, xs[1:], strict=False)):
                raise ValueError("path x values must be strictly increasing (the path is a function y(x))")
            if xs[-1] - xs[0] > 20000.0:
                raise ValueError(f"path must span at most 20000 m in x, got {xs[-1] - xs[0]:g} m")
            if any(abs(y) > 50.0 for _, y in self.path):
                raise ValueError("path y values must lie within ±50 m of lane_y_m")
            slopes = [
                abs((y1 - y0) / (x1 - x0))
                for (x0, y0), (x1, y1) in zip(self.path, self.path[1:], strict=False)
            ]
            if max(slopes) > 0.5:
                raise ValueError(
                    f"path slope |dy/dx| must be at most 0.5 (the driver targets a point one look-ahead "
                    f"ahead in x), got {max(slopes):.3g}"
                )
        return self

    def reference_path(self, *, spacing_m: float = 0.25) -> tuple[np.ndarray, np.ndarray] | None:
        """The path the driver follows in ``path`` or ``iso3888`` mode, tabulated at `spacing_m`:
        x from the car's start and y relative to `lane_y_m`, m; `None` in the other modes."""
        if self.mode == "path":
            px, py = np.array(self.path, dtype=float).T
            n = max(2, int(np.ceil((px[-1] - px[0]) / spacing_m)) + 1)
            x = np.linspace(px[0], px[-1], n)
            return x, np.interp(x, px, py)
        if self.mode == "iso3888":
            length = self.iso3888_start_m + sum(ISO3888_SECTIONS_M)
            x = np.arange(0.0, length + spacing_m, spacing_m)
            sign = 1.0 if self.direction == "left" else -1.0
            return x, iso3888_centreline(
                x, start_m=self.iso3888_start_m, offset_m=self.iso3888_offset_m, sign=sign
            )
        return None


class NoiseSpec(BaseModel):
    """Standard deviation of the white noise added to the sensor signals."""

    model_config = _MODEL
    accel_sprung_mps2: float = Field(default=0.5, ge=0.0, le=50.0)
    accel_unsprung_mps2: float = Field(default=0.5, ge=0.0, le=50.0)


class Scenario(BaseModel):
    """One ground-truth run. See the module docstring for units."""

    model_config = _MODEL
    duration_s: float = Field(gt=0.0, le=3600.0)
    timestep_s: float = Field(default=1e-3, ge=1e-4, le=2e-3)
    output_rate_hz: float = Field(default=1000.0, gt=0.0, le=10000.0)
    seed: int = Field(default=0, ge=0)
    speed_kmh: float | list[tuple[float, float]] = 60.0
    road: RoadSpec | Literal["flat"]
    pressure_kpa: float | dict[Corner, float] = 250.0
    pressure_events: list[PressureEvent] = Field(default_factory=list)
    load: list[LoadSpec] = Field(default_factory=list)
    steering: SteeringSpec = Field(default_factory=SteeringSpec)
    noise: NoiseSpec = Field(default_factory=NoiseSpec)
    contact: Literal["envelope", "native"] = "envelope"
    vehicle: dict[str, dict[str, float]] = Field(default_factory=dict)
    tire_file: Path | None = None

    @field_validator("speed_kmh")
    @classmethod
    def _speed(cls, value):
        points = [(0.0, value)] if isinstance(value, int | float) else value
        if not points:
            raise ValueError("give a speed or a profile [[t_s, speed_kmh], ...]")
        for t, v in points:
            if not 0.0 <= v <= MAX_SPEED_KMH:
                raise ValueError(f"speed must be in [0, {MAX_SPEED_KMH:g}] km/h, got {v:g}")
            if t < 0.0:
                raise ValueError(f"profile times must be ≥ 0 s, got {t:g}")
        times = [t for t, _ in points]
        if any(b <= a for a, b in zip(times, times[1:], strict=False)):
            raise ValueError("profile times must be strictly increasing")
        return value

    @field_validator("pressure_kpa")
    @classmethod
    def _pressure(cls, value):
        values = {c: value for c in CORNERS} if isinstance(value, int | float) else value
        missing = [c for c in CORNERS if c not in values]
        if missing:
            raise ValueError(f"give all four tires (fl, fr, rl, rr); missing {', '.join(missing)}")
        for corner, p in values.items():
            if not PRESSURE_MIN_KPA <= p <= PRESSURE_MAX_KPA:
                raise ValueError(
                    f"tire {corner}: pressure must be in [{PRESSURE_MIN_KPA:g}, {PRESSURE_MAX_KPA:g}] kPa, "
                    f"got {p:g}"
                )
        return value

    @model_validator(mode="after")
    def _within_run(self) -> Scenario:
        steps = self.duration_s / self.timestep_s
        if abs(steps - round(steps)) > 1e-6 * steps:
            raise ValueError(
                f"duration_s ({self.duration_s}) must be a whole number of timestep_s ({self.timestep_s})"
            )
        decimation = 1.0 / (self.output_rate_hz * self.timestep_s)
        if decimation < 1.0 - 1e-9 or abs(decimation - round(decimation)) > 1e-6:
            raise ValueError(
                f"output_rate_hz ({self.output_rate_hz:g}) must divide the step rate "
                f"1/timestep_s = {1 / self.timestep_s:g} Hz"
            )
        for i, event in enumerate(self.pressure_events):
            if event.end_s > self.duration_s:
                raise ValueError(
                    f"pressure_events[{i}] ends at {event.end_s:g} s, "
                    f"after the run's end ({self.duration_s:g} s)"
                )
        # one tyre's events must not overlap: which pressure would it have in between?
        for corner in CORNERS:
            events = sorted(
                (e.start_s, e.end_s, i) for i, e in enumerate(self.pressure_events) if e.tire == corner
            )
            for (_, end_a, i), (start_b, _, j) in zip(events, events[1:], strict=False):
                if start_b < end_a:
                    raise ValueError(
                        f"pressure_events[{i}] and [{j}] overlap on tyre {corner} "
                        f"({start_b:g} s < {end_a:g} s): one event per tyre at a time"
                    )
        if not isinstance(self.speed_kmh, int | float) and self.speed_kmh[-1][0] > self.duration_s:
            raise ValueError("speed profile extends beyond duration_s")
        self._check_on_road()
        return self

    def _check_on_road(self) -> None:
        """A road with segments is a straight strip, |y| ≤ ``HALF_WIDTH_Y`` (2 m) about the start
        line (the heightfield; beyond it the road is its edge row extended, not the road asked for):
        steering that would take a wheel off it is refused. A wheel reaches half the widest track
        plus :data:`WHEEL_MARGIN_M` (half a tyre's width and the driver's tracking error) from the
        car's centre line. ``series`` (open loop) cannot be checked before the run."""
        if self.road == "flat" or self.steering.mode == "series":
            return
        from suvtwin.mjcf.builder import HALF_WIDTH_Y

        chassis = load_vehicle(overrides=self.vehicle or None).chassis
        room = HALF_WIDTH_Y - 0.5 * max(chassis.track_front, chassis.track_rear) - WHEEL_MARGIN_M
        st = self.steering
        if st.mode == "circle":
            raise ValueError(
                f"steering.mode 'circle' needs road: flat (a road with segments is a straight strip "
                f"{2 * HALF_WIDTH_Y:g} m wide)"
            )
        path = st.reference_path()
        widest = abs(st.lane_y_m) if path is None else float(np.max(np.abs(st.lane_y_m + path[1])))
        if widest > room + 1e-9:
            field = "steering.lane_y_m" if path is None else "steering.lane_y_m + path y"
            raise ValueError(
                f"{field} must stay within ±{room:.2f} m on a road with segments (a straight strip "
                f"{2 * HALF_WIDTH_Y:g} m wide), got {widest:.2f} m"
            )

    # ---- derived quantities (SI) ----
    @property
    def n_steps(self) -> int:
        """Number of integration steps."""
        return int(round(self.duration_s / self.timestep_s))

    @property
    def decimation(self) -> int:
        """Integration steps per output sample."""
        return int(round(1.0 / (self.output_rate_hz * self.timestep_s)))

    def speed_profile(self, t: np.ndarray) -> np.ndarray:
        """Set speed at times `t` (s), m/s (linear between profile points, held at the ends)."""
        if isinstance(self.speed_kmh, int | float):
            return np.full_like(t, self.speed_kmh / 3.6, dtype=float)
        times, speeds = np.array(self.speed_kmh).T
        return np.interp(t, times, speeds / 3.6)

    def pressure_schedule(self, t: np.ndarray) -> np.ndarray:
        """Inflation pressure per tire at times `t` (s), Pa, shape (len(t), 4)."""
        base = self.pressure_kpa
        values = [base] * 4 if isinstance(base, int | float) else [base[c] for c in CORNERS]
        out = np.tile(np.array(values, dtype=float) * 1e3, (t.size, 1))
        for event in sorted(self.pressure_events, key=lambda e: e.start_s):
            i = CORNERS.index(event.tire)
            start = float(np.interp(event.start_s, t, out[:, i]))
            target = event.target_kpa * 1e3
            span = max(event.end_s - event.start_s, 1e-12)
            ramp = np.clip((t - event.start_s) / span, 0.0, 1.0)
            after = t >= event.start_s
            out[after, i] = start + (target - start) * ramp[after]
        return out

    def steer_series(self, t: np.ndarray) -> np.ndarray:
        """Open-loop road-wheel angle at times `t`, rad (zeros unless steering mode is 'series')."""
        if self.steering.mode != "series":
            return np.zeros_like(t, dtype=float)
        times, angles = np.array(self.steering.series).T
        return np.interp(t, times, angles)

    def distance_m(self) -> float:
        """Distance the run covers at its set speed, m."""
        t = np.linspace(0.0, self.duration_s, 2001)
        return float(np.trapezoid(self.speed_profile(t), t))

    def road_seed(self) -> int:
        """Seed of the road, derived from the scenario seed (independent of the noise stream)."""
        return int(np.random.SeedSequence([self.seed, 1]).generate_state(1)[0])

    def noise_seed(self) -> int:
        """Seed of the sensor noise, derived from the scenario seed."""
        return int(np.random.SeedSequence([self.seed, 2]).generate_state(1)[0])


def parse_scenario(data: object, *, source: str = "scenario") -> Scenario:
    """Validate a mapping into a :class:`Scenario`; InputError lists each bad field."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as error:
        raise InputError(f"invalid {source}: " + format_validation_error(error)) from None


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file (.yaml, .yml, .toml or .json)."""
    from suvtwin.files import read_settings

    path = Path(path)
    data = read_settings(path, what="scenario file")
    if not isinstance(data, dict):
        raise InputError(f"scenario file {str(path)!r} must hold a mapping of fields")
    if isinstance(data.get("tire_file"), str):  # relative to the scenario file
        data = {**data, "tire_file": str(path.parent / data["tire_file"])}
    return parse_scenario(data, source=f"scenario {path.name}")


def quick_scenario(
    *,
    road_class: str,
    speed_kmh: float,
    pressure_kpa: float,
    duration_s: float,
    seed: int,
    timestep_s: float = 1e-3,
    method: str = "superposition",
) -> Scenario:
    """Straight run on a single-class road long enough for the run (the CLI's short form)."""
    length = START_MARGIN_M + max(speed_kmh, 0.0) / 3.6 * max(duration_s, 0.0) + 3.0 + END_MARGIN_M + 20.0
    return parse_scenario(
        {
            "duration_s": duration_s,
            "timestep_s": timestep_s,
            "seed": seed,
            "speed_kmh": speed_kmh,
            "road": {
                "segments": [{"length_m": max(length, 20.0), "road_class": road_class}],
                "method": method,
            },
            "pressure_kpa": pressure_kpa,
        },
        source="options",
    )
