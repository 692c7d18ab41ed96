"""The report's section on paper 001's input estimation (CIE, AWIE) on the MuJoCo SUV.

Usual call: ``parts.extend(input_estimation_html(study))`` with the campaign's
``input_estimation.json`` (:func:`suvtwin.pipeline.input_estimation.input_estimation_study`).

Lin et al. 2021's Tables 2–3 beside ours (the paper's eq. 32 value; ours in the eq. 32 reading
and in the standard 100‖u − û‖/‖u‖, against the half car's true input and against the
suspension loads), and the analogs of its Figures 10–15 (estimated against true vertical
force and pitch torque over time; 30 km/h with AWIE and CIE f_tr = 0.9, 90 km/h with AWIE and
CIE f_tr = 0.1). Draws only from the stored study; never simulates.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = ["input_estimation_figure", "input_estimation_html"]

_ROAD_LABELS = {"sine_bump": "sine bump", "cleat": "rectangular cleat", "random": "ISO random road"}
_CHANNELS = ("vertical force", "pitch torque")
_FIGURE_NUMBERS = {(30, "sine_bump"): 10, (30, "cleat"): 11, (30, "random"): 12,
                   (90, "sine_bump"): 13, (90, "cleat"): 14, (90, "random"): 15}  # fmt: skip


def _rows(cells: list[dict], keep) -> pd.DataFrame:
    rows = []
    for c in cells:
        if not keep(c):
            continue
        for i, channel in enumerate(_CHANNELS):
            paper = c["paper"]
            rows.append(
                {
                    "road": _ROAD_LABELS.get(c["road"], c["road"]),
                    "km/h": f"{c['speed_kmh']:g}",
                    "method": c["method"],
                    "load": channel,
                    "paper NEE, %": "—" if paper is None else f"{paper[i]:.2f}",
                    "ours, eq. 32 reading, %": f"{c['eq32']['mean'][i]:.2f}",
                    "ours, standard vs u*, %": (
                        f"{c['aligned']['mean'][i]:.2f} ± {c['aligned']['std'][i]:.2f}"
                    ),
                    "ours, standard vs suspension loads, %": f"{c['suspension_aligned']['mean'][i]:.2f}",
                }
            )
    return pd.DataFrame(rows)


def input_estimation_figure(examples: list[dict], title: str) -> str:
    """Estimated against true vertical force (N) and pitch torque (N m) over time, one row per method.

    `examples`: the study's examples of one road and speed (``t_s``, ``truth``, ``estimate``,
    ``method``). Returns a PNG data URL.
    """
    from suvtwin.pipeline.report.figures import _png, _pyplot

    plt = _pyplot()
    fig, axes = plt.subplots(len(examples), 2, figsize=(10, 2.6 * len(examples)), squeeze=False)
    for row, ex in zip(axes, examples, strict=True):
        t = np.asarray(ex["t_s"], dtype=float)
        for j, ax in enumerate(row):
            ax.plot(t, np.asarray(ex["truth"][j]) / 1e3, color="k", lw=1.2, label="simulator (u*)")
            ax.plot(t, np.asarray(ex["estimate"][j]) / 1e3, color="tab:orange", lw=1.0, ls="--",
                    label=ex["method"])  # fmt: skip
            ax.set_ylabel(f"{_CHANNELS[j]}, {'kN' if j == 0 else 'kN m'}")
            ax.set_title(f"{ex['method']}: {_CHANNELS[j]}", fontsize=9)
            ax.legend(fontsize=7, loc="best")
        row[0].set_xlabel("time, s")
        row[1].set_xlabel("time, s")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _png(fig)


def input_estimation_html(study: dict) -> list[str]:
    """The section's HTML parts: set-up, Tables 2–3 beside the paper's, Figures 10–15 analogs."""
    s = study["settings"]
    car = s["half_car"]
    parts = [
        "<h2>Paper 001 on the MuJoCo SUV: wheel vertical force and pitch torque (CIE, AWIE)</h2>",
        "<p>Lin et al. 2021's Kalman filter with recursive least squares, constant fading (CIE) or adaptive "
        "(AWIE), on the SUV's measured heave and pitch (white noise σ = "
        f"{s['measurement_std']:.3g} m and rad, {s['n_seeds']} draws, Q = {s['q']:.3g}). Half car from the "
        f"SUV: m = {car['mass']:.0f} kg, I = {car['pitch_inertia']:.0f} kg m², "
        f"L_F = {car['front_length']:g} m, L_R = {car['rear_length']:g} m, "
        f"K_F = {car['front_stiffness']:.0f} N/m, "
        f"K_R = {car['rear_stiffness']:.0f} N/m, C_F = C_R = {car['front_damping']:.0f} N s/m. "
        "Roads: 0.1 m × 1 m sine bump and cleat on both tracks, ISO class C random road; 1.5 s runs. "
        "Truth from the simulator: the four suspension forces on the body, as the loads themselves "
        "(F_s = ΣF − mg, T_s = a₁F_front − a₂F_rear) and as the half car's input u* = [F_s, T_s] + Kx + Cẋ. "
        "The paper's NEE is its eq. 32, a difference of norms; we give that reading, 100(‖u‖ − ‖û‖)/‖u‖, "
        "and the standard 100‖u(k−1) − û(k)‖/‖u‖. Method and findings: <code>docs/input_estimation.md</code>."
        "</p>",
        "<h3>Table 2 analog (30 km/h)</h3>",
    ]
    from suvtwin.pipeline.report.page import _img, _table

    parts.append(_table(_rows(study["cells"], lambda c: c["speed_kmh"] == 30)))
    parts.append("<h3>Table 3 analog (30, 60, 90 km/h; CIE f_tr = 0.1 and AWIE)</h3>")
    parts.append(_table(_rows(study["cells"], lambda c: c["method"] != "CIE f=0.9")))
    closure = pd.DataFrame(
        [
            {"road": _ROAD_LABELS.get(c["road"], c["road"]), "km/h": f"{c['speed_kmh']:g}",
             "heave: ‖Mẍ − F_s‖/‖F_s‖, %": f"{c['percent'][0]:.2f}",
             "pitch: ‖Iθ̈ − T_s‖/‖T_s‖, %": f"{c['percent'][1]:.2f}"}
            for c in study["closure"]
        ]
    )  # fmt: skip
    parts.append(
        "<p>How far the body's own motion is from the suspension loads (the rest reaches the body through "
        "the suspension joints' constraints, mainly the tyres' longitudinal forces):</p>"
    )
    parts.append(_table(closure))
    groups: dict[tuple, list] = {}
    for ex in study["examples"]:
        groups.setdefault((int(ex["speed_kmh"]), ex["road"]), []).append(ex)
    if groups:
        parts.append("<h3>Figures 10–15 analogs: estimated against true loads</h3>")
    for (speed, road), examples in sorted(groups.items(), key=lambda kv: _FIGURE_NUMBERS.get(kv[0], 99)):
        number = _FIGURE_NUMBERS.get((speed, road))
        prefix = f"Figure {number} analog: " if number else ""
        title = f"{prefix}{_ROAD_LABELS.get(road, road)}, {speed} km/h"
        parts.append(_img(input_estimation_figure(examples, title), title))
    return parts
