"""Compiled (numba) kernels for the shaping loop: forward statics Newton and the shaping QP.

Same mathematics as the numpy reference :mod:`csjm_opt.model.cable_terms` (closed-form
cable terms), :mod:`csjm_opt.model.statics` (damped Newton on SO(3)) and
:mod:`csjm_opt.planning._dense_qp` (primal-dual active set); ``tests/test_loop_kernels.py``
checks them against those and the CasADi model. Compiled on first use and
cached on disk (``cache=True``), like :mod:`csjm_opt.planning._kernels`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def hat(w):
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
def geometry(A, B, R):
    """Cable lengths c (6,), unit vectors U in {A} (6, 3), J (6, 3)."""
    C = B @ R - A
    c = np.sqrt((C * C).sum(axis=1))
    U = C / c.reshape(6, 1)
    J = np.empty((6, 3))
    for i in range(6):
        J[i, 0] = A[i, 1] * U[i, 2] - A[i, 2] * U[i, 1]
        J[i, 1] = A[i, 2] * U[i, 0] - A[i, 0] * U[i, 2]
        J[i, 2] = A[i, 0] * U[i, 1] - A[i, 1] * U[i, 0]
    return c, U, J


@njit(cache=True)
def length_hessians(A, c, U, J):
    """Hess(c_i) (6, 3, 3), see :mod:`csjm_opt.model.cable_terms`."""
    G = np.empty((6, 3, 3))
    for i in range(6):
        a2 = A[i, 0] * A[i, 0] + A[i, 1] * A[i, 1] + A[i, 2] * A[i, 2]
        ua = U[i, 0] * A[i, 0] + U[i, 1] * A[i, 1] + U[i, 2] * A[i, 2]
        for p in range(3):
            for q in range(3):
                v = (-A[i, p] * A[i, q] - J[i, p] * J[i, q]) / c[i] - 0.5 * (U[i, p] * A[i, q] + A[i, p] * U[i, q])
                if p == q:
                    v += a2 / c[i] + ua
                G[i, p, q] = v
    return G


@njit(cache=True)
def stiffness_basis(A, B, k, R):
    """J (6, 3), K0 = J^T diag(k) J, G (6, 3, 3)."""
    c, U, J = geometry(A, B, R)
    K0 = (J.T * k) @ J
    return J, K0, length_hessians(A, c, U, J)


@njit(cache=True)
def terms(A, B, k, F, P, R, l, tau_ext):
    """Residual g, cable K, tangent K_t, tensions T, cable and point-force moments (see statics)."""
    c, U, J = geometry(A, B, R)
    G = length_hessians(A, c, U, J)
    T = np.zeros(6)
    K = np.zeros((3, 3))
    for i in range(6):
        s = c[i] - l[i]
        if s > 0:
            T[i] = k[i] * s
            K += k[i] * np.outer(J[i], J[i]) + T[i] * G[i]
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
def shaping_qp(G, K0, L, s, w, J, tau_load, t_mid, rho_rel):
    """Dense P, q, A, b of the shaping QP (see :func:`csjm_opt.shaping.shaper.qp_matrices`)."""
    M = L @ G.reshape(6, 9).T
    d = s - L @ K0.reshape(9)
    MW = M.T * w
    H = MW @ M
    curvature = np.trace(H) / 6.0
    rho = rho_rel * (curvature if curvature > 1e-300 else 1.0)
    P = 2.0 * (H + rho * np.eye(6))
    q = -2.0 * (MW @ d + rho * t_mid)
    return P, q, J.T.copy(), -tau_load


@njit(cache=True)
def pdas(P, q, A, b, lo, hi, lower, upper, max_iter, tol):
    """Primal-dual active set of :func:`csjm_opt.planning._dense_qp.solve` (no primal fallback here).

    Returns ``(x, nu, z, lower, upper, iterations, status)``; status 0 settled,
    1 singular KKT, 2 not settled (callers fall back to :mod:`csjm_opt.planning._dense_qp`).
    """
    n = q.size
    m = A.shape[0]
    scale_x = max(1.0, np.abs(hi).max())
    x = np.zeros(n)
    nu = np.zeros(m)
    z = np.zeros(n)
    for it in range(1, max_iter + 1):
        nf = 0
        for i in range(n):
            if not (lower[i] or upper[i]):
                nf += 1
        if nf < m:
            return x, nu, z, lower, upper, it, 1
        F = np.empty(nf, np.int64)
        j = 0
        for i in range(n):
            x[i] = lo[i] if lower[i] else (hi[i] if upper[i] else 0.0)
            if not (lower[i] or upper[i]):
                F[j] = i
                j += 1
        Kk = np.zeros((nf + m, nf + m))
        rhs = np.zeros(nf + m)
        Px = P @ x
        Ax = A @ x
        for a in range(nf):
            for c in range(nf):
                Kk[a, c] = P[F[a], F[c]]
            for c in range(m):
                Kk[a, nf + c] = A[c, F[a]]
                Kk[nf + c, a] = A[c, F[a]]
            rhs[a] = -q[F[a]] - Px[F[a]]
        for c in range(m):
            rhs[nf + c] = b[c] - Ax[c]
        if abs(np.linalg.det(Kk)) < 1e-300:
            return x, nu, z, lower, upper, it, 1
        sol = np.linalg.solve(Kk, rhs)
        for a in range(nf):
            x[F[a]] = sol[a]
        nu = sol[nf:].copy()
        z = P @ x + q + A.T @ nu
        changed = False
        for i in range(n):
            if lower[i]:
                if z[i] <= 0:
                    lower[i] = False
                    changed = True
            elif upper[i]:
                if z[i] >= 0:
                    upper[i] = False
                    changed = True
            elif x[i] < lo[i] - tol * scale_x:
                lower[i] = True
                changed = True
            elif x[i] > hi[i] + tol * scale_x:
                upper[i] = True
                changed = True
        if not changed:
            for i in range(n):
                if not (lower[i] or upper[i]):
                    z[i] = 0.0
            return x, nu, z, lower, upper, it, 0
    return x, nu, z, lower, upper, max_iter, 2


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
    """Tensions T (6,) and cable stiffness K (3, 3) for rest lengths ``l`` at ``R`` (slack: nothing)."""
    c, U, J = geometry(A, B, R)
    G = length_hessians(A, c, U, J)
    T = np.zeros(6)
    K = np.zeros((3, 3))
    for i in range(6):
        s = c[i] - l[i]
        if s > 0:
            T[i] = k[i] * s
            K += k[i] * np.outer(J[i], J[i]) + T[i] * G[i]
    return T, K
