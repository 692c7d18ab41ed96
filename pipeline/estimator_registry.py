"""The estimators suvtwin runs and scores, each declared once.

Usual call: ``entry = ESTIMATORS["imm_synthetic"]; batch = entry.run(signals)``; the command line
finds an entry by family and road input: ``find_estimator("imm", "synthetic")``.

An entry names one way of estimating a tyre's pressure from a corner's two accelerometers:
its campaign name, its command-line family (``suvtwin estimate --estimator``) and road input
(``--road-input``), its runner (a batch of runs in, a :class:`BatchEstimate` out), the report's
label and colour, the columns it writes besides the common ones, and which comparisons of
paper 000 apply to it. The campaign (:mod:`suvtwin.pipeline.campaign`), the report
(:mod:`suvtwin.pipeline.report`), the command line and :mod:`suvtwin.pipeline.estimation`
read this table only. To add an estimator: write it in ``suvtwin.estimators`` (which never
imports the pipeline), write a runner here that calls it, and add its entry to
:data:`ESTIMATORS`.

Importing this module is cheap (no numpy, no estimator): the runners import their estimator
when called, so the command line can build its options from the table.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from suvtwin.errors import InputError

if TYPE_CHECKING:
    import numpy as np

__all__ = [
    "COMMON_COLUMNS",
    "ESTIMATORS",
    "BatchEstimate",
    "CornerSignals",
    "Estimator",
    "estimate_columns",
    "estimator_families",
    "estimator_help",
    "find_estimator",
    "road_inputs",
]

COMMON_COLUMNS = (
    "t_s",
    "pressure_hat_kpa",
    "pressure_sigma_kpa",
    "tire_stiffness_hat_npm",
    "tire_stiffness_sigma_npm",
)
"""Columns of every estimate file, in this order: time (s), pressure and its σ (kPa), tyre
vertical stiffness and its σ (N/m)."""


@dataclass(frozen=True)
class CornerSignals:
    """What every estimator reads: one corner's accelerometers over B runs of equal length.

    `acc_sprung`, `acc_unsprung`: vertical accelerations of body and wheel, m/s², shape (B, T),
    sampled every `dt` s; `speed_mps`: mean speed per run, m/s, shape (B,); `sprung_mass`,
    `unsprung_mass`: the corner's masses the estimator assumes, kg (paper 000 eq. 2);
    `params`: the mode parameter file of model-bank estimators (``"identified"``, ``"paper"``
    or a path); `seeds`: one int per run (synthetic roads); `initial_pressure_kpa`: the initial
    estimate per run, kPa, or None for the estimator's default; `tire_file`: the tyre the runs
    were made with (a ``.tir`` file; its k_t(p), eq. 3–4, and damping), None for the SUV's;
    `speed_series_mps`: the speed at every sample, m/s, shape (B, T), for estimators that use the
    speed as it is at each time (causal ones), None where only the mean is known;
    `static_travel_m`: the corner's static suspension compression under the runs' extra load, m
    (for estimators that linearize the suspension at the travel they measure); `vehicle`: the
    scenario's vehicle overrides the runs were made with (their corner model's spring, damper,
    anti-roll bar), None for the SUV's parameter file; `loads`: the runs' extra loads on the
    chassis, (kg, (x, y, z) m from its CoG) each, for estimators that model the whole car (the
    online monitor's full car); `static_load_n`: the corner tyre's static force under them, N
    (:func:`suvtwin.pipeline.estimation.corner_static_load`), None: the corner's masses times g;
    `accel_noise_mps2`: the accelerometers' white-noise σ per sample the runs record, m/s²
    (:func:`suvtwin.pipeline.estimation.run_accel_noise`), None where unknown.
    """

    acc_sprung: np.ndarray
    acc_unsprung: np.ndarray
    dt: float
    speed_mps: np.ndarray
    corner: str
    sprung_mass: float
    unsprung_mass: float
    params: str | Path = "identified"
    seeds: np.ndarray | None = None
    initial_pressure_kpa: np.ndarray | None = None
    tire_file: str | Path | None = None
    speed_series_mps: np.ndarray | None = None
    static_travel_m: float = 0.0
    vehicle: dict | None = None
    loads: tuple = ()
    static_load_n: float | None = None
    accel_noise_mps2: float | None = None


@dataclass(frozen=True)
class BatchEstimate:
    """An estimator's output over B runs: pressure and σ (Pa), stiffness and σ (N/m), shape (B, T);
    `columns`: its further columns, name → (B, T) array, in the order they are written; `info`:
    what made it (JSON-able, the same for the whole batch)."""

    pressure_pa: np.ndarray
    pressure_sigma_pa: np.ndarray
    stiffness: np.ndarray
    stiffness_sigma: np.ndarray
    columns: dict[str, np.ndarray] = field(default_factory=dict)
    info: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Estimator:
    """One estimator as the campaign, report and command line know it.

    `name`: campaign name (``metrics.csv``'s ``estimator``); `family` and `road_input`: the command
    line's ``--estimator`` and ``--road-input`` (None: the estimator takes no road input);
    `run`: the runner; `label`, `color`: the report's legend text and matplotlib colour;
    `description`: one sentence for ``--help``; `columns`: further output columns
    (``{c}`` stands for each mode's class letter); `mode_probabilities`: it writes
    ``mode_prob_{c}`` (the report draws them); `needs_classes`: mode classes the parameter file
    must hold; `single_model_baseline`: the entry this model bank is compared with (paper 000
    Fig. 6: the IMM against its single UKF, same road input); `tolerates_gaps`: it skips missing
    (NaN) accelerometer samples itself, so a record with some is not refused.
    """

    name: str
    family: str
    road_input: str | None
    run: Callable[[CornerSignals], BatchEstimate]
    label: str
    color: str
    description: str
    columns: tuple[str, ...] = ()
    mode_probabilities: bool = False
    needs_classes: tuple[str, ...] = ()
    single_model_baseline: str | None = None
    tolerates_gaps: bool = False


def _run_mode_bank(
    signals: CornerSignals, *, road_input: str, classes: tuple[str, ...] | None
) -> BatchEstimate:
    """Paper 000's IMM of UKFs over the parameter file's modes, or one UKF on `classes`
    (Brancati & Tufano 2022, §4)."""
    import numpy as np

    from suvtwin.estimators.quarter_car import pressure_from_stiffness, stiffness_from_pressure
    from suvtwin.estimators.tire_pressure import estimate_pressure, load_modes
    from suvtwin.tire_stiffness import tire_stiffness_of

    tire = tire_stiffness_of(signals.tire_file)
    law = asdict(tire)  # kt0, p0, pfz1

    modes = load_modes(signals.params)
    if classes is not None:
        missing = [c for c in classes if c not in modes.classes]
        if missing:
            raise InputError(
                f"the single UKF uses the class {', '.join(missing)} mode, which the parameter file lacks"
            )
        modes = modes.subset(classes)
    initial = None if signals.initial_pressure_kpa is None else np.asarray(signals.initial_pressure_kpa) * 1e3
    seeds = 0 if signals.seeds is None else np.asarray(signals.seeds)
    est = estimate_pressure(
        signals.acc_sprung, signals.acc_unsprung, signals.dt, modes=modes, sprung_mass=signals.sprung_mass,
        unsprung_mass=signals.unsprung_mass, road_input=road_input, speed_mps=signals.speed_mps, seed=seeds,
        initial_stiffness=None if initial is None else stiffness_from_pressure(initial, **law),
        tire=tire,
    )  # fmt: skip
    columns: dict[str, np.ndarray] = {}
    if est.mode_probability is not None:
        for s, letter in enumerate(est.classes):
            columns[f"mode_prob_{letter}"] = est.mode_probability[:, :, s]
    for s, letter in enumerate(est.classes):
        mode_pressure = pressure_from_stiffness(est.mode_stiffness[:, :, s], **law)
        columns[f"mode_pressure_{letter}_kpa"] = mode_pressure / 1e3
    return BatchEstimate(
        pressure_pa=est.pressure_pa,
        pressure_sigma_pa=est.pressure_sigma_pa,
        stiffness=est.stiffness,
        stiffness_sigma=est.stiffness_sigma,
        columns=columns,
        info={"covariance_repairs": int(est.repairs.sum()), **est.info},
    )


def _vehicle(signals: CornerSignals):
    """The vehicle parameters of the runs (:func:`suvtwin.mjcf.vehicle.load_vehicle` with their overrides)."""
    from suvtwin.mjcf.vehicle import load_vehicle

    return load_vehicle(overrides=signals.vehicle or None)


def _run_joint(signals: CornerSignals) -> BatchEstimate:
    """The road-level-free joint estimator on the corner's linear roll-plane model
    (:func:`suvtwin.pipeline.estimation.linear_corner_model`)."""
    from suvtwin.estimators.joint import estimate_joint
    from suvtwin.pipeline.estimation import linear_corner_model
    from suvtwin.tire_stiffness import tire_stiffness_of

    qc = linear_corner_model(signals.corner, signals.sprung_mass, tire_file=signals.tire_file,
                             vehicle=_vehicle(signals))  # fmt: skip
    est = estimate_joint(
        signals.acc_sprung, signals.acc_unsprung, signals.dt, qc=qc, speed_mps=signals.speed_mps,
        tire=tire_stiffness_of(signals.tire_file),
    )  # fmt: skip
    return BatchEstimate(
        pressure_pa=est.pressure_pa,
        pressure_sigma_pa=est.pressure_sigma_pa,
        stiffness=est.stiffness,
        stiffness_sigma=est.stiffness_sigma,
        columns={"road_level_hat_m3": est.road_level},
        info={
            "road_input": "estimated level",
            "quarter_car": {"spring_rate": qc.spring_rate, "damping": qc.damping},
            **est.info,
        },
    )


def _run_online(signals: CornerSignals) -> BatchEstimate:
    """The online monitor (:mod:`suvtwin.estimators.monitor`) on the corner alone, one stream per run,
    its estimate held from each update to the next (before the first: the prior). It assumes the
    sensor noise and the tyre's static load the signals carry, as ``suvtwin monitor`` does
    (:func:`suvtwin.pipeline.monitoring.assumed_accel_noise`)."""
    import numpy as np

    from suvtwin.estimators.monitor import MonitorConfig, TyreMonitor, pressure_at
    from suvtwin.pipeline.estimation import full_car_model, linear_corner_model
    from suvtwin.pipeline.monitoring import assumed_accel_noise
    from suvtwin.tire_stiffness import (
        stiffness_at_pressure_array,
        stiffness_sigma_at_pressure_sigma,
        tire_stiffness_of,
    )

    vehicle = _vehicle(signals)
    car = full_car_model(vehicle, signals.loads, tire_file=signals.tire_file)  # the corner in its car
    qc = linear_corner_model(signals.corner, signals.sprung_mass, tire_file=signals.tire_file,
                             static_travel=signals.static_travel_m, vehicle=vehicle,
                             full_car=car, static_load=signals.static_load_n)  # fmt: skip
    config, noise_source = assumed_accel_noise(MonitorConfig(), signals.accel_noise_mps2)
    tire = tire_stiffness_of(signals.tire_file)
    n_runs, n_steps = signals.acc_sprung.shape
    t = np.arange(n_steps) * signals.dt
    p = np.empty((n_runs, n_steps))
    sig = np.empty((n_runs, n_steps))
    observable = np.zeros((n_runs, n_steps))
    level = np.full((n_runs, n_steps), np.nan)
    used = []
    for b in range(n_runs):
        speed = (signals.speed_series_mps[b] if signals.speed_series_mps is not None
                 else np.full(n_steps, signals.speed_mps[b]))  # fmt: skip
        monitor = TyreMonitor([qc], dt=signals.dt, tire=tire, names=[signals.corner], config=config)
        out = monitor.update(t, speed, signals.acc_sprung[b][:, None], signals.acc_unsprung[b][:, None])
        pb, sb = pressure_at(out, t, monitor.prior_pa, monitor.prior_sigma_pa)
        p[b], sig[b] = pb[:, 0], sb[:, 0]
        idx = np.searchsorted(out.t_s, t, side="right") - 1
        seen = idx >= 0
        observable[b, seen] = out.observable[idx[seen], 0]
        level[b, seen] = out.road_level[idx[seen]]
        used.append(int(monitor.counts["used"][0]))
    law = (tire.kt0, tire.p0, tire.pfz1)
    return BatchEstimate(
        pressure_pa=p,
        pressure_sigma_pa=sig,
        stiffness=stiffness_at_pressure_array(p, *law),
        stiffness_sigma=stiffness_sigma_at_pressure_sigma(sig, *law),
        columns={"observable": observable, "road_level_hat_m3": level},
        info={
            "road_input": "estimated level",
            "causal": True,
            "config": asdict(config),
            "accel_noise_source": noise_source,
            "windows_used": used,
        },
    )


_MODE_BANK_COLUMNS = ("mode_prob_{c}", "mode_pressure_{c}_kpa")

_IMM = "paper 000's IMM of one UKF per road class (A-D) of the parameter file"
_UKF = "paper 000's single UKF (class A mode)"


def _mode_bank(road_input: str, classes: tuple[str, ...] | None = None) -> Callable:
    return partial(_run_mode_bank, road_input=road_input, classes=classes)


ESTIMATORS: dict[str, Estimator] = {
    e.name: e
    for e in (
        Estimator(name="imm_synthetic", family="imm", road_input="synthetic", run=_mode_bank("synthetic"),
                  label="IMM, synthetic road (paper)", color="tab:red", description=_IMM,
                  columns=_MODE_BANK_COLUMNS, mode_probabilities=True, single_model_baseline="ukf_synthetic"),
        Estimator(name="imm_augmented", family="imm", road_input="augmented", run=_mode_bank("augmented"),
                  label="IMM, augmented road", color="tab:orange", description=_IMM,
                  columns=_MODE_BANK_COLUMNS, mode_probabilities=True, single_model_baseline="ukf_augmented"),
        Estimator(name="ukf_synthetic", family="ukf", road_input="synthetic",
                  run=_mode_bank("synthetic", classes=("A",)),
                  label="single UKF, synthetic road (paper)", color="tab:blue", description=_UKF,
                  columns=("mode_pressure_A_kpa",), needs_classes=("A",)),
        Estimator(name="ukf_augmented", family="ukf", road_input="augmented",
                  run=_mode_bank("augmented", classes=("A",)),
                  label="single UKF, augmented road", color="tab:cyan", description=_UKF,
                  columns=("mode_pressure_A_kpa",), needs_classes=("A",)),
        Estimator(name="joint", family="joint", road_input=None, run=_run_joint,
                  label="joint (road level estimated)", color="tab:green",
                  description="the road-level-free estimator on the corner's linear roll-plane model "
                  "(road level and waviness estimated)", columns=("road_level_hat_m3",)),
        Estimator(name="online", family="online", road_input=None, run=_run_online,
                  label="online monitor (causal)", color="tab:purple",
                  description="the online monitor (ours): causal, streaming, follows pressure changes, "
                  "flags what it cannot observe", columns=("observable", "road_level_hat_m3"),
                  tolerates_gaps=True),
    )
}  # fmt: skip
"""Every estimator, by campaign name. ``imm_*``: paper 000's IMM of four UKFs with the paper's
synthetic road or a road state (augmented); ``ukf_*``: its single UKF (mode A); ``joint``: the
road-level-free estimator."""


def estimator_families() -> tuple[str, ...]:
    """The command line's ``--estimator`` values, in registry order."""
    return tuple(dict.fromkeys(e.family for e in ESTIMATORS.values()))


def road_inputs() -> tuple[str, ...]:
    """The command line's ``--road-input`` values, in registry order."""
    return tuple(dict.fromkeys(e.road_input for e in ESTIMATORS.values() if e.road_input is not None))


def find_estimator(family: str, road_input: str | None) -> Estimator:
    """The entry of a command-line family and road input (ignored by families that take none)."""
    entries = [e for e in ESTIMATORS.values() if e.family == family]
    if not entries:
        raise InputError(f"--estimator must be one of {', '.join(estimator_families())}, got {family!r}")
    for e in entries:
        if e.road_input is None or e.road_input == road_input:
            return e
    allowed = ", ".join(str(e.road_input) for e in entries)
    raise InputError(f"--road-input for --estimator {family} must be one of {allowed}, got {road_input!r}")


def estimate_columns(batch: BatchEstimate, b: int, t_s: np.ndarray) -> dict[str, np.ndarray]:
    """The columns of run `b`'s estimate file: :data:`COMMON_COLUMNS` (kPa, N/m), then the
    estimator's own."""
    return {
        "t_s": t_s,
        "pressure_hat_kpa": batch.pressure_pa[b] / 1e3,
        "pressure_sigma_kpa": batch.pressure_sigma_pa[b] / 1e3,
        "tire_stiffness_hat_npm": batch.stiffness[b],
        "tire_stiffness_sigma_npm": batch.stiffness_sigma[b],
        **{name: values[b] for name, values in batch.columns.items()},
    }


def estimator_help() -> str:
    """The command line's help of ``--estimator``: each family and what it is."""
    first = {e.family: e for e in reversed(ESTIMATORS.values())}
    return "; ".join(f"{f}: {first[f].description}" for f in estimator_families()) + "."
