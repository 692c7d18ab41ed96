r"""Road-profile estimation on a quarter car: Kalman filter (KF) and minimum model error + KF (MME&KF).

Usual call::

    road = iso_road_model(class_level("C"), speed=40 / 3.6)
    model = discretize(PAPER_QUARTER_CAR, road, dt=1e-3, method="euler")
    kf = kalman_filter(y, model, measurement_std=0.05)                       # eq. 8–15
    w = covariance_constraint_weight(y[:2001], model, measurement_std=0.05)  # eq. 20
    mme = mme_kalman_filter(y, model, measurement_std=0.05, weight=w)        # eq. 16–21
    kf.states[..., 4]   # (runs, steps): the road elevation estimate x̂_r, m

The method of Wang et al. 2017 [1]_. A linear quarter car (sprung mass :math:`m_b`,
unsprung mass :math:`m_w`, suspension spring :math:`k_s` and damper :math:`c`, tyre spring
:math:`k_t`; eq. 1) is augmented with a second-order road model
:math:`\ddot x_r + a_2\dot x_r + a_1x_r = w_r` (eq. 3 with the process noise of eq. 4),
giving six states and two measured accelerations (eq. 2, 4)

.. math:: x = [x_b, \dot x_b, x_w, \dot x_w, x_r, \dot x_r]^T,\qquad
   y = [\ddot x_b, \ddot x_w]^T = Cx + v,\qquad \dot x = Ax + w .

Discretized by Euler, :math:`\Phi = I + AT` (eq. 7, the paper's choice) or exactly,
:math:`\Phi = e^{AT}` (``method="exact"``). A standard Kalman filter (eq. 10–14) estimates
the states, among them the road :math:`x_r` (eq. 15). The MME&KF (eq. 16–21, after Mook &
Junkins [2]_) adds, before each prediction, a model-error vector :math:`d_k` that enters
the dynamics through a matrix :math:`G`,
:math:`\hat x_{k|k-1} = \Phi\hat x_{k-1|k-1} + \Gamma_d d_k` (eq. 21, :math:`\Gamma_d = TG`
for Euler), chosen to minimize (eq. 16)

.. math:: J(d_k) = \tfrac12 (y_k - \hat y_k)^T \Sigma^{-1}(y_k - \hat y_k)
   + \tfrac12 d_k^T W d_k,\qquad \hat y_k = C\Phi\hat x_{k-1|k-1} + Dd_k

(eq. 17–18: :math:`h + T L_f h = C(I + AT)x = C\Phi x`, :math:`T L_G h = TCG`), whose
minimizer is eq. 19,
:math:`d_k = (D^T\Sigma^{-1}D + W)^{-1}D^T\Sigma^{-1}(y_k - C\Phi\hat x_{k-1|k-1})`.
Then the Kalman update with :math:`y_k - \hat y` follows (eq. 21).

The reading (docs/road_estimation.md, "The MME&KF: readings", has the ones tried and their
numbers). Three choices the paper leaves open or prints in a form that cannot work:

- **Where the error enters** (``error_input``, :func:`error_input_matrix`). Eq. 7 prints
  :math:`G` copied from :math:`A` times a :math:`d` of six equal entries; that product is
  :math:`d\,A\mathbf 1 = d\,[1, 0, 1, 0, 1, -a_1-a_2]^T`, a common shift of body, wheel and
  road which no acceleration sees (:math:`D = 0`: the MME&KF is the KF, ``"printed"``). A
  sprung-mass error changes the body's acceleration and nothing else directly: default
  ``"body"``, :math:`G = e_2`, d an acceleration error of the body, m/s². Also
  ``"mass"`` (d the relative change of the body's acceleration, eq. 7's
  :math:`d = dm_b/m_b` read as a mass ratio), ``"accelerations"`` (:math:`[e_2, e_4]`),
  ``"all"`` (:math:`G = I`, Mook & Junkins' generic error).
- **The measured accelerations contain the error** (``feedthrough``, default True). The
  outputs of eq. 2 are the accelerations :math:`\dot x_2, \dot x_4` themselves; eq. 6 adds
  :math:`\varepsilon_2` to :math:`\dot x_2` but writes :math:`y_1` without it. An
  accelerometer measures the true acceleration, error included: :math:`y = Cx + Ed + v`
  with E the acceleration rows of G, so :math:`D = C\Gamma_d + E`. Without it, d reaches
  y only through :math:`TCG` (:math:`\sim 10^{-3}`) and a small W integrates the road's
  unpredictability into a diverging "body error".
- **The covariance of the one-step residual** (``fit`` and the ``target`` of
  :func:`covariance_constraint_weight`). Mook & Junkins' MME has no process noise: with
  a perfect model the residual's covariance is R, so eq. 16 weights it by
  :math:`R^{-1}` and eq. 20 asks the post-fit residuals for R. Inside a Kalman filter the
  prediction :math:`C\Phi\hat x_{k-1|k-1}` is itself uncertain (the road's process noise,
  the state's error): the residual of a correct model has covariance
  :math:`S_k = CP_{k|k-1}C^T + R` (eq. 12's bracket). Default: :math:`\Sigma = S_k` in
  eq. 16, and eq. 20 asks the part of the residual d can reach (its
  :math:`S_k`-projection on the columns of D) for :math:`S_k`: with a correct model the
  KF meets it already and W goes to its upper bound (d = 0, the KF). ``fit="R"``,
  ``target="R"``: as printed.

W is constant (the paper's remark after eq. 20), found from the measurements alone by
bisection (:func:`covariance_constraint_weight`); it never sees the truth.

Errors of the paper corrected here (and why)
--------------------------------------------
- Eq. 4 prints row 2 of :math:`A`, and row 1 of :math:`C`, as
  :math:`[+k_s/m_b, -c/m_b, k_s/m_b, c/m_b, 0, 0]`; eq. 1 gives :math:`-k_s/m_b` in the
  first entry (eq. 7 prints it right). Eq. 6's :math:`\dot x_2` has the same slip
  (:math:`+k_s(x_1-x_3)/m_b`). Used: eq. 1. A test derives :math:`A` from the forces.
- Eq. 5 writes :math:`\dot x(k+1)`; it is :math:`x(k+1)`.
- Eq. 12 prints :math:`K_k = P C[CPC^T + R]`; the gain is
  :math:`PC^T(CPC^T+R)^{-1}`, as eq. 21 has it.
- Eq. 15 writes :math:`\hat x_r(k) = \hat x_r(k-1) + \dots`; it is the fifth row of eq. 13,
  :math:`\hat x_r(k|k) = \hat x_r(k|k-1) + K_{5,:}(y_k - C\hat x_{k|k-1})`.
- Eq. 7's :math:`G` and :math:`d` (above): replaced by an explicit error-input matrix
  (the printed product is kept as ``error_input="printed"``: it changes nothing).
- Eq. 6 writes the measured accelerations without the model error they contain (above:
  ``feedthrough``).
- Eq. 3 sets the road model's right-hand side to 0; a road then decays to zero. The road
  is the model's response to white noise :math:`w_r` (eq. 4's :math:`w`), whose intensity
  and :math:`a_1, a_2` the paper does not give: :func:`iso_road_model` sets them so that
  the model's PSD follows the ISO 8608 level of the class (two real poles at the road's
  lowest and highest spatial frequency; between them the slope :math:`w = 2`).

Time convention: arrays are ``(runs, steps, channels)``; sample k is at :math:`kT`. The
filters start from :math:`\hat x_{0|0}` and :math:`P_{0|0}` and process
:math:`y_1, y_2, \dots`; :math:`y_0` is not used. The gains do not depend on the data:
they are computed once per step and shared by every run. One Python loop runs over time,
none over runs.

References
----------
.. [1] Z. F. Wang, M. M. Dong, Y. C. Qin, L. Gu, "Road profile estimation for suspension
   system based on the minimum model error criterion combined with a Kalman filter",
   Journal of Vibroengineering 19(8), 2017. doi:10.21595/jve.2017.18230
.. [2] D. J. Mook, J. L. Junkins, "Minimum model error estimation for poorly modeled
   dynamic systems", Journal of Guidance, Control, and Dynamics 11(3), 256–261, 1988.
.. [3] ISO 8608:2016, "Mechanical vibration — Road surface profiles — Reporting of
   measured data".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.linalg import expm, solve_discrete_lyapunov

from suvtwin.errors import InputError, positive
from suvtwin.roads.iso8608 import N0_CYCLES_PER_M

__all__ = [
    "ERROR_INPUTS",
    "PAPER_QUARTER_CAR",
    "DiscreteRoadModel",
    "QuarterCar",
    "QuarterCarResponse",
    "RoadEstimate",
    "RoadModel",
    "continuous_matrices",
    "covariance_constraint_weight",
    "discretize",
    "error_input_matrix",
    "error_std_percent",
    "iso_road_model",
    "kalman_filter",
    "mme_kalman_filter",
    "road_model_psd",
    "simulate_quarter_car",
    "stationary_covariance",
]

N_STATES = 6
N_OUTPUTS = 2
ROAD = 4  # index of x_r in the state
ERROR_INPUTS = ("body", "accelerations", "all", "mass", "printed")
ORDERS = ("same-step", "delayed")
CONSTRAINTS = ("R", "innovation", "innovation-all")
FITS = ("R", "innovation")


@dataclass(frozen=True)
class QuarterCar:
    """Linear quarter car, Wang et al. 2017, eq. 1 and Table 1.

    Attributes
    ----------
    sprung_mass : float
        m_b, kg.
    unsprung_mass : float
        m_w, kg.
    suspension_stiffness : float
        k_s, N/m.
    tire_stiffness : float
        k_t, N/m.
    damping : float
        c, N s/m.
    """

    sprung_mass: float
    unsprung_mass: float
    suspension_stiffness: float
    tire_stiffness: float
    damping: float

    def __post_init__(self) -> None:
        units = {"sprung_mass": "kg", "unsprung_mass": "kg", "suspension_stiffness": "N/m",
                 "tire_stiffness": "N/m", "damping": "N s/m"}
        for name, unit in units.items():
            positive(f"QuarterCar.{name}", getattr(self, name), unit)

    def with_sprung_mass(self, sprung_mass: float) -> QuarterCar:
        """The same car with another sprung mass m_b, kg (the paper's m_b ± Δm)."""
        return QuarterCar(sprung_mass, self.unsprung_mass, self.suspension_stiffness,
                          self.tire_stiffness, self.damping)


PAPER_QUARTER_CAR = QuarterCar(  # Wang et al. 2017, Table 1
    sprung_mass=410.0,
    unsprung_mass=39.0,
    suspension_stiffness=20_000.0,
    tire_stiffness=183_000.0,
    damping=2000.0,
)


@dataclass(frozen=True)
class RoadModel:
    r"""Second-order road model :math:`\ddot x_r + a_2\dot x_r + a_1x_r = w_r`, eq. 3.

    Attributes
    ----------
    a1 : float
        1/s².
    a2 : float
        1/s.
    intensity : float
        Intensity q of the white noise :math:`w_r`, :math:`E[w_r(t)w_r(s)] = q\,\delta(t-s)`,
        m²/s³.
    """

    a1: float
    a2: float
    intensity: float

    def __post_init__(self) -> None:
        positive("RoadModel.a1", self.a1, "1/s^2")
        positive("RoadModel.a2", self.a2, "1/s")
        positive("RoadModel.intensity", self.intensity, "m^2/s^3")


def iso_road_model(
    gd_n0: float, *, speed: float, n_low: float = 0.011, n_high: float = 2.83
) -> RoadModel:
    r"""Road model whose PSD follows the ISO 8608 level between two spatial frequencies.

    Poles at :math:`\omega_1 = 2\pi n_{low}v` and :math:`\omega_2 = 2\pi n_{high}v`:
    :math:`a_1 = \omega_1\omega_2`, :math:`a_2 = \omega_1 + \omega_2`. The one-sided PSD
    over temporal frequency f is
    :math:`G(f) = 2q/((\omega^2+\omega_1^2)(\omega^2+\omega_2^2))`, :math:`\omega = 2\pi f`;
    for :math:`\omega_1 \ll \omega \ll \omega_2` it is :math:`2q/(\omega_2^2\omega^2)`. ISO
    8608 with waviness 2 gives over time :math:`G(f) = G_d(n_0)n_0^2v/f^2` (with
    :math:`n = f/v`, :math:`G(f) = G_d(n)/v`); equal when
    :math:`q = 2\pi^2G_d(n_0)n_0^2v\,\omega_2^2`.

    Parameters
    ----------
    gd_n0 : float
        ISO level :math:`G_d(n_0)`, m³ at :math:`n_0 = 0.1` cycle/m
        (``suvtwin.roads.iso8608.class_level``).
    speed : float
        Vehicle speed v, m/s.
    n_low, n_high : float, optional
        Spatial frequencies of the two poles, cycles/m (defaults 0.011 and 2.83, the ISO
        8608 reporting band). ``n_low < n_high``.
    """
    gd_n0 = positive("gd_n0", gd_n0, "m^3")
    speed = positive("speed", speed, "m/s")
    n_low = positive("n_low", n_low, "cycles/m")
    n_high = positive("n_high", n_high, "cycles/m")
    if n_low >= n_high:
        raise InputError(f"n_low must be < n_high (cycles/m), got {n_low} and {n_high}")
    w1, w2 = 2.0 * np.pi * n_low * speed, 2.0 * np.pi * n_high * speed
    q = 2.0 * np.pi**2 * gd_n0 * N0_CYCLES_PER_M**2 * speed * w2**2
    return RoadModel(a1=w1 * w2, a2=w1 + w2, intensity=q)


def road_model_psd(road: RoadModel, frequency: npt.ArrayLike) -> np.ndarray:
    r"""One-sided PSD of the road model's :math:`x_r` over temporal frequency, m²/Hz.

    :math:`G(f) = 2q/|a_1 - \omega^2 + ja_2\omega|^2`, :math:`\omega = 2\pi f`, f in Hz.
    """
    w = 2.0 * np.pi * np.asarray(frequency, dtype=float)
    return 2.0 * road.intensity / ((road.a1 - w**2) ** 2 + (road.a2 * w) ** 2)


def continuous_matrices(car: QuarterCar, road: RoadModel) -> tuple[np.ndarray, np.ndarray]:
    r"""A (6×6) and C (2×6) of eq. 4, row 2 of A (and row 1 of C) with eq. 1's sign.

    State :math:`[x_b, \dot x_b, x_w, \dot x_w, x_r, \dot x_r]` (m, m/s), output
    :math:`[\ddot x_b, \ddot x_w]` (m/s²).
    """
    mb, mw, ks, kt, c = (car.sprung_mass, car.unsprung_mass, car.suspension_stiffness,
                         car.tire_stiffness, car.damping)
    A = np.array(
        [
            [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
            [-ks / mb, -c / mb, ks / mb, c / mb, 0.0, 0.0],  # eq. 4 prints +ks/mb first
            [0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [ks / mw, c / mw, -(ks + kt) / mw, -c / mw, kt / mw, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            [0.0, 0.0, 0.0, 0.0, -road.a1, -road.a2],
        ]
    )  # eq. 4 (corrected), eq. 7
    C = A[[1, 3]].copy()  # eq. 4: the two accelerations
    return A, C


@dataclass(frozen=True)
class DiscreteRoadModel:
    r"""The filter's discrete model (eq. 5, 7).

    Attributes
    ----------
    Phi : numpy.ndarray, shape (6, 6)
        State transition, :math:`I + AT` (Euler, eq. 7) or :math:`e^{AT}` (exact).
    Q : numpy.ndarray, shape (6, 6)
        Covariance of the discrete process noise over one step, m², m²/s².
    C : numpy.ndarray, shape (2, 6)
        Measurement matrix (eq. 4), 1/s² and 1/s.
    A : numpy.ndarray, shape (6, 6)
        The continuous matrix it came from.
    dt : float
        Sampling interval T, s.
    method : str
        ``"euler"`` or ``"exact"``.
    """

    Phi: np.ndarray
    Q: np.ndarray
    C: np.ndarray
    A: np.ndarray
    dt: float
    method: str

    def error_transition(self, G: np.ndarray) -> np.ndarray:
        r""":math:`\Gamma_d` of a model error d held over one step: TG (Euler, eq. 7, 21) or
        :math:`\int_0^T e^{As}ds\,G` (exact)."""
        if self.method == "euler":
            return self.dt * G
        n, p = G.shape
        block = np.zeros((n + p, n + p))
        block[:n, :n], block[:n, n:] = self.A, G
        return expm(block * self.dt)[:n, n:]


def discretize(
    car: QuarterCar,
    road: RoadModel,
    *,
    dt: float,
    method: str = "euler",
    acceleration_noise: float = 0.0,
) -> DiscreteRoadModel:
    r"""Discrete model of the quarter car with road states, eq. 5 and 7.

    Continuous process noise: :math:`w_r` of intensity ``road.intensity`` on
    :math:`\ddot x_r`, and white accelerations of intensity ``acceleration_noise`` on
    :math:`\ddot x_b` and :math:`\ddot x_w` (the filter's allowance for model error).
    ``"euler"``: :math:`\Phi = I + AT`, :math:`Q_d = T\,BQ_cB^T` (eq. 7: :math:`Tw(k)`,
    with eq. 21's :math:`T^2Q`). ``"exact"``: :math:`\Phi = e^{AT}` and
    :math:`Q_d = \int_0^T e^{As}BQ_cB^Te^{A^Ts}ds` (Van Loan).

    Parameters
    ----------
    car : QuarterCar
        The filter's (nominal) car.
    road : RoadModel
    dt : float
        Sampling interval T, s.
    method : {"euler", "exact"}, optional
        Default ``"euler"``, the paper's (eq. 7).
    acceleration_noise : float, optional
        Intensity of the white acceleration noise on body and wheel, m²/s³ (default 0).
    """
    dt = positive("dt", dt, "s")
    if method not in ("euler", "exact"):
        raise InputError(f"method must be 'euler' or 'exact', got {method!r}")
    acceleration_noise = float(acceleration_noise)
    if not np.isfinite(acceleration_noise) or acceleration_noise < 0.0:
        raise InputError(
            f"acceleration_noise must be a finite number >= 0 m^2/s^3, got {acceleration_noise!r}"
        )
    A, C = continuous_matrices(car, road)
    Qc = np.diag([0.0, acceleration_noise, 0.0, acceleration_noise, 0.0, road.intensity])
    if method == "euler":
        Phi = np.eye(N_STATES) + A * dt  # eq. 7
        Q = Qc * dt
    else:
        block = np.zeros((2 * N_STATES, 2 * N_STATES))
        block[:N_STATES, :N_STATES] = -A
        block[:N_STATES, N_STATES:] = Qc
        block[N_STATES:, N_STATES:] = A.T
        e = expm(block * dt)
        Phi = e[N_STATES:, N_STATES:].T
        Q = Phi @ e[:N_STATES, N_STATES:]
        Q = 0.5 * (Q + Q.T)
    return DiscreteRoadModel(Phi=Phi, Q=Q, C=C, A=A, dt=dt, method=method)


# --- the truth: the quarter car driven by a given road ----------------------------------------


@dataclass(frozen=True)
class QuarterCarResponse:
    """Response of the quarter car to a road (noise-free).

    Attributes
    ----------
    states : numpy.ndarray, shape (runs, steps, 4)
        :math:`[x_b, \\dot x_b, x_w, \\dot x_w]`, m and m/s, from rest at the road's first
        elevation.
    accelerations : numpy.ndarray, shape (runs, steps, 2)
        :math:`[\\ddot x_b, \\ddot x_w]`, m/s² (eq. 2's y without noise).
    """

    states: np.ndarray
    accelerations: np.ndarray


def _car_matrices(car: QuarterCar) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 1 as ẋ = F x + B x_r, x = [x_b, ẋ_b, x_w, ẋ_w]."""
    A, _ = continuous_matrices(car, RoadModel(1.0, 1.0, 1.0))
    return A[:4, :4].copy(), A[:4, ROAD].copy()


def simulate_quarter_car(car: QuarterCar, road_height: npt.ArrayLike, *, dt: float) -> QuarterCarResponse:
    r"""The quarter car of eq. 1 driven by sampled road elevations, exact for a road linear
    between samples (first-order hold).

    The state [x, x_r, ẋ_r] with :math:`\dot x = Fx + Bx_r`, :math:`\ddot x_r = 0` over a
    step is propagated by one matrix exponential; the car starts at rest in equilibrium on
    the road's first elevation.

    Parameters
    ----------
    car : QuarterCar
        The true car (e.g. ``PAPER_QUARTER_CAR.with_sprung_mass(590.0)``).
    road_height : array_like, shape (runs, steps) or (steps,)
        Road elevation under the tyre at t = kT, m.
    dt : float
        Sampling interval T, s.

    Returns
    -------
    QuarterCarResponse
        Leading run axis always present.
    """
    dt = positive("dt", dt, "s")
    z = np.atleast_2d(np.asarray(road_height, dtype=float))
    if z.ndim != 2 or z.shape[1] < 2 or not np.all(np.isfinite(z)):
        raise InputError(
            f"road_height must be a finite (runs, steps) array (m), steps >= 2; got shape {z.shape}"
        )
    F, B = _car_matrices(car)
    block = np.zeros((6, 6))
    block[:4, :4], block[:4, 4], block[4, 5] = F, B, 1.0
    e = expm(block * dt)
    Phi, Gam0, Gam1 = e[:4, :4], e[:4, 4], e[:4, 5]
    slope = np.diff(z, axis=1) / dt
    x = np.zeros((z.shape[0], z.shape[1], 4))
    x[:, 0, 0] = x[:, 0, 2] = z[:, 0]
    for k in range(z.shape[1] - 1):
        x[:, k + 1] = x[:, k] @ Phi.T + np.outer(z[:, k], Gam0) + np.outer(slope[:, k], Gam1)
    acc = x @ F[[1, 3]].T + z[..., None] * B[[1, 3]]
    return QuarterCarResponse(states=x, accelerations=acc)


# --- the filters ------------------------------------------------------------------------------


@dataclass(frozen=True)
class RoadEstimate:
    r"""What the filters return; sample k is time kT (index 0: the initial values).

    Attributes
    ----------
    states : numpy.ndarray, shape (runs, steps, 6)
        :math:`\hat x_{k|k}` (eq. 13 / 21), m and m/s; ``states[..., 4]`` is the road
        estimate :math:`\hat x_r` (eq. 15).
    innovations : numpy.ndarray, shape (runs, steps, 2)
        :math:`y_k - C\hat x_{k|k-1}`, m/s²; NaN at k = 0.
    model_errors : numpy.ndarray, shape (runs, steps, p)
        :math:`d_k` (eq. 19) in the units of the error input (m/s² for ``"body"`` and
        ``"accelerations"``); shape (runs, steps, 0) for the plain KF.
    residuals : numpy.ndarray, shape (runs, steps, 2)
        :math:`y_k - \hat y_k` with :math:`\hat y_k = C(\Phi\hat x_{k-1|k-1} + \Gamma_d d_k)`,
        the MME fit's residual of eq. 20 (the innovation of the pure prediction for the KF),
        m/s²; NaN at k = 0.
    gain : numpy.ndarray, shape (steps, 6, 2)
        Kalman gain :math:`K_k` (eq. 12, 21), shared by all runs; NaN at k = 0.
    covariance : numpy.ndarray, shape (steps, 6, 6)
        :math:`P_{k|k}` (eq. 14), shared by all runs.
    innovation_covariance : numpy.ndarray, shape (steps, 2, 2)
        :math:`S_k = CP_{k|k-1}C^T + R` (eq. 12's bracket), m²/s⁴, shared by all runs; NaN at
        k = 0.
    """

    states: np.ndarray
    innovations: np.ndarray
    model_errors: np.ndarray
    residuals: np.ndarray
    gain: np.ndarray
    covariance: np.ndarray
    innovation_covariance: np.ndarray

    @property
    def road(self) -> np.ndarray:
        """:math:`\\hat x_r(k)`, m, shape (runs, steps)."""
        return self.states[..., ROAD]


def error_input_matrix(error_input: str, model: DiscreteRoadModel | None = None) -> np.ndarray:
    r"""G of the model error (module docstring), dimensionless.

    ``"body"`` and ``"mass"`` (6×1, e₂), ``"accelerations"`` (6×2), ``"all"`` (6×6),
    ``"printed"`` (6×1: eq. 7's G times its d of six equal entries, i.e. the row sums of
    that G, :math:`A\mathbf 1 = [1, 0, 1, 0, 1, -a_1-a_2]^T`; needs `model`).
    """
    if error_input in ("body", "mass"):
        return np.eye(N_STATES)[:, [1]]
    if error_input == "accelerations":
        return np.eye(N_STATES)[:, [1, 3]]
    if error_input == "all":
        return np.eye(N_STATES)
    if error_input == "printed":
        if model is None:
            raise InputError("error_input='printed' needs the model (its road model's a1, a2)")
        # the row sums of eq. 7's G: rows 2 and 4 are 0 exactly (the forces of a common shift)
        return np.array([[1.0], [0.0], [1.0], [0.0], [1.0], [model.A[5, 4] + model.A[5, 5]]])
    raise InputError(f"error_input must be one of {ERROR_INPUTS}, got {error_input!r}")


def _measurements(y: npt.ArrayLike) -> tuple[np.ndarray, bool]:
    y = np.asarray(y, dtype=float)
    single = y.ndim == 2
    y = y[None] if single else y
    if y.ndim != 3 or y.shape[-1] != N_OUTPUTS or y.shape[1] < 2:
        raise InputError(f"measurements must have shape (runs, steps, 2) or (steps, 2), steps >= 2, "
                         f"[m/s^2]; got {y.shape}")
    if not np.all(np.isfinite(y)):
        bad = np.argwhere(~np.isfinite(y))[0]
        raise InputError(f"measurements must be finite (m/s^2); NaN or inf at run {bad[0]}, step {bad[1]}")
    return y, single


def _measurement_covariance(measurement_std: npt.ArrayLike) -> np.ndarray:
    sigma = np.asarray(measurement_std, dtype=float)
    if sigma.ndim > 1 or sigma.size not in (1, N_OUTPUTS):
        raise InputError(f"measurement_std must be a scalar or 2 values (m/s^2), got {measurement_std!r}")
    sigma = np.broadcast_to(sigma, (N_OUTPUTS,))
    if not np.all(np.isfinite(sigma)) or np.any(sigma <= 0.0):
        raise InputError(f"measurement_std must be > 0 and finite (m/s^2), got {sigma.tolist()}")
    return np.diag(sigma**2)


def stationary_covariance(model: DiscreteRoadModel) -> np.ndarray:
    r"""Stationary covariance of the filter's model, :math:`P = \Phi P\Phi^T + Q`, m², m²/s².

    The car follows the road model's stationary random road; a filter started with it
    expects the car at rest somewhere on such a road.
    """
    P = solve_discrete_lyapunov(model.Phi, model.Q)
    return 0.5 * (P + P.T)


@dataclass(frozen=True)
class _MME:
    """One reading of eq. 16-21 (see :func:`mme_kalman_filter`)."""

    Gd: np.ndarray  # Gamma_d, (6, p): the error's effect on the state over one step
    E: np.ndarray  # (2, p): the error's direct effect on the measured accelerations (0: none)
    W: np.ndarray  # (p, p)
    order: str  # "same-step" or "delayed"
    fit: str  # eq. 16's residual weight: "R" (as printed) or "innovation" (S_k^-1)
    scale_row: np.ndarray | None  # "mass": d multiplies the model's body acceleration A_2 x


def _run(
    y: np.ndarray,
    model: DiscreteRoadModel,
    R: np.ndarray,
    P0: np.ndarray,
    x0: np.ndarray,
    mme: _MME | None,
) -> tuple[np.ndarray, ...]:
    Phi, Q, C = model.Phi, model.Q, model.C
    n_runs, n_steps, _ = y.shape
    Ri = np.linalg.inv(R)
    if mme is None:
        p = 0
        Gd, E = np.zeros((N_STATES, 0)), np.zeros((N_OUTPUTS, 0))
    else:
        Gd, E = mme.Gd, mme.E
        p = Gd.shape[1]
        D = C @ Gd + E  # eq. 18-19: D = T L_G(h) (+ E: the error in the measured accelerations)
        M = np.linalg.solve(D.T @ Ri @ D + mme.W, D.T @ Ri)  # eq. 19
    CPhi = C @ Phi
    eye = np.eye(N_STATES)
    x = np.broadcast_to(x0, (n_runs, N_STATES)).copy()
    P = P0.copy()
    out_x = np.empty((n_runs, n_steps, N_STATES))
    out_innov = np.full((n_runs, n_steps, N_OUTPUTS), np.nan)
    out_resid = np.full((n_runs, n_steps, N_OUTPUTS), np.nan)
    out_d = np.full((n_runs, n_steps, p), np.nan)
    out_K = np.full((n_steps, N_STATES, N_OUTPUTS), np.nan)
    out_S = np.full((n_steps, N_OUTPUTS, N_OUTPUTS), np.nan)
    out_P = np.empty((n_steps, N_STATES, N_STATES))
    out_x[:, 0], out_P[0] = x, P
    d_prev = np.zeros((n_runs, p))
    for k in range(1, n_steps):
        P = Phi @ P @ Phi.T + Q  # eq. 11 / 21
        S = C @ P @ C.T + R
        K = np.linalg.solve(S, C @ P).T  # eq. 12 (corrected) / 21
        IKC = eye - K @ C
        P = IKC @ P @ IKC.T + K @ R @ K.T  # eq. 14, Joseph form
        P = 0.5 * (P + P.T)
        pre = y[:, k] - x @ CPhi.T  # y_k - (y^p + S) of eq. 19
        if p and mme.fit == "innovation":
            Ri = np.linalg.inv(S)
            M = np.linalg.solve(D.T @ Ri @ D + mme.W, D.T @ Ri)
        if p == 0:
            x = x @ Phi.T  # eq. 11
            out_resid[:, k] = pre
            innov = y[:, k] - x @ C.T
        else:
            if mme.scale_row is None:
                d = pre @ M.T  # eq. 19
                fit = d @ D.T
            else:  # "mass": D_k = s_k D with s_k = A_2 x_(k-1|k-1), per run
                s = x @ mme.scale_row
                Ds = s[:, None] * D[:, 0]  # (runs, 2)
                num = np.einsum("ri,ij,rj->r", Ds, Ri, pre)
                den = np.einsum("ri,ij,rj->r", Ds, Ri, Ds) + mme.W[0, 0]
                d = (num / den)[:, None]
                fit = d * Ds
            out_d[:, k] = d
            out_resid[:, k] = pre - fit  # y_k - yhat_k (eq. 17, 20)
            applied = d if mme.order == "same-step" else d_prev
            if mme.scale_row is None:
                x = x @ Phi.T + applied @ Gd.T  # eq. 21, first line
                innov = y[:, k] - x @ C.T - applied @ E.T
            else:
                sa = (x @ mme.scale_row)[:, None] * applied
                x = x @ Phi.T + sa @ Gd.T
                innov = y[:, k] - x @ C.T - sa @ E.T
            d_prev = d
        x = x + innov @ K.T  # eq. 13 / 21
        out_x[:, k], out_innov[:, k], out_K[k], out_P[k], out_S[k] = x, innov, K, P, S
    return out_x, out_innov, out_d, out_resid, out_K, out_P, out_S


def _setup(y, model, measurement_std, state_covariance0, state0):
    y, single = _measurements(y)
    R = _measurement_covariance(measurement_std)
    if state_covariance0 is None:
        P0 = stationary_covariance(model)
    else:
        P0 = np.asarray(state_covariance0, dtype=float)
        P0 = P0 * np.eye(N_STATES) if P0.ndim == 0 else (np.diag(P0) if P0.ndim == 1 else P0)
        if P0.shape != (N_STATES, N_STATES) or not np.all(np.isfinite(P0)) or not np.allclose(P0, P0.T) \
                or np.min(np.linalg.eigvalsh(P0)) < 0.0:
            raise InputError(f"state_covariance0 must be a symmetric positive semi-definite 6x6 (or scalar, "
                             f"or 6 variances) in m^2, m^2/s^2; got {state_covariance0!r}")
    x0 = np.zeros(N_STATES) if state0 is None else np.asarray(state0, dtype=float)
    if x0.shape != (N_STATES,) or not np.all(np.isfinite(x0)):
        raise InputError(f"state0 must be 6 finite values (m, m/s), got {state0!r}")
    return y, single, R, P0, x0


def _estimate(out, single: bool) -> RoadEstimate:
    x, innov, d, resid, K, P, S = out
    if single:
        x, innov, d, resid = x[0], innov[0], d[0], resid[0]
    return RoadEstimate(states=x, innovations=innov, model_errors=d, residuals=resid, gain=K, covariance=P,
                        innovation_covariance=S)


def kalman_filter(
    measurements: npt.ArrayLike,
    model: DiscreteRoadModel,
    *,
    measurement_std: npt.ArrayLike,
    state_covariance0: npt.ArrayLike | None = None,
    state0: npt.ArrayLike | None = None,
) -> RoadEstimate:
    r"""Kalman filter of the quarter car with road states, eq. 10–15.

    Parameters
    ----------
    measurements : array_like, shape (runs, steps, 2) or (steps, 2)
        :math:`y_k = [\ddot x_b, \ddot x_w]` at t = kT, m/s²; :math:`y_0` is not used.
    model : DiscreteRoadModel
        From :func:`discretize` (the nominal car).
    measurement_std : float or array_like, shape (2,)
        σ of the two accelerometers, m/s²; :math:`R = \mathrm{diag}(\sigma^2)`.
    state_covariance0 : array_like, optional
        :math:`P_{0|0}` (eq. 10): scalar (times I), 6 variances or 6×6, m² and m²/s². If
        None, the road model's stationary covariance (:func:`stationary_covariance`).
    state0 : array_like, shape (6,), optional
        :math:`\hat x_{0|0}`; default zero.

    Returns
    -------
    RoadEstimate
        Leading run axis removed if `measurements` had none.

    Raises
    ------
    suvtwin.errors.InputError
        Measurements not finite or not (runs, steps, 2); σ ≤ 0; a bad covariance.
    """
    y, single, R, P0, x0 = _setup(measurements, model, measurement_std, state_covariance0, state0)
    return _estimate(_run(y, model, R, P0, x0, None), single)


def _weight(weight: npt.ArrayLike, p: int) -> np.ndarray:
    W = np.asarray(weight, dtype=float)
    W = W * np.eye(p) if W.ndim == 0 else (np.diag(W) if W.ndim == 1 else W)
    if W.shape != (p, p) or not np.all(np.isfinite(W)) or not np.allclose(W, W.T) \
            or np.min(np.linalg.eigvalsh(W)) <= 0.0:
        raise InputError(f"weight must be a positive definite {p}x{p} matrix (or a scalar > 0, or {p} values "
                         f"> 0), in (s^2/m)^2 for acceleration errors; got {weight!r}")
    return W


def _mme_spec(model: DiscreteRoadModel, weight, error_input: str, feedthrough: bool, order: str,
              fit: str) -> _MME:
    G = error_input_matrix(error_input, model)
    W = _weight(weight, G.shape[1])
    if order not in ORDERS:
        raise InputError(f"order must be one of {ORDERS}, got {order!r}")
    if fit not in FITS:
        raise InputError(f"fit must be one of {FITS}, got {fit!r}")
    E = G[[1, 3]].copy() if feedthrough else np.zeros((N_OUTPUTS, G.shape[1]))
    scale = model.A[1].copy() if error_input == "mass" else None
    return _MME(Gd=model.error_transition(G), E=E, W=W, order=order, fit=fit, scale_row=scale)


def mme_kalman_filter(
    measurements: npt.ArrayLike,
    model: DiscreteRoadModel,
    *,
    measurement_std: npt.ArrayLike,
    weight: npt.ArrayLike,
    error_input: str = "body",
    feedthrough: bool = True,
    order: str = "same-step",
    fit: str = "innovation",
    state_covariance0: npt.ArrayLike | None = None,
    state0: npt.ArrayLike | None = None,
) -> RoadEstimate:
    r"""MME&KF: the model error of eq. 19 added to the Kalman filter's prediction, eq. 16–21.

    Parameters
    ----------
    measurements, model, measurement_std, state_covariance0, state0
        As :func:`kalman_filter`.
    weight : float or array_like, shape (p,) or (p, p)
        W of eq. 16, positive definite, in 1/(unit of d)² (for acceleration errors
        (s²/m)²); a scalar means W·I. :func:`covariance_constraint_weight` gives eq. 20's
        choice.
    error_input : {"body", "accelerations", "all", "mass", "printed"}, optional
        Where the model error enters (:func:`error_input_matrix`); default ``"all"``
        (G = I). ``"mass"``: a dimensionless d scales the model's body acceleration,
        :math:`\ddot x_b = (1 + d)A_2x` (a sprung-mass error, d = −Δm/(m_b + Δm)).
    feedthrough : bool, optional
        If True, the measured accelerations contain the error too (they *are* the
        accelerations the error changes): :math:`y_k = Cx_k + Ed_k + v_k` with E the
        acceleration rows of G, so :math:`D = C\Gamma_d + E` in eq. 19 and the Kalman
        update uses :math:`y_k - C\hat x_{k|k-1} - Ed_k`. Default False (eq. 6–7 as printed:
        y = h(x)).
    order : {"same-step", "delayed"}, optional
        ``"same-step"`` (eq. 17, 21 as printed): d_k, fitted to y_k, corrects the prediction
        of x_k, which the Kalman update then corrects with y_k again. ``"delayed"``: d_k
        corrects the next prediction (x_{k+1}), so y_k is used once per step by each.
    fit : {"innovation", "R"}, optional
        The residual's weight in eq. 16: :math:`S_k^{-1}` (default), the inverse of the
        covariance the KF expects of the one-step prediction error (the road's process
        noise and the state's uncertainty included), or :math:`R^{-1}` (as printed).

    Returns
    -------
    RoadEstimate
        With ``model_errors`` :math:`d_k` (eq. 19).
    """
    y, single, R, P0, x0 = _setup(measurements, model, measurement_std, state_covariance0, state0)
    spec = _mme_spec(model, weight, error_input, feedthrough, order, fit)
    return _estimate(_run(y, model, R, P0, x0, spec), single)


def covariance_constraint_weight(
    measurements: npt.ArrayLike,
    model: DiscreteRoadModel,
    *,
    measurement_std: npt.ArrayLike,
    error_input: str = "body",
    feedthrough: bool = True,
    order: str = "same-step",
    fit: str = "innovation",
    target: str = "innovation",
    state_covariance0: npt.ArrayLike | None = None,
    state0: npt.ArrayLike | None = None,
    bounds: tuple[float, float] = (1e-12, 1e12),
    iterations: int = 40,
    skip: int = 0,
) -> float:
    r"""The scalar W (times I) of eq. 20: post-fit residuals with the expected covariance.

    Finds w with :math:`\overline{r_k^T\Sigma_k^{+}r_k} = m`, where
    :math:`r_k = y_k - \hat y_k` is the MME fit's residual (eq. 17) averaged over all runs
    and steps after `skip`, by bisection on log w. The residual grows with w (w → ∞ is the
    plain KF's one-step prediction error).

    ``target="innovation"`` (default): the part of the residual the error can reach, its
    :math:`S_k`-projection on the columns of D,
    :math:`\Sigma_k^{+} = S_k^{-1}D(D^TS_k^{-1}D)^{-1}D^TS_k^{-1}`, m = rank D, with
    :math:`S_k = CP_{k|k-1}C^T + R` the covariance the Kalman filter expects of its
    one-step prediction error (the road's process noise included). With a correct model
    the KF meets it already and w goes to the upper bound (d = 0, the KF); residual the
    error cannot reach (the wheel channel for G = e₂) does not push W down.
    ``"innovation-all"``: :math:`\Sigma_k^{+} = S_k^{-1}`, m = 2. ``"R"``:
    :math:`\Sigma_k^{+} = R^{-1}`, m = 2 (eq. 20 as printed; Mook & Junkins' MME has no
    process noise, so all of the residual beyond R counts as model error, the road's
    unpredictability included). Uses the measurements only, never the truth. The other
    arguments as :func:`mme_kalman_filter`.

    Returns
    -------
    float
        w, in 1/(unit of d)². If even w at the upper bound leaves residuals below the
        target (or d reaches no measurement), the upper bound; at the lower bound above
        it, the lower bound.
    """
    y, _ = _measurements(measurements)
    if target not in CONSTRAINTS:
        raise InputError(f"target must be one of {CONSTRAINTS}, got {target!r}")
    lo, hi = np.log(bounds[0]), np.log(bounds[1])
    R = _measurement_covariance(measurement_std)

    spec = _mme_spec(model, 1.0, error_input, feedthrough, order, fit)
    D = model.C @ spec.Gd + spec.E
    rank = int(np.linalg.matrix_rank(D, tol=1e-12 * max(1.0, float(np.abs(D).max()))))
    if target == "innovation" and rank == 0:
        return float(bounds[1])  # d reaches no measurement: nothing to fit (eq. 7's G as printed)

    def excess(logw: float) -> float:
        est = mme_kalman_filter(y, model, measurement_std=measurement_std, weight=np.exp(logw),
                                error_input=error_input, feedthrough=feedthrough, order=order, fit=fit,
                                state_covariance0=state_covariance0, state0=state0)
        k0 = max(skip, 1)
        r = est.residuals[:, k0:]
        if target == "R":
            Si, dof = np.broadcast_to(np.linalg.inv(R), (r.shape[1], N_OUTPUTS, N_OUTPUTS)), N_OUTPUTS
        else:
            Si, dof = np.linalg.inv(est.innovation_covariance[k0:]), N_OUTPUTS
            if target == "innovation" and rank < N_OUTPUTS:
                # the part of r that d can reach: S^-1 D (D^T S^-1 D)^-1 D^T S^-1, rank D
                SiD = Si @ D
                Si = SiD @ np.linalg.solve(D.T @ SiD, np.swapaxes(SiD, 1, 2))
                dof = rank
        return float(np.mean(np.einsum("rki,kij,rkj->rk", r, Si, r))) - dof

    if excess(hi) <= 0.0:
        return float(np.exp(hi))
    if excess(lo) >= 0.0:
        return float(np.exp(lo))
    for _ in range(int(iterations)):
        mid = 0.5 * (lo + hi)
        if excess(mid) > 0.0:
            hi = mid
        else:
            lo = mid
    return float(np.exp(0.5 * (lo + hi)))


def error_std_percent(truth: npt.ArrayLike, estimate: npt.ArrayLike) -> np.ndarray:
    r"""Error STD in % of the road's STD, :math:`100\,\mathrm{std}(\hat x_r - x_r)/\mathrm{std}(x_r)`.

    Both over the last axis (time); ``std`` is the population standard deviation (about
    each signal's own mean, so a constant offset of the estimate is not counted). Shapes
    broadcast: ``(runs, steps)`` gives ``(runs,)``.
    """
    z, zh = np.broadcast_arrays(np.asarray(truth, dtype=float), np.asarray(estimate, dtype=float))
    return 100.0 * np.std(zh - z, axis=-1) / np.std(z, axis=-1)
