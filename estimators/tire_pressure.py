r"""Tire-pressure estimators of paper 000: the IMM of UKFs and the single-UKF baseline.

Usual call::

    est = estimate_pressure(acc_s, acc_us, dt, modes=load_modes("paper"),
                            sprung_mass=466.7, unsprung_mass=61.14,
                            road_input="synthetic", speed_mps=16.7, seed=1)
    est.pressure_pa, est.pressure_sigma_pa, est.mode_probability

Brancati & Tufano 2022: each mode is the quarter car of eq. 1 with the parameters
identified for one road class (Table 3, or this project's identification), state
:math:`[z_s, z_{us}, \dot z_s, \dot z_{us}, k_t]` with :math:`k_t` a random walk
(eq. 15), measurements the two accelerations (eq. 16), Q of eq. 18, R of eq. 19
(variances), combined by the IMM (eq. 9–14, standard form: :mod:`suvtwin.estimators.imm`)
with the Markov matrix of eq. 17. With one mode (class A) it is the paper's
single-UKF baseline. :math:`k_t \to p` by the inverse of eq. 3–4.

The road under the tire is unknown to the estimator; ``road_input`` says what
each mode assumes:

``"synthetic"``
    the paper, literally: each mode is driven by an artificial road of its class
    (a shape-filter realization at the class level, eq. 5–7 calibrated as in
    :mod:`suvtwin.roads.profile`, seeded);
``"augmented"``
    each mode's state is augmented with the road elevation, a first-order
    shape-filter (eq. 6) state :math:`z_{r,k+1} = \phi z_{r,k} + w`,
    :math:`\phi = e^{-\alpha v \Delta t}`, whose noise has the class's intensity;
``"true"``
    the true road is given (an oracle, for checking the filter itself).

Every array has runs first: accelerations (B, T), outputs (B, T[, S]).

Two implementations of the same filter (``EstimatorSettings.backend``): the compiled
per-step loop of :mod:`suvtwin.estimators.imm_ukf_kernel` (default), and the numpy reference
below, batched over runs and modes, built from :mod:`suvtwin.estimators.imm` and
:mod:`suvtwin.estimators.ukf`; they agree to rounding.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np
import numpy.typing as npt

from suvtwin.errors import InputError
from suvtwin.estimators.imm import PAPER_TRANSITION, imm_mix, imm_probabilities
from suvtwin.estimators.imm_ukf_kernel import run_imm_ukf
from suvtwin.estimators.quarter_car import (
    IX_KT,
    QuarterCar,
    accelerations,
    measurement_noise,
    pressure_from_stiffness,
    pressure_sigma_from_stiffness_sigma,
    process_euler,
    process_noise,
    process_semi_implicit,
    stiffness_from_pressure,
)
from suvtwin.estimators.ukf import merwe_weights, ukf_predict, ukf_update
from suvtwin.roads.iso8608 import class_level
from suvtwin.roads.profile import SHAPE_FILTER_ALPHA, shape_filter_intensity, shape_filter_profile
from suvtwin.tire_stiffness import TireStiffness, stiffness_sigma_at_pressure_sigma, suv_tire_stiffness

__all__ = [
    "PAPER_TABLE_3",
    "EstimatorSettings",
    "ModeBank",
    "PressureEstimate",
    "estimate_pressure",
    "load_modes",
]

PAPER_TABLE_3 = {
    "A": {"cs": 6576.0, "csnl": 4319.0, "ks": 113086.0, "ksnl": 130098.0},
    "B": {"cs": 4585.0, "csnl": 6016.0, "ks": 173415.0, "ksnl": 151886.0},
    "C": {"cs": 14819.0, "csnl": 5839.0, "ks": 94544.0, "ksnl": 62836.0},
    "D": {"cs": 14708.0, "csnl": 4555.0, "ks": 118114.0, "ksnl": 121723.0},
}
"""Brancati & Tufano 2022, Table 3: QC parameters identified on the ASM SUV per road class
(cs N s/m, csnl N s²/m², ks N/m, ksnl N/m³)."""


@dataclass(frozen=True)
class ModeBank:
    """QC parameters of each mode, arrays of shape (S,), and where they come from."""

    classes: tuple[str, ...]
    cs: np.ndarray
    csnl: np.ndarray
    ks: np.ndarray
    ksnl: np.ndarray
    source: str

    def subset(self, classes: tuple[str, ...]) -> ModeBank:
        """The modes of `classes` only (e.g. ``("A",)`` for the single-UKF baseline)."""
        index = [self.classes.index(c) for c in classes]
        return ModeBank(
            classes=tuple(classes),
            cs=self.cs[index],
            csnl=self.csnl[index],
            ks=self.ks[index],
            ksnl=self.ksnl[index],
            source=self.source,
        )


def _bank(table: dict, source: str) -> ModeBank:
    classes = tuple(sorted(table))
    try:
        cols = {k: np.array([float(table[c][k]) for c in classes]) for k in ("cs", "csnl", "ks", "ksnl")}
    except (KeyError, TypeError, ValueError) as error:
        raise InputError(
            f"mode parameters ({source}): each class needs numbers cs, csnl, ks, ksnl ({error})"
        ) from None
    unknown = [c for c in classes if c not in tuple("ABCDEFGH")]
    if unknown:
        raise InputError(f"mode parameters ({source}): classes must be among A–H, got {', '.join(unknown)}")
    for name, values in cols.items():
        nonlinear = name.endswith("nl")  # the linear rates must be > 0, the non-linear terms ≥ 0
        for c, value in zip(classes, values, strict=True):
            if not np.isfinite(value) or value < 0.0 or (value == 0.0 and not nonlinear):
                allowed = "finite and ≥ 0" if nonlinear else "finite and > 0"
                raise InputError(
                    f"mode parameters ({source}): classes.{c}.{name} must be {allowed}, got {float(value)!r}"
                )
    return ModeBank(classes=classes, source=source, **cols)


IDENTIFIED_FILE = Path(str(resources.files("suvtwin.identification") / "data" / "suv_fl_paper_scale.json"))
"""QC parameters identified at paper scale on this project's SUV (front-left corner, classes A–D);
the GA settings and seed are in the file's ``metadata``, and ``python bench/identification_speed.py
paper`` makes it again (README, "Benchmarks")."""


def load_modes(source: str | Path = "identified") -> ModeBank:
    """Mode parameters: ``"identified"`` (this SUV, shipped), ``"paper"`` (Table 3) or a JSON file
    ``{"classes": {"A": {...}, ...}}``."""
    if str(source) == "paper":
        return _bank(PAPER_TABLE_3, "Brancati & Tufano 2022, Table 3")
    if str(source) == "identified":
        source = IDENTIFIED_FILE
    path = Path(source)
    if not path.is_file():
        raise InputError(f"--params: file {str(path)!r} does not exist")
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as error:
        raise InputError(f"--params: {str(path)!r} is not valid JSON ({error})") from None
    if not isinstance(data, dict) or not isinstance(data.get("classes"), dict) or not data["classes"]:
        raise InputError(
            f"--params: {str(path)!r} must hold {{'classes': {{'A': {{cs, csnl, ks, ksnl}}, ...}}}}"
        )
    return _bank(data["classes"], str(path))


@dataclass(frozen=True)
class EstimatorSettings:
    """Tuning of the estimators (the paper gives the form of Q, not its values).

    Attributes
    ----------
    q : tuple of 5 floats
        Eq. 18 diagonal: Q = diag(q·Δt³), units m²/s³ (positions), m²/s⁵ (velocities),
        N²/m²/s³ (k_t). The k_t entry lets k_t wander ~26 kN/m (10 %) in one second.
    sigma_sprung, sigma_unsprung : float
        Accelerometer noise std, m/s² (paper 000: 0.5).
    pressure_guess_kpa, pressure_sigma_kpa : float
        Initial pressure estimate and its std, kPa.
    mu_floor : float
        Floor of the IMM mode probabilities.
    alpha, beta, kappa : float
        Sigma-point parameters (alpha = 1: well-conditioned weights).
    damper_law : "signed" or "paper"
        Non-linear damper term (see :mod:`suvtwin.estimators.quarter_car`).
    discretization : "semi-implicit" or "euler"
        Process model: semi-implicit Euler (default), or forward Euler as eq. 15 (the
        paper, literally), which inflates the wheel-hop oscillation and so biases the
        pressure low (:func:`suvtwin.estimators.quarter_car.process_semi_implicit`;
        ``tests/test_tire_pressure.py`` checks the sign).
        Either way the road is taken at the middle of the step.
    initial_state_sigma : tuple of 4 floats
        Initial std of z_s, z_us (m) and v_s, v_us (m/s).
    backend : "numba" or "numpy"
        "numba" (default): the compiled per-step loop of :mod:`suvtwin.estimators.imm_ukf_kernel`
        (same algorithm and order of operations, faster than the numpy path, most of all
        for one run: ``python bench/estimator_speed.py``). "numpy": the
        readable reference built from :mod:`suvtwin.estimators.imm` and :mod:`suvtwin.estimators.ukf`,
        batched over runs and modes; the two agree to rounding (tests/test_imm_ukf_kernel.py).
    """

    q: tuple[float, float, float, float, float] = (1e-3, 1e-3, 1e1, 4e3, 6.8e14)
    sigma_sprung: float = 0.5
    sigma_unsprung: float = 0.5
    pressure_guess_kpa: float = 250.0
    pressure_sigma_kpa: float = 60.0
    mu_floor: float = 1e-4
    alpha: float = 1.0
    beta: float = 2.0
    kappa: float = 0.0
    damper_law: str = "signed"
    discretization: str = "semi-implicit"
    initial_state_sigma: tuple[float, float, float, float] = (5e-2, 5e-2, 1e-1, 3e-1)
    backend: str = "numba"


@dataclass(frozen=True)
class PressureEstimate:
    """Per-time-step output of an estimator; runs first.

    Attributes
    ----------
    t_s : (T,) s
    stiffness, stiffness_sigma : (B, T) N/m
    pressure_pa, pressure_sigma_pa : (B, T) Pa
    mode_probability : (B, T, S), or None for one mode
    mode_stiffness : (B, T, S) N/m, each mode's own k_t estimate
    classes : the modes' road classes
    repairs : (B,) number of covariance repairs
    """

    t_s: np.ndarray
    stiffness: np.ndarray
    stiffness_sigma: np.ndarray
    pressure_pa: np.ndarray
    pressure_sigma_pa: np.ndarray
    mode_probability: np.ndarray | None
    mode_stiffness: np.ndarray
    classes: tuple[str, ...]
    repairs: np.ndarray
    info: dict = field(default_factory=dict)


def _road_variance(gd_n0: float) -> float:
    """Stationary variance of the calibrated shape-filter road of level Gd(n0) (m³), m²."""
    return np.pi * shape_filter_intensity(gd_n0) / (2.0 * SHAPE_FILTER_ALPHA)


def estimate_pressure(
    acc_sprung: npt.ArrayLike,
    acc_unsprung: npt.ArrayLike,
    dt: float,
    *,
    modes: ModeBank,
    sprung_mass: float,
    unsprung_mass: float,
    road_input: str,
    speed_mps: npt.ArrayLike,
    road: npt.ArrayLike | None = None,
    settings: EstimatorSettings | None = None,
    seed: int | npt.ArrayLike = 0,
    initial_stiffness: npt.ArrayLike | None = None,
    road_levels: npt.ArrayLike | None = None,
    tire: TireStiffness | None = None,
) -> PressureEstimate:
    """Run the IMM of UKFs (or one UKF, for one mode) over a batch of runs.

    Parameters
    ----------
    acc_sprung, acc_unsprung : array_like, shape (B, T) or (T,)
        Measured vertical accelerations, m/s², sampled every `dt` s.
    dt : float
        Sample interval, s.
    modes : ModeBank
        S modes; S = 1 is the single UKF.
    sprung_mass, unsprung_mass : float
        Corner masses, kg (eq. 2).
    road_input : {"synthetic", "augmented", "true"}
    speed_mps : float or array (B,)
        Vehicle speed, m/s (sets the synthetic roads and the augmented road dynamics).
    road : array_like, shape (B, T), optional
        True road elevation, m (``road_input="true"`` only).
    settings : EstimatorSettings, optional
    seed : int or array_like of int (B,)
        Seed of the synthetic roads: one stream for the batch, or one per run (then each run's
        estimate is independent of which other runs share the batch).
    initial_stiffness : array_like (B,), optional
        Initial k_t estimate per run, N/m (default from ``settings.pressure_guess_kpa``).
    road_levels : array_like (S,), optional
        Road roughness Gd(n0) each mode assumes, m³ (default: its class's level).
    tire : TireStiffness, optional
        The tyre's k_t(p) constants (eq. 3–4); default the SUV's tyre.
    """
    settings = settings or EstimatorSettings()
    acc_s = np.atleast_2d(np.asarray(acc_sprung, dtype=float))
    acc_u = np.atleast_2d(np.asarray(acc_unsprung, dtype=float))
    if acc_s.shape != acc_u.shape:
        raise InputError(f"accelerations: sprung {acc_s.shape} and unsprung {acc_u.shape} differ in shape")
    if not (np.all(np.isfinite(acc_s)) and np.all(np.isfinite(acc_u))):
        raise InputError("accelerations must be finite (no NaN)")
    if road_input not in ("synthetic", "augmented", "true"):
        raise InputError(f"road input must be 'synthetic', 'augmented' or 'true', got {road_input!r}")
    if settings.backend not in ("numba", "numpy"):
        raise InputError(f"backend must be 'numba' or 'numpy', got {settings.backend!r}")
    n_runs, n_steps = acc_s.shape
    n_modes = len(modes.classes)
    speed = np.broadcast_to(np.asarray(speed_mps, dtype=float), (n_runs,))
    augmented = road_input == "augmented"
    n = 6 if augmented else 5
    if road_levels is not None:
        levels = np.broadcast_to(np.asarray(road_levels, dtype=float), (n_modes,))
    elif road_input != "true":
        levels = np.array([class_level(c) for c in modes.classes])
    qc = QuarterCar(
        sprung_mass=sprung_mass,
        unsprung_mass=unsprung_mass,
        spring_rate=modes.ks[:, None],
        spring_cubic=modes.ksnl[:, None],
        damping=modes.cs[:, None],
        damping_nonlinear=modes.csnl[:, None],
        damper_law=settings.damper_law,
    )
    if road_input == "true":
        if road is None:
            raise InputError("road_input 'true' needs the road elevation")
        road_in = np.atleast_2d(np.asarray(road, dtype=float))[:, None, None, :]  # (B, 1, 1, T)
    elif road_input == "synthetic":
        per_run = np.ndim(seed) > 0
        if per_run and np.shape(seed) != (n_runs,):
            raise InputError(f"seed: give one int or one per run ({n_runs}), got shape {np.shape(seed)}")
        rng = None if per_run else np.random.default_rng(seed)
        road_in = np.empty((n_runs, n_modes, 1, n_steps))
        for b in range(n_runs):
            if per_run:
                rng = np.random.default_rng(int(np.asarray(seed)[b]))
            for s in range(n_modes):
                road_in[b, s, 0] = shape_filter_profile(n_steps, speed[b] * dt, gd_n0=levels[s], rng=rng)[0]
    else:
        road_in = None
    phi = np.exp(-SHAPE_FILTER_ALPHA * speed * dt)[:, None, None]  # (B, 1, 1)

    q = np.zeros(n)
    q[:5] = settings.q
    Q = np.broadcast_to(process_noise(q, dt), (n_runs, n_modes, n, n)).copy()
    if augmented:
        variance = np.array([_road_variance(g) for g in levels])
        Q[..., 5, 5] = variance[None, :] * (1.0 - phi[:, :, 0] ** 2)
    R = measurement_noise(settings.sigma_sprung, settings.sigma_unsprung)
    w = merwe_weights(n, alpha=settings.alpha, beta=settings.beta, kappa=settings.kappa)

    tire = tire or suv_tire_stiffness()
    kt0 = stiffness_from_pressure(settings.pressure_guess_kpa * 1e3, kt0=tire.kt0, p0=tire.p0, pfz1=tire.pfz1)
    kt_sigma0 = stiffness_sigma_at_pressure_sigma(
        settings.pressure_sigma_kpa * 1e3, tire.kt0, tire.p0, tire.pfz1
    )
    x = np.zeros((n_runs, n_modes, n))
    x[..., IX_KT] = kt0 if initial_stiffness is None else np.asarray(initial_stiffness, dtype=float)[:, None]
    if road_input == "true":  # start on the known road
        x[..., 0] = road_in[:, :, 0, 0]
        x[..., 1] = road_in[:, :, 0, 0]
    P = np.zeros((n_runs, n_modes, n, n))
    sig = list(settings.initial_state_sigma) + [kt_sigma0]
    if augmented:
        sig.append(0.0)  # set per mode below
    P[..., np.arange(n), np.arange(n)] = np.array(sig) ** 2
    if augmented:
        P[..., 5, 5] = variance[None, :]
    transition = PAPER_TRANSITION if n_modes == 4 else _uniform_transition(n_modes)
    mu = np.full((n_runs, n_modes), 1.0 / n_modes)

    if settings.discretization not in ("euler", "semi-implicit"):
        raise InputError(
            f"discretization must be 'euler' or 'semi-implicit', got {settings.discretization!r}"
        )
    step = process_euler if settings.discretization == "euler" else process_semi_implicit
    if settings.backend == "numba":
        if road_input == "augmented":
            road_k = np.zeros((n_runs, 1, 1))
        else:
            road_k = road_in[:, :, 0, :]
            if road_k.shape[-1] < n_steps:
                raise InputError(f"road: {road_k.shape[-1]} samples for {n_steps} accelerations")
            try:
                road_k = np.broadcast_to(road_k, (n_runs, road_k.shape[1], road_k.shape[2]))
            except ValueError:
                raise InputError(f"road: shape {road_k.shape[::2]} does not match {n_runs} runs") from None
        kt_hat, kt_sig, mode_prob, mode_kt, repairs = run_imm_ukf(
            acc_s, acc_u, dt, road_k, phi.reshape(n_runs), Q, R, x, P, mu, transition,
            modes.ks, modes.ksnl, modes.cs, modes.csnl, sprung_mass, unsprung_mass, w,
            mu_floor=settings.mu_floor, augmented=augmented,
            semi_implicit=settings.discretization == "semi-implicit",
            signed_damper=settings.damper_law == "signed",
        )  # fmt: skip
        return _result(kt_hat, kt_sig, mode_prob, mode_kt, repairs, dt, modes, road_input, settings, tire)

    def fx(sig_pts, k):
        zr = sig_pts[..., 5] if augmented else 0.5 * (road_in[..., k] + road_in[..., k + 1])
        out = step(sig_pts[..., :5], zr, qc, dt)
        if augmented:
            out = np.concatenate([out, (phi * sig_pts[..., 5])[..., None]], axis=-1)
        return out

    def hx(sig_pts, k):
        zr = sig_pts[..., 5] if augmented else road_in[..., k]
        return np.stack(accelerations(sig_pts[..., :5], zr, qc), axis=-1)

    kt_hat = np.empty((n_runs, n_steps))
    kt_sig = np.empty((n_runs, n_steps))
    mode_prob = np.empty((n_runs, n_steps, n_modes))
    mode_kt = np.empty((n_runs, n_steps, n_modes))
    repairs = np.zeros(n_runs, dtype=int)
    z = np.stack([acc_s, acc_u], axis=-1)[:, None, :, :]  # (B, 1, T, 2)
    for k in range(n_steps):
        if k > 0:
            if n_modes > 1:
                mixed = imm_mix(x, P, mu, transition)
                x_in, P_in, cbar = mixed.x, mixed.P, mixed.cbar
            else:
                x_in, P_in, cbar = x, P, mu
            pred = ukf_predict(x_in, P_in, lambda s, k=k: fx(s, k - 1), Q, w)
            post = ukf_update(pred, z[:, :, k, :], lambda s, k=k: hx(s, k), R, w)
            repairs += pred.repaired.any(axis=-1)
            x, P = post.x, post.P
            if n_modes > 1:
                mu = imm_probabilities(cbar, post.log_likelihood, floor=settings.mu_floor)
        kt_modes = x[..., IX_KT]  # eq. 13-14 for the k_t entry only (the rest is not reported)
        kt_hat[:, k] = np.sum(mu * kt_modes, axis=-1)
        spread = P[..., IX_KT, IX_KT] + (kt_modes - kt_hat[:, k, None]) ** 2
        kt_sig[:, k] = np.sqrt(np.maximum(np.sum(mu * spread, axis=-1), 0.0))
        mode_prob[:, k] = mu
        mode_kt[:, k] = x[..., IX_KT]
    return _result(kt_hat, kt_sig, mode_prob, mode_kt, repairs, dt, modes, road_input, settings, tire)


def _result(
    kt_hat, kt_sig, mode_prob, mode_kt, repairs, dt, modes, road_input, settings, tire: TireStiffness
) -> PressureEstimate:
    n_steps = kt_hat.shape[1]
    n_modes = len(modes.classes)
    law = asdict(tire)  # kt0, p0, pfz1
    return PressureEstimate(
        t_s=np.arange(n_steps) * dt,
        stiffness=kt_hat,
        stiffness_sigma=kt_sig,
        pressure_pa=pressure_from_stiffness(kt_hat, **law),
        pressure_sigma_pa=pressure_sigma_from_stiffness_sigma(kt_sig, **law),
        mode_probability=mode_prob if n_modes > 1 else None,
        mode_stiffness=mode_kt,
        classes=modes.classes,
        repairs=repairs,
        info={
            "road_input": road_input,
            "damper_law": settings.damper_law,
            "discretization": settings.discretization,
            "modes_source": modes.source,
        },
    )


def _uniform_transition(n_modes: int) -> np.ndarray:
    """Markov matrix with 0.97 on the diagonal and the rest shared equally (eq. 17's pattern)."""
    if n_modes == 1:
        return np.ones((1, 1))
    off = 0.03 / (n_modes - 1)
    return np.full((n_modes, n_modes), off) + np.eye(n_modes) * (0.97 - off)
