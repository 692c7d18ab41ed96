"""The runs of a campaign: Monte Carlo draws and the scenario runs of paper 000 §5.4.

Usual call: ``specs = campaign_specs(config)``: one :class:`RunSpec` per ground-truth run, the
Monte Carlo runs first, then the scenario runs.

Monte Carlo (Brancati & Tufano 2022, §5.3, Table 4): pressure uniform 130–230 kPa, speed
uniform 40–80 km/h, class uniform A–D with the level drawn log-uniformly inside the class
band, not at its centre; the initial pressure estimate drawn from N(p_true, σ_p0) as the
paper draws x̂0 ~ N(x0, P0). Each run's draws depend on (seed, index) only. Scenario runs
(:data:`suvtwin.pipeline.campaign.config.SCENARIOS`) at 60 km/h, their levels drawn inside
each class band from (seed, name).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from suvtwin.errors import InputError
from suvtwin.estimators.tire_pressure import EstimatorSettings
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.campaign.cache import digest
from suvtwin.pipeline.campaign.config import SCENARIOS, CampaignConfig
from suvtwin.pipeline.scenario import END_MARGIN_M, START_MARGIN_M
from suvtwin.roads.iso8608 import draw_level_in_class

__all__ = ["MC_CLASSES", "MC_PRESSURE_KPA", "MC_SPEED_KMH", "SCENARIO_PRESSURE_KPA", "SCENARIO_SPEED_KMH",
           "RunSpec", "campaign_specs"]  # fmt: skip

SCENARIO_SPEED_KMH = 60.0
SCENARIO_PRESSURE_KPA = 200.0
MC_PRESSURE_KPA = (130.0, 230.0)
MC_SPEED_KMH = (40.0, 80.0)
MC_CLASSES = "ABCD"


@dataclass(frozen=True)
class RunSpec:
    """One ground-truth run of the campaign and how its estimators start."""

    name: str
    kind: str  # "monte_carlo" or "scenario"
    title: str
    scenario: dict
    initial_pressure_kpa: float
    info: dict = field(default_factory=dict)

    def key(self, fingerprint: dict) -> str:
        """Hash of what makes the run: scenario, code and libraries, and the contents of a tyre
        file the scenario names (editing that file must not reuse the old run)."""
        made_by = {"scenario": self.scenario, "model": fingerprint}
        tire_file = self.scenario.get("tire_file")
        if tire_file and Path(tire_file).is_file():
            made_by["tire_file_sha256"] = hashlib.sha256(Path(tire_file).read_bytes()).hexdigest()
        return digest(made_by)


def _road_length(speed_kmh: float, duration_s: float) -> float:
    return START_MARGIN_M + speed_kmh / 3.6 * duration_s + 3.0 + END_MARGIN_M + 20.0


def _monte_carlo_spec(config: CampaignConfig, index: int) -> RunSpec:
    """Run `index` of the Monte Carlo: its draws depend on (seed, index) only, so a bigger campaign
    with the same seed shares the smaller one's runs."""
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, 0, index]))
    pressure = float(rng.uniform(*MC_PRESSURE_KPA))
    speed = float(rng.uniform(*MC_SPEED_KMH))
    road_class = MC_CLASSES[int(rng.integers(0, len(MC_CLASSES)))]
    level = draw_level_in_class(road_class, rng)
    initial = float(np.clip(rng.normal(pressure, config.initial_pressure_sigma_kpa), 80.0, 350.0))
    scenario = {
        "duration_s": config.duration_s,
        "speed_kmh": speed,
        "seed": int(rng.integers(0, 2**31)),
        "road": {"segments": [{"length_m": _road_length(speed, config.duration_s), "gd_n0": level}]},
        "pressure_kpa": pressure,
    }
    info = {"road_class": road_class, "gd_n0_m3": level, "speed_kmh": speed, "pressure_kpa": pressure}
    return RunSpec(f"mc_{index:04d}", "monte_carlo", f"Monte Carlo run {index}", scenario, initial, info)


def _scenario_spec(config: CampaignConfig, name: str) -> RunSpec:
    """One §5.4 scenario at 60 km/h; levels drawn inside each class band from (seed, name)."""
    rng = np.random.default_rng(np.random.SeedSequence([config.seed, 1, list(SCENARIOS).index(name)]))
    v, duration = SCENARIO_SPEED_KMH, config.duration_s
    length = _road_length(v, duration)
    vehicle = load_vehicle()
    chassis_mass, wheelbase = vehicle.chassis.mass, vehicle.wheelbase
    pressure: float = SCENARIO_PRESSURE_KPA
    events: list[dict] = []
    load: list[dict] = []
    info: dict = {}
    if name in ("class_A", "class_D"):
        road_class = name[-1]
        level = draw_level_in_class(road_class, rng)
        segments = [{"length_m": length, "gd_n0": level}]
        info = {"road_class": road_class, "gd_n0_m3": level}
    elif name == "switch_A_to_D":
        # the corner's wheel reaches the class D segment at 5 s (front axle starts one wheelbase
        # ahead of the start margin)
        first = START_MARGIN_M + wheelbase + v / 3.6 * 5.0
        levels = [draw_level_in_class("A", rng), draw_level_in_class("D", rng)]
        segments = [{"length_m": first, "gd_n0": levels[0]}, {"length_m": length - first, "gd_n0": levels[1]}]
        info = {"road_class": "A→D", "gd_n0_m3": levels, "switch_s": 5.0}
    elif name == "pressure_drop":
        level = draw_level_in_class("B", rng)
        segments = [{"length_m": length, "gd_n0": level}]
        pressure = 230.0
        events = [{"tire": config.corner, "start_s": 4.0, "end_s": 5.5, "target_kpa": 180.0}]
        info = {"road_class": "B", "gd_n0_m3": level, "drop_s": [4.0, 5.5]}
    elif name in ("mass_plus_8", "mass_plus_24"):
        level = draw_level_in_class("B", rng)
        segments = [{"length_m": length, "gd_n0": level}]
        share = 0.08 if name == "mass_plus_8" else 0.24
        load = [{"mass_kg": share * chassis_mass, "position_m": [0.0, 0.0, 0.0]}]
        info = {"road_class": "B", "gd_n0_m3": level, "extra_mass_kg": share * chassis_mass}
    elif name == "non_iso_road":
        # measured roads bend away from w = 2; three segments, none an ISO road
        parts = [(0.35, 1.6, "B"), (0.35, 2.6, "C"), (0.30, 3.0, "B")]
        segments = [
            {"length_m": share * length, "gd_n0": draw_level_in_class(c, rng), "waviness": w}
            for share, w, c in parts
        ]
        info = {"road_class": "none", "waviness": [p[1] for p in parts]}
    else:
        raise InputError(f"unknown scenario {name!r}; allowed: {', '.join(SCENARIOS)}")
    scenario = {
        "duration_s": duration,
        "speed_kmh": v,
        "seed": int(rng.integers(0, 2**31)),
        "road": {"segments": segments},
        "pressure_kpa": pressure,
        "pressure_events": events,
        "load": load,
    }
    return RunSpec(name, "scenario", SCENARIOS[name], scenario, EstimatorSettings().pressure_guess_kpa, info)


def campaign_specs(config: CampaignConfig) -> list[RunSpec]:
    """All runs of a campaign: the Monte Carlo runs, then the scenario runs."""
    specs = [_monte_carlo_spec(config, i) for i in range(config.monte_carlo_runs)]
    return specs + [_scenario_spec(config, name) for name in config.scenarios]
