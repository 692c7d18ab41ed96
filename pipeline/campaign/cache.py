"""The campaign's content-addressed cache: every unit of work is one file named by a hash.

Usual call: ``key = digest({"scenario": ..., "model": model_fingerprint()})``; files are written
with :func:`suvtwin.files.atomic_write` (a temporary file renamed into place), and
:func:`remove_stale_temporaries` deletes what a killed run left behind.

A key hashes everything that determines a result: for a run its scenario, the code and model
files (:func:`source_digest` of :data:`SIMULATION_SOURCES`) and the library versions; for an
estimate its run file, estimator, parameter file, estimator code (:data:`ESTIMATION_SOURCES`)
and initial estimate; for a parameter file the identification settings and code. Results made
by other code get other keys, so an upgrade never reuses stale work.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
from pathlib import Path

from suvtwin.errors import RunError
from suvtwin.files import package_versions

__all__ = [
    "ESTIMATION_SOURCES",
    "IDENTIFICATION_SOURCES",
    "PREMISE_SOURCES",
    "SIMULATION_SOURCES",
    "digest",
    "model_fingerprint",
    "remove_stale_temporaries",
    "source_digest",
]

SIMULATION_SOURCES = ("suvtwin.mjcf", "suvtwin.pipeline.simulator", "suvtwin.pipeline.scenario",
                      "suvtwin.roads.profile", "suvtwin.roads.spec", "suvtwin.roads.iso8608",
                      "suvtwin.tire_stiffness", "suvtwin.tir")  # fmt: skip
"""What a ground-truth run is made by (besides its scenario): modules and packages of suvtwin."""
IDENTIFICATION_SOURCES = (*SIMULATION_SOURCES, "suvtwin.identification",
                          "suvtwin.pipeline.identification_runs", "suvtwin.quarter_car_law")  # fmt: skip
"""What a parameter file is made by (besides its settings)."""
ESTIMATION_SOURCES = ("suvtwin.estimators", "suvtwin.pipeline.estimator_registry",
                      "suvtwin.pipeline.estimation", "suvtwin.pipeline.campaign",
                      "suvtwin.quarter_car_law", "suvtwin.tire_stiffness", "suvtwin.tir")  # fmt: skip
"""What an estimate is made by (besides its run, estimator and parameter file)."""
PREMISE_SOURCES = (*ESTIMATION_SOURCES, "suvtwin.pipeline.premise", "suvtwin.pipeline.scoring",
                   "suvtwin.roads")  # fmt: skip
"""What paper 000's premise check is made by (besides its runs per class and seed)."""


def digest(obj: object, n: int = 12) -> str:
    """First `n` hex digits of the SHA-256 of `obj` as sorted JSON."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:n]


def source_digest(sources: tuple[str, ...]) -> str:
    """Hash of the code and model files of `sources` (suvtwin modules or packages, with their
    package data): results made by other code get other keys, so an upgrade never reuses stale
    work. Works the same from a source checkout and from an installed wheel."""
    sha = hashlib.sha256()
    for source in sources:
        spec = importlib.util.find_spec(source)
        if spec is None or spec.origin is None:
            raise RunError(f"campaign: cannot find the code of {source}")
        if spec.submodule_search_locations:  # a package: every code and model file under it
            root = Path(next(iter(spec.submodule_search_locations)))
            files = sorted(f for f in root.rglob("*") if "__pycache__" not in f.relative_to(root).parts)
        else:
            root, files = Path(spec.origin).parent, [Path(spec.origin)]
        for f in files:
            if f.is_file() and f.suffix in (".py", ".toml", ".xml", ".tir"):
                sha.update(f"{source}/{f.relative_to(root).as_posix()}".encode())
                sha.update(f.read_bytes())
    return sha.hexdigest()[:16]


def model_fingerprint(sources: tuple[str, ...] = SIMULATION_SOURCES) -> dict:
    """What, besides a scenario, decides a result: the code and model files and the library versions."""
    return {"code": source_digest(sources), "versions": package_versions(("suvtwin", "mujoco", "numpy"))}


def remove_stale_temporaries(out: Path) -> None:
    """Delete temporary files a killed run left behind (finished files are never temporary)."""
    for pattern in ("runs/.*.tmp*", "estimates/*/.*.tmp*", "identification/*/.*.tmp*", "premise/.*.tmp*",
                    ".*.tmp*"):  # fmt: skip
        for path in out.glob(pattern):
            path.unlink(missing_ok=True)
