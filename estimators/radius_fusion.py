r"""The monitor's pressures fused with the wheels' rolling radii against the tyre model.

Usual call::

    model = RadiusModel(pressure_kpa=grid, log_radius=log_re)          # per tyre, at its load
    fused = fuse_with_radii(p_kpa, sigma_kpa, rho, excess, excess_sigma, model, spread_permille=1.0)

Two sources of information about the four tyres' pressures p (kPa):

- the vibration monitor (:mod:`.monitor`): each tyre's estimate :math:`\hat p` with σ, the errors
  correlated by ρ (C, C) (the tyres of one track read the same road);
- the radius analysis (:mod:`.rolling_radius`): each wheel's log effective rolling radius over the
  other wheels' mean, :math:`e = A\,\delta`, with :math:`(A d)_i = d_i - \frac{1}{C-1}\sum_{j\ne i} d_j`.

The tyre model gives each tyre's log radius :math:`f_i(p_i)` at its load (MF-Tyre 6.1's effective
rolling radius: a softer tyre deflects more and rolls on a smaller radius; `model`, tabulated on a
pressure grid by the caller, so no tyre file is read here). A real tyre's radius departs from the
model's by its own offset :math:`b_i` (manufacturing, wear), taken independent with σ
``spread_permille`` ‰; the wheels' measurement noise :math:`\varepsilon` has the analysis's σ. So

.. math:: e = A\,(f(p) + b) + A\,\varepsilon, \qquad
          R = A\,\mathrm{diag}(\sigma_\delta^2 + \sigma_b^2)\,A^T,

rank C − 1 (a change all tyres share leaves every excess unchanged), used on its first C − 1 rows
(any C − 1 hold all its information). The fused estimate is the maximum a posteriori
:math:`\arg\min_p\,(p-\hat p)^T\Sigma^{-1}(p-\hat p) + (e - A f(p))^T R^{-1} (e - A f(p))`
found by Gauss–Newton (a few steps: f is smooth and nearly linear over the tyre's range), with the
covariance :math:`(\Sigma^{-1} + H^T R^{-1} H)^{-1}`, H = A diag(f'(p)) at the solution: the
Gaussian posterior (A. C. Aitken 1935; the iterated extended Kalman update, e.g. Y. Bar-Shalom,
X. R. Li, T. Kirubarajan, *Estimation with Applications to Tracking and Navigation*, Wiley 2001,
§10.3.2). σ_δ is each wheel's own σ that gives its excess the analysis's σ:
:math:`\mathrm{var}(e_i) = \sigma_\delta^2 (1 + 1/(C-1))`.

What the radii add is the contrast between the tyres, to within the spread: a tyre against the
others' mean to :math:`\approx \sigma_b \sqrt{C/(C-1)}/f'` (1 ‰ on the SUV's tyre, ~0.085 ‰/kPa at
230 kPa: ~13 kPa), and sharper as a change (the offsets stay, see :mod:`.deflation`'s calibration
after a reset). The four tyres' common level stays the vibration's.

After a change of pressure the radius analysis follows within two blocks, the vibration monitor
over tens of seconds: :func:`vibration_lag_kpa` turns the changes the radii confirmed (and a block
they hold aside as a possible one) into how far the vibration estimate may lag, added to its
variance (`lag_kpa`), so the fused estimate follows the radii there with an honest σ.

Measured on the MuJoCo SUV (``bench/monitor_mujoco.py``, 2026-12-03, no reference, spread 1 ‰):
``constant`` (100 runs) estimate − truth +3.3 ± 13.7 kPa at 10 s and −0.4 ± 8.1 at 30 s against
the vibration's +5.5 ± 20.0 and +1.0 ± 12.1, ±2σ 98.8 %; ``drop`` (230 → 180 kPa in 1.5 s, 20
runs) ±2σ during and after 86 % (vibration 68 %), within 12.5 kPa 15 s after in 80 % (15 %);
``slow_leak`` 90 % (65 %), ±2σ 98.5 % (88 % before the radius analysis followed a ramp). Each row
uses the rows up to it only (causal). No MuJoCo here: it is written by hand because it is a few
lines of linear algebra on 4×4 matrices, batched over rows with numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.interpolate

from suvtwin.errors import InputError
from suvtwin.estimators.rolling_radius import excess_of

__all__ = ["FusedPressure", "RadiusModel", "excess_cov", "excess_operator", "fuse_with_radii", "gls_step",
           "vibration_lag_kpa", "wheel_sd"]  # fmt: skip


def excess_operator(n_c: int, alive: npt.ArrayLike | None = None) -> np.ndarray:
    """A with (A d)_i = d_i − mean of the others' d (C, C): :func:`.rolling_radius.excess_of` as a
    matrix (symmetric, so its rows are the excesses of the unit vectors). `alive` (C,) bool: the
    excesses over those wheels only (a wheel-speed sensor dead, :attr:`.RollingRadius.alive`): rows
    and columns of the others 0."""
    if alive is None:
        return excess_of(np.eye(n_c))
    alive = np.asarray(alive, dtype=bool)
    out = np.zeros((n_c, n_c))
    out[np.ix_(alive, alive)] = excess_of(np.eye(int(alive.sum())))
    return out


def excess_cov(wheel_sd: np.ndarray, alive: npt.ArrayLike | None = None) -> np.ndarray:
    """Covariance of the excesses A d of wheel values d independent with σ `wheel_sd` (…, C):
    A diag(σ²) Aᵀ (A over the wheels `alive`, :func:`excess_operator`; σ of the others not used)."""
    wheel_sd = np.asarray(wheel_sd, dtype=float)
    if alive is not None:  # the other wheels' σ (NaN where not read) is not used
        wheel_sd = np.where(np.asarray(alive, dtype=bool), wheel_sd, 0.0)
    a = excess_operator(wheel_sd.shape[-1], alive)
    return (a * (wheel_sd**2)[..., None, :]) @ a.T


def wheel_sd(excess_sd: np.ndarray, n_wheels: int | None = None) -> np.ndarray:
    """The wheels' own σ that gives each excess the σ `excess_sd` (…, C): var(e_i) = σ²(1 + 1/(m − 1)),
    m the wheels the excesses are taken over (`n_wheels`, default C)."""
    excess_sd = np.asarray(excess_sd, dtype=float)
    m = excess_sd.shape[-1] if n_wheels is None else n_wheels
    return excess_sd * math.sqrt((m - 1) / m)


def gls_step(x, prior_mean, prior_info, h, resid, r):
    r"""One Gauss–Newton step of the Gaussian fusion, batched over leading axes.

    At the linearization point `x` (…, C), with the prior mean (…, C) and information
    :math:`\Sigma^{-1}` `prior_info` (…, C, C), the measurement's Jacobian `h` (…, M, C), residual
    `resid` = y − g(x) (…, M) and covariance `r` (…, M, M):
    :math:`\Lambda = \Sigma^{-1} + H^T R^{-1} H`,
    :math:`x' = x + \Lambda^{-1}(\Sigma^{-1}(\mu - x) + H^T R^{-1} r_y)`. With g linear one step is
    the exact posterior. Returns x' and :math:`\Lambda^{-1}` (symmetrized)."""
    r_inv_h = np.linalg.solve(r, h)
    info = prior_info + np.swapaxes(h, -1, -2) @ r_inv_h
    pull = (prior_info @ (prior_mean - x)[..., None])[..., 0]
    rhs = pull + (np.swapaxes(r_inv_h, -1, -2) @ resid[..., None])[..., 0]
    cov = np.linalg.inv(info)
    cov = 0.5 * (cov + np.swapaxes(cov, -1, -2))
    return x + (cov @ rhs[..., None])[..., 0], cov


@dataclass(frozen=True)
class RadiusModel:
    """Each tyre's log effective rolling radius against its pressure, tabulated.

    `pressure_kpa` (G,): increasing grid, kPa; `log_radius` (C, G): ln R_e (R_e in m) of each tyre at
    its load. Between the nodes a cubic spline (value and slope consistent, so the Gauss–Newton
    solution is the posterior's maximum; the model is smooth, and a grid of a few kPa is exact to
    well below the radius analysis's noise). Outside the grid the ends hold."""

    pressure_kpa: np.ndarray
    log_radius: np.ndarray

    def __post_init__(self) -> None:
        p = np.asarray(self.pressure_kpa, dtype=float)
        lr = np.asarray(self.log_radius, dtype=float)
        if p.ndim != 1 or p.size < 3 or not np.all(np.diff(p) > 0) or not np.all(np.isfinite(p)):
            raise InputError("radius model pressure_kpa must be an increasing grid of ≥ 3 finite values")
        if lr.ndim != 2 or lr.shape[1] != p.size or lr.shape[0] < 2 or not np.all(np.isfinite(lr)):
            raise InputError(
                f"radius model log_radius must be (tyres ≥ 2, {p.size}) finite values, got {lr.shape}"
            )

    @property
    def n_tyres(self) -> int:
        return int(np.shape(self.log_radius)[0])

    def evaluate(self, p_kpa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """ln R_e and its slope per kPa at pressures `p_kpa` (…, C), clipped to the grid."""
        grid = np.asarray(self.pressure_kpa, dtype=float)
        p = np.clip(np.asarray(p_kpa, dtype=float), grid[0], grid[-1])
        value, gain = np.empty_like(p), np.empty_like(p)
        for c, spline in enumerate(self._splines()):
            value[..., c] = spline(p[..., c])
            gain[..., c] = spline(p[..., c], 1)
        return value, gain

    def _splines(self) -> list:
        cached = self.__dict__.get("_cache")
        if cached is None:
            grid = np.asarray(self.pressure_kpa, dtype=float)
            cached = [scipy.interpolate.CubicSpline(grid, row) for row in np.asarray(self.log_radius, float)]
            object.__setattr__(self, "_cache", cached)
        return cached


@dataclass(frozen=True)
class FusedPressure:
    """Per row (K) and tyre (C): the fused pressure and its σ, kPa, and the covariance (K, C, C), kPa²
    (NaN where a row lacks an input)."""

    pressure_kpa: np.ndarray
    sigma_kpa: np.ndarray
    cov_kpa2: np.ndarray


def fuse_with_radii(
    p_kpa: npt.ArrayLike,
    sigma_kpa: npt.ArrayLike,
    rho: npt.ArrayLike,
    excess: npt.ArrayLike,
    excess_sigma: npt.ArrayLike,
    model: RadiusModel,
    *,
    spread_permille: float = 1.0,
    iterations: int = 4,
    lag_kpa: npt.ArrayLike | None = None,
) -> FusedPressure:
    r"""The vibration estimates `p_kpa` ± `sigma_kpa` (K, C), kPa, errors correlated by `rho` (C, C; or
    (K, C, C), one per row), fused
    with the radius analysis's `excess` ± `excess_sigma` (K, C; dimensionless, 1e-3 = 1 ‰) through the
    tyre `model` with the tyres' radius spread `spread_permille` (σ, ‰) — see the module docstring.
    `iterations`: Gauss–Newton steps from the vibration estimate. `lag_kpa` (K, C): how far the
    vibration estimate may lag a change the radii saw (:func:`vibration_lag_kpa`), added to its
    variance. A row with a NaN pressure or σ gives NaN; where a wheel's excess is NaN (its speed
    sensor dead: the analysis's excesses are over the other wheels, :attr:`.RollingRadius.alive`) the
    row is fused with the excesses over the wheels that have one (two at least; the other tyres keep
    their vibration estimates, moved only through `rho`)."""
    p = np.atleast_2d(np.asarray(p_kpa, dtype=float))
    sd = np.atleast_2d(np.asarray(sigma_kpa, dtype=float))
    e = np.atleast_2d(np.asarray(excess, dtype=float))
    se = np.atleast_2d(np.asarray(excess_sigma, dtype=float))
    rho = np.asarray(rho, dtype=float)
    n_k, n_c = p.shape
    if lag_kpa is not None:
        lag = np.atleast_2d(np.asarray(lag_kpa, dtype=float))
        if lag.shape != p.shape:
            raise InputError(f"fuse_with_radii: lag_kpa must be {p.shape}, got {lag.shape}")
        sd = np.sqrt(sd**2 + np.nan_to_num(lag) ** 2)
    if sd.shape != p.shape or e.shape != p.shape or se.shape != p.shape:
        raise InputError(f"fuse_with_radii: p, sigma, excess and excess_sigma must all be {p.shape}")
    if rho.shape not in ((n_c, n_c), (n_k, n_c, n_c)) or model.n_tyres != n_c:
        raise InputError(f"fuse_with_radii: rho must be ({n_c}, {n_c}) or ({n_k}, {n_c}, {n_c}) and the "
                         f"model for {n_c} tyres")  # fmt: skip
    rho = np.broadcast_to(rho, (n_k, n_c, n_c))
    if not (np.isfinite(spread_permille) and spread_permille >= 0.0):
        raise InputError(f"radius spread must be ≥ 0 ‰, got {spread_permille!r}")
    if not (isinstance(iterations, int) and iterations >= 1):
        raise InputError(f"iterations must be a positive whole number, got {iterations!r}")
    out_p = np.full((n_k, n_c), np.nan)
    out_cov = np.full((n_k, n_c, n_c), np.nan)
    # the wheels each row's excesses are taken over: those with one (all, or all but a dead sensor's)
    read = np.isfinite(e) & np.isfinite(se) & (se >= 0)
    ok = np.all(np.isfinite(p) & np.isfinite(sd) & (sd > 0), axis=1) & (read.sum(axis=1) >= 2)
    grid = np.asarray(model.pressure_kpa, dtype=float)
    for alive in np.unique(read[ok], axis=0):  # one batch per set of wheels read
        rows = ok & np.all(read == alive, axis=1)
        first = np.flatnonzero(alive)[:-1]  # any m − 1 of the m excesses hold all their information
        p_o, sd_o, e_o, se_o = p[rows], sd[rows], e[rows][:, first], se[rows]
        prior_info = np.linalg.inv(rho[rows] * (sd_o[:, :, None] * sd_o[:, None, :]))
        a = excess_operator(n_c, alive)[first]
        own = np.sqrt(wheel_sd(se_o, int(alive.sum())) ** 2 + (1e-3 * spread_permille) ** 2)
        r = excess_cov(own, alive)[:, first][:, :, first]
        x = np.clip(p_o, grid[0], grid[-1])
        for _ in range(iterations):
            f, g = model.evaluate(x)
            h = a[None, :, :] * g[:, None, :]
            resid = e_o - f @ a.T
            x, cov = gls_step(x, p_o, prior_info, h, resid, r)
            x = np.clip(x, grid[0], grid[-1])
        out_p[rows], out_cov[rows] = x, cov
    sigma = np.sqrt(np.diagonal(out_cov, axis1=1, axis2=2))
    return FusedPressure(pressure_kpa=out_p, sigma_kpa=sigma, cov_kpa2=out_cov)


def vibration_lag_kpa(
    t_blocks: npt.ArrayLike,
    excess: npt.ArrayLike,
    changes: npt.ArrayLike,
    gain_per_kpa: npt.ArrayLike,
    t_rows: npt.ArrayLike,
    *,
    tau_s: float = 30.0,
    held: npt.ArrayLike | None = None,
    trend: npt.ArrayLike | None = None,
) -> np.ndarray:
    r"""How far the vibration monitor's estimate may lag a change the radii saw, per row and tyre, kPa.

    The radius analysis restarts a wheel's memory at a change of pressure within two blocks
    (:class:`~suvtwin.estimators.rolling_radius.RollingRadius`, `changes`); the vibration monitor
    follows it over tens of seconds (on the MuJoCo ``drop`` runs, 230→180 kPa in 1.5 s, its estimate
    still held a median 45 % of the step 12 s after the change and 17 % after 28 s). At each block
    where any wheel changed, the step of the excess :math:`\Delta e` gives the wheels' steps: on the
    zero-sum excesses A is C/(C − 1) times the identity, so :math:`\tilde d = \frac{C-1}{C}\Delta e` is the
    step minus its mean, and taking most tyres as unchanged, :math:`d = \tilde d - \mathrm{median}(\tilde d)`
    (one tyre's change of either sign exactly; a change of all four is invisible to the radii);
    :math:`\Delta p = d / g` (kPa). Each change's share decays as :math:`e^{-(t - t_c)/\tau}`, and
    the changes add: :math:`L_i(t) = \sum_c |\Delta p_{i,c}|\, e^{-(t - t_c)/\tau}`. The fusion adds
    :math:`L^2` to the vibration estimate's variance (:func:`fuse_with_radii`, `lag_kpa`).

    `t_blocks` (B,), `excess` (B, C), `changes` (B, C): the radius analysis's rows (s, –, bool);
    `gain_per_kpa` (C,): each tyre's d ln R_e / dp; `t_rows` (K,): the times wanted, s. `tau_s`: the
    decay time (30 s: above the measured lag at every time after the change). `held` (B, C): a block
    the analysis holds aside as a possible change, minus the wheel's mean (0: none): while it is held
    the change it would be, :math:`|h_i|/g_i`, is added (the held wheel's excess moves by its own
    step where the others stay; a change not yet confirmed: the vibration cannot have followed it).
    `trend` (B, C): the excess's slope where the analysis follows a ramp (1/s; 0: none): the wheels'
    rates from it as the steps above, and a first-order lag of time constant τ trails a ramp of rate
    r by r τ, added while the ramp lasts and decaying as :math:`e^{-(t - t_e)/\tau}` after its last
    block :math:`t_e` (a first-order lag's error once its input stops moving). Uses the blocks up to
    each row only (causal)."""
    t_b = np.asarray(t_blocks, dtype=float)
    e = np.asarray(excess, dtype=float)
    ch = np.asarray(changes, dtype=bool)
    g = np.asarray(gain_per_kpa, dtype=float)
    t_r = np.asarray(t_rows, dtype=float)
    if not (np.isfinite(tau_s) and tau_s > 0.0):
        raise InputError(f"lag decay time must be > 0 s, got {tau_s!r}")
    n_c = g.size
    if t_b.size == 0:  # no block yet: nothing seen, no lag
        return np.zeros((t_r.size, n_c))
    # the changes: each block where a wheel changed and its step is known, decaying from its time on
    rows = np.flatnonzero(ch.any(axis=1))
    rows = rows[rows > 0]
    steps = e[rows] - e[rows - 1]  # (N, C)
    # a step over the same wheels both sides (all, or all but a dead sensor's) and at least two of them
    same = np.all(np.isfinite(e[rows]) == np.isfinite(e[rows - 1]), axis=1)
    same &= np.isfinite(steps).sum(axis=1) >= 2
    rows, steps = rows[same], steps[same]
    age = t_r[:, None] - t_b[None, rows]  # (K, N)
    decay = np.where(age >= 0.0, np.exp(-np.maximum(age, 0.0) / tau_s), 0.0)
    out = decay @ _wheel_steps_kpa(steps, g) if rows.size else np.zeros((t_r.size, n_c))
    at = np.searchsorted(t_b, t_r, side="right") - 1
    if held is not None:
        h = np.asarray(held, dtype=float)
        now = np.where(at[:, None] >= 0, np.nan_to_num(h[np.maximum(at, 0)]), 0.0)
        out += np.abs(now) / g[None, :]
    if trend is not None:
        # a first-order lag trails a ramp of rate r by r τ; once the ramp ends, that lag decays as e^(−t/τ)
        raw = np.nan_to_num(np.asarray(trend, dtype=float))
        # the wheels' rates from it: NaN for a wheel without an excess (a dead sensor's), left out
        rate = np.where(np.isfinite(e), raw, np.nan)
        # the lag the last ramp up to each block leaves, and when it was set (its last block)
        moving = np.any(raw != 0.0, axis=1)
        last = np.maximum.accumulate(np.where(moving, np.arange(t_b.size), -1))
        ramp = np.where((last >= 0)[:, None], tau_s * _wheel_steps_kpa(rate[np.maximum(last, 0)], g), 0.0)
        since = np.where(last >= 0, t_b[np.maximum(last, 0)], -np.inf)
        now = np.maximum(at, 0)
        decay = np.where(at >= 0, np.exp(-np.maximum(t_r - since[now], 0.0) / tau_s), 0.0)
        active = (at >= 0) & moving[now]
        out += ramp[now] * np.where(active, 1.0, decay)[:, None]
    return out


def _wheel_steps_kpa(excess_step: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """|Δp| per tyre (…, C), kPa, from a step of the excesses (…, C), most tyres taken as unchanged:
    d̃ = (m − 1)/m Δe, d = d̃ − median(d̃), |d|/g (:func:`vibration_lag_kpa`), over the m wheels with
    a finite step (the excesses' wheels; 0 for the others)."""
    read = np.isfinite(excess_step)  # the wheels the excesses are over (a dead sensor's NaN): m of them
    m = read.sum(axis=-1, keepdims=True)
    d = np.where(read, (m - 1) / np.maximum(m, 1) * excess_step, np.nan)
    with np.errstate(all="ignore"):  # a row with no step at all: NaN, then 0
        out = np.abs(d - np.nanmedian(np.where(m > 0, d, 0.0), axis=-1, keepdims=True)) / gain
    return np.where(read, out, 0.0)
