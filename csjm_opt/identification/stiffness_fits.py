"""Least-squares estimators of the stiffness at a pose (used by :mod:`csjm_opt.identification.identify_pose`).

All take ``dzeta`` (n, 3), body-frame displacements from the reference row
(row 0), and ``tau_load`` (n, 3), total load moments in {A}:

Higher terms ``Q q(dzeta)`` (``order`` 2 or 3) absorb the finite-displacement
curvature so that K is the derivative at the reference, not a secant.

* :func:`paper_estimate`: (49), ``K_D = Psi Omega^+`` on differences to row 0.
* :func:`affine_fit`: ``tau_load = c + K_D dzeta (+ Q q(dzeta))``, corrected
  for known orientation noise (errors in variables); covariance of
  ``K = K_D - 1/2 hat(c)``.
* :func:`symmetric_fit`: GLS for ``tau_load = (I - 1/2 hat(dzeta)) tau0 + S
  dzeta (+ Q q)``, i.e. ``K = S`` symmetric and ``K_D - K_D^T = hat(tau0)``.
* :func:`bootstrap_interval`: pairs bootstrap of the affine estimate.
"""

from __future__ import annotations

import itertools

import numpy as np

from .. import so3
from ..measurement.instruments import InstrumentNoise


def higher_terms(dzeta: np.ndarray, order: int) -> np.ndarray:
    """Monomials of ``dzeta`` of degree 2..order, the columns of the higher terms ``q(dzeta)``.

    Parameters
    ----------
    dzeta : ndarray, shape (n, 3)
        Body-frame displacements (rad).
    order : int
        Highest degree (1, 2 or 3).

    Returns
    -------
    ndarray, shape (n, m)
        ``m = 0, 6, 16`` for ``order`` 1, 2, 3.
    """
    cols = []
    for degree in range(2, order + 1):
        for powers in itertools.combinations_with_replacement(range(3), degree):
            cols.append(np.prod(dzeta[:, list(powers)], axis=1))
    return np.stack(cols, axis=1) if cols else np.zeros((len(dzeta), 0))


def n_parameters(order: int) -> int:
    """Parameters per output axis of the affine fit: 1 + 3 + higher terms.

    Parameters
    ----------
    order : int
        Highest degree in ``dzeta`` (1, 2 or 3).

    Returns
    -------
    int
        4, 10 or 20.
    """
    return 4 + higher_terms(np.zeros((1, 3)), order).shape[1]


def paper_estimate(dzeta: np.ndarray, tau_load: np.ndarray) -> np.ndarray:
    """The paper's estimate (49): ``K_D = Psi Omega^+``, columns ``dtau_i``, ``dzeta_i`` relative to row 0.

    Parameters
    ----------
    dzeta : ndarray, shape (n, 3)
        Body-frame displacements from the reference row (rad).
    tau_load : ndarray, shape (n, 3)
        Total load moments in {A} (N m).

    Returns
    -------
    ndarray, shape (3, 3)
        ``K_D`` (N m/rad).
    """
    Psi, Omega = (tau_load[1:] - tau_load[0]).T, dzeta[1:].T
    return Psi @ np.linalg.pinv(Omega)


def design_matrix(dzeta: np.ndarray, order: int) -> np.ndarray:
    """Design matrix of the affine fit: a column of ones, ``dzeta``, then the monomials of degree 2..order.

    Parameters
    ----------
    dzeta : ndarray, shape (n, 3)
        Body-frame displacements from the reference row (rad).
    order : int
        Highest degree in ``dzeta`` (1: the paper's linear fit; 2 or 3).

    Returns
    -------
    ndarray, shape (n, :func:`n_parameters` (order))
        One row per measurement, columns ``[1, dzeta, higher_terms(dzeta, order)]``.
    """
    return np.hstack([np.ones((len(dzeta), 1)), dzeta, higher_terms(dzeta, order)])


def affine_fit(dzeta: np.ndarray, tau_load: np.ndarray, order: int,
                noise: InstrumentNoise | None) -> dict[str, np.ndarray]:
    """Least squares ``tau_load = c + K_D dzeta (+ Q q(dzeta))``; covariance of ``K = K_D - 1/2 hat(c)``.

    With an orientation noise, the normal matrix of the ``dzeta`` columns is corrected for it
    (corrected least squares, errors in variables).

    Parameters
    ----------
    dzeta : ndarray, shape (n, 3)
        Body-frame displacements from the reference row (rad).
    tau_load : ndarray, shape (n, 3)
        Total load moments in {A} (N m).
    order : int
        Highest degree in ``dzeta`` (1, 2 or 3).
    noise : InstrumentNoise or None
        Instrument model of the row covariance; ``None``: estimated from the residuals.

    Returns
    -------
    dict
        ``c`` (3,) fitted load at the reference (N m); ``K_D``, ``K`` (3, 3) (N m/rad);
        ``cov_K`` (9, 9) covariance of ``K.ravel()``; ``resid`` (n, 3) (N m); ``Sigma`` (3, 3)
        row covariance (N m^2); ``design_condition`` of the column-scaled design.
    """
    X = design_matrix(dzeta, order)
    n, p = X.shape
    scale = np.maximum(np.linalg.norm(X, axis=0), 1e-300)
    Xs = X / scale
    N = Xs.T @ Xs
    if noise is not None and noise.angle_sigma_rad > 0:
        # corrected least squares: E[Z^T Z] = Z0^T Z0 + n sigma^2 I for the dzeta columns
        N[1:4, 1:4] -= n * noise.angle_sigma_rad ** 2 * np.diag(1 / scale[1:4] ** 2)
    sv = np.linalg.svd(Xs, compute_uv=False)
    design_condition = float(sv[0] / sv[-1]) if sv[-1] > 0 else float("inf")
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
            "resid": resid, "Sigma": Sigma, "design_condition": design_condition}


_SYM_INDEX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def symmetric_fit(dzeta: np.ndarray, tau_load: np.ndarray, order: int,
                   Sigma: np.ndarray) -> dict[str, np.ndarray]:
    """GLS for ``tau_load_i = (I - 1/2 hat(dzeta_i)) tau0 + S dzeta_i (+ Q q_i)``; K_sym = S.

    Parameters
    ----------
    dzeta : ndarray, shape (n, 3)
        Body-frame displacements from the reference row (rad).
    tau_load : ndarray, shape (n, 3)
        Total load moments in {A} (N m).
    order : int
        Highest degree in ``dzeta`` (1, 2 or 3).
    Sigma : ndarray, shape (3, 3)
        Row covariance (N m^2) the fit is weighted by.

    Returns
    -------
    dict
        ``K`` (3, 3) symmetric estimate ``S`` (N m/rad), ``cov_K`` (9, 9) covariance of
        ``K.ravel()``, ``tau0`` (3,) fitted load at the reference (N m).
    """
    n = len(dzeta)
    blocks = [np.eye(3)[None] - 0.5 * so3.hat(dzeta)]      # tau0 (3 params)
    E = np.zeros((6, 3, 3))
    for m, (i, j) in enumerate(_SYM_INDEX):
        E[m, i, j] = E[m, j, i] = 1.0
    blocks.append(np.einsum("mij,nj->nim", E, dzeta))       # S (6 params)
    q = higher_terms(dzeta, order)
    blocks.append(np.einsum("ik,nm->nikm", np.eye(3), q).reshape(n, 3, 3 * q.shape[1]))
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
    """Pairs bootstrap (rows resampled with replacement) percentile interval of K.

    Resamples whose fit is singular are dropped.

    Parameters
    ----------
    dzeta, tau_load, order, noise
        As in :func:`affine_fit`.
    n_boot : int
        Number of resamples.
    ci_level : float
        Confidence level in (0, 1).
    rng : numpy.random.Generator
        Source of the resampled rows.

    Returns
    -------
    ndarray, shape (2, 3, 3)
        Lower and upper percentile bounds of K (N m/rad).
    """
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
