"""The report's figures, as PNG data URLs: Monte Carlo indexes, scenario tracks, road PSD, draws.

Usual call: ``src = monte_carlo_figure(series, ("imm_synthetic", "joint"))``; each function
draws only from what the campaign stored (``series`` of
:func:`suvtwin.pipeline.campaign.metrics.score_campaign`, the run specs), never re-simulates.
Labels and colours are the registry's (:data:`suvtwin.pipeline.estimator_registry.ESTIMATORS`).
matplotlib is imported on the first figure.
"""

from __future__ import annotations

import base64
import io

import numpy as np

from suvtwin.pipeline.estimator_registry import ESTIMATORS

__all__ = [
    "draws_figure",
    "monitor_figure",
    "monte_carlo_figure",
    "road_estimate_figure",
    "road_psd_figure",
    "scenario_figure",
]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _png(fig) -> str:
    plt = _pyplot()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode()


def monte_carlo_figure(series: dict, estimators: tuple[str, ...]) -> str:
    """Figure 6 analog: per estimator, the Monte Carlo mean error (eq. 23), ± error std (eq. 24) and
    ± mean σ-bound (eq. 25) over time, kPa, with ten runs' errors."""
    n = len(estimators)
    plt = _pyplot()
    fig, axes = plt.subplots(n, 1, figsize=(9, 2.4 * n), sharex=True, squeeze=False)
    for ax, e in zip(axes[:, 0], estimators, strict=True):
        t, idx, errors = series["monte_carlo"][e]
        step = max(1, t.size // 2000)
        for row in errors[: min(10, errors.shape[0])]:
            ax.plot(t[::step], row[::step], color="tab:green", lw=0.4, alpha=0.5)
        ax.plot(t[::step], idx.mean_error[::step], color="tab:red", lw=1.5, label="mean error (eq. 23)")
        for band, style, label in (
            (idx.error_std, "b--", "± error std (eq. 24)"),
            (idx.sigma_bound, "k--", "± mean σ-bound (eq. 25)"),
        ):
            for sign in (1, -1):
                ax.plot(t[::step], sign * band[::step], style, lw=1, label=label if sign > 0 else None)
        lim = np.nanmax(np.abs(idx.mean_error[t >= 1.0])) + 2 * np.nanmax(idx.error_std[t >= 1.0])
        ax.set_ylim(-min(max(lim, 30.0), 400.0), min(max(lim, 30.0), 400.0))
        ax.set_ylabel("truth − estimate, kPa")
        ax.set_title(ESTIMATORS[e].label, fontsize=10)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, ncol=3, loc="upper right")
    axes[-1, 0].set_xlabel("time, s")
    fig.tight_layout()
    return _png(fig)


def scenario_figure(name: str, series: dict, estimators: tuple[str, ...]) -> str:
    """Figures 7–11 analogs: the estimates of scenario run `name` with ±2σ bands against the true
    pressure (kPa); below, the mode probabilities of the estimators that have them."""
    t, truth = series["truth"][name]
    imm = [e for e in estimators if ESTIMATORS[e].mode_probabilities]
    rows = 1 + len(imm)
    plt = _pyplot()
    fig, axes = plt.subplots(rows, 1, figsize=(9, 3.2 + 1.8 * len(imm)), sharex=True, squeeze=False,
                             gridspec_kw={"height_ratios": [2.2] + [1] * len(imm)})  # fmt: skip
    ax = axes[0, 0]
    step = max(1, t.size // 2000)
    ax.plot(t[::step], truth[::step], "k", lw=2, label="true pressure")
    for e in estimators:
        est = series["estimates"][(e, name)]
        p, s = est["pressure_hat_kpa"].to_numpy(), est["pressure_sigma_kpa"].to_numpy()
        ax.plot(t[::step], p[::step], color=ESTIMATORS[e].color, lw=1.2, label=ESTIMATORS[e].label)
        ax.fill_between(
            t[::step], (p - 2 * s)[::step], (p + 2 * s)[::step], color=ESTIMATORS[e].color, alpha=0.08
        )
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
        ax.set_title(f"{ESTIMATORS[e].label}: mode probabilities (trailing 1 s mean)", fontsize=9)
        ax.legend(fontsize=7, ncol=4, loc="upper right")
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("time, s")
    fig.tight_layout()
    return _png(fig)


def road_psd_figure(x_m: np.ndarray, z_m: np.ndarray) -> str:
    """Displacement PSD of the road a wheel drove over (elevation `z_m` at positions `x_m`, m, as the run
    stored them), resampled to uniform spacing, against the ISO 8608 class bands (Fig. 12 analog).

    A run stores the road as the tire met it (``{corner}_road_z_m``: enveloped over the contact
    patch), so wavelengths shorter than the patch are attenuated."""
    from suvtwin.roads.iso8608 import CLASSES, class_bounds, displacement_psd
    from suvtwin.roads.roughness import profile_psd

    order = np.argsort(x_m, kind="stable")
    x, z = np.asarray(x_m, dtype=float)[order], np.asarray(z_m, dtype=float)[order]
    grid = np.linspace(x[0], x[-1], x.size)
    n, psd = profile_psd(np.interp(grid, x, z), float(grid[1] - grid[0]), segment_m=20.0)
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4))
    keep = n > 0
    ax.loglog(n[keep], psd[keep], "k", lw=1, label="road under the wheel, enveloped (Welch)")
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


def draws_figure(specs: list) -> str:
    """The Monte Carlo draws (paper 000 Table 4): pressure against speed, and road level per class."""
    mc = [s for s in specs if s.kind == "monte_carlo"]
    plt = _pyplot()
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


def monitor_figure(example: dict, title: str) -> str:
    """One monitored tyre: true pressure, the online estimate ± 2σ, and the warning (if any), kPa over s.

    `example`: the campaign's monitor study example (``t_s``, ``truth_kpa``, ``t_est_s``,
    ``p_hat_kpa``, ``sigma_kpa``, ``warning``, ``placard_kpa``)."""
    plt = _pyplot()
    color = ESTIMATORS["online"].color
    fig, ax = plt.subplots(figsize=(9, 3.2))
    t_est = np.asarray(example["t_est_s"], dtype=float)
    p = np.asarray(example["p_hat_kpa"], dtype=float)
    sigma = np.asarray(example["sigma_kpa"], dtype=float)
    ax.plot(example["t_s"], example["truth_kpa"], color="k", lw=1.5, label="true pressure")
    ax.step(t_est, p, where="post", color=color, label="online monitor")
    ax.fill_between(t_est, p - 2 * sigma, p + 2 * sigma, step="post", color=color, alpha=0.2, label="± 2σ")
    placard = example.get("placard_kpa")
    if placard:
        ax.axhline(0.8 * placard, color="tab:red", ls=":", lw=1, label="20 % below placard")
    warned = np.flatnonzero(np.asarray(example["warning"], dtype=bool))
    if warned.size:
        ax.axvline(t_est[warned[0]], color="tab:red", lw=1, label=f"warning at {t_est[warned[0]]:.0f} s")
    ax.set_xlabel("time, s")
    ax.set_ylabel(f"pressure {example['tyre']}, kPa")
    ax.set_title(title, fontsize=10)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return _png(fig)


def road_estimate_figure(example: dict) -> str:
    """True vs estimated road under the front-left tyre (Wang et al. 2017 on the SUV), mm over the
    wheel's x, m.

    `example`: the road-estimation study's example (``x_m``, ``raw_m``, ``enveloped_m``,
    ``KF_m``, ``MME&KF_m``, ``class``, ``delta_m_kg``, ``seed``;
    :func:`suvtwin.pipeline.road_estimation.mujoco_study`)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 3.4))
    x = np.asarray(example["x_m"], dtype=float)
    raw = 1e3 * np.asarray(example["raw_m"])
    ax.plot(x, raw, color="k", lw=1.4, label="heightfield under the tyre (raw)")
    ax.plot(x, 1e3 * np.asarray(example["enveloped_m"]), color="0.5", lw=0.8, ls="--", label="enveloped")
    for name, color in (("KF", "tab:blue"), ("MME&KF", "tab:orange")):
        if f"{name}_m" in example:
            ax.plot(x, 1e3 * np.asarray(example[f"{name}_m"]), color=color, lw=1.0, label=name)
    ax.set_xlabel("distance x of the front-left wheel centre, m")
    ax.set_ylabel("road elevation, mm")
    ax.set_title(f"class {example['class']}, Δm = {example['delta_m_kg']:+.0f} kg, seed {example['seed']}",
                 fontsize=10)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    return _png(fig)
