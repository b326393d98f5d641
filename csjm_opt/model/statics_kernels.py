"""Compiled (numba) forward statics: the damped Newton on SO(3) and the terms it needs.

The compiled twin of the numpy reference in :mod:`csjm_opt.model._statics_newton`
(the method is described in :mod:`csjm_opt.model.statics`). The cable geometry
and stiffness come from :mod:`csjm_opt.model.kernels` (tested against the
numpy reference :mod:`csjm_opt.model.cable_terms`); ``tests/control/test_loop_kernels.py``
checks these against those and the CasADi model. Compiled on first use and
cached on disk (``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .kernels import geometry_into, stiffness_from_geometry_into


@njit(cache=True)
def hat(w):
    """The skew matrix ``hat(w)`` (3, 3) of a 3-vector: ``hat(w) @ v = w x v``."""
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


@njit(cache=True)
def exp_so3(w):
    """Rodrigues' formula with a small-angle series."""
    th2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2]
    W = hat(w)
    if th2 < 1e-12:
        a, b = 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    else:
        th = np.sqrt(th2)
        a, b = np.sin(th) / th, (1.0 - np.cos(th)) / th2
    return np.eye(3) + a * W + b * (W @ W)


@njit(cache=True)
def geometry(R, A, B):
    """Cable lengths c (m,), unit vectors U in {A} (m, 3), J (m, 3) (model-layer kernel)."""
    m = A.shape[0]
    c = np.empty(m)
    U = np.empty((m, 3))
    J = np.empty((m, 3))
    geometry_into(A, B, R, c, U, J)
    return c, U, J


@njit(cache=True)
def length_hessians(A, c, U, J):
    """Hess(c_i) (m, 3, 3): K of cable i alone at unit tension and zero stiffness."""
    m = A.shape[0]
    G = np.empty((m, 3, 3))
    e = np.zeros(m)
    zero_k = np.zeros(m)
    for i in range(m):
        e[i] = 1.0
        stiffness_from_geometry_into(A, zero_k, c, U, J, e, G[i])
        e[i] = 0.0
    return G


@njit(cache=True)
def stiffness_basis(A, B, k, R):
    """J (m, 3), K0 = J^T diag(k) J, G (m, 3, 3)."""
    c, U, J = geometry(R, A, B)
    K0 = (J.T * k) @ J
    return J, K0, length_hessians(A, c, U, J)


@njit(cache=True)
def terms(A, B, k, F, P, R, l, tau_ext):
    """Residual g, cable K, tangent K_t, tensions T, cable and point-force moments (see statics)."""
    c, U, J = geometry(R, A, B)
    T, K = _rest_from_geometry(A, k, c, U, J, l)
    tau_c = J.T @ T
    tau_p = np.zeros(3)
    H = np.zeros((3, 3))
    for j in range(F.shape[0]):
        f = R.T @ F[j]
        r = P[j]
        tau_p += np.array([r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]])
        fr = np.outer(f, r)
        H += (f[0] * r[0] + f[1] * r[1] + f[2] * r[2]) * np.eye(3) - 0.5 * (fr + fr.T)
    g = tau_c + tau_p + tau_ext
    K_t = K + H - 0.5 * hat(tau_c + tau_p)
    return g, K, K_t, T, tau_c, tau_p


@njit(cache=True)
def newton(A, B, k, F, P, R0, l, tau_ext, tol, max_iter, max_step, max_excursion):
    """Damped Newton of :func:`csjm_opt.model.statics._newton`: (R, terms..., iterations, converged)."""
    R = R0.copy()
    g, K, K_t, T, tau_c, tau_p = terms(A, B, k, F, P, R, l, tau_ext)
    best = np.sqrt(g @ g)
    it = 0
    while it < max_iter and best > tol:
        it += 1
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(K_t))):
            return R, g, K, K_t, T, tau_c, tau_p, it, False
        step = np.linalg.solve(K_t, g) if abs(np.linalg.det(K_t)) > 1e-12 else np.zeros(3)
        if not np.all(np.isfinite(step)) or (step @ g <= 0 and np.linalg.cond(K_t) > 1e10) or not np.any(step):
            S = 0.5 * (K_t + K_t.T)
            mu = max(0.0, -np.linalg.eigvalsh(S)[0]) + 1e-3 * max(1.0, np.abs(S).max())
            step = np.linalg.solve(S + mu * np.eye(3), g)
        norm = np.sqrt(step @ step)
        if norm > max_step:
            step = step * (max_step / norm)
        alpha = 1.0
        improved = False
        for _ in range(30):
            R_try = R @ exp_so3(alpha * step)
            out = terms(A, B, k, F, P, R_try, l, tau_ext)
            n_try = np.sqrt(out[0] @ out[0])
            if n_try < best or n_try <= tol:
                R = R_try
                g, K, K_t, T, tau_c, tau_p = out
                best = n_try
                improved = True
                break
            alpha *= 0.5
        cos = 0.5 * ((R0 * R).sum() - 1.0)
        if not improved or np.arccos(min(1.0, max(-1.0, cos))) > max_excursion:
            return R, g, K, K_t, T, tau_c, tau_p, it, False
    return R, g, K, K_t, T, tau_c, tau_p, it, best <= tol


@njit(cache=True)
def log_so3(R):
    """Rotation vector of ``R`` (rad), with small-angle and near-pi branches (see :func:`csjm_opt.so3.log`)."""
    cos = min(1.0, max(-1.0, 0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0)))
    v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    th = np.arccos(cos)
    if th < 1e-6:
        return 0.5 * (1.0 + th * th / 6.0) * v
    if th < np.pi - 1e-6:
        return 0.5 * th / np.sin(th) * v
    # near pi: axis from the symmetric part
    S = 0.5 * (R + R.T) - cos * np.eye(3)
    i = 0
    for j in range(1, 3):
        if S[j, j] > S[i, i]:
            i = j
    axis = S[i] / np.sqrt(max(S[i, i], 1e-300))
    if axis @ v < 0:
        axis = -axis
    return th * axis / np.sqrt(axis @ axis)


@njit(cache=True)
def rest_state(A, B, k, R, l):
    """Tensions T (m,) and cable stiffness K (3, 3) for rest lengths ``l`` at ``R`` (slack: nothing)."""
    c, U, J = geometry(R, A, B)
    return _rest_from_geometry(A, k, c, U, J, l)


@njit(cache=True)
def _rest_from_geometry(A, k, c, U, J, l):
    """Tensions T (m,) and cable stiffness K (3, 3) from the cable geometry (slack cables: nothing)."""
    G = length_hessians(A, c, U, J)
    T = np.zeros(A.shape[0])
    K = np.zeros((3, 3))
    for i in range(A.shape[0]):
        s = c[i] - l[i]
        if s > 0:
            T[i] = k[i] * s
            K += k[i] * np.outer(J[i], J[i]) + T[i] * G[i]
    return T, K
