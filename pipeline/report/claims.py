"""Pass/fail evaluation of paper 000's claims against the campaign's metrics: no figures, no HTML.

Usual call: ``goals = goal_table(metrics, mc_table, series, ("imm_synthetic", "joint"))``.

Each claim of Brancati & Tufano 2022 §5.3–5.4 becomes a criterion on the stored results: the
convergence time on class A and D roads (Fig. 7–8, ≤ :data:`CONVERGE_GOAL_S`), the mode
probabilities following an A → D switch (Fig. 9), tracking a pressure drop (Fig. 10), the
error with extra sprung mass (Fig. 11) and on a road of no ISO class (Fig. 13), and the
Monte Carlo indexes (Fig. 6, eq. 23–25). A criterion that does not apply to an estimator
(mode probabilities of a single model, a model bank against its single-model baseline
:attr:`suvtwin.pipeline.estimator_registry.Estimator.single_model_baseline`) is "not
applicable" (``pass`` None), never a failure.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from suvtwin.pipeline.estimator_registry import ESTIMATORS
from suvtwin.pipeline.scoring import PRESSURE_TOLERANCE_KPA

__all__ = ["CONVERGE_GOAL_S", "goal_table", "premise_goals", "premise_verdict"]

CONVERGE_GOAL_S = 3.0
"""'Converges in about 2 s': pass if the error stays within ±5 % of p0 from ≤ 3 s on."""


def _cell(value: str, ok: bool | None) -> dict:
    return {"value": value, "pass": ok}


def _goal(goal: str, criterion: str, cells: dict) -> dict:
    return {"goal": goal, "criterion": criterion, "cells": cells}


def goal_table(
    metrics: pd.DataFrame, mc_table: pd.DataFrame, series: dict, estimators: tuple[str, ...]
) -> list:
    """Each claim of paper 000 with its criterion and, per estimator, the measured value and pass/fail.

    Returns a list of ``{"goal", "criterion", "cells": {estimator: {"value", "pass"}}}``;
    ``pass`` is None where the criterion does not apply (e.g. mode probabilities of one UKF).
    """
    goals = []

    def scen(run: str, estimator: str) -> pd.Series | None:
        rows = metrics[(metrics.run == run) & (metrics.estimator == estimator)]
        return None if rows.empty else rows.iloc[0]

    for run, figure in (("class_A", "Fig. 7"), ("class_D", "Fig. 8")):
        if not (metrics.run == run).any():
            continue
        cells = {}
        for e in estimators:
            t = scen(run, e)["time_to_converge_s"]
            cells[e] = _cell(
                "never" if not np.isfinite(t) else f"{t:.2f} s", bool(np.isfinite(t) and t <= CONVERGE_GOAL_S)
            )
        goals.append(
            _goal(
                f"Converges in about 2 s on a class {run[-1]} road ({figure})",
                f"error within ±{PRESSURE_TOLERANCE_KPA:g} kPa (5 % of p0) from ≤ {CONVERGE_GOAL_S:g} s on",
                cells,
            )
        )
    if (metrics.run == "switch_A_to_D").any():
        cells = {}
        for e in estimators:
            est = series["estimates"].get((e, "switch_A_to_D"))
            if est is None or "mode_prob_A" not in est or "mode_prob_D" not in est:
                cells[e] = _cell("—", None)
                continue
            t = est["t_s"].to_numpy()
            probs = est[[f"mode_prob_{c}" for c in "ABCD" if f"mode_prob_{c}" in est]]
            first = probs[(t >= 1.0) & (t < 5.0)].mean()
            second = probs[t >= 6.0].mean()
            ok = first.idxmax() == "mode_prob_A" and second.idxmax() == "mode_prob_D"
            cells[e] = _cell(
                f"A-road: {first.idxmax()[-1]} ({first.max():.2f}); "
                f"D-road: {second.idxmax()[-1]} ({second.max():.2f})",
                ok,
            )
        goals.append(
            _goal(
                "Mode probabilities follow the road class, A then D (Fig. 9)",
                "most probable mode (mean over 1–5 s, 6–end) is A, then D",
                cells,
            )
        )
    if (metrics.run == "pressure_drop").any():
        cells = {}
        truth_t, truth = series["truth"]["pressure_drop"]
        for e in estimators:
            est = series["estimates"][(e, "pressure_drop")]
            error = np.abs(est["pressure_hat_kpa"].to_numpy() - truth)
            before = (truth_t >= 2.0) & (truth_t < 4.0)
            after = truth_t >= 7.5
            worst = max(error[before].max(), error[after].max())
            cells[e] = _cell(f"max |error| {worst:.1f} kPa", bool(worst <= PRESSURE_TOLERANCE_KPA))
        goals.append(
            _goal(
                "Tracks a 230 → 180 kPa drop over 1.5 s, converged in about 2 s (Fig. 10)",
                f"|error| ≤ {PRESSURE_TOLERANCE_KPA:g} kPa over 2–4 s and from 2 s after the drop ends",
                cells,
            )
        )
    for run, label in (("mass_plus_8", "+8 %"), ("mass_plus_24", "+24 %")):
        if not (metrics.run == run).any():
            continue
        cells = {}
        for e in estimators:
            v = scen(run, e)["mean_abs_error_after_2s_pct"]
            cells[e] = _cell(f"{v:.1f} %", bool(v < 5.0))
        goals.append(
            _goal(
                f"Mean error below 5 % with sprung mass {label}, model mass unchanged (Fig. 11)",
                "mean |error| / true pressure after 2 s < 5 %",
                cells,
            )
        )
    if (metrics.run == "non_iso_road").any():
        cells = {}
        for e in estimators:
            v = scen("non_iso_road", e)["mean_abs_error_after_2s_pct"]
            cells[e] = _cell(f"{v:.1f} %", bool(v < 5.0))
        goals.append(
            _goal(
                "Estimates the pressure on a road of no ISO class (Fig. 13)",
                "mean |error| / true pressure after 2 s < 5 %",
                cells,
            )
        )
    if not mc_table.empty:
        end = mc_table[mc_table.t_s == mc_table.t_s.max()].set_index("estimator")
        n = int(end["runs"].iloc[0])
        cells = {
            e: _cell(
                f"{end.loc[e, 'mean_error_kpa']:+.1f} kPa",
                bool(abs(end.loc[e, "mean_error_kpa"]) <= PRESSURE_TOLERANCE_KPA),
            )
            for e in estimators
        }
        goals.append(
            _goal(
                f"Monte Carlo ({n} runs): mean error around zero (Fig. 6, eq. 23)",
                f"|mean error| at the end ≤ {PRESSURE_TOLERANCE_KPA:g} kPa",
                cells,
            )
        )
        cells = {}
        for e in estimators:
            ratio = end.loc[e, "error_std_kpa"] / end.loc[e, "sigma_bound_kpa"]
            cells[e] = _cell(f"std / σ = {ratio:.2f}", bool(0.5 <= ratio <= 2.0))
        goals.append(
            _goal(
                "Monte Carlo: the error std converges to the filter's σ-bound (Fig. 6, eq. 24–25)",
                "error std / mean σ-bound at the end within 0.5–2",
                cells,
            )
        )
        cells = {}
        for e in estimators:
            cells[e] = _cell(
                f"{end.loc[e, 'inside_2sigma'] * 100:.0f} %", bool(end.loc[e, "inside_2sigma"] >= 0.9)
            )
        goals.append(
            _goal(
                "Monte Carlo: the sample errors stay within the σ-bounds (Fig. 6)",
                "≥ 90 % of runs inside ±2σ at the end",
                cells,
            )
        )
        cells = {}
        for e in estimators:
            single = ESTIMATORS[e].single_model_baseline if e in ESTIMATORS else None
            if single is None:
                cells[e] = _cell("—", None)
                continue
            if single not in end.index:
                cells[e] = _cell("no single UKF run", None)
                continue
            a, b = end.loc[e, "rmse_kpa"], end.loc[single, "rmse_kpa"]
            cells[e] = _cell(f"RMSE {a:.1f} vs {b:.1f} kPa", bool(a < b))
        goals.append(
            _goal(
                "Monte Carlo: the IMM outperforms the single UKF (Fig. 6)",
                "IMM RMSE at the end < single UKF's (same road input)",
                cells,
            )
        )
    return goals


def premise_goals(summary: pd.DataFrame, baselines: dict[str, str]) -> list:
    """Paper 000's claims on its own quarter car and roads at the class centres, per class.

    `summary`: one row per road class and estimator, as
    :func:`suvtwin.pipeline.premise.premise_summary` writes it (``road_class``, ``estimator``,
    ``runs``, ``median_time_to_converge_s``, ``converged_fraction``, ``mean_error_kpa``,
    ``error_std_kpa``, ``sigma_bound_kpa``, ``rmse_kpa``, ``inside_2sigma``,
    ``right_mode_probability``, ``most_probable_mode``); `baselines`: model bank → its single
    UKF. The criteria are those of :func:`goal_table`, applied to each class's runs: converged
    (median over the runs ≤ :data:`CONVERGE_GOAL_S`), |mean error| ≤ 12.5 kPa, error std /
    σ-bound within 0.5–2, ≥ 90 % of the runs inside ±2σ (all at the end), the driven class's
    mode the most probable, and the model bank's RMSE below its single UKF's.

    Returns a list of ``{"goal", "criterion", "cells": {estimator: {"value", "pass"}}}`` in the
    format of :func:`goal_table`, one per claim and class; ``pass`` is None where a claim does
    not apply (mode probabilities of one UKF, a model bank without its baseline, the std of one run).
    """
    estimators = tuple(dict.fromkeys(summary["estimator"]))
    classes = tuple(dict.fromkeys(summary["road_class"]))
    rows = {(r.road_class, r.estimator): r for r in summary.itertuples(index=False)}
    tol = PRESSURE_TOLERANCE_KPA

    def cells(c: str, judge) -> dict:
        out = {}
        for e in estimators:
            r = rows.get((c, e))
            out[e] = _cell("—", None) if r is None else _cell(*judge(r, e))
        return out

    def converge(r, e):
        t = r.median_time_to_converge_s
        shown = f"{t:.2f} s" if np.isfinite(t) else "never"
        return f"median {shown}; {r.converged_fraction * 100:.0f} % of {r.runs} runs converge", bool(
            np.isfinite(t) and t <= CONVERGE_GOAL_S
        )

    def mean_error(r, e):
        return f"{r.mean_error_kpa:+.1f} kPa", bool(abs(r.mean_error_kpa) <= tol)

    def std_ratio(r, e):
        ratio = r.error_std_kpa / r.sigma_bound_kpa if r.sigma_bound_kpa > 0 else np.inf
        if not np.isfinite(r.error_std_kpa):
            return "one run", None
        return f"{r.error_std_kpa:.1f} / {r.sigma_bound_kpa:.1f} kPa = {ratio:.2g}", bool(0.5 <= ratio <= 2.0)

    def inside(r, e):
        return f"{r.inside_2sigma * 100:.0f} %", bool(r.inside_2sigma >= 0.9)

    def mode(r, e):
        if not np.isfinite(r.right_mode_probability):
            return "—", None
        return (
            f"most probable {r.most_probable_mode}; mode {r.road_class}: {r.right_mode_probability:.2f}",
            r.most_probable_mode == r.road_class,
        )

    def beats_single(r, e):
        single = baselines.get(e)
        if single is None:
            return "—", None
        other = rows.get((r.road_class, single))
        if other is None:
            return "no single UKF run", None
        return f"RMSE {r.rmse_kpa:.1f} vs {other.rmse_kpa:.1f} kPa", bool(r.rmse_kpa < other.rmse_kpa)

    claims = (
        ("converges in about 2 s (Fig. 7–8)",
         f"median over the runs of the time from which |error| ≤ {tol:g} kPa to the end"
         f" ≤ {CONVERGE_GOAL_S:g} s",
         converge),
        ("mean error around zero (Fig. 6, eq. 23)", f"|mean error| at the end ≤ {tol:g} kPa", mean_error),
        ("the error std converges to the σ-bound (Fig. 6, eq. 24–25)",
         "error std / mean σ-bound at the end within 0.5–2", std_ratio),
        ("the errors stay within the σ-bounds (Fig. 6)", "≥ 90 % of runs inside ±2σ at the end", inside),
        ("the mode of the class driven is the most probable (Fig. 7–9)",
         "highest mean mode probability from 2 s on is the class's", mode),
        ("the IMM outperforms the single UKF (Fig. 6)", "RMSE at the end < single UKF's (same road input)",
         beats_single),
    )  # fmt: skip
    return [
        _goal(f"Class {c}: {claim}", criterion, cells(c, judge))
        for claim, criterion, judge in claims
        for c in classes
    ]


def premise_verdict(goals: list, estimator: str) -> dict:
    """Whether `estimator` meets every applicable claim of :func:`premise_goals`.

    Returns ``{"met", "applicable", "holds", "failed"}``: claims met, claims that apply, whether
    all that apply are met (False when none applies), and the goals it falls short of.
    """
    judged = [(g["goal"], g["cells"][estimator]["pass"]) for g in goals if estimator in g["cells"]]
    judged = [(goal, ok) for goal, ok in judged if ok is not None]
    failed = [goal for goal, ok in judged if not ok]
    return {"met": len(judged) - len(failed), "applicable": len(judged), "holds": bool(judged) and not failed,
            "failed": failed}  # fmt: skip
