"""Picture of a road: its profile and its PSD against the ISO 8608 class bands.

Usual call: ``plot_road(road, "road.png")``.

Top: elevation of both tracks over distance. Bottom: each track's Welch PSD
(log-log) over the shaded ISO 8608 classes A–H (w = 2, ×/÷2 bands), with the
fitted w = 2 line and, for a generated road, the target PSD of each segment.
"""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from suvtwin.files import save_figure  # noqa: E402
from suvtwin.roads.iso8608 import CLASSES, class_bounds, displacement_psd  # noqa: E402
from suvtwin.roads.profile import Road  # noqa: E402
from suvtwin.roads.roughness import DEFAULT_FIT_BAND, classify_profile, profile_psd  # noqa: E402

__all__ = ["plot_road"]

_TRACKS = (("left", "tab:blue"), ("right", "tab:orange"))


def plot_road(road: Road, path: str | os.PathLike, *, band: tuple[float, float] = DEFAULT_FIT_BAND) -> None:
    """Draw `road`'s profile and PSD against the ISO 8608 bands into `path` (PNG).

    Written atomically: a failure leaves no partial file.
    """
    fits = [classify_profile(road.z[i], road.spacing_m, band=band) for i in range(2)]
    n, psd = profile_psd(road.z, road.spacing_m, segment_m=4.0 / fits[0].band[0])
    fig, (ax_z, ax_g) = plt.subplots(2, 1, figsize=(9, 9), gridspec_kw={"height_ratios": [1, 1.6]})

    for i, (name, color) in enumerate(_TRACKS):
        ax_z.plot(road.x, road.z[i] * 1e3, color=color, lw=0.6, label=f"{name} track")
    ax_z.set_xlabel("distance x [m]")
    ax_z.set_ylabel("elevation z [mm]")
    ax_z.set_xlim(road.x[0], road.x[-1])
    ax_z.legend(loc="upper right", fontsize=8)
    ax_z.grid(alpha=0.3)
    if road.spec is not None:
        title = " | ".join(
            f"{s.label} ({s.length_m:g} m, Gd(n0)={s.level:.3g} m³, w={s.waviness:g})"
            for s in road.spec.segments
        )
        ax_z.set_title(
            f"{road.spec.method}, seed {road.seed}, {road.spec.tracks} tracks\n{title}", fontsize=9
        )

    valid = n > 0
    n_plot = np.logspace(np.log10(n[valid][0]), np.log10(n[-1]), 200)
    for k, letter in enumerate(CLASSES):
        lower, upper = class_bounds(letter)
        ax_g.fill_between(
            n_plot,
            displacement_psd(n_plot, gd_n0=lower),
            displacement_psd(n_plot, gd_n0=upper),
            color="0.85" if k % 2 == 0 else "0.93",
            lw=0,
        )
    for i, (name, color) in enumerate(_TRACKS):
        fit = fits[i]
        ax_g.loglog(
            n[valid],
            psd[i][valid],
            color=color,
            lw=0.8,
            label=f"{name}: Gd(n0)={fit.gd_n0:.3g} m³ → class {fit.road_class}; "
            f"free fit w={fit.waviness:.2f}",
        )
        fit_n = np.logspace(np.log10(fit.band[0]), np.log10(fit.band[1]), 20)
        ax_g.loglog(fit_n, displacement_psd(fit_n, gd_n0=fit.gd_n0), color=color, ls="--", lw=1.2)
    if road.spec is not None:
        for s in road.spec.segments:
            ax_g.loglog(
                n_plot,
                displacement_psd(n_plot, gd_n0=s.level, waviness=s.waviness),
                color="k",
                ls=":",
                lw=1.0,
            )
        ax_g.plot([], [], color="k", ls=":", label="ISO target PSD per segment")
    ax_g.axvspan(*fits[0].band, color="tab:green", alpha=0.06, label="fit band")
    ax_g.set_xlabel("spatial frequency n [cycles/m]")
    ax_g.set_ylabel("displacement PSD Gd(n) [m³]")
    ax_g.set_xlim(n_plot[0], n_plot[-1])
    class_a_floor = displacement_psd(n_plot[-1], gd_n0=class_bounds("A")[0])
    positive = psd[:, valid][psd[:, valid] > 0]
    y_low, y_high = max(positive.min(), class_a_floor / 10) / 3, positive.max() * 10
    ax_g.set_ylim(y_low, y_high)
    for letter in CLASSES:  # label each band where its centre line is inside the axes
        centre = displacement_psd(n_plot, gd_n0=class_bounds(letter)[0] * 2)
        visible = np.flatnonzero((centre > y_low * 2) & (centre < y_high / 2))
        if visible.size:
            j = visible[-1]
            ax_g.text(n_plot[j], centre[j], letter, ha="right", va="center", fontsize=9, color="0.3")
    ax_g.legend(loc="lower left", fontsize=8)
    ax_g.grid(alpha=0.3)
    ax_g.set_title("ISO 8608 classes A–H shaded (w = 2, ×/÷2 about each class mean)", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
