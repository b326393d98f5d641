"""Compiled (numba) kernels for the planner's hot path.

The CasADi functions of :mod:`csjm_opt.model.casadi_model` are the reference model;
calling them from Python costs about 30 us per call, which is the whole budget
of planning one pose. These kernels compute the same J (38) and weight moment
in compiled loops and solve the tension QP exactly by the primal-dual active
set method (see :mod:`csjm_opt.planning._active_set` for the method), one pose or many
poses in a row with each pose warm-started from the previous one's active set.
``tests/test_kernels.py`` checks them against the CasADi model and SLSQP.
Compiled on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Status codes of :func:`solve_one`.
OK, SINGULAR, NOT_CONVERGED = 0, 1, 2


@njit(cache=True)
def _det3(M):
    return (M[0, 0] * (M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1])
            - M[0, 1] * (M[1, 0] * M[2, 2] - M[1, 2] * M[2, 0])
            + M[0, 2] * (M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]))


@njit(cache=True, fastmath=False)
def rotation_error(R):
    """(||R^T R - I||_F, det R) without allocating."""
    err = 0.0
    for i in range(3):
        for j in range(3):
            s = R[0, i] * R[0, j] + R[1, i] * R[1, j] + R[2, i] * R[2, j]
            if i == j:
                s -= 1.0
            err += s * s
    return np.sqrt(err), _det3(R)


@njit(cache=True)
def jacobian_into(A, B, R, J):
    """J (6, 3) of (38): rows ``a_i x (R^T u_i)``; A, B are (6, 3) hole arrays."""
    for i in range(6):
        c0 = B[i, 0] - (R[0, 0] * A[i, 0] + R[0, 1] * A[i, 1] + R[0, 2] * A[i, 2])
        c1 = B[i, 1] - (R[1, 0] * A[i, 0] + R[1, 1] * A[i, 1] + R[1, 2] * A[i, 2])
        c2 = B[i, 2] - (R[2, 0] * A[i, 0] + R[2, 1] * A[i, 1] + R[2, 2] * A[i, 2])
        inv = 1.0 / np.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
        v0 = (R[0, 0] * c0 + R[1, 0] * c1 + R[2, 0] * c2) * inv   # R^T u_i
        v1 = (R[0, 1] * c0 + R[1, 1] * c1 + R[2, 1] * c2) * inv
        v2 = (R[0, 2] * c0 + R[1, 2] * c1 + R[2, 2] * c2) * inv
        J[i, 0] = A[i, 1] * v2 - A[i, 2] * v1
        J[i, 1] = A[i, 2] * v0 - A[i, 0] * v2
        J[i, 2] = A[i, 0] * v1 - A[i, 1] * v0


@njit(cache=True)
def weight_moment_into(m, r, g, R, out):
    """``m r x (R^T g)``: moment of a force m g (in {B}) at r (in {A}), in {A}."""
    g0 = R[0, 0] * g[0] + R[1, 0] * g[1] + R[2, 0] * g[2]
    g1 = R[0, 1] * g[0] + R[1, 1] * g[1] + R[2, 1] * g[2]
    g2 = R[0, 2] * g[0] + R[1, 2] * g[1] + R[2, 2] * g[2]
    out[0] = m * (r[1] * g2 - r[2] * g1)
    out[1] = m * (r[2] * g0 - r[0] * g2)
    out[2] = m * (r[0] * g1 - r[1] * g0)


@njit(cache=True)
def solve_one(J, b, t_ref, lo, hi, lower, upper, t, max_iter):
    """Exact solution of min 1/2||t - t_ref||^2, J^T t = b, lo <= t <= hi.

    ``lower``/``upper`` (bool, 6) are the warm-start active sets and are
    updated in place; ``t`` receives the solution. Returns a status code.
    """
    scale = max(1.0, abs(hi))
    eps = 1e-10 * scale
    M = np.empty((3, 3))
    rhs = np.empty(3)
    lam = np.empty(3)
    for _ in range(max_iter):
        M[:] = 0.0
        rhs[:] = b
        for i in range(6):
            if lower[i] or upper[i]:
                bound = lo if lower[i] else hi
                for p in range(3):
                    rhs[p] -= J[i, p] * bound
            else:
                for p in range(3):
                    rhs[p] -= J[i, p] * t_ref[i]
                    for q in range(3):
                        M[p, q] += J[i, p] * J[i, q]
        tr = (M[0, 0] + M[1, 1] + M[2, 2]) / 3.0
        det = _det3(M)
        if tr <= 0.0 or abs(det) < 1e-12 * tr * tr * tr:
            return SINGULAR
        # Cramer's rule on M lam = rhs (3x3): replace column p by rhs
        for p in range(3):
            C = M.copy()
            for q in range(3):
                C[q, p] = rhs[q]
            lam[p] = _det3(C) / det
        stable = True
        for i in range(6):
            jl = J[i, 0] * lam[0] + J[i, 1] * lam[1] + J[i, 2] * lam[2]
            if lower[i]:
                t[i] = lo
                if t[i] - t_ref[i] - jl < -eps:       # multiplier of the lower bound < 0: release
                    lower[i] = False
                    stable = False
            elif upper[i]:
                t[i] = hi
                if t[i] - t_ref[i] - jl > eps:        # multiplier of the upper bound < 0: release
                    upper[i] = False
                    stable = False
            else:
                t[i] = t_ref[i] + jl
                if t[i] < lo - eps:
                    lower[i] = True
                    stable = False
                elif t[i] > hi + eps:
                    upper[i] = True
                    stable = False
        if stable:
            return OK
    return NOT_CONVERGED


@njit(cache=True)
def plan_batch(A, B, m, r, g, Rs, taus, t_ref, lo, hi, max_iter, T, J_out, tau_w_out, status):
    """Plan ``n`` poses in order, each warm-started from the previous active set."""
    n = Rs.shape[0]
    lower = np.zeros(6, dtype=np.bool_)
    upper = np.zeros(6, dtype=np.bool_)
    b = np.empty(3)
    for k in range(n):
        jacobian_into(A, B, Rs[k], J_out[k])
        weight_moment_into(m, r, g, Rs[k], tau_w_out[k])
        for p in range(3):
            b[p] = -(taus[k, p] + tau_w_out[k, p])
        status[k] = solve_one(J_out[k], b, t_ref[k], lo, hi, lower, upper, T[k], max_iter)
        if status[k] != OK:  # cold restart once before giving up on this pose
            lower[:] = False
            upper[:] = False
            status[k] = solve_one(J_out[k], b, t_ref[k], lo, hi, lower, upper, T[k], max_iter)
            if status[k] != OK:
                lower[:] = False
                upper[:] = False


@njit(cache=True)
def solve_rows(J, b, t_ref, lo, hi, lower, upper, max_iter, T, status):
    """:func:`solve_one` for each row independently (sets updated in place)."""
    for k in range(J.shape[0]):
        status[k] = solve_one(J[k], b[k], t_ref[k], lo, hi, lower[k], upper[k], T[k], max_iter)
