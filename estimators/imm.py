r"""Interacting Multiple Model (IMM) steps over a batch of runs and a bank of modes.

Usual call, one time step (``S`` modes, states ``x``: (..., S, n))::

    mixed = imm_mix(x, P, mu, M)                  # mixing, eq. 9–11 (standard form)
    pred = ukf_predict(mixed.x, mixed.P, fx, Q, w)  # each mode's filter, eq. 15
    post = ukf_update(pred, z[..., None, :], hx, R, w)
    mu = imm_probabilities(mixed.cbar, post.log_likelihood, floor=1e-6)   # eq. 12
    x_hat, P_hat = imm_combine(post.x, post.P, mu)                        # eq. 13–14

This is the standard IMM of Blom & Bar-Shalom [1]_, as in filterpy's
``IMMEstimator`` [2]_. Where Brancati & Tufano 2022 differ:

- eq. 11 mixes the covariances without the spread-of-means term
  :math:`(\hat x^j - \hat x^{i,*})(\cdot)^T`; here it is included (without it the mixed
  covariance is too small whenever the modes disagree).
- eq. 12 divides the likelihood by :math:`\det(P^{yy})`; the Gaussian likelihood has
  :math:`\sqrt{\det(2\pi P^{yy})}`, used here. The paper's form over-weights modes
  with a small innovation covariance.
- The mode probabilities are normalized in log space (no underflow) and floored
  at `floor` (then renormalized), so a mode can recover after a road change.

References
----------
.. [1] H. A. P. Blom, Y. Bar-Shalom, "The interacting multiple model algorithm for systems
   with Markovian switching coefficients", IEEE TAC 33(8), 1988. doi:10.1109/9.1299
.. [2] R. Labbe, FilterPy 2.0, ``filterpy.kalman.IMMEstimator``.
.. [3] R. Brancati, F. Tufano, Machines 10(12), 1221, 2022, eq. 9–14 and 17.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PAPER_TRANSITION", "Mixed", "imm_combine", "imm_mix", "imm_probabilities"]

PAPER_TRANSITION = np.full((4, 4), 0.01) + np.eye(4) * 0.96
"""Markov transition matrix of Brancati & Tufano 2022, eq. 17 (0.97 on the diagonal)."""


@dataclass(frozen=True)
class Mixed:
    """Mixed initial conditions for each mode: x (..., S, n), P (..., S, n, n), and the
    predicted mode probabilities cbar (..., S)."""

    x: np.ndarray
    P: np.ndarray
    cbar: np.ndarray


def imm_mix(x: np.ndarray, P: np.ndarray, mu: np.ndarray, M: np.ndarray) -> Mixed:
    r"""IMM mixing step.

    :math:`\bar c_j = \sum_i M_{ij}\mu_i`, :math:`\omega_{ij} = M_{ij}\mu_i/\bar c_j`,
    :math:`x^{0j} = \sum_i \omega_{ij} x^i`,
    :math:`P^{0j} = \sum_i \omega_{ij}(P^i + (x^i - x^{0j})(x^i - x^{0j})^T)`.

    Parameters
    ----------
    x : numpy.ndarray, shape (..., S, n)
    P : numpy.ndarray, shape (..., S, n, n)
    mu : numpy.ndarray, shape (..., S)
    M : numpy.ndarray, shape (S, S)
        Transition probabilities, ``M[i, j]`` = P(mode j next | mode i now); rows sum to 1.
    """
    cbar = np.einsum("...i,ij->...j", mu, M)
    omega = M * mu[..., :, None] / cbar[..., None, :]
    x0 = np.einsum("...ij,...in->...jn", omega, x)
    d = x[..., None, :, :] - x0[..., :, None, :]  # (..., j, i, n): x_i - x0_j
    P0 = np.einsum("...ij,...inm->...jnm", omega, P) + np.einsum("...ij,...jin,...jim->...jnm", omega, d, d)
    return Mixed(x=x0, P=P0, cbar=cbar)


def imm_probabilities(cbar: np.ndarray, log_likelihood: np.ndarray, *, floor: float = 0.0) -> np.ndarray:
    r"""Posterior mode probabilities :math:`\mu_j \propto \bar c_j\,\Lambda_j`, (..., S).

    `log_likelihood` is each mode's :math:`\log N(y; 0, S)`. Normalized in log space;
    each probability is then raised to at least `floor` and the vector renormalized.
    """
    log_w = np.log(np.maximum(cbar, np.finfo(float).tiny)) + log_likelihood
    log_w -= log_w.max(axis=-1, keepdims=True)
    mu = np.exp(log_w)
    mu /= mu.sum(axis=-1, keepdims=True)
    if floor > 0.0:
        mu = np.maximum(mu, floor)
        mu /= mu.sum(axis=-1, keepdims=True)
    return mu


def imm_combine(x: np.ndarray, P: np.ndarray, mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Combined estimate :math:`\hat x = \sum_j \mu_j x^j`,
    :math:`\hat P = \sum_j \mu_j (P^j + (x^j - \hat x)(\cdot)^T)` (eq. 13–14)."""
    x_hat = (mu[..., None, :] @ x)[..., 0, :]
    n = x.shape[-1]
    d = x - x_hat[..., None, :]
    P_hat = (mu[..., None, :] @ P.reshape(P.shape[:-2] + (n * n,)))[..., 0, :].reshape(P.shape[:-3] + (n, n))
    P_hat = P_hat + (np.swapaxes(d, -1, -2) * mu[..., None, :]) @ d
    return x_hat, P_hat
