"""What a road is made of: the validated description a road is generated from.

Usual call: ``spec = RoadSpec(segments=[SegmentSpec(length_m=300, road_class="C")], spacing_m=0.02)``.

A road is a sequence of segments (each with its own ISO 8608 roughness level
and waviness) on two parallel wheel tracks, plus deterministic obstacles. The
spec is a frozen pydantic model so that it validates user files (YAML, TOML,
JSON) with messages that name the field and the allowed range; the generator in
:mod:`suvtwin.roads.profile` turns it into arrays. All lengths in m, levels in m³ at
n0 = 0.1 cycle/m (ISO 8608 cycle form).
"""

from __future__ import annotations

import re
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from suvtwin.errors import InputError, cut
from suvtwin.roads.iso8608 import CLASSES, class_bounds, class_level, class_of_level
from suvtwin.roads.limits import (
    MAX_ROAD_LENGTH_M,
    MAX_ROAD_SAMPLES,
    MAX_SPACING_M,
    MAX_TRACK_SPACING_M,
    MIN_RECOMMENDED_LENGTH_M,
    TRACK_SPACING_M,
)

__all__ = [
    "MAX_SPACING_M",
    "MIN_RECOMMENDED_LENGTH_M",
    "ObstacleSpec",
    "RoadSpec",
    "SegmentSpec",
    "format_validation_error",
    "parse_road_spec",
]

_MODEL = ConfigDict(frozen=True, extra="forbid", str_strip_whitespace=True, allow_inf_nan=False)


class SegmentSpec(BaseModel):
    """One stretch of road with a single roughness level.

    Give `road_class` (its geometric-mean level is used), or `gd_n0` (any level:
    real roads sit anywhere in a class band), or both if they agree.
    """

    model_config = _MODEL

    length_m: float = Field(gt=0.0, description="segment length, m")
    road_class: str | None = Field(default=None, description="ISO 8608 class A–H")
    gd_n0: float | None = Field(
        default=None, gt=0.0, lt=1.0, description="level Gd(n0) at n0 = 0.1 cycle/m, m^3"
    )
    waviness: float = Field(default=2.0, ge=1.0, le=3.5, description="PSD exponent w, -")

    @field_validator("road_class")
    @classmethod
    def _known_class(cls, value: str | None) -> str | None:
        if value is None:
            return None
        letter = value.upper()
        if letter not in CLASSES:
            raise ValueError(f"must be one of A–H, got {value!r}")
        return letter

    @model_validator(mode="after")
    def _level_given(self) -> SegmentSpec:
        if self.road_class is None and self.gd_n0 is None:
            raise ValueError("give road_class (A–H) or gd_n0 (m^3 at 0.1 cycle/m)")
        if self.road_class is not None and self.gd_n0 is not None:
            lower, upper = class_bounds(self.road_class)
            if not lower <= self.gd_n0 <= upper:
                raise ValueError(
                    f"gd_n0 = {self.gd_n0:.3g} m^3 lies outside class {self.road_class} "
                    f"[{lower:.3g}, {upper:.3g}] m^3"
                )
        return self

    @property
    def level(self) -> float:
        """Roughness level Gd(n0) used for this segment, m³."""
        return self.gd_n0 if self.gd_n0 is not None else class_level(self.road_class)

    @property
    def label(self) -> str:
        """ISO 8608 class this segment's level belongs to."""
        return self.road_class if self.road_class is not None else class_of_level(self.level)


class ObstacleSpec(BaseModel):
    """A deterministic obstacle added on top of the random profile.

    - ``sine_bump``: half-sine of height `height_m` over `length_m`
      (Lin et al. 2021, eq. 23, written in distance: z = h0·sin(π·s/D)).
    - ``cleat``: rectangular step up of `height_m` over `length_m`.
    - ``pothole``: rectangular depression of depth `height_m` over `length_m`.
    """

    model_config = _MODEL

    kind: Literal["sine_bump", "cleat", "pothole"]
    position_m: float = Field(ge=0.0, description="distance of the obstacle's start, m")
    length_m: float = Field(gt=0.0, le=50.0, description="obstacle length along x, m")
    height_m: float = Field(gt=0.0, le=0.5, description="bump/cleat height or pothole depth, m")
    track: Literal["left", "right", "both"] = "both"


class RoadSpec(BaseModel):
    """A whole road: segments, grid, generator, track correlation, obstacles."""

    model_config = _MODEL

    segments: list[SegmentSpec] = Field(min_length=1)
    spacing_m: float = Field(default=0.02, gt=0.0, le=MAX_SPACING_M, description="grid spacing along x, m")
    method: Literal["shape-filter", "superposition", "gaussian"] = "superposition"
    tracks: Literal["independent", "identical", "correlated", "isotropic"] = "independent"
    track_correlation: float = Field(
        default=0.5, ge=0.0, le=1.0, description="left/right correlation for 'correlated', -"
    )
    track_spacing_m: float = Field(
        default=TRACK_SPACING_M, gt=0.0, le=MAX_TRACK_SPACING_M,
        description="distance between the wheel tracks for 'isotropic', m",
    )  # fmt: skip
    n_min: float = Field(default=0.01, gt=0.0, description="lowest generated frequency, cycles/m")
    n_max: float = Field(default=10.0, gt=0.0, description="highest generated frequency, cycles/m")
    transition_m: float = Field(
        default=2.0, ge=0.0, le=50.0, description="cross-fade length between segments, m"
    )
    obstacles: list[ObstacleSpec] = Field(default_factory=list)

    @model_validator(mode="after")
    def _consistent(self) -> RoadSpec:
        if self.n_min >= self.n_max:
            raise ValueError(f"n_min ({self.n_min}) must be below n_max ({self.n_max}) cycles/m")
        nyquist = 0.5 / self.spacing_m
        if self.n_max > nyquist + 1e-9:
            raise ValueError(
                f"n_max = {self.n_max} cycles/m exceeds the grid's Nyquist frequency "
                f"1/(2·spacing_m) = {nyquist:.4g} cycles/m"
            )
        if self.method == "shape-filter":
            for i, seg in enumerate(self.segments):
                if seg.waviness != 2.0:
                    raise ValueError(
                        f"segments[{i}].waviness = {seg.waviness}: the shape filter makes "
                        "w = 2 only; use method 'superposition' or 'gaussian' for other waviness"
                    )
        if len(self.segments) > 1:
            shortest = min(seg.length_m for seg in self.segments)
            if self.transition_m > shortest:
                raise ValueError(
                    f"transition_m = {self.transition_m} m exceeds the shortest segment ({shortest:g} m)"
                )
        total = self.length_m
        if total > MAX_ROAD_LENGTH_M:
            raise ValueError(f"the segments' total length {total:g} m exceeds {MAX_ROAD_LENGTH_M:g} m")
        if total / self.spacing_m + 1 > MAX_ROAD_SAMPLES:
            raise ValueError(
                f"{total:g} m at spacing_m = {self.spacing_m:g} m is {total / self.spacing_m + 1:.3g} grid "
                f"points, more than {MAX_ROAD_SAMPLES:,}: coarsen the spacing or shorten the road"
            )
        for i, obstacle in enumerate(self.obstacles):
            if obstacle.position_m + obstacle.length_m > total:
                raise ValueError(
                    f"obstacles[{i}] ends at {obstacle.position_m + obstacle.length_m:g} m, "
                    f"beyond the road's end at {total:g} m"
                )
        return self

    @property
    def length_m(self) -> float:
        """Total road length, m."""
        return float(sum(seg.length_m for seg in self.segments))


def format_validation_error(error: ValidationError, *, prefix: str = "") -> str:
    """One line per problem: ``field.path: message``, for the CLI.

    Union branches are hidden from the path (``road: RoadSpec | "flat"`` reports
    ``road.segments[0]...``), and a literal branch's "should be 'flat'" is dropped
    when the other branch has something more specific to say.
    """
    items = error.errors()
    lines = []
    for item in items:
        parts = [str(p) for p in item["loc"]]
        if any(p.startswith("literal[") for p in parts) and len(items) > 1:
            continue
        kept = [p for p in parts if not re.match(r"^(function-[\w-]+\[.*\]|[A-Z]\w*)$", p)]
        path = prefix + ".".join(f"[{p}]" if p.isdigit() else p for p in kept).replace(".[", "[")
        message = item["msg"].removeprefix("Value error, ")
        if item["type"] == "extra_forbidden":
            message = "unknown field"
        elif item["type"] not in ("missing", "value_error"):
            message = f"{message} (got {cut(repr(item.get('input')))})"
        lines.append(f"{path or '(top level)'}: {cut(message)}")
        if len(lines) == 20 and len(items) > 21:
            lines.append(f"… and {len(items) - 20} more problems")
            break
    return "; ".join(lines)



def parse_road_spec(data: object) -> RoadSpec:
    """Validate a mapping (from YAML/TOML/JSON) into a :class:`RoadSpec`.

    Raises
    ------
    InputError
        With every problem, each naming its field path.
    """
    try:
        return RoadSpec.model_validate(data)
    except ValidationError as error:
        raise InputError("invalid road: " + format_validation_error(error)) from None
