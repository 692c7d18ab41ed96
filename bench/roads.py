"""Benchmark: time to generate and classify 1 km of road at 0.02 m spacing.

Run: ``python bench/roads.py`` — prints one JSON object. Target (issue 2):
generating 1 km at 0.02 m takes well under a second with either generator.
"""

from __future__ import annotations

import json
import platform
import time

import numpy as np

from suvtwin.roads.profile import generate_road
from suvtwin.roads.roughness import classify_profile
from suvtwin.roads.spec import RoadSpec, SegmentSpec

REPEATS = 20


def _median_seconds(fn) -> float:
    times = []
    for i in range(REPEATS):
        start = time.perf_counter()
        fn(i)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> dict:
    result = {"length_m": 1000.0, "spacing_m": 0.02, "samples_per_track": 50001, "repeats": REPEATS}
    for method in ("shape-filter", "superposition"):
        spec = RoadSpec(
            segments=[SegmentSpec(length_m=1000.0, road_class="C")], spacing_m=0.02, method=method
        )
        generate_road(spec, seed=0)  # warm-up
        result[f"generate_{method}_s"] = _median_seconds(lambda i, s=spec: generate_road(s, seed=i))
    road = generate_road(RoadSpec(segments=[SegmentSpec(length_m=1000.0, road_class="C")]), seed=0)
    result["classify_one_track_s"] = _median_seconds(lambda i: classify_profile(road.z[0], road.spacing_m))
    result["python"] = platform.python_version()
    result["machine"] = platform.machine()
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main()
