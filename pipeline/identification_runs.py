"""Identification from the ground truth: MuJoCo scenarios per road class → QC parameters per class.

Usual call: ``params = identify_classes(("A", "B"), duration_s=10, seed=1, pop_size=100, n_gen=1000)``.

For each class (paper 000 §5.2): nine straight runs — speeds 40, 60, 80 km/h ×
pressures 130, 180, 230 kPa — on roads of that class, each road's level drawn
log-uniformly inside the class band (seeded; real roads sit anywhere in a band).
The chosen corner's noise-free sprung and unsprung accelerations, the road under its
tire and its k_t(p) become a :class:`suvtwin.identification.quarter_car_fit.FitData`; the GA
then fits (cs, csnl, ks, ksnl). The result is the parameter file the estimators load
(``{"classes": {"A": {...}}, "metadata": {...}}``) and a Table-3-like table.
"""

from __future__ import annotations

import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from suvtwin.errors import InputError
from suvtwin.estimators.quarter_car import sprung_mass_share
from suvtwin.files import atomic_write, package_versions
from suvtwin.identification.quarter_car_fit import DEFAULT_BOUNDS, PARAMETER_NAMES, FitData, identify
from suvtwin.mjcf.vehicle import CORNERS, load_vehicle
from suvtwin.pipeline.scenario import parse_scenario
from suvtwin.pipeline.simulator import simulate
from suvtwin.roads.iso8608 import CLASSES, draw_level_in_class

__all__ = [
    "PAPER_PRESSURES_KPA",
    "PAPER_SPEEDS_KMH",
    "class_fit_data",
    "identify_class",
    "identify_classes",
    "parameter_file_content",
    "write_parameter_file",
]

PAPER_SPEEDS_KMH = (40.0, 60.0, 80.0)
PAPER_PRESSURES_KPA = (130.0, 180.0, 230.0)


def _scenario_seeds(road_class: str, seed: int) -> np.random.SeedSequence:
    return np.random.SeedSequence([seed, CLASSES.index(road_class)])


def corner_run(args: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """One noise-free straight run: ``(road_class, level, speed_kmh, pressure_kpa, duration_s, seed,
    corner)`` → road under the tire (m), sprung and unsprung acceleration (m/s²), k_t (N/m)."""
    road_class, level, speed, pressure, duration, run_seed, corner = args
    length = 10.0 + speed / 3.6 * duration + 40.0
    scenario = parse_scenario(
        {
            "duration_s": duration,
            "speed_kmh": speed,
            "seed": run_seed,
            "road": {"segments": [{"length_m": length, "gd_n0": level}]},
            "pressure_kpa": pressure,
            "noise": {"accel_sprung_mps2": 0.0, "accel_unsprung_mps2": 0.0},
        }
    )
    table = simulate(scenario).table
    return (
        table[f"{corner}_road_z_m"].to_numpy(),
        table[f"{corner}_accel_sprung_true_mps2"].to_numpy(),
        table[f"{corner}_accel_unsprung_true_mps2"].to_numpy(),
        float(table[f"{corner}_tire_stiffness_npm"].iloc[0]),
    )


def corner_masses(corner: str) -> tuple[float, float]:
    """Sprung (paper 000 eq. 2, no load) and unsprung mass of a corner of the SUV, kg."""
    vehicle = load_vehicle()
    front = corner.startswith("f")
    ms = sprung_mass_share(
        vehicle.chassis.mass,
        a_opposite=vehicle.chassis.a2 if front else vehicle.chassis.a1,
        wheelbase=vehicle.wheelbase,
    )
    return ms, float(vehicle.unsprung_mass[CORNERS.index(corner)])


def class_fit_data(
    road_class: str, *, duration_s: float, seed: int, corner: str = "fl", jobs: int = 1
) -> tuple[FitData, dict]:
    """Simulate the nine scenarios of one class and return the fit data and what was run."""
    if road_class not in CLASSES:
        raise InputError(f"--classes: each class must be one of A–H, got {road_class!r}")
    if corner not in CORNERS:
        raise InputError(f"corner must be one of fl, fr, rl, rr, got {corner!r}")
    rng = np.random.default_rng(_scenario_seeds(road_class, seed))
    tasks, labels = [], []
    for speed in PAPER_SPEEDS_KMH:
        for pressure in PAPER_PRESSURES_KPA:
            level = draw_level_in_class(road_class, rng)
            tasks.append(
                (road_class, level, speed, pressure, duration_s, int(rng.integers(0, 2**31)), corner)
            )
            labels.append(f"{speed:g}kmh_{pressure:g}kPa")
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            runs = list(pool.map(corner_run, tasks))
    else:
        runs = [corner_run(t) for t in tasks]
    ms, mus = corner_masses(corner)
    data = FitData(
        road=np.array([r[0] for r in runs]),
        accel_sprung=np.array([r[1] for r in runs]),
        accel_unsprung=np.array([r[2] for r in runs]),
        stiffness=np.array([r[3] for r in runs]),
        sprung_mass=ms,
        unsprung_mass=mus,
        dt=1e-3,
        labels=tuple(labels),
    )
    scenarios = [
        {"label": label, "speed_kmh": t[2], "pressure_kpa": t[3], "gd_n0_m3": t[1], "seed": t[5]}
        for label, t in zip(labels, tasks, strict=True)
    ]
    return data, {"corner": corner, "duration_s": duration_s, "scenarios": scenarios}


def _identify_one(args: tuple) -> tuple[str, dict, dict]:
    road_class, duration_s, seed, corner, pop_size, n_gen, progress, position, figures = args
    data, runs = class_fit_data(road_class, duration_s=duration_s, seed=seed, corner=corner)
    result = identify(
        data, pop_size=pop_size, n_gen=n_gen, seed=seed,
        progress=f"class {road_class}" if progress else None, progress_position=position,
    )  # fmt: skip
    figure_files = []
    if figures is not None:
        from suvtwin.identification.figures import plot_fit, plot_pareto

        pareto = f"{figures}_pareto_{road_class}.png"
        plot_pareto(result, data, pareto, title=f"class {road_class}")
        figure_files.append(pareto)
        wanted = [f"60kmh_{p:g}kPa" for p in (230.0, 130.0)]
        if road_class == "B" and all(w in data.labels for w in wanted):
            fig5 = f"{figures}_fig5_B.png"
            plot_fit(data, result.parameters, [data.labels.index(w) for w in wanted], fig5)
            figure_files.append(fig5)
    objectives = dict(
        zip(
            [f"rmse_sprung_{x}" for x in data.labels] + [f"rmse_unsprung_{x}" for x in data.labels],
            (float(v) for v in result.objectives),
            strict=True,
        )  # fmt: skip
    )
    return (
        road_class,
        result.parameters,
        {**runs, "objectives_mps2": objectives, "front_size": len(result.front_x), "figures": figure_files},
    )


def identify_classes(
    classes: tuple[str, ...],
    *,
    duration_s: float,
    seed: int,
    pop_size: int,
    n_gen: int,
    corner: str = "fl",
    jobs: int = 1,
    progress: bool = False,
    figures: str | None = None,
) -> dict:
    """Identify every class in `classes` (one process per class with ``jobs > 1``); return the file.

    With `figures` (a path prefix), also draw ``{figures}_pareto_{class}.png`` and, for class B,
    the Figure 5 analog ``{figures}_fig5_B.png``.
    """
    tasks = [
        (c, duration_s, seed, corner, pop_size, n_gen, progress, i, figures) for i, c in enumerate(classes)
    ]
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            results = list(pool.map(_identify_one, tasks))
    else:
        results = [_identify_one(t) for t in tasks]
    return parameter_file_content(results, pop_size=pop_size, n_gen=n_gen, seed=seed)


def identify_class(
    road_class: str,
    *,
    duration_s: float,
    seed: int,
    pop_size: int,
    n_gen: int,
    corner: str = "fl",
    progress: bool = False,
    position: int = 0,
    figures: str | None = None,
) -> tuple[str, dict, dict]:
    """Identify one class: ``(class, parameters, information)``, the pieces
    :func:`parameter_file_content` assembles (the campaign caches them one class at a time)."""
    return _identify_one((road_class, duration_s, seed, corner, pop_size, n_gen, progress, position, figures))


def parameter_file_content(
    results: list[tuple[str, dict, dict]], *, pop_size: int, n_gen: int, seed: int
) -> dict:
    """The parameter file's content from per-class results of one GA configuration."""
    return {
        "classes": {c: params for c, params, _ in results},
        "metadata": {
            "source": "suvtwin identification (paper 000 §5.2 on the MuJoCo SUV)",
            "units": {"cs": "N s/m", "csnl": "N s^2/m^2", "ks": "N/m", "ksnl": "N/m^3"},
            "damper_law": "signed",
            "discretization": "semi-implicit Euler, road at mid-step, 1 kHz",
            "algorithm": {
                "name": "NSGA-III",
                "reference_directions": "energy",
                "pop_size": pop_size,
                "n_gen": n_gen,
                "seed": seed,
            },  # fmt: skip
            "selection": "non-dominated solution nearest the origin, objectives normalized by ideal/nadir",
            "bounds": {n: list(DEFAULT_BOUNDS[n]) for n in PARAMETER_NAMES},
            "per_class": {c: info for c, _, info in results},
            "versions": package_versions(("suvtwin", "mujoco", "numpy", "pymoo", "numba")),
        },
    }


def write_parameter_file(content: dict, path: str | Path) -> None:
    """Write the parameter file (JSON) and, beside it, the Table-3-like table as CSV and Markdown."""
    path = Path(path)
    atomic_write(path, lambda tmp: Path(tmp).write_text(json.dumps(content, indent=2, sort_keys=True)))
    classes = sorted(content["classes"])
    rows = [("parameter", "unit", *[f"class {c}" for c in classes])]
    units = content["metadata"]["units"]
    for name in PARAMETER_NAMES:
        rows.append((name, units[name], *[f"{content['classes'][c][name]:.6g}" for c in classes]))
    csv = "\n".join(",".join(r) for r in rows) + "\n"
    md = "| " + " | ".join(rows[0]) + " |\n|" + "---|" * len(rows[0]) + "\n"
    md += "".join("| " + " | ".join(r) + " |\n" for r in rows[1:])
    atomic_write(path.with_suffix(".csv"), lambda tmp: Path(tmp).write_text(csv))
    atomic_write(path.with_suffix(".md"), lambda tmp: Path(tmp).write_text(md))
