"""Execution of a campaign: a process pool, the workers, and the stages in order.

Usual call: ``summary = run_campaign(preset("quick"), "results/", jobs=2, progress=True)``.

Stages (Brancati & Tufano 2022, §5.2–5.4): identification (or a given parameter file),
ground-truth runs, estimation (each estimator of the configuration, from
:data:`suvtwin.pipeline.estimator_registry.ESTIMATORS`, on the chosen corner's accelerometers,
with the *nominal* corner masses, paper 000 eq. 2), scoring
(:mod:`suvtwin.pipeline.campaign.metrics`), paper 000's premise check (its IMM on its own quarter
car, roads at the class centres: :mod:`suvtwin.pipeline.premise`, ``premise.csv``) and the report
(:mod:`suvtwin.pipeline.report`).
Every unit of work is a file of the content-addressed cache
(:mod:`suvtwin.pipeline.campaign.cache`), so a re-run reuses finished work and an interrupted
run resumes where it stopped. Each estimate depends on its own run only (per-run seeds; the
batched filters are independent across the batch), so a resumed campaign gives the same bytes
as an uninterrupted one. A cached file is verified before it is reused (its recorded SHA-256:
:func:`~suvtwin.pipeline.campaign.cache.verify_cached`); a damaged one is reported and made
again. One process works in a campaign folder at a time
(:func:`~suvtwin.pipeline.campaign.cache.campaign_lock`).
"""

from __future__ import annotations

import json
import time
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path

import numpy as np

from suvtwin.errors import InputError
from suvtwin.estimators.tire_pressure import IDENTIFIED_FILE, PAPER_TABLE_3, load_modes
from suvtwin.files import atomic_write, package_versions
from suvtwin.pipeline.campaign.cache import (
    ESTIMATION_SOURCES,
    IDENTIFICATION_SOURCES,
    PREMISE_SOURCES,
    SIMULATION_SOURCES,
    campaign_lock,
    digest,
    drop_inherited_lock,
    lock_identity,
    model_fingerprint,
    record_digest,
    remove_stale_temporaries,
    sidecar,
    verify_cached,
    write_cached,
)
from suvtwin.pipeline.campaign.config import CampaignConfig
from suvtwin.pipeline.campaign.metrics import score_campaign
from suvtwin.pipeline.campaign.runs import RunSpec, campaign_specs
from suvtwin.pipeline.estimator_registry import ESTIMATORS, CornerSignals, estimate_columns
from suvtwin.pipeline.identification_runs import (
    corner_masses,
    identify_class,
    parameter_file_content,
    write_parameter_file,
)
from suvtwin.pipeline.scenario import parse_scenario

__all__ = ["run_campaign"]


def _simulate_to(args: tuple[dict, str]) -> str:
    from suvtwin.pipeline.simulator import simulate, write_run

    scenario, path = args
    result = simulate(parse_scenario(scenario, source="campaign scenario"))
    write_cached(path, lambda tmp: write_run(result, tmp))
    return path


def _read_corner(path: str, corner: str) -> dict:
    import pyarrow.parquet as pq

    columns = ["t_s", "speed_mps", f"{corner}_accel_sprung_mps2", f"{corner}_accel_unsprung_mps2"]
    frame = pq.read_table(path, columns=columns).to_pandas()
    return {
        "t": frame["t_s"].to_numpy(),
        "speed": float(frame["speed_mps"].mean()),
        "speed_series": frame["speed_mps"].to_numpy(dtype=float),
        "acc_s": frame[columns[2]].to_numpy(),
        "acc_u": frame[columns[3]].to_numpy(),
    }


def _estimate_to(args: tuple) -> list[str]:
    """Run one estimator on a batch of runs and write one estimate file per run."""
    import pandas as pd

    estimator, params_path, corner, run_paths, out_paths, initial_kpa, seeds = args
    data = [_read_corner(p, corner) for p in run_paths]
    if len({d["t"].size for d in data}) != 1:
        raise InputError("a batch of runs must have equal lengths")
    acc_s = np.array([d["acc_s"] for d in data])
    acc_u = np.array([d["acc_u"] for d in data])
    speed = np.array([max(d["speed"], 1.0) for d in data])
    dt = float(np.mean(np.diff(data[0]["t"])))
    ms, mus = corner_masses(corner)
    signals = CornerSignals(
        acc_sprung=acc_s, acc_unsprung=acc_u, dt=dt, speed_mps=speed, corner=corner, sprung_mass=ms,
        unsprung_mass=mus, params=params_path, seeds=np.asarray(seeds),
        initial_pressure_kpa=np.asarray(initial_kpa),
        speed_series_mps=np.array([d["speed_series"] for d in data]),
    )  # fmt: skip
    batch = ESTIMATORS[estimator].run(signals)
    for b, out in enumerate(out_paths):
        table = pd.DataFrame(estimate_columns(batch, b, data[b]["t"]))
        write_cached(out, lambda tmp, table=table: table.to_parquet(tmp, index=False, compression="zstd"))
    return out_paths


# ---------------------------------------------------------------- orchestration
class _Pool:
    """A process pool of `jobs` workers, or the calling process for ``jobs == 1``. `lock`: the
    campaign lock's identity (:func:`~suvtwin.pipeline.campaign.cache.lock_identity`), which forked
    workers let go of, so that workers orphaned by a killed parent never hold the folder."""

    def __init__(self, jobs: int, lock: tuple[int, int, int] | None = None):
        self.executor = None
        if jobs > 1:
            self.executor = ProcessPoolExecutor(max_workers=jobs, initializer=drop_inherited_lock,
                                                initargs=(lock,))  # fmt: skip

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
    key = digest(
        {
            "identification": ident.model_dump(),
            "corner": config.corner,
            "model": model_fingerprint(IDENTIFICATION_SOURCES),
        }
    )
    folder = out / "identification" / key
    path = folder / "params.json"
    if verify_cached(path):
        return path, {"source": str(path), "cached": True, "wall_time_s": 0.0, "key": key}
    folder.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    todo = [c for c in ident.classes if not verify_cached(folder / f"class_{c}.json")]
    tasks = [(c, ident.model_dump(), config.corner, progress, i, str(folder)) for i, c in enumerate(todo)]
    pool.run(_identify_class_to, tasks, desc="identification", total=len(tasks), unit="class", progress=False)
    results = []
    for c in ident.classes:
        part = json.loads((folder / f"class_{c}.json").read_text())
        results.append((c, part["parameters"], part["information"]))
    content = parameter_file_content(results, pop_size=ident.pop_size, n_gen=ident.n_gen, seed=ident.seed)
    write_parameter_file(content, path)
    record_digest(path)  # killed before this: read in full when next reused, then recorded
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
    write_cached(path, lambda tmp: Path(tmp).write_text(text))
    return str(path)


def _simulation(specs: list[RunSpec], fingerprint: dict, out: Path, pool: _Pool, progress: bool
                ) -> tuple[dict[str, Path], int]:  # fmt: skip
    """The ground-truth runs: their files by run name (simulated now unless cached), and how many
    were simulated."""
    runs_dir = out / "runs"
    runs_dir.mkdir(exist_ok=True)
    run_paths = {s.name: runs_dir / f"{s.name}-{s.key(fingerprint)}.parquet" for s in specs}
    todo = [(s.scenario, str(run_paths[s.name])) for s in specs if not verify_cached(run_paths[s.name])]
    pool.run(_simulate_to, todo, desc="ground truth", total=len(todo), unit="run", progress=progress)
    return run_paths, len(todo)


def _estimation(
    config: CampaignConfig,
    specs: list[RunSpec],
    run_paths: dict[str, Path],
    params_path: Path,
    out: Path,
    pool: _Pool,
    progress: bool,
) -> tuple[dict[tuple[str, str], Path], int]:
    """Every estimator on every run: the estimate files by (estimator, run) (made now unless cached),
    and how many were made. Runs are estimated in batches of ``config.chunk_size``."""
    params_key = digest(
        {
            "classes": json.loads(Path(params_path).read_text())["classes"],
            "code": model_fingerprint(ESTIMATION_SOURCES),
        }
    )
    est_paths: dict[tuple[str, str], Path] = {}
    tasks = []
    for estimator in config.estimators:
        folder = out / "estimates" / f"{estimator}-{params_key}-{config.corner}"
        folder.mkdir(parents=True, exist_ok=True)
        missing = []
        for s in specs:
            key = digest({"run": run_paths[s.name].name, "initial": s.initial_pressure_kpa})
            path = folder / f"{s.name}-{key}.parquet"
            est_paths[(estimator, s.name)] = path
            if not verify_cached(path):
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
    return est_paths, n_est


def _premise(config: CampaignConfig, out: Path):
    """Paper 000's premise check (:mod:`suvtwin.pipeline.premise`): its summary per class and
    estimator (None when the configuration asks for no runs), and whether it was run now. The
    runs' scores are cached in ``premise/runs-<key>.csv``; the summary is always made from that file."""
    if config.premise_runs_per_class == 0:
        return None, False
    import pandas as pd

    from suvtwin.pipeline.premise import premise_study, premise_summary

    key = digest(
        {"runs_per_class": config.premise_runs_per_class, "seed": config.seed,
         "model": model_fingerprint(PREMISE_SOURCES)}
    )  # fmt: skip
    path = out / "premise" / f"runs-{key}.csv"
    made = not verify_cached(path)
    if made:
        runs = premise_study(config.premise_runs_per_class, seed=config.seed)
        path.parent.mkdir(exist_ok=True)
        write_cached(path, lambda tmp: runs.to_csv(tmp, index=False, float_format="%.6g"))
    return premise_summary(pd.read_csv(path)), made


def _json_ready(obj):
    """The monitor study as plain JSON: numpy scalars as Python numbers, NaN and inf as null."""
    if isinstance(obj, dict):
        return {str(k): _json_ready(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_ready(v) for v in obj]
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if np.isfinite(obj) else None
    return obj


def _write_study(path: Path, study: dict | None) -> None:
    """Write a study's results as JSON (atomically), or remove the file of an earlier configuration
    when this one asked for none."""
    if study is None:
        path.unlink(missing_ok=True)
        return
    text = json.dumps(study, indent=1)
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))


def _input_estimation_study(config: CampaignConfig, out: Path) -> dict | None:
    """Paper 001's input-estimation study on the SUV (:func:`suvtwin.pipeline.input_estimation.
    input_estimation_study`, scenario and noise seed ``config.seed``), written to
    ``out/input_estimation.json``; None (and no such file left) when the configuration asks for none.
    Nine 1.5 s simulations and the estimators: ~20 s, not cached."""
    path = out / "input_estimation.json"
    if config.input_estimation_seeds == 0:
        path.unlink(missing_ok=True)
        return None
    from suvtwin.pipeline.input_estimation import input_estimation_study

    study = input_estimation_study(n_seeds=config.input_estimation_seeds, seed=config.seed)
    text = json.dumps(study)
    atomic_write(path, lambda tmp: Path(tmp).write_text(text))
    return study


def _monitor_study(config: CampaignConfig, out: Path, jobs: int) -> dict | None:
    """The online monitor's study: the ``slow_leak`` and ``warning`` sets of
    :mod:`suvtwin.pipeline.monitor_scenarios` (their own seeds, levels anywhere in the class band),
    simulated into ``out/monitor/<set>/`` (cached by scenario and simulator code), all four tyres
    monitored (the warning runs against their placard), scored by
    :func:`suvtwin.pipeline.monitor_scoring.score_set` beside issue 12's targets. For each set also
    one run's trace of its changed or deflated tyre, for the report's figure. None if no runs."""
    sets = [("slow_leak", config.monitor_leak_runs), ("warning", config.monitor_warning_runs)]
    if not any(n for _, n in sets):
        return None
    from suvtwin.pipeline.monitor_scenarios import monitor_traces, run_key, scenario_set, simulate_cached
    from suvtwin.pipeline.monitor_scoring import issue_targets, score_set

    study: dict = {}
    fingerprint = model_fingerprint()
    for name, n in sets:
        if n == 0:
            continue
        runs = scenario_set(name, n)
        folder = out / "monitor" / name
        # simulate_cached writes <run key>.parquet (or <run key>.failed.json) without records: check
        # what it will reuse here, and record what it made
        for r in runs:
            key = run_key(r.scenario, fingerprint)
            verify_cached(folder / f"{key}.parquet")
            verify_cached(folder / f"{key}.failed.json")
        paths, simulation = simulate_cached(runs, folder, jobs=jobs)
        for path in paths:
            if path is not None and not sidecar(path).is_file():
                record_digest(path)
        kept = [(r, p) for r, p in zip(runs, paths, strict=True) if p is not None]
        traces, _, cost = monitor_traces([r for r, _ in kept], [p for _, p in kept], jobs=jobs)
        done = [(r, t) for (r, _), t in zip(kept, traces, strict=True) if t is not None]
        scores = score_set(name, [t for _, t in done], [r.info for r, _ in done])
        example = None
        if done:
            run, trace = done[0]
            tyre = run.info["change"]["tire"] if "change" in run.info else run.info["deflated"][0]
            c = ("fl", "fr", "rl", "rr").index(tyre)
            example = {"run": run.name, "tyre": tyre, "t_s": trace.t_s[::100].tolist(),
                       "truth_kpa": trace.truth_kpa[::100, c].tolist(), "t_est_s": trace.t_est.tolist(),
                       "p_hat_kpa": trace.p_hat[:, c].tolist(), "sigma_kpa": trace.sigma[:, c].tolist(),
                       "warning": trace.warning[:, c].tolist(), "placard_kpa": run.placard_kpa}  # fmt: skip
        study[name] = {
            "scores": scores,
            "targets": issue_targets(name, scores),
            "simulation_failed": simulation.get("failed", {}),
            "monitor_failed": cost["failed"],
            "monitor_realtime_factor": cost["realtime_factor"],
            "example": example,
        }
    return study


ROAD_ESTIMATION_SOURCES = (*SIMULATION_SOURCES, "suvtwin.estimators.road_estimation",
                           "suvtwin.pipeline.road_estimation", "suvtwin.roads")  # fmt: skip
"""What the road-profile study is made by (besides its seeds)."""


def _road_estimation_study(config: CampaignConfig, out: Path) -> tuple[dict | None, bool]:
    """The road-profile study on the SUV (:func:`suvtwin.pipeline.road_estimation.mujoco_study`, Wang
    et al. 2017's Table 2) with ``config.road_estimation_seeds`` seeds (None when 0), and whether it
    was made now. Cached in ``road_estimation/study-<key>.json`` (key: seeds and code)."""
    if config.road_estimation_seeds == 0:
        return None, False
    from suvtwin.pipeline.road_estimation import mujoco_study

    seeds = list(range(config.road_estimation_seeds))
    key = digest({"seeds": seeds, "model": model_fingerprint(ROAD_ESTIMATION_SOURCES)})
    path = out / "road_estimation" / f"study-{key}.json"
    made = not verify_cached(path)
    if made:
        text = json.dumps(_json_ready(mujoco_study(seeds)), indent=1)
        path.parent.mkdir(exist_ok=True)
        write_cached(path, lambda tmp: Path(tmp).write_text(text))
    return json.loads(path.read_text()), made


LATERAL_DETECTION_SOURCES = (*SIMULATION_SOURCES, "suvtwin.estimators.lateral_detection",
                             "suvtwin.pipeline.lateral_detection",
                             "suvtwin.pipeline.monitor_scenarios")  # fmt: skip
"""What the lateral detection study is made by (besides its number of runs)."""


def _lateral_detection_study(config: CampaignConfig, out: Path, jobs: int) -> tuple[dict | None, bool]:
    """Solmaz's detector on ``config.lateral_detection_runs`` ISO 3888-1 lane changes per tyre case
    (:func:`suvtwin.pipeline.lateral_detection.monte_carlo_study`; runs in
    ``lateral_detection/runs/``), None when 0, and whether it was made now. Cached in
    ``lateral_detection/study-<key>.json`` (key: runs and code)."""
    if config.lateral_detection_runs == 0:
        return None, False
    from suvtwin.pipeline.lateral_detection import monte_carlo_study

    n = config.lateral_detection_runs
    key = digest({"runs": n, "model": model_fingerprint(LATERAL_DETECTION_SOURCES)})
    path = out / "lateral_detection" / f"study-{key}.json"
    made = not verify_cached(path)
    if made:
        study = monte_carlo_study(n, out / "lateral_detection" / "runs", jobs=jobs)
        text = json.dumps(_json_ready(study))
        path.parent.mkdir(exist_ok=True)
        write_cached(path, lambda tmp: Path(tmp).write_text(text))
    return json.loads(path.read_text()), made


def run_campaign(config: CampaignConfig, out: str | Path, *, jobs: int = 1, progress: bool = False) -> dict:
    """Run (or resume) the campaign in folder `out`; write metrics and the report there.

    Returns the summary written to ``out/campaign.json`` (configuration, its hash, stage
    wall times, file names). One process at a time works in `out`: another one running there
    raises :class:`~suvtwin.errors.InputError` naming it, before anything is written or removed.
    """
    if jobs < 1:
        raise InputError(f"--jobs must be ≥ 1, got {jobs}")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {str(out)!r} exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    with campaign_lock(out) as lock:
        remove_stale_temporaries(out)
        return _run_locked(config, out, jobs, progress, lock_identity(lock))


def _run_locked(config: CampaignConfig, out: Path, jobs: int, progress: bool,
                lock: tuple[int, int, int] | None) -> dict:  # fmt: skip
    """:func:`run_campaign` once the folder is held."""
    started = time.perf_counter()
    timings: dict[str, float] = {}
    fingerprint = model_fingerprint()
    specs = campaign_specs(config)
    pool = _Pool(jobs, lock)
    try:
        t0 = time.perf_counter()
        params_path, ident_info = _identification(config, out, pool, progress)
        timings["identification_s"] = time.perf_counter() - t0

        t0 = time.perf_counter()
        run_paths, simulated = _simulation(specs, fingerprint, out, pool, progress)
        timings["simulation_s"] = time.perf_counter() - t0
        timings["simulated_runs"] = simulated

        t0 = time.perf_counter()
        est_paths, made = _estimation(config, specs, run_paths, params_path, out, pool, progress)
        timings["estimation_s"] = time.perf_counter() - t0
        timings["estimates_made"] = made
    finally:
        pool.close()

    t0 = time.perf_counter()
    metrics, mc_table, series = score_campaign(config, specs, run_paths, est_paths)
    atomic_write(out / "metrics.csv", lambda tmp: metrics.to_csv(tmp, index=False, float_format="%.6g"))
    atomic_write(out / "monte_carlo.csv", lambda tmp: mc_table.to_csv(tmp, index=False, float_format="%.6g"))
    timings["scoring_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    premise, timings["premise_made"] = _premise(config, out)
    if premise is not None:
        atomic_write(out / "premise.csv", lambda tmp: premise.to_csv(tmp, index=False, float_format="%.6g"))
    else:  # none asked for: no premise.csv of an earlier configuration left beside these results
        (out / "premise.csv").unlink(missing_ok=True)
    timings["premise_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    monitor = _monitor_study(config, out, jobs)
    if monitor is not None:
        monitor = _json_ready(monitor)
    _write_study(out / "monitor.json", monitor)
    timings["monitor_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    input_estimation = _input_estimation_study(config, out)
    timings["input_estimation_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    road_estimation, timings["road_estimation_made"] = _road_estimation_study(config, out)
    _write_study(out / "road_estimation.json", road_estimation)
    timings["road_estimation_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    lateral_detection, timings["lateral_detection_made"] = _lateral_detection_study(config, out, jobs)
    _write_study(out / "lateral_detection.json", lateral_detection)
    timings["lateral_detection_s"] = time.perf_counter() - t0
    summary = {
        "config": config.model_dump(mode="json"),
        "config_hash": digest(config.model_dump(mode="json")),
        "model": fingerprint,
        "identification": ident_info,
        "params_file": str(params_path),
        "runs": {s.name: str(run_paths[s.name].relative_to(out)) for s in specs},
        "versions": package_versions(("suvtwin", "mujoco", "numpy", "scipy", "pymoo", "numba")),
    }
    summary["timings"] = timings
    from suvtwin.pipeline.report import write_report

    t0 = time.perf_counter()
    write_report(out / "report.html", config, specs, metrics, mc_table, series, params_path, summary,
                 premise=premise, monitor=monitor, input_estimation=input_estimation,
                 road_estimation=road_estimation, lateral_detection=lateral_detection)  # fmt: skip
    timings["report_s"] = time.perf_counter() - t0
    timings["total_s"] = time.perf_counter() - started
    atomic_write(out / "campaign.json", lambda tmp: Path(tmp).write_text(json.dumps(summary, indent=2)))
    return summary
