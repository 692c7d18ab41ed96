"""Benchmark: start-up time of the ``suvtwin`` command line.

Run: ``python bench/startup.py [--repeats 5]`` — prints one JSON object: the wall time of
``suvtwin --help`` and of each subcommand's ``--help``, and the wall time of a 10 s
``suvtwin simulate`` (class C road, 60 km/h, 200 kPa, seed 1) next to the simulation time
that the command prints ("N steps in X s"). Each number is the best of `--repeats` runs
of a fresh process (subprocess, ``time.perf_counter``); the machine may be shared, and
the best run is the least disturbed one. Targets (issue 11): every ``--help`` ≤ 0.5 s,
the 10 s simulate ≤ 1.5 s wall on a quiet 2-core machine.

The simulate command is run once before timing, so that numba's on-disk cache of the
force kernel exists (a first run after a change of the kernel compiles it, ~10 s).
``simulate_10s.libraries_floor_s`` is the wall time of a process that only imports the
libraries the command needs (numpy, numba, MuJoCo, pydantic, pyarrow) and loads one cached
compiled function (numba sets up its compiler on the first one): the part of the start
that no change to suvtwin can remove.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SUBCOMMANDS = ("road", "classify", "simulate", "render", "estimate", "score", "identify", "run")
FLOOR = (
    "import os; os.environ.setdefault('MUJOCO_GL', 'disabled')\n"
    "import numpy as np, numba, mujoco, pydantic, pyarrow.parquet\n"
    "from suvtwin.mjcf.kernel import road_height\n"
    "road_height(0.5, 0.5, np.array([0, 1, 0, 1, 3, 3, 0, 1.0]), np.zeros((3, 3)))\n"
)
SIMULATE = ("simulate", "--road-class", "C", "--speed", "60", "--pressure", "200", "--duration", "10",
            "--seed", "1", "--no-progress")  # fmt: skip


def _command() -> list[str]:
    """The installed ``suvtwin`` script beside this interpreter, else ``python -m`` the CLI module."""
    script = Path(sys.executable).with_name("suvtwin")
    if script.is_file():
        return [str(script)]
    found = shutil.which("suvtwin")
    return [found] if found else [sys.executable, "-m", "suvtwin.pipeline.cli"]


def _run(args: list[str]) -> tuple[float, str]:
    """Wall time of one run, s, and its standard output; raises if the command fails."""
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(args)} exited {done.returncode}: {done.stderr.strip()}")
    return wall, done.stdout


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="runs per command; the best is reported")
    repeats = parser.parse_args().repeats
    cmd = _command()

    helps = {"suvtwin --help": min(_run([*cmd, "--help"])[0] for _ in range(repeats))}
    for name in SUBCOMMANDS:
        helps[f"suvtwin {name} --help"] = min(_run([*cmd, name, "--help"])[0] for _ in range(repeats))

    with tempfile.TemporaryDirectory() as folder:
        args = [*cmd, *SIMULATE, "--out", str(Path(folder) / "run.parquet")]
        _run(args)  # warm numba's cache (and the OS's file cache)
        walls, sims = [], []
        for _ in range(repeats):
            wall, out = _run(args)
            match = re.search(r"steps in ([0-9.]+) s", out)
            walls.append(wall)
            sims.append(float(match.group(1)) if match else float("nan"))
    floor = min(_run([sys.executable, "-c", FLOOR])[0] for _ in range(repeats))
    result = {
        "command": cmd,
        "repeats": repeats,
        "help_wall_s": {k: round(v, 3) for k, v in helps.items()},
        "help_wall_max_s": round(max(helps.values()), 3),
        "simulate_10s": {
            "args": " ".join(SIMULATE),
            "wall_s": round(min(walls), 3),
            "printed_simulation_s": round(min(sims), 3),
            "overhead_s": round(min(walls) - min(sims), 3),
            "libraries_floor_s": round(floor, 3),
        },
        "targets": {"help_wall_max_s": 0.5, "simulate_10s_wall_s": 1.5},
    }
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
