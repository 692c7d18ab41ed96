"""Statistics of generated roads against ISO 8608, per class and generator.

Run: ``python bench/road_statistics.py [n_seeds]`` — prints JSON. For every class
A–H and both generators, `n_seeds` (default 20) roads of 300 m at 0.02 m: how many
fitted Gd(n0) (w = 2, left track) lie inside the class bounds, the free-fit
waviness, and the mean elevation std against the square root of the target PSD's
integral (ISO PSD over 0.01–10 cycles/m for superposition; the shape filter's
own PSD q/(α²+Ω²) over all Ω, and for comparison the ISO band integral).
"""

from __future__ import annotations

import json
import sys

import numpy as np
from scipy import integrate

from suvtwin.roads.iso8608 import CLASSES, class_bounds, class_level, displacement_psd
from suvtwin.roads.profile import SHAPE_FILTER_ALPHA, generate_road, shape_filter_intensity
from suvtwin.roads.roughness import classify_profile
from suvtwin.roads.spec import RoadSpec, SegmentSpec


def main(n_seeds: int = 20) -> dict:
    out = {"length_m": 300.0, "spacing_m": 0.02, "n_seeds": n_seeds, "classes": {}}
    for a, letter in enumerate(CLASSES):
        level = class_level(letter)
        lower, upper = class_bounds(letter)
        iso_std = np.sqrt(integrate.quad(lambda n, g=level: displacement_psd(n, gd_n0=g), 0.01, 10.0)[0])
        q = shape_filter_intensity(level)
        filter_std = np.sqrt(np.pi * q / (2 * SHAPE_FILTER_ALPHA))
        row = {}
        for method in ("shape-filter", "superposition"):
            spec = RoadSpec(segments=[SegmentSpec(length_m=300.0, road_class=letter)], method=method)
            fits, stds = [], []
            for seed in range(n_seeds):
                road = generate_road(spec, seed=1000 * a + seed)  # fresh seeds per class
                fits.append(classify_profile(road.z[0], road.spacing_m))
                stds.append(float(road.z[0].std()))
            gd = np.array([f.gd_n0 for f in fits])
            w = np.array([f.waviness for f in fits])
            target = filter_std if method == "shape-filter" else iso_std
            row[method] = {
                "inside_class": int(np.sum((gd >= lower) & (gd <= upper))),
                "gd_n0_over_class_mean": [
                    float(np.min(gd) / level),
                    float(np.mean(gd) / level),
                    float(np.max(gd) / level),
                ],
                "waviness_min_mean_max": [float(w.min()), float(w.mean()), float(w.max())],
                "std_mean_m": float(np.mean(stds)),
                "std_over_target": float(np.mean(stds) / target),
                "std_over_iso_band_target": float(np.mean(stds) / iso_std),
            }
        out["classes"][letter] = row
    print(json.dumps(out, indent=1))
    return out


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
