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

Written by hand: no maintained library linearizes a piecewise polynomial spring this way.

References
----------
.. [1] J. B. Roberts, P. D. Spanos, *Random Vibration and Statistical Linearization*, Wiley
   1990 (Dover 2003), ch. 5.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.special import ndtr

from suvtwin.errors import InputError

__all__ = [
    "SuspensionLaw",
    "damper_force",
    "equivalent_spring_rate",
    "gaussian_damper_force",
    "gaussian_spring_force",
    "gaussian_spring_rate",
    "partial_moment",
    "spring_force",
    "spring_rate",
    "static_travel",
]

_SQRT_2PI = math.sqrt(2.0 * math.pi)


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


def spring_force(s: npt.ArrayLike, law: SuspensionLaw) -> np.ndarray:
    """Spring and stop force beyond the preload, :math:`F_s(s) - F_s(0)`, N, at compression `s` (m)."""
    s = np.asarray(s, dtype=float)
    k = law.spring_rate
    out = k * s + k * law.progression * np.maximum(s, 0.0) ** 3
    if math.isfinite(law.bump_clearance):
        eb = np.maximum(s - law.bump_clearance, 0.0)
        out = out + law.bump_linear * eb + law.bump_quadratic * eb**2
    if math.isfinite(law.rebound_clearance):
        er = np.maximum(-s - law.rebound_clearance, 0.0)
        out = out - law.rebound_linear * er - law.rebound_quadratic * er**2
    return out


def spring_rate(s: npt.ArrayLike, law: SuspensionLaw) -> np.ndarray:
    """Local rate :math:`F_s'(s)`, N/m, at compression `s` (m)."""
    s = np.asarray(s, dtype=float)
    out = law.spring_rate * (1.0 + 3.0 * law.progression * np.maximum(s, 0.0) ** 2)
    if math.isfinite(law.bump_clearance):
        eb = s - law.bump_clearance
        out = out + np.where(eb > 0.0, law.bump_linear + 2.0 * law.bump_quadratic * eb, 0.0)
    if math.isfinite(law.rebound_clearance):
        er = -s - law.rebound_clearance
        out = out + np.where(er > 0.0, law.rebound_linear + 2.0 * law.rebound_quadratic * er, 0.0)
    return out


def damper_force(v: npt.ArrayLike, law: SuspensionLaw) -> np.ndarray:
    """Damper force, N (> 0 resists compression), at compression velocity `v` (m/s)."""
    v = np.asarray(v, dtype=float)
    a = np.abs(v)
    knee = law.knee_velocity
    comp = law.compression_low * a - (law.compression_low - law.compression_high) * np.maximum(a - knee, 0.0)
    reb = law.rebound_low * a - (law.rebound_low - law.rebound_high) * np.maximum(a - knee, 0.0)
    return np.where(v >= 0.0, comp, -reb)


def partial_moment(n: int, mu: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    r""":math:`E[Y^n\,[Y > 0]]` for :math:`Y \sim N(\mu, \sigma^2)`, n = 0…3 (σ > 0).

    With :math:`z = \mu/\sigma`, Φ and φ the standard normal cdf and pdf: Φ;
    μΦ + σφ; (μ² + σ²)Φ + μσφ; (μ³ + 3μσ²)Φ + σφ(μ² + 2σ²)."""
    mu = np.asarray(mu, dtype=float)
    sigma = np.asarray(sigma, dtype=float)
    z = mu / sigma
    cdf = ndtr(z)
    pdf = np.exp(-0.5 * z * z) / _SQRT_2PI
    if n == 0:
        return cdf
    if n == 1:
        return mu * cdf + sigma * pdf
    if n == 2:
        return (mu * mu + sigma * sigma) * cdf + mu * sigma * pdf
    if n == 3:
        return (mu**3 + 3.0 * mu * sigma * sigma) * cdf + sigma * pdf * (mu * mu + 2.0 * sigma * sigma)
    raise ValueError(f"partial_moment: n must be 0–3, got {n}")


def _floor(sigma: npt.ArrayLike) -> np.ndarray:
    return np.maximum(np.asarray(sigma, dtype=float), 1e-9)  # σ → 0: the deterministic limit


def gaussian_spring_force(law: SuspensionLaw, mean: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    """:math:`E[F_s(m + x)] - F_s(0)`, N, for travel `mean` m and std `sigma` σ (m), x Gaussian."""
    m, sd = np.asarray(mean, dtype=float), _floor(sigma)
    k = law.spring_rate
    out = k * m + k * law.progression * partial_moment(3, m, sd)
    if math.isfinite(law.bump_clearance):
        e = m - law.bump_clearance
        out = out + law.bump_linear * partial_moment(1, e, sd) + law.bump_quadratic * partial_moment(2, e, sd)
    if math.isfinite(law.rebound_clearance):
        e = -m - law.rebound_clearance
        out = out - law.rebound_linear * partial_moment(1, e, sd)
        out = out - law.rebound_quadratic * partial_moment(2, e, sd)
    return out


def gaussian_spring_rate(law: SuspensionLaw, mean: npt.ArrayLike, sigma: npt.ArrayLike) -> np.ndarray:
    """Equivalent (statistically linearized) rate :math:`E[F_s'(m + x)]`, N/m, x ~ N(0, σ²)."""
    m, sd = np.asarray(mean, dtype=float), _floor(sigma)
    out = law.spring_rate * (1.0 + 3.0 * law.progression * partial_moment(2, m, sd))
    if math.isfinite(law.bump_clearance):
        e = m - law.bump_clearance
        out = out + law.bump_linear * partial_moment(0, e, sd)
        out = out + 2.0 * law.bump_quadratic * partial_moment(1, e, sd)
    if math.isfinite(law.rebound_clearance):
        e = -m - law.rebound_clearance
        out = out + law.rebound_linear * partial_moment(0, e, sd)
        out = out + 2.0 * law.rebound_quadratic * partial_moment(1, e, sd)
    return out


def gaussian_damper_force(law: SuspensionLaw, sigma_velocity: npt.ArrayLike) -> np.ndarray:
    """Mean damper force :math:`E[F_d(v)]`, N, for a zero-mean Gaussian velocity of std σ_v (m/s).

    Each side is :math:`c_{lo} E[|v|; side] - (c_{lo} - c_{hi}) E[(|v| - v_k)^+; side]`, with
    :math:`E[v^+] = σ_v/\\sqrt{2π}` and the knee term the partial moment of order 1 at
    :math:`μ = -v_k`; negative when rebound damps more than compression."""
    sv = _floor(sigma_velocity)
    half = sv / _SQRT_2PI
    beyond = partial_moment(1, -law.knee_velocity, sv) if math.isfinite(law.knee_velocity) else 0.0 * sv
    comp = law.compression_low * half - (law.compression_low - law.compression_high) * beyond
    reb = law.rebound_low * half - (law.rebound_low - law.rebound_high) * beyond
    return comp - reb


def static_travel(law: SuspensionLaw, extra_force: npt.ArrayLike) -> np.ndarray:
    """Compression (m) at which the spring carries `extra_force` (N) beyond its preload:
    the solution of :math:`F_s(s) - F_s(0) = ΔF` (Newton; F_s is increasing)."""
    target = np.asarray(extra_force, dtype=float)
    s = target / law.spring_rate
    for _ in range(60):
        step = (spring_force(s, law) - target) / spring_rate(s, law)
        s = s - step
        if np.all(np.abs(step) < 1e-12):
            break
    return s


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
    and :math:`k_{eq} = E[F_s'(m + x)]`. Arrays broadcast."""
    s0 = np.asarray(static, dtype=float)
    sd = _floor(sigma)
    target = spring_force(s0, law) - gaussian_damper_force(law, sigma_velocity)
    m = np.broadcast_to(s0, np.broadcast(s0, sd, target).shape).astype(float)
    for _ in range(60):
        rate = gaussian_spring_rate(law, m, sd)
        step = (gaussian_spring_force(law, m, sd) - target) / rate
        step = np.clip(step, -0.05, 0.05)
        m = m - step
        if np.all(np.abs(step) < 1e-10):
            break
    return m, gaussian_spring_rate(law, m, sd)
