"""Quarter-car ground truth: Monte Carlo runs of a linear quarter car on ISO 8608 roads.

Usual call: ``runs = quarter_car_runs(20, 5000, seed=1)``.

The light stand-in for the MuJoCo SUV (:mod:`suvtwin.pipeline.simulator`) where an
estimator is checked against its own model class: each run draws a true pressure
uniformly in 130–230 kPa and a road whose level lies anywhere inside a class band
(classes cycling A, B, C, D), integrates the quarter car finely (RK4 with
`substeps` per sample, :func:`suvtwin.estimators.quarter_car.simulate_quarter_car`)
with k_t(p) of Brancati & Tufano 2022, eq. 3–4, and adds white accelerometer
noise. Tests and benches share it, so they measure on the same runs.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from suvtwin.estimators.quarter_car import QuarterCar, simulate_quarter_car, stiffness_from_pressure
from suvtwin.roads.iso8608 import draw_level_in_class
from suvtwin.roads.profile import generate_road
from suvtwin.roads.spec import RoadSpec, SegmentSpec

__all__ = ["TEST_CORNER", "TIMESTEP_S", "SPEED_MPS", "QuarterCarRuns", "quarter_car_runs"]

TIMESTEP_S = 1e-3
"""Sample interval of the runs, s."""
SPEED_MPS = 60 / 3.6
"""Driving speed of the runs, m/s (60 km/h)."""
TEST_CORNER = QuarterCar(
    sprung_mass=466.7, unsprung_mass=61.14, spring_rate=32000.0, spring_cubic=0.0,
    damping=2200.0, damping_nonlinear=0.0,
)
"""Linear corner of the SUV's size: masses kg, spring N/m, damper N s/m."""


@dataclass(frozen=True)
class QuarterCarRuns:
    """What :func:`quarter_car_runs` returns; arrays over runs first.

    Attributes
    ----------
    pressure : numpy.ndarray, shape (n_runs,)
        True inflation pressure, Pa.
    waviness : numpy.ndarray, shape (n_runs,)
        Waviness w of each run's road PSD, -.
    gd_n0 : numpy.ndarray, shape (n_runs,)
        Road roughness level Gd(n0) of each run (ISO 8608, n0 = 0.1 cycle/m), m³.
    road : numpy.ndarray, shape (n_runs, n_steps)
        Road elevation under the tire at each sample, m.
    acc : numpy.ndarray, shape (n_runs, n_steps, 2)
        Measured sprung and unsprung acceleration (truth plus noise), m/s².
    """

    pressure: np.ndarray
    waviness: np.ndarray
    gd_n0: np.ndarray
    road: np.ndarray
    acc: np.ndarray


def quarter_car_runs(
    n_runs: int,
    n_steps: int,
    *,
    seed: int,
    waviness: float | tuple[float, float] = 2.0,
    quarter_car: QuarterCar = TEST_CORNER,
    noise_mps2: float = 0.5,
    substeps: int = 5,
) -> QuarterCarRuns:
    """Simulate `n_runs` quarter-car runs of `n_steps` samples at 60 km/h, 1 kHz.

    Parameters
    ----------
    n_runs, n_steps : int
        Number of runs and of samples per run.
    seed : int
        Seeds the draws (pressure, waviness, levels, noise) and each run's road.
    waviness : float or (float, float), optional
        Road PSD exponent w; a pair draws w uniformly in that range per run. Default 2.
    quarter_car : QuarterCar, optional
        The corner's masses, spring and damper (k_t comes from the drawn pressure).
    noise_mps2 : float, optional
        Standard deviation of the white accelerometer noise, m/s². Default 0.5.
    substeps : int, optional
        RK4 substeps per sample. Default 5.
    """
    rng = np.random.default_rng(seed)
    pressure = rng.uniform(130e3, 230e3, n_runs)
    w = np.full(n_runs, float(waviness)) if np.ndim(waviness) == 0 else rng.uniform(*waviness, n_runs)
    gd_n0 = np.array([draw_level_in_class("ABCD"[b % 4], rng) for b in range(n_runs)])
    length_m = SPEED_MPS * n_steps * TIMESTEP_S + 5
    road = np.array(
        [
            generate_road(
                RoadSpec(
                    segments=[SegmentSpec(length_m=length_m, waviness=float(w[b]),
                                          gd_n0=float(gd_n0[b]))],
                    spacing_m=SPEED_MPS * TIMESTEP_S / 1.0001,
                ),
                seed=seed * 100 + b,
            ).z[0][:n_steps]
            for b in range(n_runs)
        ]
    )  # fmt: skip
    x0 = np.zeros((n_runs, 5))
    x0[:, 0] = x0[:, 1] = road[:, 0]
    x0[:, 4] = stiffness_from_pressure(pressure)
    _, acc = simulate_quarter_car(x0, road, quarter_car, TIMESTEP_S, substeps=substeps)
    return QuarterCarRuns(pressure, w, gd_n0, road, acc + rng.normal(0.0, noise_mps2, acc.shape))

