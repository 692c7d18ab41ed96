r"""Quarter-car parameters per road class by a multi-objective genetic algorithm (paper 000 §5.2).

Usual call::

    data = FitData(road=..., accel_sprung=..., accel_unsprung=..., stiffness=..., sprung_mass=466.7,
                   unsprung_mass=61.14, dt=1e-3)
    result = identify(data, pop_size=100, n_gen=1000, seed=1)
    result.parameters   # {"cs": ..., "csnl": ..., "ks": ..., "ksnl": ...}

Decision variables (Brancati & Tufano 2022, Table 2): linear damping :math:`c_s`
(N s/m), non-linear damping :math:`c_{snl}` (N s²/m²), linear spring :math:`k_s`
(N/m), cubic spring :math:`k_{snl}` (N/m³); fixed: sprung mass (eq. 2), unsprung
mass, and the tire stiffness :math:`k_t(p)` of each scenario (eq. 3–4). Objectives
(eq. 20–21): the RMSE of the sprung and of the unsprung acceleration in each
scenario — 18 for the paper's nine (3 speeds × 3 pressures).

The quarter car (eq. 1, :mod:`suvtwin.quarter_car_law`) is driven by the known road under
the tire and simulated with the discretization the estimator uses
(:func:`suvtwin.estimators.quarter_car.process_semi_implicit`, road at mid-step), for a
whole population × all scenarios in one compiled loop: this is the hot loop of the GA,
so it is compiled with numba like the other per-step loops.

The algorithm is pymoo's NSGA-III with Das–Dennis-free "energy" reference
directions (suited to 18 objectives); problem, algorithm and termination are kept
apart as pymoo does. The chosen solution is the non-dominated one nearest the origin
after normalizing each objective to [0, 1] between its best and worst value over the
final non-dominated set (``(f - ideal) / (nadir - ideal)``); pymoo's compromise
picker is an empty stub, so this rule is written here.

No MuJoCo here: the pipeline feeds arrays.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pymoo.algorithms.moo.nsga3 import NSGA3
from pymoo.core.problem import Problem
from pymoo.optimize import minimize
from pymoo.util.nds.non_dominated_sorting import NonDominatedSorting
from pymoo.util.ref_dirs import get_reference_directions

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit
from suvtwin.quarter_car_law import sprung_acceleration, suspension_force, unsprung_acceleration

__all__ = [
    "DEFAULT_BOUNDS",
    "PARAMETER_NAMES",
    "FitData",
    "IdentificationResult",
    "QuarterCarFit",
    "identify",
    "objectives",
    "select_compromise",
    "simulate_accelerations",
]

PARAMETER_NAMES = ("cs", "csnl", "ks", "ksnl")

DEFAULT_BOUNDS = {
    "cs": (200.0, 20000.0),  # N s/m: covers SUV dampers (1-4 kN s/m) and Table 3 (4.6-14.8 kN s/m)
    "csnl": (0.0, 20000.0),  # N s^2/m^2: Table 3 has 4.3-6.0 k
    "ks": (10000.0, 250000.0),  # N/m: SUV wheel rates 20-60 k; Table 3 has 95-173 k
    "ksnl": (0.0, 5.0e6),  # N/m^3: Table 3 has 0.06-0.15 M; progressive springs reach ~1e6
}
"""Search bounds of the decision variables, SI units (lower, upper)."""


@dataclass(frozen=True)
class FitData:
    """Scenarios of one road class: inputs and measured outputs of the quarter car.

    Attributes
    ----------
    road : (S, T) m, road elevation under the tire at each sample
    accel_sprung, accel_unsprung : (S, T) m/s², vertical accelerations to reproduce
    stiffness : (S,) N/m, tire stiffness k_t(p) of each scenario (eq. 3–4)
    sprung_mass, unsprung_mass : kg
    dt : s, sample interval
    damper_law : "signed" (|v|·v, default) or "paper" (v²)
    labels : optional scenario names
    """

    road: np.ndarray
    accel_sprung: np.ndarray
    accel_unsprung: np.ndarray
    stiffness: np.ndarray
    sprung_mass: float
    unsprung_mass: float
    dt: float
    damper_law: str = "signed"
    labels: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        shapes = {np.shape(self.road), np.shape(self.accel_sprung), np.shape(self.accel_unsprung)}
        if len(shapes) != 1 or np.ndim(self.road) != 2:
            raise InputError(f"fit data: road and accelerations must share one (S, T) shape, got {shapes}")
        if np.shape(self.stiffness) != (np.shape(self.road)[0],):
            raise InputError("fit data: one tire stiffness per scenario")
        for name in ("road", "accel_sprung", "accel_unsprung", "stiffness"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise InputError(f"fit data: {name} holds NaN or infinite values")


@cached_njit
def _simulate_scenario(cs, csnl, ks, ksnl, road, k_t, ms, mus, dt, signed, acc_s, acc_u):
    """Accelerations of one QC on one road (writes acc_s, acc_u of shape (T,)), m/s²."""
    zs = road[0]
    zu = road[0]
    vs = 0.0
    vu = 0.0
    n_t = road.shape[0]
    for k in range(n_t):
        force = suspension_force(zs, zu, vs, vu, ks, ksnl, cs, csnl, signed)  # eq. 1
        acc_s[k] = sprung_acceleration(force, ms)
        acc_u[k] = unsprung_acceleration(force, k_t, zu, road[k], mus)
        if k + 1 < n_t:  # semi-implicit Euler, road at mid-step
            mid = 0.5 * (road[k] + road[k + 1])
            vs += acc_s[k] * dt
            vu += unsprung_acceleration(force, k_t, zu, mid, mus) * dt
            zs += vs * dt
            zu += vu * dt


@cached_njit
def _rmse_population(params, road, acc_s, acc_u, kt, ms, mus, dt, signed):
    """RMSE of sprung and unsprung acceleration, shape (P, 2S): columns s (sprung) and S + s."""
    n_pop, n_sc, n_t = params.shape[0], road.shape[0], road.shape[1]
    out = np.empty((n_pop, 2 * n_sc))
    sim_s = np.empty(n_t)
    sim_u = np.empty(n_t)
    for p in range(n_pop):
        for s in range(n_sc):
            _simulate_scenario(
                params[p, 0],
                params[p, 1],
                params[p, 2],
                params[p, 3],
                road[s],
                kt[s],
                ms,
                mus,
                dt,
                signed,
                sim_s,
                sim_u,
            )
            err_s = 0.0
            err_u = 0.0
            for k in range(n_t):
                err_s += (sim_s[k] - acc_s[s, k]) ** 2
                err_u += (sim_u[k] - acc_u[s, k]) ** 2
            out[p, s] = np.sqrt(err_s / n_t)
            out[p, n_sc + s] = np.sqrt(err_u / n_t)
    return out


def simulate_accelerations(parameters: dict, data: FitData, scenario: int) -> tuple[np.ndarray, np.ndarray]:
    """Sprung and unsprung acceleration (m/s², shape (T,)) of the QC with `parameters` in one scenario."""
    acc_s = np.empty(data.road.shape[1])
    acc_u = np.empty(data.road.shape[1])
    _simulate_scenario(
        *(float(parameters[n]) for n in PARAMETER_NAMES),
        np.ascontiguousarray(data.road[scenario], dtype=float),
        float(data.stiffness[scenario]),
        float(data.sprung_mass),
        float(data.unsprung_mass),
        float(data.dt),
        data.damper_law == "signed",
        acc_s,
        acc_u,
    )
    return acc_s, acc_u


def objectives(params: np.ndarray, data: FitData) -> np.ndarray:
    """Eq. 20–21 for a population: (P, 4) parameters → (P, 2S) RMSEs in m/s².

    Columns 0…S−1 are the sprung accelerations of each scenario, S…2S−1 the unsprung.
    A simulation that diverges gets an infinite RMSE.
    """
    params = np.atleast_2d(np.asarray(params, dtype=float))
    with np.errstate(over="ignore", invalid="ignore"):
        out = _rmse_population(
            params,
            np.ascontiguousarray(data.road, dtype=float),
            np.ascontiguousarray(data.accel_sprung, dtype=float),
            np.ascontiguousarray(data.accel_unsprung, dtype=float),
            np.asarray(data.stiffness, dtype=float),
            float(data.sprung_mass),
            float(data.unsprung_mass),
            float(data.dt),
            data.damper_law == "signed",
        )
    out[~np.isfinite(out)] = np.inf
    return out


class QuarterCarFit(Problem):
    """pymoo problem: 4 decision variables (cs, csnl, ks, ksnl), 2S objectives (eq. 20–21)."""

    def __init__(self, data: FitData, bounds: dict | None = None):
        bounds = bounds or DEFAULT_BOUNDS
        xl = np.array([bounds[n][0] for n in PARAMETER_NAMES])
        xu = np.array([bounds[n][1] for n in PARAMETER_NAMES])
        super().__init__(n_var=4, n_obj=2 * data.road.shape[0], xl=xl, xu=xu)
        self.data = data

    def _evaluate(self, x, out, *args, **kwargs):
        out["F"] = np.minimum(objectives(x, self.data), 1e6)  # diverged runs: a large finite value


def select_compromise(F: np.ndarray) -> int:
    """Index of the non-dominated row of F nearest the origin after per-objective normalization.

    Each objective is scaled to [0, 1] between its best (ideal) and worst (nadir)
    value over the non-dominated rows; ties in a constant objective count as 0.
    """
    F = np.asarray(F, dtype=float)
    front = NonDominatedSorting().do(F, only_non_dominated_front=True)
    sub = F[front]
    ideal, nadir = sub.min(axis=0), sub.max(axis=0)
    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    distance = np.linalg.norm((sub - ideal) / span, axis=1)
    return int(front[int(np.argmin(distance))])


@dataclass(frozen=True)
class IdentificationResult:
    """The chosen parameters (SI), their objectives, and the final population's front."""

    parameters: dict
    objectives: np.ndarray
    front_x: np.ndarray
    front_f: np.ndarray
    info: dict = field(default_factory=dict)


def identify(
    data: FitData,
    *,
    pop_size: int,
    n_gen: int,
    seed: int,
    bounds: dict | None = None,
    n_ref_dirs: int | None = None,
    progress: str | None = None,
    progress_position: int = 0,
) -> IdentificationResult:
    """Fit (cs, csnl, ks, ksnl) to `data` with NSGA-III and pick the compromise solution.

    Parameters
    ----------
    pop_size : int
        Population size; raised to the number of reference directions if below it.
    n_gen : int
        Generations (paper: 1000).
    seed : int
        Seed of the reference directions and of the GA: same seed, same parameters.
    n_ref_dirs : int, optional
        Number of energy reference directions (default: `pop_size`, at least objectives + 1).
    progress : str, optional
        Show a progress bar over generations with this label (stderr).
    progress_position : int
        Line of that bar when several run side by side.
    """
    if pop_size < 4 or n_gen < 1:
        raise InputError(f"pop_size must be ≥ 4 and n_gen ≥ 1, got {pop_size} and {n_gen}")
    problem = QuarterCarFit(data, bounds)
    # energy directions need more points than objectives; the population at least one per direction
    n_dirs = max(n_ref_dirs or pop_size, problem.n_obj + 1)
    ref_dirs = get_reference_directions("energy", problem.n_obj, n_dirs, seed=seed)
    algorithm = NSGA3(ref_dirs=ref_dirs, pop_size=max(pop_size, n_dirs))
    callback = None
    if progress is not None:
        from pymoo.core.callback import Callback
        from tqdm import tqdm

        class _Bar(Callback):
            def __init__(self):
                super().__init__()
                self.bar = tqdm(
                    total=n_gen, desc=progress, position=progress_position, unit="gen", leave=False
                )

            def notify(self, algorithm):
                self.bar.update(1)

        callback = _Bar()
    extra = {} if callback is None else {"callback": callback}
    result = minimize(problem, algorithm, ("n_gen", n_gen), seed=seed, verbose=False, **extra)
    if callback is not None:
        callback.bar.close()
    X = np.atleast_2d(result.pop.get("X"))
    F = np.atleast_2d(result.pop.get("F"))
    best = select_compromise(F)
    front = NonDominatedSorting().do(F, only_non_dominated_front=True)
    return IdentificationResult(
        parameters=dict(zip(PARAMETER_NAMES, (float(v) for v in X[best]), strict=True)),
        objectives=F[best],
        front_x=X[front],
        front_f=F[front],
        info={"pop_size": pop_size, "n_gen": n_gen, "seed": seed, "damper_law": data.damper_law},
    )
