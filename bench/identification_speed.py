"""Benchmark: wall time of the quarter-car identification.

Run: ``python bench/identification_speed.py [quick|paper]`` — prints JSON.

- ``quick``: one class (B), nine 10 s MuJoCo runs, NSGA-III pop 100 × 100 generations;
  target (issue 5) ≤ 60 s.
- ``paper``: classes A–D, pop 100 × 1000 generations (paper 000), two processes
  (2 cores); target ≤ 10 min. Also writes the parameter file to
  ``bench_identified_params.json`` for inspection.
"""

from __future__ import annotations

import json
import sys
import time

from suvtwin.pipeline.identification_runs import identify_classes, write_parameter_file


def main(mode: str = "quick") -> dict:
    start = time.perf_counter()
    if mode == "paper":
        content = identify_classes(
            ("A", "B", "C", "D"), duration_s=10.0, seed=1, pop_size=100, n_gen=1000, jobs=2
        )
        write_parameter_file(content, "bench_identified_params.json")
    else:
        content = identify_classes(("B",), duration_s=10.0, seed=1, pop_size=100, n_gen=100, jobs=1)
    wall = time.perf_counter() - start
    result = {"mode": mode, "wall_time_s": wall, "classes": content["classes"]}
    print(json.dumps(result, indent=2))
    return result


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "quick")
