"""The report's section on Solmaz's deflated-tyre detection (16 two-track models) on the MuJoCo SUV.

Usual call: ``parts.extend(lateral_detection_html(study))`` with the campaign's
``lateral_detection.json`` (:func:`suvtwin.pipeline.lateral_detection.monte_carlo_study`).

The analog of the paper's Figure 7 (the selected model over time in one lane change, per
detector variant), the confusion matrix over tyres (true model vs final pick), the detection
delay histogram, the false-alarm rate, and what the MF-Tyre pressure coefficients imply for the
paper's premise. Draws only from the stored study; never simulates.
"""

from __future__ import annotations

import html

import numpy as np
import pandas as pd

__all__ = ["lateral_detection_html", "selected_model_figure"]

_NAMES = {1: "RR", 2: "RL", 4: "FR", 8: "FL", 16: "none"}
_VARIANT_LABELS = {
    "esc_body": "ESC sensor fixed to the body (roll's g·sin φ in a_y), β by eq. 10",
    "roll_compensated": "roll-compensated a_y, β by eq. 10",
    "ideal_sideslip": "roll-compensated a_y, true β",
}
_CASE_LABELS = {
    "shipped": "shipped tyre (cornering stiffness rises at low pressure, PPY1 < 0)",
    "softer_deflated": "sensitivity tyre (cornering stiffness 20 % lower at 150 kPa, paper's premise)",
}


def _name(n: int | str) -> str:
    n = int(n)
    if n in _NAMES:
        return f"{n} ({_NAMES[n]})"
    flags = [w for w, bit in (("FL", 8), ("FR", 4), ("RL", 2), ("RR", 1)) if n & bit]
    return f"{n} ({' '.join(flags)})"


def selected_model_figure(example: dict, title: str) -> str:
    """Selected model number over time, one line per detector variant (the paper's Fig. 7 analog).
    Returns a PNG data URL."""
    from suvtwin.pipeline.report.figures import _png, _pyplot

    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 3.2))
    truth = None
    for variant, color in zip(_VARIANT_LABELS, ("tab:red", "tab:blue", "tab:green"), strict=True):
        series = example.get(variant)
        if not series or "selected" not in series:
            continue
        ax.step(
            series["t_s"],
            series["selected"],
            where="post",
            color=color,
            lw=1.0,
            label=_VARIANT_LABELS[variant],
        )
        truth = series["truth"]
        onset = series["onset_s"]
    if truth is not None:
        ax.axhline(truth, color="k", lw=0.8, ls="--", label=f"truth: model {_name(truth)}")
        ax.axvline(onset, color="0.5", lw=0.8, ls=":", label="steering onset")
    ax.set_ylim(0, 17)
    ax.set_yticks([1, 2, 4, 8, 12, 15, 16])
    ax.set_xlabel("time, s")
    ax.set_ylabel("selected model")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    return _png(fig)


def _delay_figure(study: dict) -> str:
    from suvtwin.pipeline.report.figures import _png, _pyplot

    plt = _pyplot()
    cases = list(study["cases"])
    fig, axes = plt.subplots(1, len(cases), figsize=(4.6 * len(cases), 3.0), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        for variant, color in zip(_VARIANT_LABELS, ("tab:red", "tab:blue", "tab:green"), strict=True):
            d = study["cases"][case]["variants"][variant]["delay_s"]
            edges = np.asarray(d["histogram_edges_s"], dtype=float)
            counts = np.asarray(d["histogram_counts"], dtype=float)
            ax.step(np.arange(edges.size - 1), counts, where="mid", color=color, label=variant)
            ax.set_xticks(np.arange(edges.size - 1))
            ax.set_xticklabels(
                [f"{a:g}–{b:g}" for a, b in zip(edges[:-1], edges[1:], strict=True)], rotation=45, fontsize=7
            )
        ax.set_title(case, fontsize=9)
        ax.set_xlabel("delay after steering onset, s")
        ax.set_ylabel("deflated runs found")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return _png(fig)


def _tire_text(t: dict) -> str:
    if "front" in t:
        return f"front {_tire_text(t['front'])}, rear {_tire_text(t['rear'])}"
    return f"k₁ {t['k1']:.3f}, k₂ {t['k2_n']:.0f} N, k₃ {t['k3_per_rad']:.2f} /rad"


def _bank_text(bank: dict) -> str:
    slip = bank.get("fit", {}).get("nominal", {}).get("slip_angles", "tyre")
    if slip == "detector":
        how = "per-axle effective characteristics, fitted against the detector's eq. 8 slip and eq. 7 loads"
    else:
        how = "one tyre on all wheels, fitted against the tyres' own slip angles and loads"
    return f"nominal {_tire_text(bank['nominal'])}; deflated {_tire_text(bank['deflated'])} ({how})"


def lateral_detection_html(study: dict) -> list[str]:
    """HTML parts of the section (see the module docstring)."""
    from suvtwin.pipeline.report.page import _img, _table

    parts = [
        "<h2>Deflated-tyre detection from ESC signals (Solmaz, 16 two-track models) on the SUV</h2>",
        f"<p>{study['runs_per_case']} ISO 3888-1 double lane changes per tyre case, driven by pure "
        "pursuit on the standard's centreline (flat road, 80–120 km/h, left or right, one tyre "
        "FL/FR/RL/RR at 130–180 kPa or none, extra load 0–300 kg). The bank's arctan tyres are fitted "
        "to the SUV's MF tyre from simulator runs at 250 kPa (nominal) and 155 kPa (the bank's one "
        "deflated level). Final pick = the model selected at the end of the run; delay = steering "
        "onset to the first sample from which the true model stays selected. Method, mapping and "
        "findings: <code>docs/lateral_detection.md</code>.</p>",
    ]
    rows = []
    for case, c in study["cases"].items():
        for variant, s in c["variants"].items():
            q = s["delay_s"]["quantiles_0_25_50_75_90_100"]
            fa = s["false_alarm_rate_no_deflation"]
            rows.append(
                {
                    "tyre": case,
                    "detector": variant,
                    "runs": s["runs"],
                    "correct tyre %": f"{100 * s['correct_rate']:.1f}",
                    "delay median / 90 % s": "—" if q is None else f"{q[2]:.2f} / {q[4]:.2f}",
                    "false alarms (no deflation) %": "—" if fa is None else f"{100 * fa:.1f}",
                }
            )
    parts.append(_table(pd.DataFrame(rows)))
    for case, c in study["cases"].items():
        parts.append(f"<h3>{html.escape(_CASE_LABELS.get(case, case))}</h3>")
        parts.append(f"<p>Fitted bank: {_bank_text(c['bank'])}.</p>")
        for variant in ("roll_compensated", "esc_body"):
            matrix = c["variants"][variant]["confusion_truth_vs_final"]
            picks = sorted({int(p) for row in matrix.values() for p, n in row.items() if n})
            frame = pd.DataFrame(
                [
                    {"true \\ final": _name(t), **{_name(p): row.get(str(p), 0) for p in picks}}
                    for t, row in matrix.items()
                ]
            )
            parts.append(f"<p>Confusion matrix, {html.escape(_VARIANT_LABELS[variant])}:</p>")
            parts.append(_table(frame))
        if c.get("example"):
            d = c["example"]["draw"]
            title = (
                f"{case}: run {d['i']}, {d['speed_kmh']:g} km/h, {d['direction']}, "
                f"{d['tyre'] or 'none'} at {d['pressure_kpa']:g} kPa, load {d['load_kg']:g} kg"
            )
            parts.append(_img(selected_model_figure(c["example"], title), title))
    parts.append(_img(_delay_figure(study), "detection delay histograms"))
    table = study.get("cornering_stiffness_vs_pressure", {})
    if table:
        rows = []
        for case, t in table.items():
            for fz, k, ch in zip(t["loads_n"], t["stiffness_n_per_rad"], t["change_percent"], strict=True):
                rows.append(
                    {
                        "tyre": case,
                        "load N": f"{fz:.0f}",
                        "C at 250 kPa, kN/rad": f"{k[0] / 1e3:.1f}",
                        "C at 150 kPa, kN/rad": f"{k[-1] / 1e3:.1f}",
                        "change %": f"{ch:+.1f}",
                    }
                )
        parts.append(
            "<p><b>What the MF-Tyre pressure coefficients imply.</b> The shipped tyre's PPY1 &lt; 0 (the TNO "
            "example tyre's value) makes its cornering stiffness <em>rise</em> as the pressure falls, the "
            "opposite of paper 004's premise (its deflated tyre is softer: k₂ 4500 N &lt; 5650 N, k₃ 12 &lt; "
            "15 /rad). The detector is therefore also scored on a labelled sensitivity tyre whose stiffness "
            "falls (PPY1 = +0.5, PPY2 = 0; friction terms unchanged). Zero-slip cornering stiffness of the "
            "simulator's tyre:</p>"
        )
        parts.append(_table(pd.DataFrame(rows)))
    return parts
