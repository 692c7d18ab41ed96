"""Scoring of a campaign: per-run metrics and the Monte Carlo indexes, from the stored files.

Usual call: ``metrics, mc_table, series = score_campaign(config, specs, run_paths, est_paths)``.

Per run and estimator: :func:`suvtwin.pipeline.scoring.run_metrics` and the errors at 2 s
and the end; over the Monte Carlo runs: the indexes of Brancati & Tufano 2022 eq. 23–25 at
2 s, 5 s and the end (:data:`MC_TIMES_S`). Everything is read from the run and estimate files;
``series`` holds what the report draws (kPa, s; and the road under the estimated corner's wheel,
m, for the scenario runs).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from suvtwin.pipeline.campaign.config import CampaignConfig
from suvtwin.pipeline.campaign.runs import RunSpec
from suvtwin.pipeline.scoring import PRESSURE_TOLERANCE_KPA, monte_carlo_indexes, run_metrics

__all__ = ["MC_TIMES_S", "score_campaign"]

MC_TIMES_S = (2.0, 5.0)


def score_campaign(
    config: CampaignConfig,
    specs: list[RunSpec],
    run_paths: dict[str, Path],
    est_paths: dict[tuple[str, str], Path],
) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """Per-run metrics (one row per run and estimator), Monte Carlo indexes at 2 s, 5 s and the end,
    and the time series the report draws (kPa; ``series["road"][run]``: (x, z) of the road under the
    corner's wheel, m, for the scenario runs)."""
    corner = config.corner
    rows, series = [], {"truth": {}, "estimates": {}}
    for s in specs:
        road = [f"{corner}_road_z_m", "x_m"] if s.kind == "scenario" else []
        run = pq.read_table(run_paths[s.name], columns=["t_s", f"{corner}_pressure_kpa", *road]).to_pandas()
        t, truth = run["t_s"].to_numpy(), run[f"{corner}_pressure_kpa"].to_numpy()
        series["truth"][s.name] = (t, truth)
        if road:  # the road elevation under the corner's wheel against the distance driven, m
            series.setdefault("road", {})[s.name] = (run["x_m"].to_numpy(), run[road[0]].to_numpy())
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
