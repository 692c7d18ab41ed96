r"""The SUV's suspension force laws and their Gaussian equivalent linearization.

Usual call::

    law = SuspensionLaw.of(vehicle.suspension, spring_rate=38000.0)   # in the pipeline
    mean, k_eq = equivalent_spring_rate(law, static_travel, sigma_travel, sigma_velocity)

The laws (SI units; travel s in m, compression > 0, measured from the design position where
the spring's preload carries the corner's static load; velocity v = ds/dt in m/s):

.. math::

    F_s(s) - F_s(0) = k s + k\,\pi s^3 [s > 0]
        + \bigl(b_1 e_b + b_2 e_b^2\bigr)[e_b > 0]
        - \bigl(r_1 e_r + r_2 e_r^2\bigr)[e_r > 0],
    \quad e_b = s - c_b,\ e_r = -s - c_r,

a progressive spring (cubic term in compression only) with bump and rebound stops, and the
digressive, asymmetric damper :math:`F_d(v) = c_{lo} |v|` up to the knee velocity
:math:`v_k`, :math:`c_{lo} v_k + c_{hi}(|v| - v_k)` beyond, with compression slopes for
:math:`v > 0` and rebound slopes (negative force) for :math:`v < 0`. The simulator's compiled
kernel (``suvtwin.mjcf.kernel``) applies these laws at every step; the tests check that the
two agree.

**Equivalent linearization.** On a rough road the travel is a random process around a mean
m; a linear model of the corner needs the rate that reproduces the spring's force in the
mean-square sense, which for a Gaussian travel :math:`s = m + x`,
:math:`x \sim N(0, \sigma^2)`, is :math:`k_{eq} = E[F_s'(m + x)]` (statistical
linearization, Roberts & Spanos [1]_, ch. 5; by Stein's lemma :math:`E[x F_s(m + x)] =
\sigma^2 E[F_s'(m + x)]`). The mean itself moves away from the static travel: the corner's
average forces still carry the static load,
:math:`E[F_s(m + x)] + E[F_d(v)] = F_s(s_0)`, where the asymmetric damper's mean force
(rebound stiffer than compression: negative) pulls the body down ("jacking down") and the
progressive spring and the bump stop push it up. Both expectations have closed forms in the
normal distribution's partial moments (:func:`partial_moment`), evaluated here over arrays.

**What the linearization leaves.** An asymmetric damper's force has an even part in v
(:math:`F_d(v) + F_d(-v) \ne 0`), which no linear model holds: it is uncorrelated with v, so the
statistical linearization drops it, yet it is a force between body and wheel whose spectrum lies
at sums of the velocity's frequencies (twice the body bounce, twice the wheel hop). Regressed
on :math:`|v| - E|v|` (:func:`damper_even_slope`), its spectrum is that of a rectified Gaussian
process (:func:`rectified_psd`); the online monitor adds its response to the corner's spectrum. The whole
residual, the even part and the odd part a digressive knee leaves, has its spectrum from the
damper's Hermite coefficients (:func:`damper_hermite`, :func:`damper_residual_psd`); in the
monitor's projected likelihood it changed nothing measurable (100 MuJoCo ``constant`` runs,
observable tyres at 30 s: −0.5 ± 9.2 kPa against −0.1 ± 9.1 with the even part), so the monitor
keeps the even part; ``bench/two_channel_mujoco.py`` uses the whole.

The spring's residual (the progression, the stops) has its spectrum the same way
(:func:`spring_hermite`, :func:`spring_residual_psd`). It is a diagnostic, not used by the monitor:
on the MuJoCo SUV's class D runs the bump stop cuts the travel's upper tail, the travel is not
Gaussian there, and the formula came out several times the actual residual of the loaded rears at
5–10 Hz (``bench/spring_residual.py`` measures it from the simulator's travel).

Written by hand: no maintained library linearizes a piecewise polynomial spring this way.

References
----------
.. [1] J. B. Roberts, P. D. Spanos, *Random Vibration and Statistical Linearization*, Wiley
   1990 (Dover 2003), ch. 5.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt
from scipy.special import ndtr

from suvtwin.errors import InputError
from suvtwin.jit import cached_njit

__all__ = [
    "SuspensionLaw",
    "damper_even_slope",
    "damper_force",
    "damper_hermite",
    "damper_residual_psd",
    "equivalent_spring_rate",
    "gaussian_damper_force",
    "gaussian_spring_force",
    "gaussian_spring_rate",
    "partial_moment",
    "rectified_psd",
    "spring_force",
    "spring_hermite",
    "spring_rate",
    "spring_residual_psd",
    "static_travel",
]

_SQRT_2PI = math.sqrt(2.0 * math.pi)
_SQRT_2 = math.sqrt(2.0)
_SIGMA_FLOOR = 1e-9  # σ → 0: the deterministic limit


@dataclass(frozen=True)
class SuspensionLaw:
    """One corner's suspension at the wheel: spring with stops, digressive damper (SI units).

    ``spring_rate`` k (N/m); ``progression`` π (1/m², cubic term k·π·s³ in compression);
    ``bump_clearance`` c_b (m), ``bump_linear`` b₁ (N/m), ``bump_quadratic`` b₂ (N/m²);
    ``rebound_clearance`` c_r (m), ``rebound_linear`` r₁, ``rebound_quadratic`` r₂;
    damper slopes (N s/m) ``compression_low``/``compression_high``,
    ``rebound_low``/``rebound_high`` below/above ``knee_velocity`` (m/s). The defaults make a
    linear spring without stops and no damper."""

    spring_rate: float
    progression: float = 0.0
    bump_clearance: float = math.inf
    bump_linear: float = 0.0
    bump_quadratic: float = 0.0
    rebound_clearance: float = math.inf
    rebound_linear: float = 0.0
    rebound_quadratic: float = 0.0
    compression_low: float = 0.0
    compression_high: float = 0.0
    rebound_low: float = 0.0
    rebound_high: float = 0.0
    knee_velocity: float = math.inf

    def __post_init__(self) -> None:
        for name in ("spring_rate", "progression", "bump_linear", "bump_quadratic", "rebound_linear",
                     "rebound_quadratic", "compression_low", "compression_high", "rebound_low",
                     "rebound_high"):  # fmt: skip
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise InputError(f"suspension {name} must be finite and ≥ 0, got {value!r}")
        if not self.spring_rate > 0.0:
            raise InputError(f"suspension spring_rate must be > 0 N/m, got {self.spring_rate!r}")
        for name in ("bump_clearance", "rebound_clearance", "knee_velocity"):
            if not getattr(self, name) > 0.0:
                raise InputError(f"suspension {name} must be > 0, got {getattr(self, name)!r}")

    @functools.cached_property
    def values(self) -> np.ndarray:
        """The 13 values in field order, for the compiled functions (made once; read-only)."""
        out = np.array([getattr(self, f.name) for f in fields(self)], dtype=float)
        out.setflags(write=False)
        return out

    @classmethod
    def of(cls, suspension, *, spring_rate: float) -> SuspensionLaw:
        """The law of a corner of a vehicle's ``Suspension`` parameters (``suvtwin.mjcf.vehicle``)
        with that corner's wheel rate `spring_rate` (N/m)."""
        s = suspension
        return cls(
            spring_rate=float(spring_rate), progression=s.spring_progression,
            bump_clearance=s.bump_stop_clearance, bump_linear=s.bump_stop_linear,
            bump_quadratic=s.bump_stop_quadratic, rebound_clearance=s.rebound_stop_clearance,
            rebound_linear=s.rebound_stop_linear, rebound_quadratic=s.rebound_stop_quadratic,
            compression_low=s.damper_compression_low, compression_high=s.damper_compression_high,
            rebound_low=s.damper_rebound_low, rebound_high=s.damper_rebound_high,
            knee_velocity=s.damper_knee_velocity,
        )  # fmt: skip


@cached_njit
def _pm(n, mu, sd):
    """:func:`partial_moment` of one (μ, σ), compiled."""
    z = mu / sd
    cdf = 0.5 * math.erfc(-z / _SQRT_2)
    pdf = math.exp(-0.5 * z * z) / _SQRT_2PI
    if n == 0:
        return cdf
    if n == 1:
        return mu * cdf + sd * pdf
    if n == 2:
        return (mu * mu + sd * sd) * cdf + mu * sd * pdf
    return (mu**3 + 3.0 * mu * sd * sd) * cdf + sd * pdf * (mu * mu + 2.0 * sd * sd)


@cached_njit
def _mean_force(q, m, sd):
    """E[F_s(m + x)] − F_s(0), x ~ N(0, sd²); `q` the law's :attr:`SuspensionLaw.values`."""
    k, prog, cb, b1, b2, cr, r1, r2 = q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7]
    out = k * m + k * prog * _pm(3, m, sd)
    if not math.isinf(cb):
        out += b1 * _pm(1, m - cb, sd) + b2 * _pm(2, m - cb, sd)
    if not math.isinf(cr):
        out -= r1 * _pm(1, -m - cr, sd) + r2 * _pm(2, -m - cr, sd)
    return out


@cached_njit
def _mean_rate(q, m, sd):
    """E[F_s'(m + x)], x ~ N(0, sd²)."""
    k, prog, cb, b1, b2, cr, r1, r2 = q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7]
    out = k * (1.0 + 3.0 * prog * _pm(2, m, sd))
    if not math.isinf(cb):
        out += b1 * _pm(0, m - cb, sd) + 2.0 * b2 * _pm(1, m - cb, sd)
    if not math.isinf(cr):
        out += r1 * _pm(0, -m - cr, sd) + 2.0 * r2 * _pm(1, -m - cr, sd)
    return out


@cached_njit
def _mean_damper(q, sv):
    """E[F_d(v)], v ~ N(0, sv²)."""
    c_lo, c_hi, r_lo, r_hi, knee = q[8], q[9], q[10], q[11], q[12]
    half = sv / _SQRT_2PI
    beyond = 0.0 if math.isinf(knee) else _pm(1, -knee, sv)
    return (c_lo * half - (c_lo - c_hi) * beyond) - (r_lo * half - (r_lo - r_hi) * beyond)


@cached_njit
def _force(q, s):
    """F_s(s) − F_s(0)."""
    k, prog, cb, b1, b2, cr, r1, r2 = q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7]
    out = k * s + (k * prog * s**3 if s > 0.0 else 0.0)
    if s > cb:
        out += b1 * (s - cb) + b2 * (s - cb) ** 2
    if -s > cr:
        out -= r1 * (-s - cr) + r2 * (-s - cr) ** 2
    return out


@cached_njit
def _damper(q, v):
    """F_d(v): the digressive damper's force at compression velocity v (:func:`damper_force`)."""
    c_lo, c_hi, r_lo, r_hi, knee = q[8], q[9], q[10], q[11], q[12]
    a = abs(v)
    over = max(a - knee, 0.0)
    if v >= 0.0:
        return c_lo * a - (c_lo - c_hi) * over
    return -(r_lo * a - (r_lo - r_hi) * over)


@cached_njit
def _rate(q, s):
    """F_s'(s)."""
    k, prog, cb, b1, b2, cr, r1, r2 = q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7]
    out = k * (1.0 + (3.0 * prog * s * s if s > 0.0 else 0.0))
    if s > cb:
        out += b1 + 2.0 * b2 * (s - cb)
    if -s > cr:
        out += r1 + 2.0 * r2 * (-s - cr)
    return out


@cached_njit
def _equivalent(q, s0, sd, sv):
    """Mean travel and equivalent rate (see :func:`equivalent_spring_rate`), one corner state."""
    target = _force(q, s0) - _mean_damper(q, sv)
    m = s0
    for _ in range(60):
        step = (_mean_force(q, m, sd) - target) / _mean_rate(q, m, sd)
        step = min(max(step, -0.05), 0.05)
        m -= step
        if abs(step) < 1e-10:
            break
    return m, _mean_rate(q, m, sd)


@cached_njit
def _kernel(which, q, a, b, c, out0, out1):
    """Apply one law function elementwise over flat arrays a, b, c (unused ones ignored)."""
    for i in range(a.size):
        if which == 0:
            out0[i] = _mean_force(q, a[i], max(b[i], _SIGMA_FLOOR))
        elif which == 1:
            out0[i] = _mean_rate(q, a[i], max(b[i], _SIGMA_FLOOR))
        elif which == 2:
            out0[i] = _mean_damper(q, max(a[i], _SIGMA_FLOOR))
        elif which == 3:
            out0[i] = _force(q, a[i])
        elif which == 4:
            out0[i] = _rate(q, a[i])
        elif which == 5:
            s = b[i] / q[0]  # static travel: F_s(s) − F_s(0) = b (Newton; F_s increases)
            for _ in range(60):
                step = (_force(q, s) - b[i]) / _rate(q, s)
                s -= step
                if abs(step) < 1e-12:
                    break
            out0[i] = s
        elif which == 6:
            out0[i], out1[i] = _equivalent(q, a[i], max(b[i], _SIGMA_FLOOR), max(c[i], _SIGMA_FLOOR))
        elif which == 8:
            out0[i] = _damper(q, a[i])
        else:
            out0[i] = _pm(int(c[i]), a[i], b[i])


def _apply(which: int, law_values: np.ndarray, *args) -> tuple[np.ndarray, np.ndarray]:
    arrays = np.broadcast_arrays(*[np.asarray(x, dtype=float) for x in args])
    shape = arrays[0].shape
    flat = [np.ascontiguousarray(x).ravel() for x in arrays] + [np.zeros(1)] * (3 - len(arrays))
    flat = [f if f.size == flat[0].size else np.zeros(flat[0].size) for f in flat]
    out0, out1 = np.empty(flat[0].size), np.empty(flat[0].size)
    _kernel(which, law_values, flat[0], flat[1], flat[2], out0, out1)
    return out0.reshape(shape), out1.reshape(shape)


def partial_moment(n: int, mu: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    r""":math:`E[Y^n\,[Y > 0]]` for :math:`Y \sim N(\mu, \sigma^2)`, n = 0…3 (σ > 0).

    With :math:`z = \mu/\sigma`, Φ and φ the standard normal cdf and pdf: Φ;
    μΦ + σφ; (μ² + σ²)Φ + μσφ; (μ³ + 3μσ²)Φ + σφ(μ² + 2σ²)."""
    if n not in (0, 1, 2, 3):
        raise ValueError(f"partial_moment: n must be 0–3, got {n}")
    return _apply(7, np.zeros(13), mu, sigma, float(n))[0]


def spring_force(s: npt.ArrayLike, law: SuspensionLaw) -> np.ndarray:
    """Spring and stop force beyond the preload, :math:`F_s(s) - F_s(0)`, N, at compression `s` (m)."""
    return _apply(3, law.values, s)[0]


def spring_rate(s: npt.ArrayLike, law: SuspensionLaw) -> np.ndarray:
    """Local rate :math:`F_s'(s)`, N/m, at compression `s` (m)."""
    return _apply(4, law.values, s)[0]


def damper_force(v: npt.ArrayLike, law: SuspensionLaw) -> np.ndarray:
    """Damper force, N (> 0 resists compression), at compression velocity `v` (m/s): the low slopes
    below the knee velocity, the high ones beyond it."""
    return _apply(8, law.values, v)[0]


def gaussian_spring_force(law: SuspensionLaw, mean: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    """:math:`E[F_s(m + x)] - F_s(0)`, N, for travel `mean` m and std `sigma` σ (m), x Gaussian."""
    return _apply(0, law.values, mean, sigma)[0]


def gaussian_spring_rate(law: SuspensionLaw, mean: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    """Equivalent (statistically linearized) rate :math:`E[F_s'(m + x)]`, N/m, x ~ N(0, σ²)."""
    return _apply(1, law.values, mean, sigma)[0]


def gaussian_damper_force(law: SuspensionLaw, sigma_velocity: npt.ArrayLike) -> np.ndarray:
    """Mean damper force :math:`E[F_d(v)]`, N, for a zero-mean Gaussian velocity of std σ_v (m/s).

    Each side is :math:`c_{lo} E[|v|; side] - (c_{lo} - c_{hi}) E[(|v| - v_k)^+; side]`, with
    :math:`E[v^+] = σ_v/\\sqrt{2π}` and the knee term the partial moment of order 1 at
    :math:`μ = -v_k`; negative when rebound damps more than compression."""
    return _apply(2, law.values, sigma_velocity)[0]


def static_travel(law: SuspensionLaw, extra_force: npt.ArrayLike) -> np.ndarray:
    """Compression (m) at which the spring carries `extra_force` (N) beyond its preload:
    the solution of :math:`F_s(s) - F_s(0) = ΔF` (Newton; F_s is increasing)."""
    return _apply(5, law.values, 0.0, extra_force)[0]


def equivalent_spring_rate(
    law: SuspensionLaw,
    static: npt.ArrayLike,
    sigma: npt.ArrayLike,
    sigma_velocity: npt.ArrayLike = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Mean travel m (m) and equivalent rate :math:`k_{eq}` (N/m) of a corner vibrating on a road.

    `static` :math:`s_0` (m): the travel at rest (:func:`static_travel` of the corner's extra
    load); `sigma` σ (m) and `sigma_velocity` σ_v (m/s): the travel's and its velocity's
    standard deviations. m solves :math:`E[F_s(m + x)] = F_s(s_0) - F_s(0) - E[F_d(v)]` (the
    average forces carry the static load; Newton, :math:`\partial_m E[F_s(m + x)] = k_{eq}(m)`),
    and :math:`k_{eq} = E[F_s'(m + x)]`. Arrays broadcast; compiled (the online monitor calls it
    at every update)."""
    return _apply(6, law.values, static, sigma, sigma_velocity)


def damper_even_slope(law: SuspensionLaw, sigma_velocity: npt.ArrayLike) -> np.ndarray:
    r"""Slope b (N s/m) of the damper's even part on :math:`|v| - E|v|`, v ~ N(0, σ_v²) (m/s).

    :math:`F_e(v) = (F_d(v) + F_d(-v))/2` depends on a = |v| only; b is its least-squares slope on
    a, :math:`\mathrm{Cov}(F_e, a)/\mathrm{Var}\,a`. With :func:`damper_force`'s knee at
    :math:`v_k`, :math:`F_e = \alpha a - \beta (a - v_k)^+`, α = (c_{c,lo} − c_{r,lo})/2 and
    β = ((c_{c,lo} − c_{c,hi}) − (c_{r,lo} − c_{r,hi}))/2; a is half-normal, and with κ = v_k/σ_v,
    φ the standard normal density and Q its upper tail (the partial moments of the normal law):
    :math:`\mathrm{Var}\,a = \sigma_v^2(1 - 2/\pi)`, :math:`E a = \sigma_v\sqrt{2/\pi}`,
    :math:`E(a - v_k)^+ = 2\sigma_v(\varphi(\kappa) - \kappa Q(\kappa))`,
    :math:`E[a (a - v_k)^+] = 2\sigma_v^2 Q(\kappa)`, so

    .. math:: b = \alpha - \beta\,\frac{2Q(\kappa) - 2\sqrt{2/\pi}\,(\varphi(\kappa)
       - \kappa Q(\kappa))}{1 - 2/\pi}.

    Below the knee (κ → ∞) it is α exactly (negative when rebound damps more); 0 for a symmetric
    damper. Closed form: exact, where the trapezoid rule it replaces had to resolve the kink."""
    sv = np.maximum(np.asarray(sigma_velocity, dtype=float), _SIGMA_FLOOR)
    alpha = 0.5 * (law.compression_low - law.rebound_low)
    beta = 0.5 * ((law.compression_low - law.compression_high) - (law.rebound_low - law.rebound_high))
    kappa = law.knee_velocity / sv
    tail = ndtr(-kappa)
    density = np.exp(-0.5 * kappa**2) / math.sqrt(2.0 * math.pi)
    cov = 2.0 * tail - 2.0 * math.sqrt(2.0 / math.pi) * (density - kappa * tail)  # Cov((a − v_k)⁺, a)/σ²
    return alpha - beta * cov / (1.0 - 2.0 / math.pi)


_HERMITE_X = np.linspace(-8.0, 8.0, 4001)
"""Nodes of the Hermite coefficients' trapezoid rule, in σ (the laws have kinks: at 0 and the knee for
the damper, at the stops for the spring, where Gauss–Hermite nodes converge slowly)."""
_HERMITE_W = np.exp(-0.5 * _HERMITE_X**2)
_HERMITE_W[[0, -1]] *= 0.5
_HERMITE_W /= _HERMITE_W.sum()


def _hermite(values: np.ndarray, n_max: int) -> tuple[np.ndarray, np.ndarray]:
    """Hermite coefficients (..., n_max + 1) and mean square (...) of a function's `values` (..., X) at
    the nodes :data:`_HERMITE_X` of a standard normal variable (trapezoid rule); :math:`h_n` by its
    three-term recurrence, stable for every order used here."""
    x = _HERMITE_X
    weighted = values * _HERMITE_W
    coef = np.empty(values.shape[:-1] + (n_max + 1,))
    h_prev, h = np.zeros_like(x), np.ones_like(x)
    for n in range(n_max + 1):
        coef[..., n] = weighted @ h
        h_prev, h = h, (x * h - math.sqrt(n) * h_prev) / math.sqrt(n + 1)
    return coef, (weighted * values).sum(axis=-1)


def damper_hermite(
    law: SuspensionLaw, sigma_velocity: npt.ArrayLike, n_max: int = 40
) -> tuple[np.ndarray, np.ndarray]:
    r"""Hermite coefficients of the damper's force at a Gaussian velocity v ~ N(0, σ_v²).

    Returns `coef` (..., n_max + 1), :math:`b_n = E[F_d(\sigma_v x)\,h_n(x)]` (N) with
    :math:`h_n = He_n/\sqrt{n!}` the orthonormal probabilists' Hermite polynomials, x ~ N(0, 1),
    and `power` (...), :math:`E[F_d^2]` (N²). :math:`b_0` is the mean force (the jacking),
    :math:`b_1/\sigma_v` the statistically linearized damping :math:`E[F_d'(v)]` (N s/m; Stein's
    lemma), and :math:`E[F_d^2] - \sum_n b_n^2` what orders above `n_max` hold (a knee's
    coefficients fall off slowly). Trapezoid rule over ±8σ on 4001 points."""
    sv = np.maximum(np.asarray(sigma_velocity, dtype=float), _SIGMA_FLOOR)
    return _hermite(damper_force(sv[..., None] * _HERMITE_X, law), n_max)


def spring_hermite(
    law: SuspensionLaw, mean: npt.ArrayLike, sigma: npt.ArrayLike, n_max: int = 40
) -> tuple[np.ndarray, np.ndarray]:
    r"""Hermite coefficients of the spring's force (stops included) at a Gaussian travel
    s = m + σx, x ~ N(0, 1): :math:`a_n = E[(F_s(m + \sigma x) - F_s(0))\,h_n(x)]` (N), (..., n_max + 1),
    and `power` :math:`E[(F_s - F_s(0))^2]` (N²), as :func:`damper_hermite`. :math:`a_0` is
    :func:`gaussian_spring_force`, :math:`a_1/\sigma` :func:`gaussian_spring_rate` (Stein's lemma);
    the orders from 2 on are what the linearization leaves (the progression's cubic term, the
    stops)."""
    m = np.asarray(mean, dtype=float)
    sd = np.maximum(np.asarray(sigma, dtype=float), _SIGMA_FLOOR)
    m, sd = np.broadcast_arrays(m, sd)
    return _hermite(spring_force(m[..., None] + sd[..., None] * _HERMITE_X, law), n_max)


def _cosines(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """cos(2π a_i b_j) (A, B), read-only: the cosine transforms' tables, made once per pair of axes
    (a monitor calls with the same frequencies and lags every window)."""
    a, b = np.ascontiguousarray(a, dtype=float), np.ascontiguousarray(b, dtype=float)
    return _cosine_table(a.tobytes(), b.tobytes())


@functools.lru_cache(maxsize=32)
def _cosine_table(a: bytes, b: bytes) -> np.ndarray:
    x, y = np.frombuffer(a), np.frombuffer(b)
    table = np.cos(2.0 * np.pi * x[:, None] * y[None, :])
    table.flags.writeable = False
    return table


def _lag_correlation(
    f_in, psd, df, f_out, max_lag_s: float
) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """Lags τ (0 to `max_lag_s`, 8 per period of the highest of `f_in`, `f_out`), their step, the
    variance (..., 1) and the correlation ρ(τ) (..., lags) of a process of one-sided PSD `psd` on
    `f_in` with bin widths `df` (the cosine transform)."""
    f_in = np.asarray(f_in, dtype=float)
    top = max(float(f_in.max()), float(np.max(f_out)))
    d_tau = 1.0 / (8.0 * top)
    tau = np.arange(0.0, max_lag_s + 0.5 * d_tau, d_tau)
    psd = np.asarray(psd, dtype=float) * np.asarray(df, dtype=float)
    cov = psd @ _cosines(f_in, tau)
    var = np.maximum(cov[..., :1], 1e-300)
    return tau, d_tau, var, np.clip(cov / var, -1.0, 1.0)


def _lag_window_psd(cov: np.ndarray, tau: np.ndarray, d_tau: float, max_lag_s: float, f_out) -> np.ndarray:
    """One-sided PSD at `f_out` (Hz) of an autocovariance `cov` (..., lags) on the lags `tau`,
    `d_tau` apart (:func:`_lag_correlation`): 4 ∫ C(τ) w(τ) cos(2πfτ) dτ (trapezoid at τ = 0), w
    Parzen's lag window over `max_lag_s` (its transform is ≥ 0)."""
    x = tau / max_lag_s
    parzen = np.where(x <= 0.5, 1.0 - 6.0 * x**2 + 6.0 * x**3, 2.0 * (1.0 - x) ** 3)
    weight = np.full(tau.size, d_tau) * parzen
    weight[0] *= 0.5
    f_out = np.asarray(f_out, dtype=float)
    return 4.0 * (cov * weight) @ _cosines(tau, f_out)


def damper_residual_psd(
    law: SuspensionLaw,
    f_in: npt.ArrayLike,
    psd: npt.ArrayLike,
    df: npt.ArrayLike,
    f_out: npt.ArrayLike,
    *,
    max_lag_s: float = 4.0,
    n_max: int = 40,
) -> np.ndarray:
    r"""One-sided PSD (N²/Hz) at `f_out` of what the damper's statistical linearization leaves,
    :math:`r = F_d(v) - E[F_d] - c_{eq} v`, for a zero-mean Gaussian velocity v.

    v's one-sided PSD `psd` ((..., F_in), (m/s)²/Hz) is given on `f_in` (Hz) with bin widths
    `df`. For jointly Gaussian v(t), v(t + τ) of correlation ρ(τ), Mehler's expansion gives
    :math:`E[F_d(v(t))F_d(v(t+\tau))] = \sum_n b_n^2 \rho^n` (:func:`damper_hermite`), so r has
    the autocovariance :math:`C(\tau) = \sum_{n \ge 2} b_n^2 \rho(\tau)^n` (the orders above
    `n_max` added as :math:`\rho^{n_{max}+1}` times their power) — the even part (an asymmetric
    damper's; n even) and the odd part a digressive knee leaves (n odd ≥ 3). r is uncorrelated
    with v at every lag (the Hermite orders are orthogonal), so a linear model with damping
    :math:`c_{eq}` and r as a separate force between body and wheel holds the damper to second
    order (Roberts & Spanos [1]_, ch. 5). C's cosine transform with Parzen's lag window as in
    :func:`rectified_psd` (same `max_lag_s` limits)."""
    tau, d_tau, var, rho = _lag_correlation(f_in, psd, df, f_out, max_lag_s)
    coef, power = damper_hermite(law, np.sqrt(var[..., 0]), n_max)
    return _lag_window_psd(_mehler_residual(coef, power, rho), tau, d_tau, max_lag_s, f_out)


def spring_residual_psd(
    law: SuspensionLaw,
    mean: npt.ArrayLike,
    f_in: npt.ArrayLike,
    psd: npt.ArrayLike,
    df: npt.ArrayLike,
    f_out: npt.ArrayLike,
    *,
    max_lag_s: float = 4.0,
    n_max: int = 40,
) -> np.ndarray:
    r"""One-sided PSD (N²/Hz) at `f_out` of what the spring's statistical linearization leaves,
    :math:`r = F_s(m + x) - E[F_s] - k_{eq} x`, for a Gaussian travel of mean `mean` m (m, (...))
    and zero-mean part x of one-sided PSD `psd` ((..., F_in), m²/Hz) on `f_in` (Hz), bin widths `df`.

    As :func:`damper_residual_psd` with the spring's Hermite coefficients (:func:`spring_hermite`):
    :math:`C(\tau) = \sum_{n \ge 2} a_n^2 \rho_x(\tau)^n`. Where the travel reaches a stop, its
    force comes in short pulses: power spread far above the travel's own frequencies (the stop's mean
    rate is in :math:`k_{eq}`, its pulses are not). Added to a linear model's response as a separate
    force, r needs its cross-spectrum with the road-driven part too: r is uncorrelated with the travel
    at every lag, so where an output follows the travel r's net contribution is negative. Its
    cross-spectrum with the damper's residual is left out."""
    tau, d_tau, var, rho = _lag_correlation(f_in, psd, df, f_out, max_lag_s)
    coef, power = spring_hermite(law, mean, np.sqrt(var[..., 0]), n_max)
    return _lag_window_psd(_mehler_residual(coef, power, rho), tau, d_tau, max_lag_s, f_out)


def _mehler_residual(coef: np.ndarray, power: np.ndarray, rho: np.ndarray) -> np.ndarray:
    r"""Autocovariance (..., lags) of :math:`f(X_t) - b_0 - b_1 X_t/\sigma` for a Gaussian process of
    correlation `rho` (..., lags) and f's Hermite coefficients `coef` (..., N + 1) and mean square
    `power`: Mehler's :math:`\sum_{n=2}^{N} b_n^2 \rho^n`, the orders above N as
    :math:`\rho^{N+1}` times their power."""
    cov = np.zeros_like(rho)
    rho_n = rho.copy()
    for n in range(2, coef.shape[-1]):
        rho_n = rho_n * rho
        cov += coef[..., n, None] ** 2 * rho_n
    rest = np.maximum(power - (coef**2).sum(axis=-1), 0.0)
    return cov + rest[..., None] * rho_n * rho


def rectified_psd(
    f_in: npt.ArrayLike,
    psd: npt.ArrayLike,
    df: npt.ArrayLike,
    f_out: npt.ArrayLike,
    *,
    max_lag_s: float = 4.0,
) -> np.ndarray:
    r"""One-sided PSD of :math:`|v| - E|v|` at `f_out` (Hz) for a zero-mean Gaussian v.

    v's one-sided PSD `psd` ((..., F_in), units²/Hz) is given on `f_in` (Hz) with bin widths `df`
    (Hz). For a bivariate normal pair of std σ and correlation ρ,
    :math:`E|XY| = \tfrac{2\sigma^2}{\pi}(\sqrt{1-\rho^2} + \rho\arcsin\rho)` (the full-wave
    rectifier; Papoulis & Pillai, *Probability, Random Variables and Stochastic Processes*, 4th
    ed., 2002, ch. 9), so |v| has the autocovariance
    :math:`C(\tau) = \tfrac{2\sigma^2}{\pi}(\sqrt{1-\rho^2} + \rho\arcsin\rho - 1)`,
    :math:`\rho(\tau) = R(\tau)/\sigma^2` from v's PSD by the cosine transform; C's cosine
    transform over lags up to `max_lag_s` gives the PSD, :math:`4\int_0^\infty C\cos(2\pi f\tau)\,d\tau`,
    with Parzen's lag window over that span (its transform is ≥ 0, so is the PSD; it smooths the
    PSD over about 1.9/`max_lag_s` Hz). `max_lag_s` must stay below 1/(2 max(df)): a PSD given
    on bins df apart repeats its autocovariance every 1/df s. Leading term (ρ²/2): the velocity
    spectrum convolved with itself."""
    tau, d_tau, var, rho = _lag_correlation(f_in, psd, df, f_out, max_lag_s)
    cov_abs = (2.0 * var / np.pi) * (np.sqrt(1.0 - rho**2) + rho * np.arcsin(rho) - 1.0)
    return _lag_window_psd(cov_abs, tau, d_tau, max_lag_s, f_out)
