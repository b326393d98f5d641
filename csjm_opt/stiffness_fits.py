"""Least-squares estimators of the stiffness at a pose (used by :mod:`csjm_opt.identify`).

All take ``dzeta`` (n, 3), body-frame displacements from the reference row
(row 0), and ``tau_load`` (n, 3), total load moments in {A}:

* :func:`paper_estimate`: (49), ``K_D = Psi Omega^+`` on differences to row 0.
* :func:`affine_fit`: ``tau_load = c + K_D dzeta (+ Q q(dzeta))``, corrected
  for known orientation noise (errors in variables); covariance of
  ``K = K_D - 1/2 hat(c)``.
* :func:`symmetric_fit`: GLS for ``tau_load = (I - 1/2 hat(dzeta)) tau0 + S
  dzeta (+ Q q)``, i.e. ``K = S`` symmetric and ``K_D - K_D^T = hat(tau0)``.
* :func:`bootstrap_interval`: pairs bootstrap of the affine estimate.
"""

from __future__ import annotations

import numpy as np

from . import so3
from .instruments import InstrumentNoise


def quadratic_terms(dzeta: np.ndarray) -> np.ndarray:
    """(n, 6) second-order monomials of dzeta: x^2, y^2, z^2, xy, xz, yz."""
    x, y, z = dzeta.T
    return np.stack([x * x, y * y, z * z, x * y, x * z, y * z], axis=1)


def paper_estimate(dzeta: np.ndarray, tau_load: np.ndarray) -> np.ndarray:
    """(49): ``K_D = Psi Omega^+`` with columns ``dtau_i``, ``dzeta_i`` relative to the reference."""
    Psi, Omega = (tau_load[1:] - tau_load[0]).T, dzeta[1:].T
    return Psi @ np.linalg.pinv(Omega)


def design_matrix(dzeta: np.ndarray, order: int) -> np.ndarray:
    cols = [np.ones((len(dzeta), 1)), dzeta]
    if order == 2:
        cols.append(quadratic_terms(dzeta))
    return np.hstack(cols)


def affine_fit(dzeta: np.ndarray, tau_load: np.ndarray, order: int,
                noise: InstrumentNoise | None) -> dict[str, np.ndarray]:
    """Least squares ``tau_load = c + K_D dzeta (+ Q q(dzeta))``; covariance of ``K = K_D - 1/2 hat(c)``."""
    X = design_matrix(dzeta, order)
    n, p = X.shape
    scale = np.maximum(np.linalg.norm(X, axis=0), 1e-300)
    Xs = X / scale
    N = Xs.T @ Xs
    if noise is not None and noise.angle_sigma_rad > 0:
        # corrected least squares: E[Z^T Z] = Z0^T Z0 + n sigma^2 I for the dzeta columns
        N[1:4, 1:4] -= n * noise.angle_sigma_rad ** 2 * np.diag(1 / scale[1:4] ** 2)
    G = np.linalg.inv(N)
    B = (G @ (Xs.T @ tau_load)) / scale[:, None]          # (p, 3): column i = output axis i
    G = G / np.outer(scale, scale)
    resid = tau_load - X @ B
    c, K_D = B[0], B[1:4].T
    if noise is not None:
        Sigma = np.diag(np.asarray(noise.tau_sigma_Nm) ** 2) + noise.angle_sigma_rad ** 2 * K_D @ K_D.T
    else:
        Sigma = resid.T @ resid / (n - p)
    cov_B = np.kron(Sigma, G)                               # theta = B.T.ravel(): (axis i, param a)
    L = np.zeros((9, 3 * p))                                # K.ravel() = L theta
    for i in range(3):
        for j in range(3):
            L[3 * i + j, i * p + 1 + j] = 1.0
            # -1/2 hat(c)[i, j] = -1/2 eps_{i k j} c_k  -> depends on c_k, k = 3 - i - j
            if i != j:
                k = 3 - i - j
                sign = -0.5 * (so3.hat(np.eye(3)[k])[i, j])
                L[3 * i + j, k * p] = sign
    return {"c": c, "K_D": K_D, "K": K_D - 0.5 * so3.hat(c), "cov_K": L @ cov_B @ L.T,
            "resid": resid, "Sigma": Sigma}


_SYM_INDEX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def symmetric_fit(dzeta: np.ndarray, tau_load: np.ndarray, order: int,
                   Sigma: np.ndarray) -> dict[str, np.ndarray]:
    """GLS for ``tau_load_i = (I - 1/2 hat(dzeta_i)) tau0 + S dzeta_i (+ Q q_i)``; K_sym = S."""
    n = len(dzeta)
    blocks = [np.eye(3)[None] - 0.5 * so3.hat(dzeta)]      # tau0 (3 params)
    E = np.zeros((6, 3, 3))
    for m, (i, j) in enumerate(_SYM_INDEX):
        E[m, i, j] = E[m, j, i] = 1.0
    blocks.append(np.einsum("mij,nj->nim", E, dzeta))       # S (6 params)
    if order == 2:
        q = quadratic_terms(dzeta)
        blocks.append(np.einsum("ik,nm->nikm", np.eye(3), q).reshape(n, 3, 18))
    A = np.concatenate(blocks, axis=2)                      # (n, 3, P)
    W_half = _whitener(Sigma)                               # W = W_half^T W_half = Sigma^-1
    Aw = np.einsum("ij,njp->nip", W_half, A).reshape(3 * n, -1)
    yw = (tau_load @ W_half.T).reshape(-1)
    scale = np.maximum(np.linalg.norm(Aw, axis=0), 1e-300)
    cov = np.linalg.inv((Aw / scale).T @ (Aw / scale)) / np.outer(scale, scale)
    theta = cov @ (Aw.T @ yw)
    M = np.zeros((9, A.shape[2]))
    for m, (i, j) in enumerate(_SYM_INDEX):
        M[3 * i + j, 3 + m] = M[3 * j + i, 3 + m] = 1.0
    return {"K": (M @ theta).reshape(3, 3), "cov_K": M @ cov @ M.T, "tau0": theta[:3]}


def _whitener(Sigma: np.ndarray) -> np.ndarray:
    """``Sigma^-1/2``, with eigenvalues floored (noise-free data give a near-zero Sigma)."""
    w, V = np.linalg.eigh(0.5 * (Sigma + Sigma.T))
    top = max(float(w.max()), 0.0)
    w = np.maximum(w, top * 1e-10) if top > 0 else np.ones(3)
    return (V / np.sqrt(w)).T


def bootstrap_interval(dzeta, tau_load, order, noise, n_boot, ci_level, rng) -> np.ndarray:
    """Pairs bootstrap (rows resampled with replacement) percentile interval of K."""
    n = len(dzeta)
    Ks = []
    for _ in range(n_boot):
        rows = rng.integers(0, n, n)
        try:
            Ks.append(affine_fit(dzeta[rows], tau_load[rows], order, noise)["K"])
        except np.linalg.LinAlgError:
            continue
    a = (1 - ci_level) / 2
    return np.quantile(np.array(Ks), [a, 1 - a], axis=0)
