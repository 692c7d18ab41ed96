"""Figures of an identification: Pareto-front projections and the paper's Figure 5 analog.

Usual call: ``plot_pareto(result, data, "pareto_B.png", title="class B")``;
``plot_fit(data, parameters, [i_230, i_130], "fig5_B.png")``.

- Pareto projections: the 18 objectives are nine (sprung, unsprung) RMSE pairs, one per
  scenario; each panel plots one scenario's pair over the final non-dominated set, with
  the chosen compromise marked.
- Figure 5 analog (Brancati & Tufano 2022): unsprung acceleration of the ground truth
  and of the identified quarter car at 60 km/h on a class B road, at 230 and 130 kPa.
"""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from suvtwin.files import save_figure  # noqa: E402
from suvtwin.identification.quarter_car_fit import FitData, IdentificationResult, simulate_accelerations  # noqa: E402

__all__ = ["plot_fit", "plot_pareto"]


def plot_pareto(result: IdentificationResult, data: FitData, path: str | os.PathLike, *, title: str) -> None:
    """Nine panels: sprung vs unsprung RMSE (m/s²) per scenario over the final front (PNG)."""
    n = data.road.shape[0]
    cols = 3
    rows = int(np.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.8 * rows), squeeze=False)
    labels = data.labels or tuple(f"scenario {i}" for i in range(n))
    for i in range(rows * cols):
        ax = axes[i // cols][i % cols]
        if i >= n:
            ax.axis("off")
            continue
        ax.scatter(result.front_f[:, i], result.front_f[:, n + i], s=8, color="0.5", label="non-dominated")
        ax.scatter(
            result.objectives[i], result.objectives[n + i], s=40, color="tab:red", marker="*", label="chosen"
        )
        ax.set_title(labels[i].replace("_", ", "), fontsize=9)
        ax.set_xlabel("sprung RMSE [m/s²]", fontsize=8)
        ax.set_ylabel("unsprung RMSE [m/s²]", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"Pareto front projections, {title} (eq. 20–21 objectives)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=100)


def plot_fit(
    data: FitData, parameters: dict, scenarios: list[int], path: str | os.PathLike, *, window_s: float = 1.0
) -> None:
    """Unsprung acceleration, ground truth vs identified QC, one panel per scenario (PNG)."""
    fig, axes = plt.subplots(len(scenarios), 1, figsize=(9, 3.0 * len(scenarios)), squeeze=False)
    t = np.arange(data.road.shape[1]) * data.dt
    start = max(t[-1] / 2 - window_s / 2, 0.0)
    keep = (t >= start) & (t <= start + window_s)
    for ax, i in zip(axes[:, 0], scenarios, strict=True):
        _, model = simulate_accelerations(parameters, data, i)
        truth = data.accel_unsprung[i]
        nrmse = np.sqrt(np.mean((model - truth) ** 2)) / np.sqrt(np.mean(truth**2))
        ax.plot(t[keep], truth[keep], color="k", lw=1.0, label="MuJoCo SUV")
        ax.plot(
            t[keep], model[keep], color="tab:red", lw=1.0, ls="--", label=f"identified QC (NRMSE {nrmse:.2f})"
        )
        label = data.labels[i].replace("_", ", ") if data.labels else f"scenario {i}"
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("unsprung acceleration [m/s²]")
        ax.legend(fontsize=8, loc="upper right")
        ax.grid(alpha=0.3)
    fig.suptitle("Figure 5 analog: unsprung acceleration, class B road, 60 km/h", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=100)
