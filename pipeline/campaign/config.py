"""What a campaign runs: its settings (pydantic, validated) and the two presets.

Usual call: ``config = preset("quick", monte_carlo_runs=10)``; bad settings raise
:class:`suvtwin.errors.InputError` naming the field and its allowed range.

The scenario names of paper 000 §5.4 are :data:`SCENARIOS`; the estimator names are those of
:data:`suvtwin.pipeline.estimator_registry.ESTIMATORS`.
"""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from suvtwin.errors import InputError
from suvtwin.pipeline.estimator_registry import ESTIMATORS
from suvtwin.roads.spec import format_validation_error

__all__ = ["SCENARIOS", "CampaignConfig", "IdentificationConfig", "preset"]

SCENARIOS: dict[str, str] = {
    "class_A": "class A road (Fig. 7)",
    "class_D": "class D road (Fig. 8)",
    "switch_A_to_D": "class A road, class D from 5 s (Fig. 9)",
    "pressure_drop": "class B road, 230 → 180 kPa from 4.0 to 5.5 s (Fig. 10)",
    "mass_plus_8": "sprung mass +8 % (1931 kg), class B road (Fig. 11)",
    "mass_plus_24": "sprung mass +24 % (2217 kg), class B road (Fig. 11)",
    "non_iso_road": "a road of no ISO class: waviness 1.6 / 2.6 / 3.0 segments (Fig. 12–13 stand-in)",
}
"""Scenario runs of paper 000 §5.4, at 60 km/h, each road level drawn inside its class band."""

_MODEL = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


class IdentificationConfig(BaseModel):
    """GA settings of the identification stage (paper 000 §5.2)."""

    model_config = _MODEL
    classes: str = Field(default="ABCD", pattern="^[A-D]{1,4}$")
    pop_size: int = Field(default=100, ge=8, le=2000)
    n_gen: int = Field(default=1000, ge=1, le=10000)
    duration_s: float = Field(default=10.0, ge=2.0, le=60.0)
    seed: int = Field(default=1, ge=0)


class CampaignConfig(BaseModel):
    """What a campaign runs. Two presets: :func:`preset` ("quick", "full")."""

    model_config = _MODEL
    name: str = "custom"
    seed: int = Field(default=2022, ge=0)
    monte_carlo_runs: int = Field(default=100, ge=0, le=10000)
    duration_s: float = Field(default=10.0, ge=8.0, le=60.0)
    corner: str = Field(default="fl", pattern="^(fl|fr|rl|rr)$")
    scenarios: tuple[str, ...] = tuple(SCENARIOS)
    estimators: tuple[str, ...] = tuple(ESTIMATORS)
    identification: IdentificationConfig = Field(default_factory=IdentificationConfig)
    params_file: str | None = None
    """Skip the identification: a parameter file, ``"identified"`` (shipped) or ``"paper"`` (Table 3)."""
    initial_pressure_sigma_kpa: float = Field(default=60.0, ge=0.0, le=150.0)
    chunk_size: int = Field(default=25, ge=1, le=1000)
    premise_runs_per_class: int = Field(default=25, ge=0, le=1000)
    """Runs per class A–D of paper 000's premise check (:mod:`suvtwin.pipeline.premise`); 0: none."""
    monitor_leak_runs: int = Field(default=20, ge=0, le=1000)
    """Slow-leak runs (one tyre 20 % down over 30 s, all four tyres monitored) of the online monitor's
    study (:mod:`suvtwin.pipeline.monitor_scenarios`, set ``slow_leak``); 0: none."""
    monitor_warning_runs: int = Field(default=100, ge=0, le=1000)
    """Deflation-warning runs (one tyre or all four 20 % below placard) of the monitor's study (set
    ``warning``); 0: none."""
    input_estimation_seeds: int = Field(default=0, ge=0, le=1000)
    """Noise draws of paper 001's input-estimation study on the SUV (CIE, AWIE on the sine bump, cleat
    and random road at 30/60/90 km/h, :func:`suvtwin.pipeline.input_estimation.input_estimation_study`);
    0: not run."""
    road_estimation_seeds: int = Field(default=0, ge=0, le=20)
    """Seeds of the road-profile study on the SUV (Wang et al. 2017's Table 2, 18 cells, 9 MuJoCo
    runs per seed: :func:`suvtwin.pipeline.road_estimation.mujoco_study`); 0: none."""
    lateral_detection_runs: int = Field(default=0, ge=0, le=1000)
    """ISO 3888-1 lane changes per tyre case of the deflated-tyre detection study (Solmaz's 16
    two-track models: :func:`suvtwin.pipeline.lateral_detection.monte_carlo_study`); 0: none."""

    @model_validator(mode="after")
    def _known_names(self) -> CampaignConfig:
        if self.monte_carlo_runs == 0 and not self.scenarios:
            raise ValueError(
                "nothing to run: monte_carlo_runs is 0 and scenarios is empty; give monte_carlo_runs ≥ 1 "
                f"or scenarios among {', '.join(SCENARIOS)}"
            )
        if not self.estimators:
            raise ValueError(f"estimators is empty: give at least one of {', '.join(ESTIMATORS)}")
        for name in self.scenarios:
            if name not in SCENARIOS:
                raise ValueError(f"unknown scenario {name!r}; allowed: {', '.join(SCENARIOS)}")
        for name in self.estimators:
            if name not in ESTIMATORS:
                raise ValueError(f"unknown estimator {name!r}; allowed: {', '.join(ESTIMATORS)}")
        if self.params_file is None:
            for name in self.estimators:
                missing = [c for c in ESTIMATORS[name].needs_classes if c not in self.identification.classes]
                if missing:
                    raise ValueError(
                        f"estimator {name} uses the class {', '.join(missing)} mode: "
                        f"identification.classes must hold {''.join(missing)}"
                    )
        return self


def preset(name: str, **overrides) -> CampaignConfig:
    """The ``quick`` (40 Monte Carlo runs, GA 100 × 100, premise check 6 runs per class, monitor study
    2 slow leaks and 4 warning runs) or ``full`` (paper scale: 100 runs, GA 100 × 1000, premise check
    25 runs per class, monitor study 20 slow leaks and 100 warning runs, paper 001's input-estimation
    study with 10 noise draws, road-profile study 3 seeds, lateral detection study 100 lane changes
    per tyre case) campaign, with optional field overrides
    (e.g. ``monte_carlo_runs=40``, ``road_estimation_seeds=3`` for the road-profile study in a quick
    campaign)."""
    presets = {
        "quick": {
            "name": "quick",
            "monte_carlo_runs": 40,
            "identification": {"pop_size": 100, "n_gen": 100},
            "premise_runs_per_class": 6,
            "monitor_leak_runs": 2,
            "monitor_warning_runs": 4,
        },
        "full": {
            "name": "full",
            "monte_carlo_runs": 100,
            "identification": {"pop_size": 100, "n_gen": 1000},
            "premise_runs_per_class": 25,
            "monitor_leak_runs": 20,
            "monitor_warning_runs": 100,
            "input_estimation_seeds": 10,
            "road_estimation_seeds": 3,
            "lateral_detection_runs": 100,
        },
    }
    if name not in presets:
        raise InputError(f"campaign preset must be quick or full, got {name!r}")
    data = {**presets[name], **{k: v for k, v in overrides.items() if v is not None}}
    if isinstance(overrides.get("identification"), dict):
        data["identification"] = {**presets[name]["identification"], **overrides["identification"]}
    try:
        return CampaignConfig.model_validate(data)
    except ValidationError as error:
        raise InputError("invalid campaign settings: " + format_validation_error(error)) from None
