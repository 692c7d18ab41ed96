r"""Compiled per-step loop of the IMM of UKFs of paper 000 (the ``backend="numba"`` path).

Usual call (what :func:`suvtwin.estimators.tire_pressure.estimate_pressure` does)::

    kt_hat, kt_sig, mode_prob, mode_kt, repairs = run_imm_ukf(
        acc_s, acc_u, dt, road, phi, Q, R, x0, P0, mu0, transition,
        ks, ksnl, cs, csnl, sprung_mass, unsprung_mass, w, mu_floor=1e-4,
        augmented=False, semi_implicit=True, signed_damper=True)

What it computes: for each run (B) and each time step (T), exactly the algorithm of the
numpy reference path of :func:`~estimators.tire_pressure.estimate_pressure`, built from
:mod:`suvtwin.estimators.imm` (mixing, mode probabilities) and :mod:`suvtwin.estimators.ukf` (scaled
unscented transform), in the same order of operations — Brancati & Tufano 2022:

- eq. 9–11: IMM mixing, standard form (with the spread-of-means term);
- eq. 15 / semi-implicit Euler: quarter-car process model (eq. 1,
  :func:`suvtwin.quarter_car_law.accelerations`) on each sigma point,
  road at mid-step (synthetic or true road), or the augmented 6th road state with AR(1)
  dynamics :math:`z_{r,k+1} = \phi z_{r,k}`;
- eq. 16: measurement = sprung and unsprung accelerations (m/s²);
- eq. 12: mode probabilities from the Gaussian log-likelihood
  :math:`-\tfrac12(y^T S^{-1} y + \log\det S + m \log 2\pi)`, normalized in log space and
  floored at ``mu_floor``;
- eq. 13–14: the combined :math:`k_t` (N/m) and its standard deviation, including the
  spread of the modes' means;
- eq. 18–19: Q and R (given by the caller, (m, m/s, N/m)² and (m/s²)²).

The UKF follows filterpy 2.0's order: sigma points from the (mixed) posterior, process
model, unscented transform + Q, sigma points redrawn from the prior, measurement model,
update. Sigma-point square roots use a robust Cholesky factorization identical in logic
to :func:`suvtwin.estimators.ukf.robust_cholesky`: try Cholesky; on failure symmetrize, retry with
diagonal jitter 0, 1e-12, 1e-9, 1e-6 × the mean |diagonal|, then clip the eigenvalues
at 1e-9 × that mean; a run's repair count grows by one for each step in which any of its
modes needed a repair.

Why hand-written: the numpy path advances a whole batch per call but pays ~20 numpy
calls per time step, so one run is bound by Python overhead. We know of no maintained
library with a batched, compiled IMM of UKFs: filterpy is pure Python with one object
per filter (its speed against both paths: ``python bench/estimator_speed.py``),
pykalman's unscented filters are single-model numpy code, and JAX-based filter libraries
would add a JIT framework this project does not use. Here the loops over runs,
modes, sigma points and matrix entries are compiled with numba (``cache=True``: the
first call in a fresh environment compiles for a few seconds, later processes load the
cached machine code); all matrices are 5×5 or 6×6, so explicit loops beat BLAS calls.
"""

from __future__ import annotations

import numpy as np

from suvtwin.estimators.ukf import SigmaWeights
from suvtwin.jit import cached_njit
from suvtwin.quarter_car_law import accelerations

__all__ = ["robust_cholesky_batch", "run_imm_ukf"]

_TINY = np.finfo(float).tiny
_LOG_2PI = np.log(2.0 * np.pi)


@cached_njit
def _cholesky(a, L):
    """Lower Cholesky factor of `a` (reading its lower triangle, as LAPACK's ``potrf('L')``)
    into `L`; False, as LAPACK's failure, when a pivot is not positive (or NaN)."""
    n = a.shape[0]
    for j in range(n):
        s = a[j, j]
        for k in range(j):
            s -= L[j, k] * L[j, k]
        if not s > 0.0:
            return False
        d = np.sqrt(s)
        L[j, j] = d
        for i in range(j + 1, n):
            t = a[i, j]
            for k in range(j):
                t -= L[i, k] * L[j, k]
            L[i, j] = t / d
        for i in range(j):
            L[i, j] = 0.0
    return True


@cached_njit
def _robust_cholesky(a, L, work):
    """Lower Cholesky factor of `a` into `L`, repairing `a` if it is not positive definite
    (same ladder as :func:`suvtwin.estimators.ukf.robust_cholesky`). Returns whether it repaired."""
    if _cholesky(a, L):
        return False
    n = a.shape[0]
    sym = np.empty((n, n))
    scale = 0.0
    for i in range(n):
        for j in range(n):
            sym[i, j] = 0.5 * (a[i, j] + a[j, i])
        scale += abs(sym[i, i])
    scale = max(scale / n, _TINY)
    for jitter in (0.0, 1e-12, 1e-9, 1e-6):
        add = jitter * scale
        for i in range(n):
            for j in range(n):
                work[i, j] = sym[i, j]
            work[i, i] = sym[i, i] + add
        if _cholesky(work, L):
            return True
    values, vectors = np.linalg.eigh(sym)
    floor = 1e-9 * scale
    for i in range(n):
        values[i] = max(values[i], floor)
    for i in range(n):
        for j in range(n):
            t = 0.0
            for k in range(n):
                t += vectors[i, k] * values[k] * vectors[j, k]
            work[i, j] = t
    if not _cholesky(work, L):
        raise ValueError("robust Cholesky: matrix not positive definite after eigenvalue clipping")
    return True


@cached_njit
def _robust_cholesky_batch(a, out, repaired):
    for b in range(a.shape[0]):
        work = np.empty(a.shape[1:])
        repaired[b] = _robust_cholesky(np.ascontiguousarray(a[b]), out[b], work)


def robust_cholesky_batch(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The compiled robust Cholesky on a batch (..., n, n): ``(L, repaired)`` as
    :func:`suvtwin.estimators.ukf.robust_cholesky` returns them (for tests)."""
    a = np.asarray(a, dtype=float)
    flat = np.ascontiguousarray(a.reshape(-1, a.shape[-2], a.shape[-1]))
    out = np.zeros_like(flat)
    repaired = np.zeros(flat.shape[0], dtype=np.bool_)
    _robust_cholesky_batch(flat, out, repaired)
    return out.reshape(a.shape), repaired.reshape(a.shape[:-2])


@cached_njit
def _sigma_points(x, P, c, sig, A, L, work):
    """Scaled sigma points x, x ± columns of chol(c·P) into `sig` (2n+1, n); returns repaired."""
    n = x.shape[0]
    for i in range(n):
        for j in range(n):
            A[i, j] = c * P[i, j]
    repaired = _robust_cholesky(A, L, work)
    for j in range(n):
        sig[0, j] = x[j]
    for i in range(n):
        for j in range(n):
            sig[1 + i, j] = x[j] + L[j, i]
            sig[1 + n + i, j] = x[j] - L[j, i]
    return repaired


@cached_njit
def _run(
    acc_s, acc_u, dt, road, phi, Q, R, x0, P0, mu0, transition, ks, ksnl, cs, csnl, ms, mus,
    wm, wc, lam, mu_floor, augmented, semi_implicit, signed, kt_hat, kt_sig, mode_prob, mode_kt, repairs,
):  # fmt: skip
    n_runs, n_steps = acc_s.shape
    n_modes = x0.shape[1]
    n = x0.shape[2]
    n_sig = 2 * n + 1
    c = n + lam
    multi = n_modes > 1
    per_mode_road = road.shape[1] > 1
    log2pi2 = 2 * _LOG_2PI
    # work buffers, reused by every run and step
    x = np.empty((n_modes, n))
    P = np.empty((n_modes, n, n))
    mu = np.empty(n_modes)
    x_in = np.empty((n_modes, n))
    P_in = np.empty((n_modes, n, n))
    cbar = np.empty(n_modes)
    omega = np.empty((n_modes, n_modes))
    ll = np.empty(n_modes)
    sig = np.empty((n_sig, n))
    sig_f = np.empty((n_sig, n))
    sig_h = np.empty((n_sig, 2))
    A = np.empty((n, n))
    L = np.empty((n, n))
    work = np.empty((n, n))
    xp = np.empty(n)
    Pp = np.empty((n, n))
    pxz = np.empty((n, 2))
    K = np.empty((n, 2))
    KS = np.empty((n, 2))
    for b in range(n_runs):
        x[:, :] = x0[b]
        P[:, :, :] = P0[b]
        mu[:] = mu0[b]
        for k in range(n_steps):
            if k > 0:
                # --- IMM mixing (eq. 9-11, standard form), as estimators.imm.imm_mix
                if multi:
                    for j in range(n_modes):
                        t = 0.0
                        for i in range(n_modes):
                            t += mu[i] * transition[i, j]
                        cbar[j] = t
                    for i in range(n_modes):
                        for j in range(n_modes):
                            omega[i, j] = transition[i, j] * mu[i] / cbar[j]
                    for j in range(n_modes):
                        for a in range(n):
                            t = 0.0
                            for i in range(n_modes):
                                t += omega[i, j] * x[i, a]
                            x_in[j, a] = t
                        for a in range(n):
                            for e in range(n):
                                t = 0.0
                                for i in range(n_modes):
                                    t += omega[i, j] * P[i, a, e]
                                P_in[j, a, e] = t
                        for a in range(n):
                            for e in range(n):
                                t = 0.0
                                for i in range(n_modes):
                                    t += omega[i, j] * (x[i, a] - x_in[j, a]) * (x[i, e] - x_in[j, e])
                                P_in[j, a, e] += t
                else:
                    x_in[:, :] = x
                    P_in[:, :, :] = P
                    cbar[:] = mu
                any_repair = False
                for s in range(n_modes):
                    sr = s if per_mode_road else 0
                    # --- predict (eq. 15): sigma points of the mixed posterior through the QC
                    if _sigma_points(x_in[s], P_in[s], c, sig, A, L, work):
                        any_repair = True
                    zr_mid = 0.0
                    if not augmented:
                        zr_mid = 0.5 * (road[b, sr, k - 1] + road[b, sr, k])
                    for j in range(n_sig):
                        zr = sig[j, 5] if augmented else zr_mid
                        a_s, a_u = accelerations(
                            sig[j, 0], sig[j, 1], sig[j, 2], sig[j, 3], sig[j, 4], zr,
                            ks[s], ksnl[s], cs[s], csnl[s], ms, mus, signed,
                        )  # fmt: skip
                        for e in range(n):
                            sig_f[j, e] = sig[j, e]
                        if semi_implicit:
                            sig_f[j, 2] += a_s * dt
                            sig_f[j, 3] += a_u * dt
                            sig_f[j, 0] += sig_f[j, 2] * dt
                            sig_f[j, 1] += sig_f[j, 3] * dt
                        else:
                            sig_f[j, 0] += sig[j, 2] * dt
                            sig_f[j, 1] += sig[j, 3] * dt
                            sig_f[j, 2] += a_s * dt
                            sig_f[j, 3] += a_u * dt
                        if augmented:
                            sig_f[j, 5] = phi[b] * sig[j, 5]
                    # unscented transform + Q
                    for e in range(n):
                        t = 0.0
                        for j in range(n_sig):
                            t += wm[j] * sig_f[j, e]
                        xp[e] = t
                    for a in range(n):
                        for e in range(n):
                            t = 0.0
                            for j in range(n_sig):
                                t += (sig_f[j, a] - xp[a]) * wc[j] * (sig_f[j, e] - xp[e])
                            Pp[a, e] = t + Q[b, s, a, e]
                    # sigma points redrawn from the prior (filterpy's order)
                    if _sigma_points(xp, Pp, c, sig, A, L, work):
                        any_repair = True
                    # --- update (eq. 16): accelerations of the prior sigma points
                    for j in range(n_sig):
                        zr = sig[j, 5] if augmented else road[b, sr, k]
                        a_s, a_u = accelerations(
                            sig[j, 0], sig[j, 1], sig[j, 2], sig[j, 3], sig[j, 4], zr,
                            ks[s], ksnl[s], cs[s], csnl[s], ms, mus, signed,
                        )  # fmt: skip
                        sig_h[j, 0] = a_s
                        sig_h[j, 1] = a_u
                    zp0 = 0.0
                    zp1 = 0.0
                    for j in range(n_sig):
                        zp0 += wm[j] * sig_h[j, 0]
                        zp1 += wm[j] * sig_h[j, 1]
                    s00 = 0.0
                    s01 = 0.0
                    s10 = 0.0
                    s11 = 0.0
                    for j in range(n_sig):
                        d0 = sig_h[j, 0] - zp0
                        d1 = sig_h[j, 1] - zp1
                        s00 += d0 * wc[j] * d0
                        s01 += d0 * wc[j] * d1
                        s10 += d1 * wc[j] * d0
                        s11 += d1 * wc[j] * d1
                    s00 += R[0, 0]
                    s01 += R[0, 1]
                    s10 += R[1, 0]
                    s11 += R[1, 1]
                    for a in range(n):
                        p0 = 0.0
                        p1 = 0.0
                        for j in range(n_sig):
                            da = (sig[j, a] - xp[a]) * wc[j]
                            p0 += da * (sig_h[j, 0] - zp0)
                            p1 += da * (sig_h[j, 1] - zp1)
                        pxz[a, 0] = p0
                        pxz[a, 1] = p1
                    det = s00 * s11 - s01 * s10
                    i00 = s11 / det
                    i01 = -s01 / det
                    i10 = -s10 / det
                    i11 = s00 / det
                    y0 = acc_s[b, k] - zp0
                    y1 = acc_u[b, k] - zp1
                    for a in range(n):
                        K[a, 0] = pxz[a, 0] * i00 + pxz[a, 1] * i10
                        K[a, 1] = pxz[a, 0] * i01 + pxz[a, 1] * i11
                        x[s, a] = xp[a] + (K[a, 0] * y0 + K[a, 1] * y1)
                        KS[a, 0] = K[a, 0] * s00 + K[a, 1] * s10
                        KS[a, 1] = K[a, 0] * s01 + K[a, 1] * s11
                    for a in range(n):
                        for e in range(n):
                            P[s, a, e] = Pp[a, e] - (KS[a, 0] * K[e, 0] + KS[a, 1] * K[e, 1])
                    maha = (y0 * i00 + y1 * i10) * y0 + (y0 * i01 + y1 * i11) * y1
                    ll[s] = -0.5 * (maha + np.log(det) + log2pi2)
                if any_repair:
                    repairs[b] += 1
                # --- mode probabilities (eq. 12), as estimators.imm.imm_probabilities
                if multi:
                    top = -np.inf
                    for s in range(n_modes):
                        ll[s] = np.log(max(cbar[s], _TINY)) + ll[s]
                        top = max(top, ll[s])
                    total = 0.0
                    for s in range(n_modes):
                        mu[s] = np.exp(ll[s] - top)
                        total += mu[s]
                    for s in range(n_modes):
                        mu[s] /= total
                    if mu_floor > 0.0:
                        total = 0.0
                        for s in range(n_modes):
                            mu[s] = max(mu[s], mu_floor)
                            total += mu[s]
                        for s in range(n_modes):
                            mu[s] /= total
            # --- combined k_t and its std (eq. 13-14, k_t entry only)
            t = 0.0
            for s in range(n_modes):
                t += mu[s] * x[s, 4]
            kt_hat[b, k] = t
            v = 0.0
            for s in range(n_modes):
                spread = x[s, 4] - t
                v += mu[s] * (P[s, 4, 4] + spread * spread)
            kt_sig[b, k] = np.sqrt(max(v, 0.0))
            for s in range(n_modes):
                mode_prob[b, k, s] = mu[s]
                mode_kt[b, k, s] = x[s, 4]


def run_imm_ukf(
    acc_s: np.ndarray,
    acc_u: np.ndarray,
    dt: float,
    road: np.ndarray,
    phi: np.ndarray,
    Q: np.ndarray,
    R: np.ndarray,
    x0: np.ndarray,
    P0: np.ndarray,
    mu0: np.ndarray,
    transition: np.ndarray,
    ks: np.ndarray,
    ksnl: np.ndarray,
    cs: np.ndarray,
    csnl: np.ndarray,
    sprung_mass: float,
    unsprung_mass: float,
    w: SigmaWeights,
    *,
    mu_floor: float,
    augmented: bool,
    semi_implicit: bool,
    signed_damper: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Run the IMM of UKFs over B runs × T steps × S modes (state size n = 5, or 6 augmented).

    Parameters
    ----------
    acc_s, acc_u : (B, T) measured sprung / unsprung accelerations, m/s².
    dt : sample interval, s.
    road : (B, 1 or S, T) road elevation each mode assumes, m (ignored when `augmented`;
        then any (B, 1, 1) array).
    phi : (B,) AR(1) coefficient of the augmented road state (ignored otherwise).
    Q : (B, S, n, n) process noise; R : (2, 2) measurement noise.
    x0, P0, mu0 : (B, S, n), (B, S, n, n), (B, S) initial states, covariances, mode probabilities.
    transition : (S, S) Markov matrix (eq. 17); unused for one mode.
    ks, ksnl, cs, csnl : (S,) each mode's QC parameters (N/m, N/m³, N s/m, N s²/m²).
    sprung_mass, unsprung_mass : kg.
    w : sigma-point weights (:func:`suvtwin.estimators.ukf.merwe_weights`).

    Returns
    -------
    kt_hat, kt_sigma : (B, T) N/m; mode_probability, mode_stiffness : (B, T, S);
    repairs : (B,) int, steps in which a covariance was repaired.
    """
    acc_s = np.ascontiguousarray(acc_s, dtype=float)
    acc_u = np.ascontiguousarray(acc_u, dtype=float)
    n_runs, n_steps = acc_s.shape
    n_modes = x0.shape[1]
    kt_hat = np.empty((n_runs, n_steps))
    kt_sig = np.empty((n_runs, n_steps))
    mode_prob = np.empty((n_runs, n_steps, n_modes))
    mode_kt = np.empty((n_runs, n_steps, n_modes))
    repairs = np.zeros(n_runs, dtype=np.int64)

    def f(a):
        return np.ascontiguousarray(a, dtype=float)

    _run(
        acc_s, acc_u, float(dt), f(road), f(np.broadcast_to(phi, (n_runs,))), f(Q), f(R), f(x0), f(P0),
        f(mu0), f(transition), f(ks), f(ksnl), f(cs), f(csnl), float(sprung_mass), float(unsprung_mass),
        f(w.wm), f(w.wc), float(w.lam), float(mu_floor), bool(augmented), bool(semi_implicit),
        bool(signed_damper), kt_hat, kt_sig, mode_prob, mode_kt, repairs,
    )  # fmt: skip
    return kt_hat, kt_sig, mode_prob, mode_kt, repairs
