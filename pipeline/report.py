"""The campaign's report: one self-contained HTML page (figures embedded as PNG).

Usual call: ``write_report("results/report.html", config, specs, metrics, mc_table, series, params, summary)``
(done by :func:`suvtwin.pipeline.campaign.run_campaign`).

Sections: what was run; the goals table (each claim of Brancati & Tufano 2022 §5.3–5.4
against what our estimators did on the open ground truth, pass / falls short); the
vehicle and the roads; the identified parameters (Table 3 analog, Figure 5 analog);
the Monte Carlo indexes (eq. 23–25, Figure 6 analog); the scenario runs (Figures 7–13
analogs: pressure tracks and mode probabilities); the metrics table; how to reproduce.
"""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from suvtwin.estimators.tire_pressure import PAPER_TABLE_3  # noqa: E402
from suvtwin.files import atomic_write  # noqa: E402
from suvtwin.mjcf.vehicle import load_vehicle  # noqa: E402
from suvtwin.pipeline.estimation import PRESSURE_TOLERANCE_KPA  # noqa: E402

__all__ = ["goal_table", "write_report"]

LABELS = {
    "imm_synthetic": "IMM, synthetic road (paper)",
    "imm_augmented": "IMM, augmented road",
    "ukf_synthetic": "single UKF, synthetic road (paper)",
    "ukf_augmented": "single UKF, augmented road",
    "joint": "joint (road level estimated)",
}
COLORS = {
    "imm_synthetic": "tab:red",
    "imm_augmented": "tab:orange",
    "ukf_synthetic": "tab:blue",
    "ukf_augmented": "tab:cyan",
    "joint": "tab:green",
}
CONVERGE_GOAL_S = 3.0
"""'Converges in about 2 s': pass if the error stays within ±5 % of p0 from ≤ 3 s on."""


def _png(fig) -> str:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode()


def _img(src: str, alt: str) -> str:
    return f'<img src="{src}" alt="{html.escape(alt)}">'


def _file_img(path: Path, alt: str) -> str:
    if not path.is_file():
        return f"<p><em>{html.escape(alt)}: figure not available ({html.escape(path.name)}).</em></p>"
    return _img("data:image/png;base64," + base64.b64encode(path.read_bytes()).decode(), alt)


def _table(frame: pd.DataFrame, *, digits: int = 3) -> str:
    def fmt(v):
        if isinstance(v, float | np.floating):
            return "—" if not np.isfinite(v) else f"{v:.{digits}g}"
        return html.escape(str(v))

    head = "".join(f"<th>{html.escape(str(c))}</th>" for c in frame.columns)
    body = "".join(
        "<tr>" + "".join(f"<td>{fmt(v)}</td>" for v in row) + "</tr>" for row in frame.itertuples(False)
    )
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _short(value) -> str:
    """A value for a caption: floats to 3 significant digits, lists element-wise."""
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_short(v) for v in value) + "]"
    return f"{value:.3g}" if isinstance(value, float) else str(value)


# ---------------------------------------------------------------- goals
def _cell(value: str, ok: bool | None) -> dict:
    return {"value": value, "pass": ok}


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
            {
                "goal": f"Converges in about 2 s on a class {run[-1]} road ({figure})",
                "criterion": f"error within ±{PRESSURE_TOLERANCE_KPA:g} kPa (5 % of p0) from ≤ {CONVERGE_GOAL_S:g} s on",
                "cells": cells,
            }
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
                f"A-road: {first.idxmax()[-1]} ({first.max():.2f}); D-road: {second.idxmax()[-1]} ({second.max():.2f})",
                ok,
            )
        goals.append(
            {
                "goal": "Mode probabilities follow the road class, A then D (Fig. 9)",
                "criterion": "most probable mode (mean over 1–5 s, 6–end) is A, then D",
                "cells": cells,
            }
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
            {
                "goal": "Tracks a 230 → 180 kPa drop over 1.5 s, converged in about 2 s (Fig. 10)",
                "criterion": f"|error| ≤ {PRESSURE_TOLERANCE_KPA:g} kPa over 2–4 s and from 2 s after the drop ends",
                "cells": cells,
            }
        )
    for run, label in (("mass_plus_8", "+8 %"), ("mass_plus_24", "+24 %")):
        if not (metrics.run == run).any():
            continue
        cells = {}
        for e in estimators:
            v = scen(run, e)["mean_abs_error_after_2s_pct"]
            cells[e] = _cell(f"{v:.1f} %", bool(v < 5.0))
        goals.append(
            {
                "goal": f"Mean error below 5 % with sprung mass {label}, model mass unchanged (Fig. 11)",
                "criterion": "mean |error| / true pressure after 2 s < 5 %",
                "cells": cells,
            }
        )
    if (metrics.run == "non_iso_road").any():
        cells = {}
        for e in estimators:
            v = scen("non_iso_road", e)["mean_abs_error_after_2s_pct"]
            cells[e] = _cell(f"{v:.1f} %", bool(v < 5.0))
        goals.append(
            {
                "goal": "Estimates the pressure on a road of no ISO class (Fig. 13)",
                "criterion": "mean |error| / true pressure after 2 s < 5 %",
                "cells": cells,
            }
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
            {
                "goal": f"Monte Carlo ({n} runs): mean error around zero (Fig. 6, eq. 23)",
                "criterion": f"|mean error| at the end ≤ {PRESSURE_TOLERANCE_KPA:g} kPa",
                "cells": cells,
            }
        )
        cells = {}
        for e in estimators:
            ratio = end.loc[e, "error_std_kpa"] / end.loc[e, "sigma_bound_kpa"]
            cells[e] = _cell(f"std / σ = {ratio:.2f}", bool(0.5 <= ratio <= 2.0))
        goals.append(
            {
                "goal": "Monte Carlo: the error std converges to the filter's σ-bound (Fig. 6, eq. 24–25)",
                "criterion": "error std / mean σ-bound at the end within 0.5–2",
                "cells": cells,
            }
        )
        cells = {}
        for e in estimators:
            cells[e] = _cell(
                f"{end.loc[e, 'inside_2sigma'] * 100:.0f} %", bool(end.loc[e, "inside_2sigma"] >= 0.9)
            )
        goals.append(
            {
                "goal": "Monte Carlo: the sample errors stay within the σ-bounds (Fig. 6)",
                "criterion": "≥ 90 % of runs inside ±2σ at the end",
                "cells": cells,
            }
        )
        cells = {}
        for e in estimators:
            if not e.startswith("imm"):
                cells[e] = _cell("—", None)
                continue
            single = "ukf" + e[3:]
            if single not in end.index:
                cells[e] = _cell("no single UKF run", None)
                continue
            a, b = end.loc[e, "rmse_kpa"], end.loc[single, "rmse_kpa"]
            cells[e] = _cell(f"RMSE {a:.1f} vs {b:.1f} kPa", bool(a < b))
        goals.append(
            {
                "goal": "Monte Carlo: the IMM outperforms the single UKF (Fig. 6)",
                "criterion": "IMM RMSE at the end < single UKF's (same road input)",
                "cells": cells,
            }
        )
    return goals


def _goals_html(goals: list, estimators: tuple[str, ...]) -> str:
    head = "<th>claim of the paper</th><th>criterion</th>" + "".join(
        f"<th>{html.escape(LABELS[e])}</th>" for e in estimators
    )
    rows = []
    for g in goals:
        cells = []
        for e in estimators:
            c = g["cells"].get(e, {"value": "—", "pass": None})
            cls, mark = {True: ("pass", "✓ pass"), False: ("fail", "✗ falls short"), None: ("na", "")}[
                c["pass"]
            ]
            cells.append(f'<td class="{cls}">{html.escape(c["value"])}<br><b>{mark}</b></td>')
        rows.append(
            f"<tr><td>{html.escape(g['goal'])}</td><td>{html.escape(g['criterion'])}</td>{''.join(cells)}</tr>"
        )
    return f"<table class='goals'><thead><tr>{head}</tr></thead><tbody>{''.join(rows)}</tbody></table>"


# ---------------------------------------------------------------- figures
def _monte_carlo_figure(series: dict, estimators: tuple[str, ...]) -> str:
    n = len(estimators)
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.4 * n), sharex=True, squeeze=False)
    for ax, e in zip(axes[:, 0], estimators, strict=True):
        t, idx, errors = series["monte_carlo"][e]
        step = max(1, t.size // 2000)
        for row in errors[: min(10, errors.shape[0])]:
            ax.plot(t[::step], row[::step], color="tab:green", lw=0.4, alpha=0.5)
        ax.plot(t[::step], idx.mean_error[::step], color="tab:red", lw=1.5, label="mean error (eq. 23)")
        for sign in (1, -1):
            ax.plot(
                t[::step],
                sign * idx.error_std[::step],
                "b--",
                lw=1,
                label="± error std (eq. 24)" if sign > 0 else None,
            )
            ax.plot(
                t[::step],
                sign * idx.sigma_bound[::step],
                "k--",
                lw=1,
                label="± mean σ-bound (eq. 25)" if sign > 0 else None,
            )
        lim = np.nanmax(np.abs(idx.mean_error[t >= 1.0])) + 2 * np.nanmax(idx.error_std[t >= 1.0])
        ax.set_ylim(-min(max(lim, 30.0), 400.0), min(max(lim, 30.0), 400.0))
        ax.set_ylabel("truth − estimate, kPa")
        ax.set_title(LABELS[e], fontsize=10)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, ncol=3, loc="upper right")
    axes[-1, 0].set_xlabel("time, s")
    fig.tight_layout()
    return _png(fig)


def _scenario_figure(name: str, series: dict, estimators: tuple[str, ...]) -> str:
    t, truth = series["truth"][name]
    imm = [e for e in estimators if e.startswith("imm")]
    rows = 1 + len(imm)
    fig, axes = plt.subplots(rows, 1, figsize=(9, 3.2 + 1.8 * len(imm)), sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [2.2] + [1] * len(imm)})  # fmt: skip
    ax = axes[0, 0]
    step = max(1, t.size // 2000)
    ax.plot(t[::step], truth[::step], "k", lw=2, label="true pressure")
    for e in estimators:
        est = series["estimates"][(e, name)]
        p, s = est["pressure_hat_kpa"].to_numpy(), est["pressure_sigma_kpa"].to_numpy()
        ax.plot(t[::step], p[::step], color=COLORS[e], lw=1.2, label=LABELS[e])
        ax.fill_between(t[::step], (p - 2 * s)[::step], (p + 2 * s)[::step], color=COLORS[e], alpha=0.08)
    ax.set_ylim(max(truth.min() - 150.0, -100.0), truth.max() + 150.0)
    ax.set_ylabel("pressure, kPa")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="lower right")
    for ax, e in zip(axes[1:, 0], imm, strict=True):
        est = series["estimates"][(e, name)]
        for c, color in zip("ABCD", ("tab:blue", "tab:orange", "tab:green", "tab:red"), strict=True):
            col = f"mode_prob_{c}"
            if col in est:
                prob = est[col].to_numpy()
                # one-second moving average, as the paper's figures show
                k = max(1, int(round(1.0 / (t[1] - t[0]))))
                csum = np.concatenate([[0.0], np.cumsum(prob)])
                first = np.maximum(np.arange(1, prob.size + 1) - k, 0)
                smooth = (csum[1:] - csum[first]) / (np.arange(1, prob.size + 1) - first)  # trailing mean
                ax.plot(t[::step], smooth[::step], color=color, lw=1.2, label=f"mode {c}")
        ax.set_ylim(-0.02, 1.02)
        ax.set_ylabel("mode prob.")
        ax.set_title(f"{LABELS[e]}: mode probabilities (trailing 1 s mean)", fontsize=9)
        ax.legend(fontsize=7, ncol=4, loc="upper right")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time, s")
    fig.tight_layout()
    return _png(fig)


def _road_psd_figure(spec) -> str:
    """Displacement PSD of a scenario's road (left track) against the ISO class bands (Fig. 12 analog)."""
    from suvtwin.pipeline.scenario import parse_scenario
    from suvtwin.roads.iso8608 import CLASSES, class_bounds, displacement_psd
    from suvtwin.roads.profile import generate_road
    from suvtwin.roads.roughness import profile_psd
    from suvtwin.roads.spec import RoadSpec

    scenario = parse_scenario(spec.scenario)
    road = generate_road(RoadSpec.model_validate(spec.scenario["road"]), seed=scenario.road_seed())
    n, psd = profile_psd(road.z[0], road.spacing_m, segment_m=20.0)
    fig, ax = plt.subplots(figsize=(6.5, 4))
    keep = n > 0
    ax.loglog(n[keep], psd[keep], "k", lw=1, label="road (Welch)")
    grid = np.logspace(-2, 1, 50)
    for c in CLASSES[:5]:
        lower, upper = class_bounds(c)
        ax.fill_between(
            grid, displacement_psd(grid, gd_n0=lower), displacement_psd(grid, gd_n0=upper), alpha=0.12
        )
        ax.text(0.012, displacement_psd(0.012, gd_n0=np.sqrt(lower * upper)), c, fontsize=8)
    ax.set_xlabel("spatial frequency n, cycles/m")
    ax.set_ylabel("Gd(n), m³")
    ax.set_xlim(0.01, 10)
    shown = psd[keep & (n <= 10.0) & (psd > 0)]
    ax.set_ylim(shown.min() / 10, shown.max() * 100)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _png(fig)


def _draws_figure(specs: list) -> str:
    mc = [s for s in specs if s.kind == "monte_carlo"]
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.2))
    colors = {"A": "tab:blue", "B": "tab:orange", "C": "tab:green", "D": "tab:red"}
    for s in mc:
        c = s.info["road_class"]
        axes[0].scatter(s.info["speed_kmh"], s.info["pressure_kpa"], color=colors[c], s=12)
        axes[1].scatter(s.info["gd_n0_m3"], "ABCD".index(c), color=colors[c], s=12)
    axes[0].set_xlabel("speed, km/h")
    axes[0].set_ylabel("true pressure, kPa")
    axes[1].set_xscale("log")
    axes[1].set_yticks(range(4), list("ABCD"))
    axes[1].set_xlabel("road level Gd(n0), m³ (n0 = 0.1 cycle/m)")
    axes[1].set_ylabel("class")
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    return _png(fig)


# ---------------------------------------------------------------- page
_CSS = """
body{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
table{border-collapse:collapse;margin:0.8em 0;font-size:0.8em}
th,td{border:1px solid #ccc;padding:3px 6px;text-align:right;vertical-align:top}
th{background:#f2f2f2} td:first-child,th:first-child{text-align:left}
table.goals td{text-align:left} td.pass{background:#e6f4e6} td.fail{background:#fbe4e4} td.na{color:#888}
img{max-width:100%;border:1px solid #eee;margin:0.5em 0} h2{border-bottom:2px solid #ddd;padding-bottom:0.2em}
code,pre{background:#f6f6f6;padding:1px 4px} pre{padding:0.6em;overflow-x:auto;font-size:0.8em}
.note{background:#fff8e1;border-left:4px solid #f0c040;padding:0.5em 1em}
"""


def write_report(
    path: str | Path,
    config,
    specs: list,
    metrics: pd.DataFrame,
    mc_table: pd.DataFrame,
    series: dict,
    params_path: str | Path,
    summary: dict,
) -> None:
    """Write the self-contained HTML report of a campaign (atomically)."""
    estimators = tuple(config.estimators)
    vehicle = load_vehicle()
    params = json.loads(Path(params_path).read_text())
    goals = goal_table(metrics, mc_table, series, estimators)
    parts = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>suvtwin campaign: {html.escape(config.name)}</title>"
    ]
    parts.append(f"<style>{_CSS}</style></head><body>")
    parts.append(f"<h1>suvtwin validation campaign — {html.escape(config.name)}</h1>")
    n_mc = sum(s.kind == "monte_carlo" for s in specs)
    parts.append(
        "<p>This report re-runs the validation of the tire-pressure estimator of Brancati &amp; Tufano "
        "(<i>Sensors</i> 2022, “Indirect estimation of tire pressure … via IMM”) on an open ground truth: "
        "a MuJoCo model of a segment-D SUV with pressure-dependent tires, driven over ISO 8608 random roads. "
        "The paper's estimator is a bank of four unscented Kalman filters (UKF), one quarter-car model per "
        "road class A–D, mixed by an Interacting Multiple Model (IMM); it reads the vertical accelerations "
        f"of one corner's body and wheel (corner <code>{html.escape(config.corner)}</code>, 0.5 m/s² noise) and "
        "estimates the tire's vertical stiffness, hence its pressure. We score it, its single-UKF baseline, "
        "and a road-level-free estimator of ours against the pressure that was really in the tire.</p>"
    )
    parts.append(
        f"<p>Runs: {n_mc} Monte Carlo runs and {len(specs) - n_mc} scenario runs, {config.duration_s:g} s each, "
        f"1 kHz. Estimators: {', '.join(LABELS[e] for e in estimators)}.</p>"
    )
    parts.append(
        "<div class='note'><b>How to read the estimators.</b> <i>synthetic road</i>: each IMM mode drives its "
        "quarter car with an artificial road of its class, as the paper does. <i>augmented road</i>: each mode "
        "estimates the road as a shape-filter state with its class's intensity. <i>joint</i>: estimates the "
        "road roughness level and waviness together with the stiffness (Whittle likelihood over pressure × level × waviness) on the "
        "corner's linear roll-plane corner model (heave and roll, anti-roll bar, tire damping; damping marginalized over the damper's range), with no class assumption. All use the nominal (empty-vehicle) "
        "sprung mass, also when the car is loaded. The paper's IMM mixing omits the spread-of-means term "
        "and its likelihood uses det(P); we implement the standard IMM.</div>"
    )

    parts.append("<h2>1. Goals: the paper's claims against this ground truth</h2>")
    parts.append(_goals_html(goals, estimators))
    n_pass = {e: sum(g["cells"].get(e, {}).get("pass") is True for g in goals) for e in estimators}
    n_app = {e: sum(g["cells"].get(e, {}).get("pass") is not None for g in goals) for e in estimators}
    parts.append(
        "<p>Claims met: "
        + "; ".join(f"{html.escape(LABELS[e])} {n_pass[e]}/{n_app[e]}" for e in estimators)
        + ". A claim that falls short is a finding about the method on this vehicle, not a tuning target.</p>"
    )

    parts.append("<h2>2. The vehicle and the roads</h2>")
    c, w, s = vehicle.chassis, vehicle.wheel, vehicle.suspension
    vt = pd.DataFrame(
        [
            ("chassis (sprung) mass", f"{c.mass:g} kg"),
            (
                "wheel (unsprung) mass front / rear",
                f"{w.unsprung_mass_front:g} / {w.unsprung_mass_rear:g} kg",
            ),
            ("CoG to front / rear axle (a1 / a2)", f"{c.a1:g} / {c.a2:g} m"),
            ("track front / rear", f"{c.track_front:g} / {c.track_rear:g} m"),
            (
                "spring rate at the wheel front / rear",
                f"{s.spring_rate_front:g} / {s.spring_rate_rear:g} N/m",
            ),
            (
                "damping, low speed, compression / rebound",
                f"{s.damper_compression_low:g} / {s.damper_rebound_low:g} N s/m",
            ),
            ("anti-roll bar front / rear (wheel-rate equivalent)", f"{s.anti_roll_front:g} / {s.anti_roll_rear:g} N/m"),
            (
                "tire vertical stiffness",
                "kt(p) = kt0·(1 + PFZ1·(p − p0)/p0), paper 000 eq. 3–4 (kt0 264.7 kN/m at p0 250 kPa)",
            ),
        ],
        columns=["parameter", "value"],
    )
    parts.append(_table(vt))
    parts.append(
        "<p>Monte Carlo draws (paper 000 Table 4): pressure uniform 130–230 kPa, speed uniform 40–80 km/h, "
        "class uniform A–D, and the road level log-uniform <i>inside</i> the class band (real roads sit "
        "anywhere in a band that spans 4× in Gd). Initial pressure estimate drawn from N(p_true, "
        f"{config.initial_pressure_sigma_kpa:g} kPa) as the paper draws x̂0 ~ N(x0, P0); scenario runs "
        "start from 250 kPa.</p>"
    )
    if n_mc:
        parts.append(_img(_draws_figure(specs), "Monte Carlo draws"))

    parts.append("<h2>3. Identified quarter-car parameters (Table 3 analog)</h2>")
    meta = params.get("metadata", {})
    alg = meta.get("algorithm", {})
    parts.append(
        f"<p>Source: <code>{html.escape(str(params_path))}</code>. "
        + (
            f"NSGA-III (pymoo), population {alg.get('pop_size')} × {alg.get('n_gen')} generations, seed "
            f"{alg.get('seed')}, 18 objectives (sprung and unsprung acceleration RMSE in nine runs: 40/60/80 km/h × "
            f"130/180/230 kPa per class); chosen: {html.escape(str(meta.get('selection', '')))}.</p>"
            if alg
            else "</p>"
        )
    )
    rows = []
    for name, unit in (("cs", "N s/m"), ("csnl", "N s²/m²"), ("ks", "N/m"), ("ksnl", "N/m³")):
        row = {"parameter": name, "unit": unit}
        for cl in sorted(params["classes"]):
            row[f"class {cl} (ours)"] = float(params["classes"][cl][name])
        for cl in "ABCD":
            row[f"class {cl} (paper)"] = float(PAPER_TABLE_3[cl][name])
        rows.append(row)
    parts.append(_table(pd.DataFrame(rows), digits=4))
    folder = Path(params_path).parent
    fig5 = folder / "fig_fig5_B.png"
    if fig5.is_file():
        parts.append(
            "<p>Figure 5 analog: unsprung acceleration, MuJoCo vs the identified class B quarter car, 60 km/h, 230 and 130 kPa.</p>"
        )
        parts.append(_file_img(fig5, "Figure 5 analog"))
    pareto = folder / "fig_pareto_B.png"
    if pareto.is_file():
        parts.append(
            "<p>Pareto front projections, class B (sprung vs unsprung RMSE per scenario; chosen solution marked).</p>"
        )
        parts.append(_file_img(pareto, "Pareto projections class B"))

    if n_mc:
        parts.append(f"<h2>4. Monte Carlo, {n_mc} runs (Figure 6 analog)</h2>")
        parts.append(
            "<p>Per time step over the runs: mean error (truth − estimate, eq. 23), its standard deviation "
            "(eq. 24) and the mean σ-bound the filter reports (eq. 25), in kPa; thin green lines are individual "
            "runs. An honest filter has its error std near its σ-bound.</p>"
        )
        parts.append(_img(_monte_carlo_figure(series, estimators), "Monte Carlo indexes"))
        mc_show = mc_table.copy()
        mc_show["estimator"] = mc_show["estimator"].map(LABELS)
        parts.append(_table(mc_show))

    scen = [s for s in specs if s.kind == "scenario"]
    if scen:
        parts.append("<h2>5. Scenario runs (Figures 7–13 analogs)</h2>")
        parts.append(
            "<p>Estimates with their ±2σ bands (shaded) against the true pressure; below, the IMM's mode probabilities.</p>"
        )
        for s in scen:
            parts.append(f"<h3>{html.escape(s.title)}</h3>")
            info = ", ".join(f"{k} = {_short(v)}" for k, v in s.info.items())
            parts.append(f"<p><small>{html.escape(info)}</small></p>")
            if s.name == "non_iso_road":
                parts.append(_img(_road_psd_figure(s), "road PSD against the ISO bands"))
            parts.append(_img(_scenario_figure(s.name, series, estimators), s.title))

    parts.append("<h2>6. Metrics</h2>")
    parts.append(
        "<p>Per run and estimator (all rows in <code>metrics.csv</code>; Monte Carlo rows summarized by the "
        f"indexes above). Converged: error within ±{PRESSURE_TOLERANCE_KPA:g} kPa (5 % of p0) from then to the end; "
        "mean error and RMSE (estimate − truth) after convergence, or over the last half if it never converges; "
        "inside 1σ / 2σ over the same samples.</p>"
    )
    cols = ["run", "estimator", "true_pressure_end_kpa", "estimate_end_kpa", "time_to_converge_s", "mean_error_kpa",
            "rmse_kpa", "mean_abs_error_after_2s_pct", "inside_2sigma"]  # fmt: skip
    shown = metrics[metrics.kind == "scenario"][cols].copy()
    shown["estimator"] = shown["estimator"].map(LABELS)
    shown.columns = ["run", "estimator", "true p at end, kPa", "estimate at end, kPa", "converged at, s",
                     "mean error, kPa", "RMSE, kPa", "mean |error| after 2 s, %", "inside ±2σ"]  # fmt: skip
    parts.append(_table(shown))
    if n_mc:
        mc_rows = metrics[metrics.kind == "monte_carlo"]
        agg = (
            mc_rows.groupby(["estimator", "road_class"])
            .agg(
                runs=("run", "size"),
                median_time_to_converge_s=("time_to_converge_s", "median"),
                converged_fraction=("time_to_converge_s", lambda x: float(np.isfinite(x).mean())),
                mean_error_end_kpa=("error_end_kpa", "mean"),
                rmse_end_kpa=("error_end_kpa", lambda x: float(np.sqrt(np.mean(np.square(x))))),
                **(
                    {"median_level_estimate_over_truth": ("road_level_ratio_end", "median")}
                    if "road_level_ratio_end" in mc_rows
                    else {}
                ),
            )
            .reset_index()
        )
        agg["estimator"] = agg["estimator"].map(LABELS)
        parts.append("<p>Monte Carlo runs by road class (error = estimate − truth at the end):</p>")
        parts.append(_table(agg))

    parts.append("<h2>7. Reproduce</h2>")
    timings = summary.get("timings", {})
    parts.append(
        f"<p>Configuration hash <code>{html.escape(summary['config_hash'])}</code>. Re-running the same command "
        "with the same output folder reuses every finished run and estimate.</p>"
    )
    parts.append(
        "<pre>"
        + html.escape(
            json.dumps(
                {
                    "config": summary["config"],
                    "versions": summary["versions"],
                    "identification": summary["identification"],
                    "timings_of_previous_stages": timings,
                },
                indent=1,
            )
        )
        + "</pre>"
    )
    parts.append("</body></html>")
    text = "\n".join(parts)
    atomic_write(path, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
