r"""Paper 000's premise check: its IMM on its own quarter car, on roads at the class centres.

Usual call: ``runs = premise_study(runs_per_class=3, seed=2022)``, then
``table = premise_summary(runs)`` (one row per road class and estimator).

Brancati & Tufano 2022 claim that their IMM of four UKFs (one quarter car per ISO road
class A–D, Table 3) estimates the tyre pressure within a few seconds without knowing the
road, and better than a single UKF (§5.3–5.4, Fig. 6–9). This study gives the method the
most favourable truth there is, the conditions its claims were made under:

- the truth *is* the paper's quarter car (eq. 1, non-linear spring and damper) with the
  Table 3 parameters of the class being driven, the corner masses of Table 1 (eq. 2:
  sprung 466.7 kg, unsprung 61.14 kg) and k_t(p) of eq. 3–4 (k_t0 = 264.7 kN/m at
  p0 = 250 kPa; PFZ1 of the SUV's tyre file), integrated finely (RK4, 2 substeps per
  sample, :func:`suvtwin.estimators.quarter_car.simulate_quarter_car`); the damper's
  quadratic term is the sign-preserving :math:`|\dot d|\dot d`, as in the estimator;
- the road is the paper's own (the first-order shape filter of eq. 5–7, α = 0.127 rad/m,
  calibrated to the ISO level, :func:`suvtwin.roads.profile.generate_road` with
  ``method="shape-filter"``) with its level exactly at the class centre (ISO 8608 geometric
  mean of the band, :func:`suvtwin.roads.iso8608.class_level`), the level each IMM mode assumes;
- the draws of Table 4: pressure uniform 130–230 kPa, speed uniform 40–80 km/h; 10 s per
  run (Fig. 7: "after 2 of 10 s"); accelerometer noise 0.5 m/s² (§5.3);
- the estimators are the registry's, unchanged
  (:data:`suvtwin.pipeline.estimator_registry.ESTIMATORS`), with the modes of Table 3
  (``params="paper"``): the IMM and the single UKF (mode A), each with the paper's
  synthetic road input and with the augmented road state. Two controls, not the paper's
  method (:data:`CONTROLS`), run the same filters given the true road: they tell a filter
  that does not work from a premise that does not hold.

Not stated by the paper, taken from the campaign's defaults: sampling at 1 kHz, the initial
pressure estimate drawn from N(p_true, 60 kPa) (the paper: x̂0 ~ N(x0, P0), P0 not given),
clipped to 80–350 kPa.

Each run's draws depend on (seed, class, index) only, so a bigger study with the same seed
shares a smaller one's runs. The scores are those of the campaign
(:mod:`suvtwin.pipeline.scoring`): per run :func:`~suvtwin.pipeline.scoring.run_metrics`,
per class the indexes of eq. 23–25 at the end (:func:`~suvtwin.pipeline.scoring.monte_carlo_indexes`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from suvtwin.errors import InputError
from suvtwin.estimators.quarter_car import (
    QuarterCar,
    simulate_quarter_car,
    sprung_mass_share,
    stiffness_from_pressure,
)
from suvtwin.estimators.tire_pressure import PAPER_TABLE_3, estimate_pressure, load_modes
from suvtwin.pipeline.estimator_registry import ESTIMATORS, BatchEstimate, CornerSignals
from suvtwin.pipeline.scoring import PRESSURE_TOLERANCE_KPA, monte_carlo_indexes, run_metrics
from suvtwin.roads.iso8608 import class_level
from suvtwin.roads.profile import generate_road
from suvtwin.roads.spec import RoadSpec, SegmentSpec

__all__ = [
    "PAPER_CLASSES",
    "PAPER_DURATION_S",
    "PAPER_PRESSURE_KPA",
    "PAPER_SPEED_KMH",
    "PAPER_SPRUNG_MASS",
    "PAPER_UNSPRUNG_MASS",
    "BASELINES",
    "CONTROLS",
    "PREMISE_ESTIMATORS",
    "PremiseTruth",
    "premise_study",
    "premise_summary",
    "premise_truth",
]

PAPER_CLASSES = "ABCD"
"""The road classes of the IMM's modes (Table 3)."""
PAPER_PRESSURE_KPA = (130.0, 230.0)
"""Table 4: true pressure, uniform, kPa."""
PAPER_SPEED_KMH = (40.0, 80.0)
"""Table 4: speed, uniform, km/h."""
PAPER_DURATION_S = 10.0
"""Length of a run, s (Fig. 7–9: 10 s)."""
PAPER_SPRUNG_MASS = sprung_mass_share(1788.0, a_opposite=1.471, wheelbase=1.347 + 1.471)
"""Front corner sprung mass, kg: eq. 2 with Table 1 (chassis 1788 kg, a1 1.347 m, a2 1.471 m)."""
PAPER_UNSPRUNG_MASS = 61.14
"""Front wheel mass, kg (Table 1)."""
NOISE_MPS2 = 0.5
"""Accelerometer noise std, m/s² (§5.3)."""
TIMESTEP_S = 1e-3
"""Sample interval, s (not stated by the paper; the campaign's 1 kHz)."""
INITIAL_SIGMA_KPA = 60.0
"""Std of the initial pressure estimate around the truth, kPa (the campaign's default)."""
PREMISE_ESTIMATORS = ("imm_synthetic", "imm_augmented", "ukf_synthetic", "ukf_augmented")
"""Paper 000's IMM and single UKF, with the paper's synthetic road and with the road state."""
CONTROLS: dict[str, str] = {
    "imm_true_road": "IMM, true road given (control)",
    "ukf_true_road": "single UKF, true road given (control)",
}
"""Controls, not the paper's method: the same filters given the true road (an oracle). If they
meet the claims where the paper's road inputs do not, the filters work and what fails is the
premise that the unknown road can be stood in for."""
BASELINES: dict[str, str] = {
    **{name: e.single_model_baseline for name, e in ESTIMATORS.items() if e.single_model_baseline},
    "imm_true_road": "ukf_true_road",
}
"""Each model bank of the study → its single-UKF baseline (paper 000 Fig. 6)."""


@dataclass(frozen=True)
class PremiseTruth:
    """The quarter-car runs of the study; arrays over runs first.

    Attributes
    ----------
    road_class : (B,) class letter driven (and of the truth's Table 3 parameters)
    gd_n0 : (B,) road level, m³ (the class centre)
    pressure_kpa : (B,) true pressure, kPa
    speed_mps : (B,) speed, m/s
    initial_pressure_kpa : (B,) the estimators' initial pressure, kPa
    road_seed : (B,) seed of each run's road
    estimator_seed : (B,) seed of the estimators' synthetic roads, drawn apart from `road_seed`
        (the road generator and the estimators' synthetic roads are the same shape filter: with
        one seed the class's synthetic road would be the true road)
    road : (B, T) elevation under the tyre, m
    acc : (B, T, 2) measured sprung and unsprung acceleration (truth + noise), m/s²
    dt : sample interval, s
    """

    road_class: np.ndarray
    gd_n0: np.ndarray
    pressure_kpa: np.ndarray
    speed_mps: np.ndarray
    initial_pressure_kpa: np.ndarray
    road_seed: np.ndarray
    estimator_seed: np.ndarray
    road: np.ndarray
    acc: np.ndarray
    dt: float


def premise_truth(
    runs_per_class: int, *, seed: int, duration_s: float = PAPER_DURATION_S, substeps: int = 2
) -> PremiseTruth:
    """Simulate `runs_per_class` runs on each class A–D at its centre level (see the module).

    Run `i` of class `c` draws its pressure, speed, initial estimate, road seed, the estimators'
    seed and its noise from ``SeedSequence([seed, 2, index of c, i])``.
    """
    if not 1 <= runs_per_class <= 10000:
        raise InputError(f"premise runs per class must be 1–10000, got {runs_per_class}")
    if not 2.0 <= duration_s <= 600.0:
        raise InputError(f"premise duration must be 2–600 s, got {duration_s}")
    n_steps = int(round(duration_s / TIMESTEP_S))
    draws = []
    for ci, c in enumerate(PAPER_CLASSES):
        for i in range(runs_per_class):
            rng = np.random.default_rng(np.random.SeedSequence([seed, 2, ci, i]))
            pressure = float(rng.uniform(*PAPER_PRESSURE_KPA))
            speed = float(rng.uniform(*PAPER_SPEED_KMH)) / 3.6
            initial = float(np.clip(rng.normal(pressure, INITIAL_SIGMA_KPA), 80.0, 350.0))
            road_seed, estimator_seed = (int(k) for k in rng.integers(0, 2**31, 2))
            draws.append((c, pressure, speed, initial, road_seed, estimator_seed, rng))
    roads = []
    for c, _, speed, _, road_seed, _, _ in draws:
        spacing = speed * TIMESTEP_S
        spec = RoadSpec(
            segments=[SegmentSpec(length_m=spacing * (n_steps + 10), gd_n0=class_level(c))],
            spacing_m=spacing, method="shape-filter",
        )  # fmt: skip
        roads.append(generate_road(spec, seed=road_seed).z[0][:n_steps])
    road = np.array(roads)
    table = {k: np.array([PAPER_TABLE_3[d[0]][k] for d in draws]) for k in ("ks", "ksnl", "cs", "csnl")}
    qc = QuarterCar(
        sprung_mass=PAPER_SPRUNG_MASS, unsprung_mass=PAPER_UNSPRUNG_MASS, spring_rate=table["ks"],
        spring_cubic=table["ksnl"], damping=table["cs"], damping_nonlinear=table["csnl"],
    )  # fmt: skip
    pressure = np.array([d[1] for d in draws])
    x0 = np.zeros((len(draws), 5))
    x0[:, 0] = x0[:, 1] = road[:, 0]
    x0[:, 4] = stiffness_from_pressure(pressure * 1e3)
    _, acc = simulate_quarter_car(x0, road, qc, TIMESTEP_S, substeps=substeps)
    noise = np.array([d[6].normal(0.0, NOISE_MPS2, (n_steps, 2)) for d in draws])
    return PremiseTruth(
        road_class=np.array([d[0] for d in draws]),
        gd_n0=np.array([class_level(d[0]) for d in draws]),
        pressure_kpa=pressure,
        speed_mps=np.array([d[2] for d in draws]),
        initial_pressure_kpa=np.array([d[3] for d in draws]),
        road_seed=np.array([d[4] for d in draws]),
        estimator_seed=np.array([d[5] for d in draws]),
        road=road,
        acc=acc + noise,
        dt=TIMESTEP_S,
    )


def premise_study(
    runs_per_class: int = 3,
    *,
    seed: int = 2022,
    duration_s: float = PAPER_DURATION_S,
    estimators: tuple[str, ...] = PREMISE_ESTIMATORS,
    controls: bool = True,
) -> pd.DataFrame:
    """Run paper 000's estimators (and, with `controls`, :data:`CONTROLS`) on
    :func:`premise_truth`; one row per run and estimator.

    Columns: ``road_class``, ``run`` (index within the class), ``estimator``, ``pressure_kpa``,
    ``speed_kmh``, ``initial_pressure_kpa``, the :class:`~suvtwin.pipeline.scoring.RunMetrics`
    of the run (``time_to_converge_s`` (inf if never), ``mean_error_kpa``, ``rmse_kpa``,
    ``inside_1sigma``, ``inside_2sigma``; estimate − truth), ``estimate_end_kpa``,
    ``sigma_end_kpa``, and for model banks ``mode_prob_{c}``: the mean probability of mode c
    from 2 s on.
    """
    for e in estimators:
        if e not in ESTIMATORS:
            raise InputError(f"premise estimator must be one of {', '.join(ESTIMATORS)}, got {e!r}")
    truth = premise_truth(runs_per_class, seed=seed, duration_s=duration_s)
    n_steps = truth.acc.shape[1]
    t = np.arange(n_steps) * truth.dt
    signals = CornerSignals(
        acc_sprung=truth.acc[:, :, 0], acc_unsprung=truth.acc[:, :, 1], dt=truth.dt,
        speed_mps=truth.speed_mps, corner="fl", sprung_mass=PAPER_SPRUNG_MASS,
        unsprung_mass=PAPER_UNSPRUNG_MASS, params="paper", seeds=truth.estimator_seed,
        initial_pressure_kpa=truth.initial_pressure_kpa,
    )  # fmt: skip
    rows = []
    names = (*estimators, *(CONTROLS if controls else ()))
    for e in names:
        batch = ESTIMATORS[e].run(signals) if e in ESTIMATORS else _true_road(signals, truth.road, e)
        for b in range(truth.pressure_kpa.size):
            p_hat = batch.pressure_pa[b] / 1e3
            sig = batch.pressure_sigma_pa[b] / 1e3
            truth_b = np.full(n_steps, truth.pressure_kpa[b])
            m = run_metrics(t, truth_b, p_hat, sig, tolerance=PRESSURE_TOLERANCE_KPA)
            row = {
                "road_class": str(truth.road_class[b]),
                "run": b % runs_per_class,
                "estimator": e,
                "pressure_kpa": float(truth.pressure_kpa[b]),
                "speed_kmh": float(truth.speed_mps[b] * 3.6),
                "initial_pressure_kpa": float(truth.initial_pressure_kpa[b]),
                "time_to_converge_s": m.time_to_converge_s if np.isfinite(m.time_to_converge_s) else np.inf,
                "mean_error_kpa": m.mean_error,
                "rmse_kpa": m.rmse,
                "inside_1sigma": m.inside_1sigma,
                "inside_2sigma": m.inside_2sigma,
                "estimate_end_kpa": float(p_hat[-1]),
                "sigma_end_kpa": float(sig[-1]),
            }
            for c in PAPER_CLASSES:
                col = f"mode_prob_{c}"
                if col in batch.columns:
                    row[col] = float(batch.columns[col][b][t >= 2.0].mean())
            rows.append(row)
    return pd.DataFrame(rows)


def _true_road(signals: CornerSignals, road: np.ndarray, name: str) -> BatchEstimate:
    """A control of :data:`CONTROLS`: the IMM (or the class A UKF) of the Table 3 modes given the
    true road (``road_input="true"``)."""
    modes = load_modes("paper")
    if name.startswith("ukf"):
        modes = modes.subset(("A",))
    est = estimate_pressure(
        signals.acc_sprung, signals.acc_unsprung, signals.dt, modes=modes, sprung_mass=signals.sprung_mass,
        unsprung_mass=signals.unsprung_mass, road_input="true", road=road, speed_mps=signals.speed_mps,
        initial_stiffness=stiffness_from_pressure(np.asarray(signals.initial_pressure_kpa) * 1e3),
    )  # fmt: skip
    columns = {}
    if est.mode_probability is not None:
        columns = {f"mode_prob_{c}": est.mode_probability[:, :, s] for s, c in enumerate(est.classes)}
    return BatchEstimate(est.pressure_pa, est.pressure_sigma_pa, est.stiffness, est.stiffness_sigma, columns)


def premise_summary(runs: pd.DataFrame) -> pd.DataFrame:
    """Per road class and estimator, the campaign's indexes over the runs of :func:`premise_study`.

    Columns: ``road_class``, ``estimator``, ``runs``; ``median_time_to_converge_s`` (inf when
    most runs never stay within ±12.5 kPa), ``converged_fraction``; at the end of the runs, the
    indexes of paper 000 eq. 23–25 (``mean_error_kpa``: truth − estimate, ``error_std_kpa``,
    ``sigma_bound_kpa``), ``rmse_kpa`` and ``inside_2sigma`` (fraction of runs whose end error
    is within ±2σ); ``inside_2sigma_samples``: mean fraction of a run's scored samples within
    ±2σ; ``right_mode_probability``: mean probability, from 2 s on, of the mode of the class
    driven, and ``most_probable_mode`` (NaN / "" for a single model).
    """
    rows = []
    for (c, e), g in runs.groupby(["road_class", "estimator"], sort=False):
        truth = g["pressure_kpa"].to_numpy()[:, None]
        est = g["estimate_end_kpa"].to_numpy()[:, None]
        sig = g["sigma_end_kpa"].to_numpy()[:, None]
        idx = monte_carlo_indexes(truth, est, sig)
        error = (est - truth)[:, 0]
        probs = {k: g[f"mode_prob_{k}"].mean() for k in PAPER_CLASSES if f"mode_prob_{k}" in g}
        probs = {k: v for k, v in probs.items() if np.isfinite(v)}  # a single model has none (NaN in a file)
        rows.append(
            {
                "road_class": c,
                "estimator": e,
                "runs": len(g),
                "median_time_to_converge_s": float(np.median(g["time_to_converge_s"])),
                "converged_fraction": float(np.isfinite(g["time_to_converge_s"]).mean()),
                "mean_error_kpa": float(idx.mean_error[0]),
                "error_std_kpa": float(idx.error_std[0]),
                "sigma_bound_kpa": float(idx.sigma_bound[0]),
                "rmse_kpa": float(np.sqrt(np.mean(error**2))),
                "inside_2sigma": float(np.mean(np.abs(error) <= 2 * sig[:, 0])),
                "inside_2sigma_samples": float(g["inside_2sigma"].mean()),
                "right_mode_probability": float(probs[c]) if c in probs else np.nan,
                "most_probable_mode": max(probs, key=probs.get) if probs else "",
            }
        )
    return pd.DataFrame(rows)
