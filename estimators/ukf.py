r"""Unscented Kalman filter over a batch of independent filters (additive noise).

Usual call, one step for a batch of filters::

    w = merwe_weights(n, alpha=1e-3, beta=2.0, kappa=0.0)
    pred = ukf_predict(x, P, fx, Q, w)                # x: (..., n), P: (..., n, n)
    post = ukf_update(pred, z, hx, R, w)              # z: (..., m)

The algorithm is the scaled unscented transform with Van der Merwe's sigma points
[1]_ [2]_, in the same order of operations as filterpy 2.0's
``UnscentedKalmanFilter`` (after the prediction, sigma points are redrawn from the
prior mean and covariance and passed through the measurement model), so that the
two agree to rounding. Every array carries a leading
batch shape ``...`` (runs, modes, population): one call advances all of them, with
no Python loop over the batch — filterpy's one-object-per-filter design cannot.

Numerical robustness: a covariance whose Cholesky factorization fails is repaired
— symmetrized, then jittered on the diagonal (1e-12 to 1e-6 of its mean
variance), then, as a last resort, projected on the positive semi-definite cone
by clipping its eigenvalues — and every repair is counted in the result, never
raised.

References
----------
.. [1] R. van der Merwe, "Sigma-Point Kalman Filters for Probabilistic Inference in
   Dynamic State-Space Models", PhD thesis, OGI, 2004.
.. [2] S. J. Julier, J. K. Uhlmann, "Unscented filtering and nonlinear estimation",
   Proc. IEEE 92(3), 2004. doi:10.1109/JPROC.2003.823141
.. [3] R. Labbe, FilterPy 2.0, ``filterpy.kalman.UnscentedKalmanFilter``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = [
    "Prediction",
    "SigmaWeights",
    "Update",
    "merwe_weights",
    "robust_cholesky",
    "sigma_points",
    "ukf_predict",
    "ukf_update",
    "unscented_transform",
]


@dataclass(frozen=True)
class SigmaWeights:
    """Scaled sigma-point parameters and weights.

    Attributes
    ----------
    n : int
        State dimension.
    lam : float
        :math:`\\lambda = \\alpha^2 (n + \\kappa) - n`.
    wm, wc : numpy.ndarray, shape (2n+1,)
        Weights of the mean and of the covariance.
    """

    n: int
    lam: float
    wm: np.ndarray
    wc: np.ndarray


def merwe_weights(n: int, *, alpha: float, beta: float, kappa: float) -> SigmaWeights:
    """Van der Merwe scaled sigma-point weights (as filterpy's ``MerweScaledSigmaPoints``).

    :math:`W^m_0 = \\lambda/(n+\\lambda)`, :math:`W^c_0 = W^m_0 + 1 - \\alpha^2 + \\beta`,
    :math:`W_i = 1/(2(n+\\lambda))`.
    """
    lam = alpha**2 * (n + kappa) - n
    wm = np.full(2 * n + 1, 0.5 / (n + lam))
    wc = wm.copy()
    wm[0] = lam / (n + lam)
    wc[0] = lam / (n + lam) + (1.0 - alpha**2 + beta)
    return SigmaWeights(n=n, lam=lam, wm=wm, wc=wc)


def robust_cholesky(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Lower Cholesky factor of a batch of matrices, repairing those that are not PD.

    Parameters
    ----------
    a : numpy.ndarray, shape (..., n, n)

    Returns
    -------
    L : numpy.ndarray, shape (..., n, n)
        ``L @ L.T`` equals `a` where `a` is positive definite, else its repair.
    repaired : numpy.ndarray of bool, shape (...)
        Which matrices needed a repair.
    """
    try:
        return np.linalg.cholesky(a), np.zeros(a.shape[:-2], dtype=bool)
    except np.linalg.LinAlgError:
        pass
    flat = a.reshape(-1, a.shape[-2], a.shape[-1])
    out = np.empty_like(flat)
    repaired = np.zeros(flat.shape[0], dtype=bool)
    eye = np.eye(a.shape[-1])
    for i, m in enumerate(flat):
        try:
            out[i] = np.linalg.cholesky(m)
            continue
        except np.linalg.LinAlgError:
            repaired[i] = True
        sym = 0.5 * (m + m.T)
        scale = max(float(np.mean(np.abs(np.diag(sym)))), np.finfo(float).tiny)
        for jitter in (0.0, 1e-12, 1e-9, 1e-6):
            try:
                out[i] = np.linalg.cholesky(sym + jitter * scale * eye)
                break
            except np.linalg.LinAlgError:
                continue
        else:
            values, vectors = np.linalg.eigh(sym)
            values = np.maximum(values, 1e-9 * scale)
            out[i] = np.linalg.cholesky((vectors * values) @ vectors.T)
    return out.reshape(a.shape), repaired.reshape(a.shape[:-2])


def sigma_points(x: np.ndarray, P: np.ndarray, w: SigmaWeights) -> tuple[np.ndarray, np.ndarray]:
    """Sigma points :math:`x, x \\pm` columns of :math:`\\sqrt{(n+\\lambda)P}`.

    Returns ``(sigmas, repaired)`` with sigmas of shape (..., 2n+1, n).
    """
    root, repaired = robust_cholesky((w.n + w.lam) * P)
    cols = np.swapaxes(root, -1, -2)  # rows = columns of L = rows of filterpy's upper factor
    sigmas = np.concatenate([x[..., None, :], x[..., None, :] + cols, x[..., None, :] - cols], axis=-2)
    return sigmas, repaired


def unscented_transform(
    sigmas: np.ndarray, w: SigmaWeights, noise: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    """Weighted mean (..., d) and covariance (..., d, d) of sigma points (..., 2n+1, d), plus `noise`."""
    mean = w.wm @ sigmas
    dev = sigmas - mean[..., None, :]
    cov = (np.swapaxes(dev, -1, -2) * w.wc) @ dev
    if noise is not None:
        cov = cov + noise
    return mean, cov


@dataclass(frozen=True)
class Prediction:
    """Result of :func:`ukf_predict`: prior mean (..., n), covariance (..., n, n), sigma
    points redrawn from them (..., 2n+1, n), and which covariances were repaired (...)."""

    x: np.ndarray
    P: np.ndarray
    sigmas: np.ndarray
    repaired: np.ndarray


@dataclass(frozen=True)
class Update:
    """Result of :func:`ukf_update`.

    Attributes
    ----------
    x, P : posterior mean (..., n) and covariance (..., n, n)
    y : innovation (..., m)
    S : innovation covariance (..., m, m)
    K : gain (..., n, m)
    log_likelihood : (...,) :math:`\\log N(y; 0, S)`
    """

    x: np.ndarray
    P: np.ndarray
    y: np.ndarray
    S: np.ndarray
    K: np.ndarray
    log_likelihood: np.ndarray


def ukf_predict(
    x: np.ndarray, P: np.ndarray, fx: Callable[[np.ndarray], np.ndarray], Q: np.ndarray, w: SigmaWeights
) -> Prediction:
    """Propagate mean and covariance through the process model.

    Parameters
    ----------
    x : numpy.ndarray, shape (..., n)
    P : numpy.ndarray, shape (..., n, n)
    fx : callable
        Process model on sigma points: (..., 2n+1, n) → (..., 2n+1, n); anything it
        needs (time step, inputs, per-mode parameters) it closes over or broadcasts.
    Q : numpy.ndarray, shape ([...,] n, n)
        Additive process noise covariance.
    """
    sigmas, repaired = sigma_points(x, P, w)
    x_prior, P_prior = unscented_transform(fx(sigmas), w, Q)
    sigmas_prior, repaired_prior = sigma_points(x_prior, P_prior, w)
    return Prediction(x=x_prior, P=P_prior, sigmas=sigmas_prior, repaired=repaired | repaired_prior)


def _inverse_and_logdet(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse and log-determinant of a batch of SPD matrices (closed form for 2 x 2)."""
    if S.shape[-1] == 2:
        a, b, c, d = S[..., 0, 0], S[..., 0, 1], S[..., 1, 0], S[..., 1, 1]
        det = a * d - b * c
        inv = np.stack([np.stack([d, -b], -1), np.stack([-c, a], -1)], -2) / det[..., None, None]
        return inv, np.log(det)
    return np.linalg.inv(S), np.linalg.slogdet(S)[1]


def ukf_update(
    pred: Prediction,
    z: np.ndarray,
    hx: Callable[[np.ndarray], np.ndarray],
    R: np.ndarray,
    w: SigmaWeights,
) -> Update:
    """Correct a prediction with measurement `z` (..., m) through ``hx`` ((..., 2n+1, n) → (..., 2n+1, m)).

    :math:`S = \\sum W^c (\\mathcal Z - \\hat z)(\\cdot)^T + R`,
    :math:`K = P_{xz} S^{-1}`, :math:`x^+ = x^- + K(z - \\hat z)`,
    :math:`P^+ = P^- - K S K^T`.
    """
    sigmas_h = hx(pred.sigmas)
    zp, S = unscented_transform(sigmas_h, w, R)
    dx = pred.sigmas - pred.x[..., None, :]
    dz = sigmas_h - zp[..., None, :]
    pxz = (np.swapaxes(dx, -1, -2) * w.wc) @ dz
    S_inv, logdet = _inverse_and_logdet(S)
    K = pxz @ S_inv
    y = z - zp
    x_post = pred.x + (K @ y[..., None])[..., 0]
    P_post = pred.P - K @ S @ np.swapaxes(K, -1, -2)
    m = y.shape[-1]
    maha = (y[..., None, :] @ S_inv @ y[..., :, None])[..., 0, 0]
    log_likelihood = -0.5 * (maha + logdet + m * np.log(2.0 * np.pi))
    return Update(x=x_post, P=P_post, y=y, S=S, K=K, log_likelihood=log_likelihood)
