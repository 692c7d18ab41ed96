"""Paper 000's validation campaign on the MuJoCo SUV: identification, Monte Carlo, scenario runs.

Usual call: ``summary = run_campaign(preset("quick"), "results/", jobs=2, progress=True)``.

Stages, in order (Brancati & Tufano 2022, §5.2–5.4):

1. **Identification** — the GA fits quarter-car parameters per class A–D
   (:func:`suvtwin.pipeline.identification_runs.identify_classes`); or a given parameter file.
2. **Ground-truth runs** — the Monte Carlo runs (§5.3: pressure uniform 130–230 kPa,
   speed uniform 40–80 km/h, class uniform A–D with the level drawn log-uniformly
   inside the class band, not at its centre; initial pressure estimate drawn from
   N(p_true, σ_p0) as the paper draws x̂0 ~ N(x0, P0)) and the scenario runs of §5.4
   (:data:`SCENARIOS`), simulated in parallel processes.
3. **Estimation** — on the chosen corner's accelerometers: the paper's IMM of four
   UKFs with both road inputs, its single UKF (mode A) with both, and the road-level-free
   joint estimator (:data:`ESTIMATORS`). All estimators use the *nominal* corner masses
   (paper 000 eq. 2, empty vehicle), also on the runs with extra load: the paper's
   sensitivity test keeps the quarter car's sprung mass fixed.
4. **Scoring** — per run and estimator (:func:`suvtwin.pipeline.scoring.run_metrics`) and the
   Monte Carlo indexes (eq. 23–25); then :mod:`suvtwin.pipeline.report` writes ``report.html``.

Caching and resume: every unit of work is one file named by the hash of everything
that determines it (scenario, code and model files and library versions for a run;
the run, estimator, parameter file, estimator code and initial estimate for an
estimate; the identification settings and code for a parameter file), written
atomically. A re-run reuses finished files;
an interrupted run resumes where it stopped without redoing or duplicating work.
Each estimate depends on its own run only (per-run seeds; the batched filters are
independent across the batch), so a resumed campaign gives the same bytes as an
uninterrupted one.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from suvtwin.errors import InputError, RunError
from suvtwin.estimators.joint import estimate_joint
from suvtwin.estimators.quarter_car import pressure_from_stiffness, stiffness_from_pressure
from suvtwin.estimators.tire_pressure import (
    IDENTIFIED_FILE,
    PAPER_TABLE_3,
    EstimatorSettings,
    estimate_pressure,
    load_modes,
)
from suvtwin.files import atomic_write, package_versions
from suvtwin.mjcf.vehicle import load_vehicle
from suvtwin.pipeline.estimation import PRESSURE_TOLERANCE_KPA, linear_corner_model
from suvtwin.pipeline.identification_runs import (
    corner_masses,
    identify_class,
    parameter_file_content,
    write_parameter_file,
)
from suvtwin.pipeline.scenario import END_MARGIN_M, START_MARGIN_M, parse_scenario
from suvtwin.pipeline.scoring import monte_carlo_indexes, run_metrics
from suvtwin.roads.iso8608 import draw_level_in_class
from suvtwin.roads.spec import format_validation_error

__all__ = [
    "ESTIMATORS",
    "SCENARIOS",
    "CampaignConfig",
    "IdentificationConfig",
    "RunSpec",
    "campaign_specs",
    "preset",
    "run_campaign",
]

ESTIMATORS: dict[str, tuple[str, str | None]] = {
    "imm_synthetic": ("imm", "synthetic"),
    "imm_augmented": ("imm", "augmented"),
    "ukf_synthetic": ("ukf", "synthetic"),
    "ukf_augmented": ("ukf", "augmented"),
    "joint": ("joint", None),
}
"""Estimator name → (kind, road input). ``imm_*``: paper 000's IMM of four UKFs;
``ukf_*``: its single UKF (mode A); ``joint``: the road-level-free estimator."""

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

SCENARIO_SPEED_KMH = 60.0
SCENARIO_PRESSURE_KPA = 200.0
MC_PRESSURE_KPA = (130.0, 230.0)
MC_SPEED_KMH = (40.0, 80.0)
MC_CLASSES = "ABCD"
_MODEL = ConfigDict(frozen=True, extra="forbid")


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

    @model_validator(mode="after")
    def _known_names(self) -> CampaignConfig:
        for name in self.scenarios:
            if name not in SCENARIOS:
                raise ValueError(f"unknown scenario {name!r}; allowed: {', '.join(SCENARIOS)}")
        for name in self.estimators:
            if name not in ESTIMATORS:
                raise ValueError(f"unknown estimator {name!r}; allowed: {', '.join(ESTIMATORS)}")
        if "ukf_synthetic" in self.estimators or "ukf_augmented" in self.estimators:
            if "A" not in self.identification.classes and self.params_file is None:
                raise ValueError("the single UKF uses the class A mode: identification.classes must hold A")
        return self


def preset(name: str, **overrides) -> CampaignConfig:
    """The ``quick`` (40 Monte Carlo runs, GA 100 × 100) or ``full`` (paper scale: 100 runs, GA 100 × 1000)
    campaign, with optional field overrides (e.g. ``monte_carlo_runs=40``)."""
    presets = {
        "quick": {"name": "quick", "monte_carlo_runs": 40, "identification": {"pop_size": 100, "n_gen": 100}},
        "full": {"name": "full", "monte_carlo_runs": 100, "identification": {"pop_size": 100, "n_gen": 1000}},
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


def _digest(obj: object, n: int = 12) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:n]


SIMULATION_SOURCES = ("suvtwin.mjcf", "suvtwin.pipeline.simulator", "suvtwin.pipeline.scenario",
                      "suvtwin.roads.profile", "suvtwin.roads.spec", "suvtwin.roads.iso8608")  # fmt: skip
"""What a ground-truth run is made by (besides its scenario): modules and packages of suvtwin."""
IDENTIFICATION_SOURCES = (*SIMULATION_SOURCES, "suvtwin.identification",
                          "suvtwin.pipeline.identification_runs")  # fmt: skip
ESTIMATION_SOURCES = ("suvtwin.estimators", "suvtwin.pipeline.campaign")


def _source_digest(sources: tuple[str, ...]) -> str:
    """Hash of the code and model files of `sources` (suvtwin modules or packages, with their
    package data): results made by other code get other keys, so an upgrade never reuses stale
    work. Works the same from a source checkout and from an installed wheel."""
    digest = hashlib.sha256()
    for source in sources:
        spec = importlib.util.find_spec(source)
        if spec is None or spec.origin is None:
            raise RunError(f"campaign: cannot find the code of {source}")
        if spec.submodule_search_locations:  # a package: every code and model file under it
            root = Path(next(iter(spec.submodule_search_locations)))
            files = sorted(f for f in root.rglob("*") if "__pycache__" not in f.relative_to(root).parts)
        else:
            root, files = Path(spec.origin).parent, [Path(spec.origin)]
        for f in files:
            if f.is_file() and f.suffix in (".py", ".toml", ".xml", ".tir"):
                digest.update(f"{source}/{f.relative_to(root).as_posix()}".encode())
                digest.update(f.read_bytes())
    return digest.hexdigest()[:16]


def _model_fingerprint(sources: tuple[str, ...] = SIMULATION_SOURCES) -> dict:
    """What, besides a scenario, decides a result: the code and model files and the library versions."""
    return {"code": _source_digest(sources), "versions": package_versions(("suvtwin", "mujoco", "numpy"))}


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
        return _digest({"scenario": self.scenario, "model": fingerprint})


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


# ---------------------------------------------------------------- workers (run in processes)
def _simulate_to(args: tuple[dict, str]) -> str:
    from suvtwin.pipeline.simulator import simulate, write_run

    scenario, path = args
    write_run(simulate(parse_scenario(scenario, source="campaign scenario")), path)
    return path


def _read_corner(path: str, corner: str) -> dict:
    columns = ["t_s", "speed_mps", f"{corner}_accel_sprung_mps2", f"{corner}_accel_unsprung_mps2"]
    frame = pq.read_table(path, columns=columns).to_pandas()
    return {
        "t": frame["t_s"].to_numpy(),
        "speed": float(frame["speed_mps"].mean()),
        "acc_s": frame[columns[2]].to_numpy(),
        "acc_u": frame[columns[3]].to_numpy(),
    }


def _estimate_to(args: tuple) -> list[str]:
    """Run one estimator on a batch of runs and write one estimate file per run."""
    estimator, params_path, corner, run_paths, out_paths, initial_kpa, seeds = args
    data = [_read_corner(p, corner) for p in run_paths]
    if len({d["t"].size for d in data}) != 1:
        raise InputError("a batch of runs must have equal lengths")
    acc_s = np.array([d["acc_s"] for d in data])
    acc_u = np.array([d["acc_u"] for d in data])
    speed = np.array([max(d["speed"], 1.0) for d in data])
    dt = float(np.mean(np.diff(data[0]["t"])))
    ms, mus = corner_masses(corner)
    kind, road_input = ESTIMATORS[estimator]
    columns: list[dict] = [{"t_s": d["t"]} for d in data]
    if kind == "joint":
        est = estimate_joint(acc_s, acc_u, dt, qc=linear_corner_model(corner, ms), speed_mps=speed)
        for b, col in enumerate(columns):
            col["road_level_hat_m3"] = est.road_level[b]
    else:
        modes = load_modes(params_path)
        if kind == "ukf":
            modes = modes.subset(("A",))
        est = estimate_pressure(
            acc_s, acc_u, dt, modes=modes, sprung_mass=ms, unsprung_mass=mus, road_input=road_input,
            speed_mps=speed, seed=np.asarray(seeds), initial_stiffness=stiffness_from_pressure(
                np.asarray(initial_kpa) * 1e3),
        )  # fmt: skip
        for b, col in enumerate(columns):
            if est.mode_probability is not None:
                for s, letter in enumerate(est.classes):
                    col[f"mode_prob_{letter}"] = est.mode_probability[b, :, s]
            for s, letter in enumerate(est.classes):
                col[f"mode_pressure_{letter}_kpa"] = (
                    pressure_from_stiffness(est.mode_stiffness[b, :, s]) / 1e3
                )
    for b, (col, out) in enumerate(zip(columns, out_paths, strict=True)):
        table = pd.DataFrame(
            {
                "t_s": col.pop("t_s"),
                "pressure_hat_kpa": est.pressure_pa[b] / 1e3,
                "pressure_sigma_kpa": est.pressure_sigma_pa[b] / 1e3,
                "tire_stiffness_hat_npm": est.stiffness[b],
                "tire_stiffness_sigma_npm": est.stiffness_sigma[b],
                **col,
            }
        )
        atomic_write(out, lambda tmp, table=table: table.to_parquet(tmp, index=False, compression="zstd"))
    return out_paths


# ---------------------------------------------------------------- orchestration
class _Pool:
    """A process pool of `jobs` workers, or the calling process for ``jobs == 1``."""

    def __init__(self, jobs: int):
        self.executor = ProcessPoolExecutor(max_workers=jobs) if jobs > 1 else None

    def run(self, fn, tasks: list, *, desc: str, total: int | None, unit: str, progress: bool) -> None:
        """Run ``fn(task)`` for every task; the bar advances by ``len(result)`` or 1 per task."""
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=total if total is not None else len(tasks), desc=desc, unit=unit, leave=True)

        def advance(result):
            if bar is not None:
                bar.update(len(result) if isinstance(result, list) else 1)

        try:
            if self.executor is None:
                for task in tasks:
                    advance(fn(task))
                return
            pending: set[Future] = {self.executor.submit(fn, t) for t in tasks}
            try:
                while pending:
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    for future in done:
                        advance(future.result())
            except BaseException:
                for future in pending:
                    future.cancel()
                raise
        finally:
            if bar is not None:
                bar.close()

    def close(self) -> None:
        if self.executor is not None:
            self.executor.shutdown(wait=True, cancel_futures=True)


def _identification(config: CampaignConfig, out: Path, pool: _Pool, progress: bool) -> tuple[Path, dict]:
    """The parameter file the IMM uses: given, cached, or identified now."""
    if config.params_file is not None:
        if config.params_file == "paper":
            path = out / "identification" / "paper_table_3.json"
            path.parent.mkdir(parents=True, exist_ok=True)
            content = {"classes": PAPER_TABLE_3, "metadata": {"source": "Brancati & Tufano 2022, Table 3"}}
            atomic_write(
                path, lambda tmp: Path(tmp).write_text(json.dumps(content, indent=2, sort_keys=True))
            )
        else:
            path = IDENTIFIED_FILE if config.params_file == "identified" else Path(config.params_file)
        load_modes(path)  # validates
        return path, {"source": str(path), "cached": True, "wall_time_s": 0.0}
    ident = config.identification
    key = _digest(
        {
            "identification": ident.model_dump(),
            "corner": config.corner,
            "model": _model_fingerprint(IDENTIFICATION_SOURCES),
        }
    )
    folder = out / "identification" / key
    path = folder / "params.json"
    if path.is_file():
        return path, {"source": str(path), "cached": True, "wall_time_s": 0.0, "key": key}
    folder.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    todo = [c for c in ident.classes if not (folder / f"class_{c}.json").is_file()]
    tasks = [(c, ident.model_dump(), config.corner, progress, i, str(folder)) for i, c in enumerate(todo)]
    pool.run(_identify_class_to, tasks, desc="identification", total=len(tasks), unit="class", progress=False)
    results = []
    for c in ident.classes:
        part = json.loads((folder / f"class_{c}.json").read_text())
        results.append((c, part["parameters"], part["information"]))
    content = parameter_file_content(results, pop_size=ident.pop_size, n_gen=ident.n_gen, seed=ident.seed)
    write_parameter_file(content, path)
    wall = time.perf_counter() - started
    return path, {"source": str(path), "cached": False, "wall_time_s": wall, "key": key, "classes_run": todo}


def _identify_class_to(args: tuple) -> str:
    """Identify one class and write its parameters and information to ``class_{c}.json``."""
    road_class, ident, corner, progress, position, folder = args
    _, parameters, information = identify_class(
        road_class, duration_s=ident["duration_s"], seed=ident["seed"], pop_size=ident["pop_size"],
        n_gen=ident["n_gen"], corner=corner, progress=progress, position=position, figures=f"{folder}/fig",
    )  # fmt: skip
    text = json.dumps({"parameters": parameters, "information": information}, indent=1)
    path = Path(folder) / f"class_{road_class}.json"
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))
    return str(path)


def _remove_stale_temporaries(out: Path) -> None:
    """Delete temporary files a killed run left behind (finished files are never temporary)."""
    for pattern in ("runs/.*.tmp*", "estimates/*/.*.tmp*", "identification/*/.*.tmp*", ".*.tmp*"):
        for path in out.glob(pattern):
            path.unlink(missing_ok=True)


def run_campaign(config: CampaignConfig, out: str | Path, *, jobs: int = 1, progress: bool = False) -> dict:
    """Run (or resume) the campaign in folder `out`; write metrics and the report there.

    Returns the summary written to ``out/campaign.json`` (configuration, its hash, stage
    wall times, file names).
    """
    if jobs < 1:
        raise InputError(f"--jobs must be ≥ 1, got {jobs}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {str(out)!r} exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    _remove_stale_temporaries(out)
    started = time.perf_counter()
    timings: dict[str, float] = {}
    fingerprint = _model_fingerprint()
    specs = campaign_specs(config)
    pool = _Pool(jobs)
    try:
        t0 = time.perf_counter()
        params_path, ident_info = _identification(config, out, pool, progress)
        timings["identification_s"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        runs_dir = out / "runs"
        runs_dir.mkdir(exist_ok=True)
        run_paths = {s.name: runs_dir / f"{s.name}-{s.key(fingerprint)}.parquet" for s in specs}
        todo = [(s.scenario, str(run_paths[s.name])) for s in specs if not run_paths[s.name].is_file()]
        pool.run(_simulate_to, todo, desc="ground truth", total=len(todo), unit="run", progress=progress)
        timings["simulation_s"] = time.perf_counter() - t0
        timings["simulated_runs"] = len(todo)

        t0 = time.perf_counter()
        params_key = _digest(
            {
                "classes": json.loads(Path(params_path).read_text())["classes"],
                "code": _model_fingerprint(ESTIMATION_SOURCES),
            }
        )
        est_paths: dict[tuple[str, str], Path] = {}
        tasks = []
        for estimator in config.estimators:
            folder = out / "estimates" / f"{estimator}-{params_key}-{config.corner}"
            folder.mkdir(parents=True, exist_ok=True)
            missing = []
            for s in specs:
                key = _digest({"run": run_paths[s.name].name, "initial": s.initial_pressure_kpa})
                path = folder / f"{s.name}-{key}.parquet"
                est_paths[(estimator, s.name)] = path
                if not path.is_file():
                    missing.append(s)
            for i in range(0, len(missing), config.chunk_size):
                chunk = missing[i : i + config.chunk_size]
                tasks.append(
                    (
                        estimator, str(params_path), config.corner,
                        [str(run_paths[s.name]) for s in chunk],
                        [str(est_paths[(estimator, s.name)]) for s in chunk],
                        [s.initial_pressure_kpa for s in chunk],
                        [int(s.scenario["seed"]) for s in chunk],
                    )
                )  # fmt: skip
        n_est = sum(len(t[3]) for t in tasks)
        pool.run(_estimate_to, tasks, desc="estimation", total=n_est, unit="estimate", progress=progress)
        timings["estimation_s"] = time.perf_counter() - t0
        timings["estimates_made"] = n_est
    finally:
        pool.close()

    t0 = time.perf_counter()
    metrics, mc_table, series = score_campaign(config, specs, run_paths, est_paths)
    atomic_write(out / "metrics.csv", lambda tmp: metrics.to_csv(tmp, index=False, float_format="%.6g"))
    atomic_write(out / "monte_carlo.csv", lambda tmp: mc_table.to_csv(tmp, index=False, float_format="%.6g"))
    timings["scoring_s"] = time.perf_counter() - t0
    summary = {
        "config": config.model_dump(mode="json"),
        "config_hash": _digest(config.model_dump(mode="json")),
        "model": fingerprint,
        "identification": ident_info,
        "params_file": str(params_path),
        "runs": {s.name: str(run_paths[s.name].relative_to(out)) for s in specs},
        "versions": package_versions(("suvtwin", "mujoco", "numpy", "scipy", "pymoo", "numba")),
    }
    summary["timings"] = timings
    from suvtwin.pipeline.report import write_report

    t0 = time.perf_counter()
    write_report(out / "report.html", config, specs, metrics, mc_table, series, params_path, summary)
    timings["report_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - started
    atomic_write(out / "campaign.json", lambda tmp: Path(tmp).write_text(json.dumps(summary, indent=2)))
    return summary


# ---------------------------------------------------------------- scoring
MC_TIMES_S = (2.0, 5.0)


def score_campaign(
    config: CampaignConfig,
    specs: list[RunSpec],
    run_paths: dict[str, Path],
    est_paths: dict[tuple[str, str], Path],
) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Per-run metrics (one row per run and estimator), Monte Carlo indexes at 2 s, 5 s and the end,
    and the time series the report draws (kPa)."""
    corner = config.corner
    rows, series = [], {"truth": {}, "estimates": {}}
    for s in specs:
        run = pq.read_table(run_paths[s.name], columns=["t_s", f"{corner}_pressure_kpa"]).to_pandas()
        t, truth = run["t_s"].to_numpy(), run[f"{corner}_pressure_kpa"].to_numpy()
        series["truth"][s.name] = (t, truth)
        for estimator in config.estimators:
            est = pd.read_parquet(est_paths[(estimator, s.name)])
            series["estimates"][(estimator, s.name)] = est
            p_hat, sig = est["pressure_hat_kpa"].to_numpy(), est["pressure_sigma_kpa"].to_numpy()
            m = run_metrics(t, truth, p_hat, sig, tolerance=PRESSURE_TOLERANCE_KPA)
            error = p_hat - truth
            after = t >= 2.0
            row = {
                "kind": s.kind,
                "run": s.name,
                "estimator": estimator,
                "road_class": s.info.get("road_class", ""),
                "speed_kmh": s.scenario["speed_kmh"],
                "true_pressure_end_kpa": float(truth[-1]),
                "initial_estimate_kpa": s.initial_pressure_kpa,
                "estimate_end_kpa": float(p_hat[-1]),
                "error_2s_kpa": float(np.interp(2.0, t, error)),
                "error_end_kpa": float(error[-1]),
                "mean_abs_error_after_2s_pct": float(np.mean(np.abs(error[after]) / truth[after]) * 100),
                "max_abs_error_after_2s_kpa": float(np.max(np.abs(error[after]))),
                "time_to_converge_s": m.time_to_converge_s,
                "mean_error_kpa": m.mean_error,
                "rmse_kpa": m.rmse,
                "inside_1sigma": m.inside_1sigma,
                "inside_2sigma": m.inside_2sigma,
                "sigma_end_kpa": float(sig[-1]),
            }
            level = s.info.get("gd_n0_m3")
            if "road_level_hat_m3" in est and isinstance(level, float):
                # the road level the estimator found, over the level the road was made with
                row["road_level_ratio_end"] = float(est["road_level_hat_m3"].iloc[-1] / level)
            for letter in "ABCD":
                col = f"mode_prob_{letter}"
                if col in est:
                    row[f"{col}_mean"] = float(est[col].mean())
            rows.append(row)
    metrics = pd.DataFrame(rows)
    mc_rows = []
    mc = [s for s in specs if s.kind == "monte_carlo"]
    if mc:
        t = series["truth"][mc[0].name][0]
        truth = np.array([series["truth"][s.name][1] for s in mc])
        for estimator in config.estimators:
            p_hat = np.array([series["estimates"][(estimator, s.name)]["pressure_hat_kpa"] for s in mc])
            sig = np.array([series["estimates"][(estimator, s.name)]["pressure_sigma_kpa"] for s in mc])
            idx = monte_carlo_indexes(truth, p_hat, sig)
            series.setdefault("monte_carlo", {})[estimator] = (t, idx, truth - p_hat)
            for when in (*MC_TIMES_S, float(t[-1])):
                k = min(int(np.searchsorted(t, when - 1e-9)), t.size - 1)
                error = p_hat[:, k] - truth[:, k]
                mc_rows.append(
                    {
                        "estimator": estimator,
                        "t_s": float(t[k]),
                        "runs": len(mc),
                        "mean_error_kpa": float(idx.mean_error[k]),
                        "error_std_kpa": float(idx.error_std[k]),
                        "sigma_bound_kpa": float(idx.sigma_bound[k]),
                        "rmse_kpa": float(np.sqrt(np.mean(error**2))),
                        "inside_2sigma": float(np.mean(np.abs(error) <= 2 * sig[:, k])),
                        "within_5pct_p0": float(np.mean(np.abs(error) <= PRESSURE_TOLERANCE_KPA)),
                    }
                )
    return metrics, pd.DataFrame(mc_rows), series
