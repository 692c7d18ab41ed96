r"""Half-car input estimation: wheel vertical force and pitch torque by CIE and AWIE.

Usual call::

    system = discretize(PAPER_HALF_CAR, dt=1e-3)
    est = estimate_inputs(z, system, input_noise=1e2, measurement_std=1e-8, fading=0.1)  # CIE
    est = estimate_inputs(z, system, input_noise=1e2, measurement_std=1e-8, fading="adaptive")  # AWIE
    est.inputs        # (runs, steps, 2): [F_V in N, T_theta in N m]

The method of Lin et al. 2021 [1]_ (after Ma et al. 2003 [2]_): a two-degree-of-freedom
half car (body heave ``z`` and pitch ``theta``, no wheel masses) whose road excitation is
lumped into two inputs, the vertical wheel force :math:`F_V` and the pitch torque
:math:`T_\theta` (eq. 1–5),

.. math:: \dot X = F X + G u,\quad Z = H X,\qquad X = [z, \dot z, \theta, \dot\theta],
   \quad u = [F_V, T_\theta],

discretized exactly for a piecewise-constant input, :math:`\Phi = e^{F\Delta T}`,
:math:`\Gamma = \int_0^{\Delta T} e^{F s} G\,ds` (eq. 6–7; both from one exponential of
the augmented matrix ``[[F, G], [0, 0]]``). The measurements are ``z`` and ``theta`` with
white noise of standard deviation σ. A *simple* Kalman filter that treats the input as
process noise :math:`\Gamma w`, :math:`E[ww^T] = Q`, gives the innovation
:math:`\bar Z(k)` and its covariance :math:`S(k)` (eq. 8–14). An unknown input held
constant biases the innovation by :math:`B_s(k)\,u`, with the sensitivity matrices of
eq. 15–16; a recursive least-squares estimator with fading factor :math:`\gamma`
(eq. 17–19) regresses the innovations on :math:`B_s` to give :math:`\hat u(k)`. CIE uses a
constant :math:`\gamma = f_{tr}`; AWIE sets it at every step from the innovation,
:math:`\gamma(k) = 1` if :math:`|\bar Z(k)| \le \sigma`, else :math:`\sigma/|\bar Z(k)|`
(eq. 20–22).

Time convention (one for the whole module): arrays are ``(runs, steps, channels)``;
sample ``k`` is at time :math:`k\Delta T`. The truth obeys
:math:`X(k+1) = \Phi X(k) + \Gamma u(k)` from :math:`X(0) = 0`, so :math:`Z(k)` carries the
inputs up to :math:`u(k-1)` and the estimate :math:`\hat u(k)`, formed from
:math:`Z(1..k)`, estimates :math:`u(k-1)` at best. The filter starts from
:math:`\bar X(0|0)`, :math:`P(0|0)`, :math:`\hat u(0)`, :math:`P_b(0)`,
:math:`M_s(0) = 0` (the paper's §3.2: zero state, ``1e10·I``, zero input, ``1e8·I``) and
processes :math:`Z(1), Z(2), \dots`; :math:`Z(0)` is not used.

Errors of the paper corrected here (and why)
--------------------------------------------
- Eq. 2 prints :math:`I\ddot\theta = F_{S_R}L_R + F_{S_F}L_F - F_{C_R}L_F - F_{C_F}L_F`;
  the signs and the lever arm of the rear damper contradict eq. 1's force definitions
  and the matrices of eq. 3–4. Used: :math:`I\ddot\theta = (F_{S_R} + F_{C_R})L_R -
  (F_{S_F} + F_{C_F})L_F`, which *is* eq. 3–4.
- Eq. 3's stiffness matrix has :math:`C_FL_F - C_RL_R` in row 2, column 1; eq. 4's
  :math:`F` (and symmetry) give :math:`K_FL_F - K_RL_R`. Used: eq. 4.
- Eq. 8 writes :math:`\bar X(k/k+1)`; it is the prediction :math:`\bar X(k|k-1)`.
- Eq. 19 writes :math:`\hat u(k) = \hat u(k+1) + \dots`; it is :math:`\hat u(k-1)`, as
  in eq. 22.
- Eq. 25 (sine bump force) has :math:`C_R` in the front wheel's bracket (eq. 26 has
  :math:`C_F`; Table 1's equal dampers hide it) and the rear wheel's window
  :math:`U_{tL} - U_{tp1}`, which is zero at every time since the rear wheel reaches the
  bump after the front has left it: the rear wheel would never act. Used
  :math:`U_{tL} - U_{tp2}` (eq. 26 and 27–28 have the same slip). The rear wheel's sine
  is taken from its own start, :math:`\sin(\omega_f(t - t_{RS}))`; with the paper's
  L/D = 2 it equals the printed :math:`\sin(\omega_f t)`.
- Eq. 27–28 (rectangular cleat) keep only the springs: the dampers' response to the
  cleat's steps, :math:`C h_0\,\delta(t - t_i)`, is dropped. The paper's truth is then
  the model driven by eq. 27–28 (as here, :func:`cleat_inputs`), not a car on a cleat;
  a car on a real cleat also receives an impulse :math:`\pm C h_0` (N s) at each edge.
- Eq. 29–30 (random road) give both wheels the same elevation :math:`z_R(s)` at the same
  time and drop the dampers, so :math:`T_\theta/F_V = (K_FL_F - K_RL_R)/(K_F+K_R)` is a
  constant: the two "inputs" are one signal. :func:`road_inputs` gives both the literal
  form (same elevation, zero rates) and a car's (rear wheel delayed by L/v, with dampers).
- Eq. 32, the NEE, is :math:`(\sqrt{\sum u^2} - \sqrt{\sum \hat u^2})/\sum u^2 \times 100`
  as printed: units 1/N (or 1/(N m)), and a difference of norms that is blind to a wrong
  shape or timing. :func:`normalized_error` is the standard
  :math:`100\,\lVert u - \hat u\rVert/\lVert u\rVert`; :func:`norm_difference_error`
  gives both readings of eq. 32 (printed, and divided by :math:`\lVert u\rVert`).
- The vector innovation's :math:`|\bar z(k)|` of eq. 20 is read as the Euclidean norm of
  the innovation with each channel divided by its own σ (with equal σ, the paper's
  :math:`|\bar z|/\sigma`).

Numerics: eq. 12 and 18 are evaluated in their Joseph form
:math:`(I-KB)P(I-KB)^T + KSK^T`, algebraically equal for the optimal gain; the paper's
initial :math:`P = 10^{10}` with :math:`R = 10^{-16}` spans 26 orders of magnitude, and the
short form loses positive definiteness to cancellation.

The Kalman filter's and the CIE's gains do not depend on the data; they are computed once
per step and shared by the whole batch of runs. AWIE's :math:`P_b` depends on each run's
innovations and is carried per run. One Python loop runs over time steps, none over runs.

References
----------
.. [1] D.-C. Lin, T.-T. Nguyen, J.-S. Pan, C.-D. Lee, "Vertical Vehicle Dynamics
   Estimated Inputs with Clouding Road Profiles", 2021 (received April 2021, revised June
   2021; our copy of the paper does not print the journal).
.. [2] C.-K. Ma, P.-C. Tuan, J.-M. Chang, D.-C. Lin, "Adaptive weighting inverse method
   for the estimation of input loads", International Journal of Systems Science 34(3),
   181–194, 2003.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.linalg import expm

from suvtwin.errors import InputError, positive

__all__ = [
    "PAPER_HALF_CAR",
    "DiscreteHalfCar",
    "HalfCar",
    "InputEstimate",
    "cleat_inputs",
    "continuous_matrices",
    "discretize",
    "estimate_inputs",
    "norm_difference_error",
    "normalized_error",
    "road_inputs",
    "simulate_measurements",
    "sine_bump_inputs",
]

N_STATES = 4
N_INPUTS = 2
N_OUTPUTS = 2


@dataclass(frozen=True)
class HalfCar:
    """Two-degree-of-freedom half car (heave and pitch of the body), Lin et al. 2021, Fig. 1.

    Attributes
    ----------
    mass : float
        Body mass m, kg.
    pitch_inertia : float
        Pitch moment of inertia I about the centre of gravity, kg m².
    front_stiffness, rear_stiffness : float
        Suspension spring rates K_F, K_R, N/m.
    front_damping, rear_damping : float
        Damping coefficients C_F, C_R, N s/m.
    front_length, rear_length : float
        Distances L_F, L_R from the centre of gravity to the front and rear axle, m.
    """

    mass: float
    pitch_inertia: float
    front_stiffness: float
    rear_stiffness: float
    front_damping: float
    rear_damping: float
    front_length: float
    rear_length: float

    def __post_init__(self) -> None:
        units = {"mass": "kg", "pitch_inertia": "kg m^2", "front_stiffness": "N/m",
                 "rear_stiffness": "N/m", "front_damping": "N s/m", "rear_damping": "N s/m",
                 "front_length": "m", "rear_length": "m"}
        for name, unit in units.items():
            positive(f"HalfCar.{name}", getattr(self, name), unit)

    @property
    def wheelbase(self) -> float:
        """L = L_F + L_R, m."""
        return self.front_length + self.rear_length


PAPER_HALF_CAR = HalfCar(  # Lin et al. 2021, Table 1
    mass=2000.0,
    pitch_inertia=600.0,
    front_stiffness=5000.0,
    rear_stiffness=5000.0,
    front_damping=500.0,
    rear_damping=500.0,
    front_length=0.8,
    rear_length=1.2,
)


def continuous_matrices(car: HalfCar) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""State-space matrices F (4×4, 1/s and 1/s²), G (4×2), H (2×4) of eq. 4–5.

    State :math:`X = [z, \dot z, \theta, \dot\theta]` (m, m/s, rad, rad/s), input
    :math:`u = [F_V, T_\theta]` (N, N m), output :math:`Z = [z, \theta]`.
    """
    m, inertia = car.mass, car.pitch_inertia
    kf, kr, cf, cr = car.front_stiffness, car.rear_stiffness, car.front_damping, car.rear_damping
    lf, lr = car.front_length, car.rear_length
    F = np.array(
        [
            [0.0, 1.0, 0.0, 0.0],
            [-(kf + kr) / m, -(cf + cr) / m, -(kf * lf - kr * lr) / m, -(cf * lf - cr * lr) / m],
            [0.0, 0.0, 0.0, 1.0],
            [
                -(kf * lf - kr * lr) / inertia,
                -(cf * lf - cr * lr) / inertia,
                -(kf * lf**2 + kr * lr**2) / inertia,
                -(cf * lf**2 + cr * lr**2) / inertia,
            ],
        ]
    )  # eq. 4
    G = np.array([[0.0, 0.0], [1.0 / m, 0.0], [0.0, 0.0], [0.0, 1.0 / inertia]])  # eq. 4
    H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])  # eq. 5
    return F, G, H


@dataclass(frozen=True)
class DiscreteHalfCar:
    r"""Exact zero-order-hold discretization of the half car (eq. 6–7).

    Attributes
    ----------
    Phi : numpy.ndarray, shape (4, 4)
        :math:`\Phi = e^{F\Delta T}`.
    Gamma : numpy.ndarray, shape (4, 2)
        :math:`\Gamma = \int_0^{\Delta T} e^{Fs}G\,ds`, state per unit input over one step.
    H : numpy.ndarray, shape (2, 4)
        Measurement matrix (z and θ).
    dt : float
        Sampling interval ΔT, s.
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    H: np.ndarray
    dt: float


def discretize(car: HalfCar, *, dt: float) -> DiscreteHalfCar:
    r"""Φ and Γ of eq. 6 from one matrix exponential.

    :math:`\exp\left(\begin{bmatrix}F & G\\ 0 & 0\end{bmatrix}\Delta T\right) =
    \begin{bmatrix}\Phi & \Gamma\\ 0 & I\end{bmatrix}` (Van Loan's construction), exact for
    an input held constant over each step.

    Parameters
    ----------
    car : HalfCar
    dt : float
        Sampling interval ΔT, s (> 0).
    """
    dt = positive("dt", dt, "s")
    F, G, H = continuous_matrices(car)
    block = np.zeros((N_STATES + N_INPUTS, N_STATES + N_INPUTS))
    block[:N_STATES, :N_STATES] = F
    block[:N_STATES, N_STATES:] = G
    e = expm(block * dt)
    return DiscreteHalfCar(Phi=e[:N_STATES, :N_STATES], Gamma=e[:N_STATES, N_STATES:], H=H, dt=dt)


# --- the paper's exact inputs (eq. 3, 23–30) -----------------------------------------------


def road_inputs(
    car: HalfCar,
    front_height: npt.ArrayLike,
    front_rate: npt.ArrayLike,
    rear_height: npt.ArrayLike,
    rear_rate: npt.ArrayLike,
) -> np.ndarray:
    r"""Wheel vertical force and pitch torque from the road under each axle, eq. 3.

    :math:`F_V = C_F\dot z_F + C_R\dot z_R + K_Fz_F + K_Rz_R`,
    :math:`T_\theta = C_FL_F\dot z_F - C_RL_R\dot z_R + K_FL_Fz_F - K_RL_Rz_R`.
    Eq. 29–30 (random road) are this with ``rear_height = front_height`` and zero rates.

    Parameters
    ----------
    front_height, rear_height : array_like
        Road elevation under the front and rear axle, m (broadcast together).
    front_rate, rear_rate : array_like
        Their time derivatives, m/s.

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        ``[F_V, T_theta]`` in N and N m.
    """
    zf, vf, zr, vr = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (front_height, front_rate, rear_height, rear_rate))
    )
    front = car.front_stiffness * zf + car.front_damping * vf
    rear = car.rear_stiffness * zr + car.rear_damping * vr
    return np.stack([front + rear, car.front_length * front - car.rear_length * rear], axis=-1)


def _pulse_geometry(car: HalfCar, speed: float, height: float, length: float) -> tuple[float, float, float]:
    speed = positive("speed", speed, "m/s")
    length = positive("obstacle length", length, "m")
    height = float(height)
    if not np.isfinite(height):
        raise InputError(f"obstacle height must be finite (m), got {height!r}")
    return speed, height, length


def sine_bump_inputs(
    car: HalfCar, t: npt.ArrayLike, *, speed: float, height: float, length: float
) -> np.ndarray:
    r"""Exact inputs of a half-sine bump met by the front wheel at t = 0, eq. 23–26 (corrected).

    Front wheel on the bump for :math:`0 \le t \le t_{FE} = D/v`, rear wheel for
    :math:`t_{RS} = L/v \le t \le t_{RE} = (L + D)/v`, each at
    :math:`z = h_0\sin(\omega_f\tau)`, :math:`\omega_f = \pi v/D`, τ the time since that
    wheel reached the bump. Eq. 25–26 as corrected in the module docstring (C_F in the
    front bracket, rear window :math:`U_{tL} - U_{tp2}`).

    Parameters
    ----------
    t : array_like
        Times, s.
    speed : float
        Vehicle speed v, m/s.
    height : float
        Bump height h_0, m.
    length : float
        Bump length D, m.

    Returns
    -------
    numpy.ndarray, shape (len(t), 2)
        ``[F_V, T_theta]``, N and N m.
    """
    speed, height, length = _pulse_geometry(car, speed, height, length)
    t = np.asarray(t, dtype=float)
    w = np.pi * speed / length  # eq. 23
    t_fe = length / speed
    t_rs = car.wheelbase / speed
    t_re = t_rs + t_fe
    front_on = (t >= 0.0) & (t <= t_fe)  # 1 - U_tp1
    rear_on = (t > t_rs) & (t <= t_re)  # U_tL - U_tp2 (printed: U_tL - U_tp1, always 0)
    tau_f, tau_r = t, t - t_rs
    zf = np.where(front_on, height * np.sin(w * tau_f), 0.0)
    vf = np.where(front_on, height * w * np.cos(w * tau_f), 0.0)
    zr = np.where(rear_on, height * np.sin(w * tau_r), 0.0)
    vr = np.where(rear_on, height * w * np.cos(w * tau_r), 0.0)
    return road_inputs(car, zf, vf, zr, vr)  # eq. 25–26


def cleat_inputs(car: HalfCar, t: npt.ArrayLike, *, speed: float, height: float, length: float) -> np.ndarray:
    r"""Inputs of a rectangular cleat met by the front wheel at t = 0, eq. 27–28 (corrected).

    :math:`F_V = h_0K_F(1 - U_{tp1}) + h_0K_R(U_{tL} - U_{tp2})`,
    :math:`T_\theta = h_0L_FK_F(1 - U_{tp1}) - h_0L_RK_R(U_{tL} - U_{tp2})`: the springs
    only, as the paper defines its exact input; the dampers' impulses
    :math:`\pm C h_0` (N s) at the cleat's edges are not in it (module docstring).

    Parameters and returns as :func:`sine_bump_inputs` (``length`` is the cleat's length D).
    """
    speed, height, length = _pulse_geometry(car, speed, height, length)
    t = np.asarray(t, dtype=float)
    t_fe = length / speed
    t_rs = car.wheelbase / speed
    front_on = (t >= 0.0) & (t <= t_fe)
    rear_on = (t > t_rs) & (t <= t_rs + t_fe)
    zero = np.zeros_like(t)
    return road_inputs(car, np.where(front_on, height, 0.0), zero, np.where(rear_on, height, 0.0), zero)


# --- truth and estimation ------------------------------------------------------------------


def _measurement_std(measurement_std: npt.ArrayLike) -> np.ndarray:
    sigma = np.broadcast_to(np.asarray(measurement_std, dtype=float), (N_OUTPUTS,)).copy()
    if not np.all(np.isfinite(sigma)) or np.any(sigma <= 0.0):
        raise InputError(
            f"measurement_std must be > 0 and finite (m for z, rad for theta), got {sigma.tolist()}"
        )
    return sigma


def simulate_measurements(
    system: DiscreteHalfCar,
    inputs: npt.ArrayLike,
    *,
    measurement_std: npt.ArrayLike,
    rng: np.random.Generator,
    n_runs: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    r"""The paper's truth: :math:`X(k+1) = \Phi X(k) + \Gamma u(k)`, :math:`Z = HX + v` (eq. 6–7).

    Parameters
    ----------
    system : DiscreteHalfCar
    inputs : array_like, shape (steps, 2)
        Exact inputs u(k) = [F_V, T_θ] at t = kΔT, N and N m, held over each step.
    measurement_std : float or array_like, shape (2,)
        Noise standard deviation σ of z (m) and θ (rad).
    rng : numpy.random.Generator
        Source of the noise.
    n_runs : int, optional
        Number of independent noise draws (default 1).

    Returns
    -------
    states : numpy.ndarray, shape (steps, 4)
        Noise-free X(k), from X(0) = 0.
    measurements : numpy.ndarray, shape (n_runs, steps, 2)
        Z(k) with noise.
    """
    u = np.asarray(inputs, dtype=float)
    if u.ndim != 2 or u.shape[1] != N_INPUTS or not np.all(np.isfinite(u)):
        raise InputError(f"inputs must be a finite (steps, 2) array [N, N m], got shape {u.shape}")
    if int(n_runs) < 1:
        raise InputError(f"n_runs must be >= 1, got {n_runs!r}")
    sigma = _measurement_std(measurement_std)
    # X(k) = sum_j Phi^(k-1-j) Gamma u(j): one loop over steps (4 numbers each)
    x = np.zeros((u.shape[0], N_STATES))
    for k in range(1, u.shape[0]):
        x[k] = system.Phi @ x[k - 1] + system.Gamma @ u[k - 1]  # eq. 6
    clean = x @ system.H.T
    noise = rng.standard_normal((int(n_runs), u.shape[0], N_OUTPUTS)) * sigma
    return x, clean[None] + noise  # eq. 7


@dataclass(frozen=True)
class InputEstimate:
    r"""What the input estimator returns; sample k is time kΔT (index 0: the initial values).

    Attributes
    ----------
    inputs : numpy.ndarray, shape (runs, steps, 2)
        :math:`\hat u(k)` = [F_V, T_θ], N and N m (eq. 19 / 22); estimates u(k-1).
    states : numpy.ndarray, shape (runs, steps, 4)
        The simple Kalman filter's :math:`\bar X(k|k)` (eq. 14), m, m/s, rad, rad/s.
    innovations : numpy.ndarray, shape (runs, steps, 2)
        :math:`\bar Z(k)` (eq. 13), m and rad; NaN at k = 0.
    fading : numpy.ndarray, shape (runs, steps)
        The fading factor γ(k) used at step k (f_tr for CIE, eq. 20 for AWIE); NaN at k = 0.
    input_covariance : numpy.ndarray, shape (runs, steps, 2, 2)
        :math:`P_b(k)` (eq. 18 / 21), N², N² m², N² m.
    innovation_covariance : numpy.ndarray, shape (steps, 2, 2)
        :math:`S(k)` (eq. 10), shared by all runs; NaN at k = 0.
    sensitivity : numpy.ndarray, shape (steps, 2, 2)
        :math:`B_s(k)` (eq. 15), m/N and rad/(N m); NaN at k = 0.
    kalman_gain : numpy.ndarray, shape (steps, 4, 2)
        :math:`K_a(k)` (eq. 11); NaN at k = 0.
    """

    inputs: np.ndarray
    states: np.ndarray
    innovations: np.ndarray
    fading: np.ndarray
    input_covariance: np.ndarray
    innovation_covariance: np.ndarray
    sensitivity: np.ndarray
    kalman_gain: np.ndarray


def _covariance(value: npt.ArrayLike, n: int, name: str, unit: str) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = a * np.eye(n)
    elif a.ndim == 1 and a.shape == (n,):
        a = np.diag(a)
    if a.shape != (n, n) or not np.all(np.isfinite(a)):
        raise InputError(
            f"{name} must be a scalar, {n} variances or a {n}x{n} matrix ({unit}), got {value!r}"
        )
    if not np.allclose(a, a.T) or np.min(np.linalg.eigvalsh(a)) < 0.0:
        raise InputError(f"{name} must be symmetric positive semi-definite ({unit}), got {a.tolist()}")
    return a


def estimate_inputs(
    measurements: npt.ArrayLike,
    system: DiscreteHalfCar,
    *,
    input_noise: npt.ArrayLike,
    measurement_std: npt.ArrayLike,
    fading: float | str,
    adaptive_threshold: npt.ArrayLike | None = None,
    state_covariance0: npt.ArrayLike = 1e10,
    input_covariance0: npt.ArrayLike = 1e8,
    state0: npt.ArrayLike | None = None,
    input0: npt.ArrayLike | None = None,
) -> InputEstimate:
    r"""CIE (constant fading) or AWIE (adaptive fading) input estimation, eq. 8–22.

    Parameters
    ----------
    measurements : array_like, shape (runs, steps, 2) or (steps, 2)
        Z(k) = [z, θ] at t = kΔT, m and rad; Z(0) is not used.
    system : DiscreteHalfCar
        From :func:`discretize`.
    input_noise : float or array_like, shape (2,) or (2, 2)
        Q, covariance of the fictitious input noise w (eq. 6), N² / (N m)²; a scalar means
        Q·I (the paper: 1e2).
    measurement_std : float or array_like, shape (2,)
        σ of z (m) and θ (rad); R = diag(σ²) (eq. 7).
    fading : float in (0, 1] or "adaptive"
        CIE's constant fading factor f_tr (eq. 17–18; the paper: 0.1 and 0.9; 1 is plain
        least squares), or ``"adaptive"`` for AWIE (eq. 20–22).
    adaptive_threshold : float or array_like, shape (2,), optional
        AWIE's σ in eq. 20, m and rad. If None, ``measurement_std``.
    state_covariance0 : float or array_like, optional
        P(0|0), scalar (times I) or 4 variances or 4×4; default 1e10 (§3.2).
    input_covariance0 : float or array_like, optional
        P_b(0), N² / (N m)²; default 1e8 (§3.2).
    state0, input0 : array_like, optional
        X̄(0|0) and û(0); default zero (§3.2).

    Returns
    -------
    InputEstimate
        Leading run axis removed if `measurements` had none.

    Raises
    ------
    suvtwin.errors.InputError
        Measurements not finite or not of 2 channels, fading outside (0, 1], σ ≤ 0, a
        covariance not symmetric positive semi-definite.
    """
    z = np.asarray(measurements, dtype=float)
    single = z.ndim == 2
    z = z[None] if single else z
    if z.ndim != 3 or z.shape[-1] != N_OUTPUTS or z.shape[1] < 2:
        raise InputError(
            f"measurements must have shape (runs, steps, 2) or (steps, 2) with steps >= 2, got {z.shape}"
        )
    if not np.all(np.isfinite(z)):
        bad = np.argwhere(~np.isfinite(z))[0]
        raise InputError(f"measurements must be finite (m, rad); NaN or inf at run {bad[0]}, step {bad[1]}")
    adaptive = isinstance(fading, str)
    if adaptive:
        if fading != "adaptive":
            raise InputError(f"fading must be a number in (0, 1] or 'adaptive', got {fading!r}")
        threshold = _measurement_std(measurement_std if adaptive_threshold is None else adaptive_threshold)
        gamma_const = np.nan
    else:
        gamma_const = float(fading)
        if not (0.0 < gamma_const <= 1.0):
            raise InputError(f"fading must be in (0, 1] (or 'adaptive'), got {fading!r}")
    sigma = _measurement_std(measurement_std)
    Q = _covariance(input_noise, N_INPUTS, "input_noise", "N^2, (N m)^2")
    R = np.diag(sigma**2)
    P = _covariance(state_covariance0, N_STATES, "state_covariance0", "m^2, rad^2, ...")
    Pb0 = _covariance(input_covariance0, N_INPUTS, "input_covariance0", "N^2, (N m)^2")

    Phi, Gamma, H = system.Phi, system.Gamma, system.H
    n_runs, n_steps, _ = z.shape
    eye_x, eye_u = np.eye(N_STATES), np.eye(N_INPUTS)
    GQG = Gamma @ Q @ Gamma.T

    x = np.zeros((n_runs, N_STATES)) if state0 is None else np.broadcast_to(
        np.asarray(state0, dtype=float), (n_runs, N_STATES)).copy()
    u = np.zeros((n_runs, N_INPUTS)) if input0 is None else np.broadcast_to(
        np.asarray(input0, dtype=float), (n_runs, N_INPUTS)).copy()
    Pb = np.broadcast_to(Pb0, (n_runs, N_INPUTS, N_INPUTS)).copy() if adaptive else Pb0.copy()
    Ms = np.zeros((N_STATES, N_STATES))

    out_u = np.empty((n_runs, n_steps, N_INPUTS))
    out_x = np.empty((n_runs, n_steps, N_STATES))
    out_innov = np.full((n_runs, n_steps, N_OUTPUTS), np.nan)
    out_gamma = np.full((n_runs, n_steps), np.nan)
    out_Pb = np.empty((n_runs, n_steps, N_INPUTS, N_INPUTS))
    out_S = np.full((n_steps, N_OUTPUTS, N_OUTPUTS), np.nan)
    out_B = np.full((n_steps, N_OUTPUTS, N_INPUTS), np.nan)
    out_K = np.full((n_steps, N_STATES, N_OUTPUTS), np.nan)
    out_u[:, 0], out_x[:, 0], out_Pb[:, 0] = u, x, Pb

    for k in range(1, n_steps):
        # simple Kalman filter, shared gains (eq. 8–12)
        x = x @ Phi.T  # eq. 8
        P = Phi @ P @ Phi.T + GQG  # eq. 9
        S = H @ P @ H.T + R  # eq. 10
        Ka = np.linalg.solve(S, H @ P).T  # eq. 11 (S, P symmetric)
        IKH = eye_x - Ka @ H
        P = IKH @ P @ IKH.T + Ka @ R @ Ka.T  # eq. 12, Joseph form
        P = 0.5 * (P + P.T)
        innov = z[:, k] - x @ H.T  # eq. 13
        x = x + innov @ Ka.T  # eq. 14
        # sensitivities (eq. 15–16)
        PhiM_I = Phi @ Ms + eye_x
        Bs = H @ PhiM_I @ Gamma  # eq. 15
        Ms = IKH @ PhiM_I  # eq. 16
        # recursive least squares with fading (eq. 17–22)
        if adaptive:
            rho = np.sqrt(np.sum((innov / threshold) ** 2, axis=-1))
            gamma = np.where(rho <= 1.0, 1.0, 1.0 / np.maximum(rho, 1.0))  # eq. 20
            Pf = Pb / gamma[:, None, None]
            BPf = Bs @ Pf  # (runs, 2, 2)
            Kb = np.linalg.solve(BPf @ Bs.T + S, BPf).transpose(0, 2, 1)  # eq. 20
            IKB = eye_u - Kb @ Bs
            Pb = IKB @ Pf @ IKB.transpose(0, 2, 1) + Kb @ S @ Kb.transpose(0, 2, 1)  # eq. 21, Joseph
            Pb = 0.5 * (Pb + Pb.transpose(0, 2, 1))
            resid = innov - u @ Bs.T
            u = u + np.einsum("rij,rj->ri", Kb, resid)  # eq. 22
        else:
            gamma = gamma_const
            Pf = Pb / gamma
            BPf = Bs @ Pf
            Kb = np.linalg.solve(BPf @ Bs.T + S, BPf).T  # eq. 17
            IKB = eye_u - Kb @ Bs
            Pb = IKB @ Pf @ IKB.T + Kb @ S @ Kb.T  # eq. 18, Joseph form
            Pb = 0.5 * (Pb + Pb.T)
            u = u + (innov - u @ Bs.T) @ Kb.T  # eq. 19 (û(k-1) on the right)
        out_u[:, k], out_x[:, k], out_innov[:, k], out_gamma[:, k], out_Pb[:, k] = u, x, innov, gamma, Pb
        out_S[k], out_B[k], out_K[k] = S, Bs, Ka

    est = InputEstimate(
        inputs=out_u,
        states=out_x,
        innovations=out_innov,
        fading=out_gamma,
        input_covariance=out_Pb,
        innovation_covariance=out_S,
        sensitivity=out_B,
        kalman_gain=out_K,
    )
    if single:
        est = InputEstimate(
            inputs=out_u[0], states=out_x[0], innovations=out_innov[0], fading=out_gamma[0],
            input_covariance=out_Pb[0], innovation_covariance=out_S, sensitivity=out_B, kalman_gain=out_K,
        )
    return est


# --- error metrics --------------------------------------------------------------------------


def normalized_error(exact: npt.ArrayLike, estimate: npt.ArrayLike) -> np.ndarray:
    r"""Standard normalized estimation error :math:`100\,\lVert u - \hat u\rVert_2/\lVert u\rVert_2`, %.

    The sum runs over the time axis (second to last): ``exact`` and ``estimate`` of shape
    ``(..., steps, 2)`` give ``(..., 2)``, one value per input channel.
    """
    u, uh = np.broadcast_arrays(np.asarray(exact, dtype=float), np.asarray(estimate, dtype=float))
    return 100.0 * np.linalg.norm(u - uh, axis=-2) / np.linalg.norm(u, axis=-2)


def norm_difference_error(
    exact: npt.ArrayLike, estimate: npt.ArrayLike, *, printed: bool = False
) -> np.ndarray:
    r"""Eq. 32: the difference of the norms of u and û, normalized.

    ``printed=False``: :math:`100(\lVert u\rVert - \lVert\hat u\rVert)/\lVert u\rVert`, %
    (dimensionless; signed). ``printed=True``: eq. 32 as printed,
    :math:`100(\lVert u\rVert - \lVert\hat u\rVert)/\sum u^2`, in %/N (or %/(N m)): its
    value changes with the unit of force. Neither sees an error of shape or timing that
    keeps the norm. Shapes as :func:`normalized_error`.
    """
    u, uh = np.broadcast_arrays(np.asarray(exact, dtype=float), np.asarray(estimate, dtype=float))
    nu, nh = np.linalg.norm(u, axis=-2), np.linalg.norm(uh, axis=-2)
    return 100.0 * (nu - nh) / (nu**2 if printed else nu)
