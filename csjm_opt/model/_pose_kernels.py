"""Compiled (numba) cable physics at one pose: geometry, J (38), weight moment, K, checks.

The ``*_into`` functions write into arrays the caller owns (~1 us a call).
Re-exported by :mod:`csjm_opt.model.kernels`, whose docstring describes the conventions and
argument names; the stacked and parallel twins are in
:mod:`csjm_opt.model._batch_kernels`. Compiled on first use and cached on disk
(``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Status codes of :func:`checked_stiffness_into`.
OK, NOT_A_ROTATION, NON_FINITE = 0, 1, 2


@njit(cache=True)
def det3(M):
    """Determinant of a 3x3 matrix."""
    return (M[0, 0] * (M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1])
            - M[0, 1] * (M[1, 0] * M[2, 2] - M[1, 2] * M[2, 0])
            + M[0, 2] * (M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]))


@njit(cache=True)
def rotation_error(R):
    """(||R^T R - I||_F, det R) without allocating."""
    err = 0.0
    for i in range(3):
        for j in range(3):
            s = R[0, i] * R[0, j] + R[1, i] * R[1, j] + R[2, i] * R[2, j]
            if i == j:
                s -= 1.0
            err += s * s
    return np.sqrt(err), det3(R)


@njit(cache=True)
def geometry_into(A, B, R, c, U, J):
    """Cable lengths ``c`` (m,), unit vectors ``U`` in {A} (m, 3), J (m, 3) of (38); m = ``A.shape[0]``."""
    for i in range(A.shape[0]):
        # v = R^T b_i - a_i, the cable vector in {A}
        v0 = R[0, 0] * B[i, 0] + R[1, 0] * B[i, 1] + R[2, 0] * B[i, 2] - A[i, 0]
        v1 = R[0, 1] * B[i, 0] + R[1, 1] * B[i, 1] + R[2, 1] * B[i, 2] - A[i, 1]
        v2 = R[0, 2] * B[i, 0] + R[1, 2] * B[i, 1] + R[2, 2] * B[i, 2] - A[i, 2]
        ci = np.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        c[i] = ci
        u0, u1, u2 = v0 / ci, v1 / ci, v2 / ci
        U[i, 0], U[i, 1], U[i, 2] = u0, u1, u2
        J[i, 0] = A[i, 1] * u2 - A[i, 2] * u1
        J[i, 1] = A[i, 2] * u0 - A[i, 0] * u2
        J[i, 2] = A[i, 0] * u1 - A[i, 1] * u0


@njit(cache=True)
def weight_moment_into(mr, g, R, out):
    """``(m r) x (R^T g)``: moment of the force m g (in {B}) at r (in {A}), in {A}."""
    g0 = R[0, 0] * g[0] + R[1, 0] * g[1] + R[2, 0] * g[2]
    g1 = R[0, 1] * g[0] + R[1, 1] * g[1] + R[2, 1] * g[2]
    g2 = R[0, 2] * g[0] + R[1, 2] * g[1] + R[2, 2] * g[2]
    out[0] = mr[1] * g2 - mr[2] * g1
    out[1] = mr[2] * g0 - mr[0] * g2
    out[2] = mr[0] * g1 - mr[1] * g0


@njit(cache=True)
def stiffness_from_geometry_into(A, k, c, U, J, T, K):
    """K = sum_{t_i > 0} (k_i j_i j_i^T + t_i Hess(c_i)) into ``K`` (3, 3); t_i <= 0: slack."""
    for p in range(3):
        for q in range(3):
            K[p, q] = 0.0
    for i in range(A.shape[0]):
        t = T[i]
        if not t > 0.0:
            continue
        a0, a1, a2 = A[i, 0], A[i, 1], A[i, 2]
        u0, u1, u2 = U[i, 0], U[i, 1], U[i, 2]
        j0, j1, j2 = J[i, 0], J[i, 1], J[i, 2]
        tc = t / c[i]
        kt = k[i] - tc                       # coefficient of j j^T
        diag = tc * (a0 * a0 + a1 * a1 + a2 * a2) + t * (u0 * a0 + u1 * a1 + u2 * a2)
        h = 0.5 * t
        K[0, 0] += kt * j0 * j0 - tc * a0 * a0 - 2.0 * h * u0 * a0 + diag
        K[1, 1] += kt * j1 * j1 - tc * a1 * a1 - 2.0 * h * u1 * a1 + diag
        K[2, 2] += kt * j2 * j2 - tc * a2 * a2 - 2.0 * h * u2 * a2 + diag
        K[0, 1] += kt * j0 * j1 - tc * a0 * a1 - h * (u0 * a1 + a0 * u1)
        K[0, 2] += kt * j0 * j2 - tc * a0 * a2 - h * (u0 * a2 + a0 * u2)
        K[1, 2] += kt * j1 * j2 - tc * a1 * a2 - h * (u1 * a2 + a1 * u2)
    K[1, 0] = K[0, 1]
    K[2, 0] = K[0, 2]
    K[2, 1] = K[1, 2]


@njit(cache=True)
def stiffness_into(A, B, k, R, T, K):
    """K at one pose for tensions ``T`` (m,) into ``K`` (3, 3)."""
    m = A.shape[0]
    c = np.empty(m)
    U = np.empty((m, 3))
    J = np.empty((m, 3))
    geometry_into(A, B, R, c, U, J)
    stiffness_from_geometry_into(A, k, c, U, J, T, K)


@njit(cache=True)
def rest_terms_into(A, B, k, R, l, K, T, tau):
    """For rest lengths ``l``: tensions ``T = k (c - l)``, 0 when slack; ``tau = J^T T``; K."""
    m = A.shape[0]
    c = np.empty(m)
    U = np.empty((m, 3))
    J = np.empty((m, 3))
    geometry_into(A, B, R, c, U, J)
    for i in range(m):
        s = c[i] - l[i]
        T[i] = k[i] * s if s > 0.0 else 0.0
    for p in range(3):
        s = 0.0
        for i in range(m):
            s += J[i, p] * T[i]
        tau[p] = s
    stiffness_from_geometry_into(A, k, c, U, J, T, K)


@njit(cache=True)
def pose_terms_into(A, B, mr, g, R, c, J, tau_w):
    """What a controller needs per step without K: lengths, J and the weight moment."""
    U = np.empty((A.shape[0], 3))
    geometry_into(A, B, R, c, U, J)
    weight_moment_into(mr, g, R, tau_w)


@njit(cache=True)
def checked_stiffness_into(A, B, k, mr, g, R, T, t_lo, t_hi, tau_ext, check_eq, rot_tol, K, info):
    """K with the checks of :func:`csjm_opt.model.joint_stiffness.stiffness`, in one call.

    Returns a status code; ``info`` (2,) receives the largest bound violation
    (N) and the equilibrium residual ``||J^T T + tau_ext + tau_w||`` (N m, when
    ``check_eq``) of the taut cables (``T_i > 0``; slack ones are exempt). Bounds are not checked
    when ``t_lo > t_hi``.
    """
    for i in range(3):
        for j in range(3):
            if not np.isfinite(R[i, j]):
                return NON_FINITE
    m = A.shape[0]
    viol = 0.0
    for i in range(m):
        if not np.isfinite(T[i]):
            return NON_FINITE
        if t_lo <= t_hi and T[i] > 0.0:            # t <= 0: a slack cable, not a bound violation
            viol = max(viol, t_lo - T[i], T[i] - t_hi)
    info[0] = viol
    err, det = rotation_error(R)
    if err > rot_tol or det <= 0.0:
        return NOT_A_ROTATION
    c = np.empty(m)
    U = np.empty((m, 3))
    J = np.empty((m, 3))
    geometry_into(A, B, R, c, U, J)
    stiffness_from_geometry_into(A, k, c, U, J, T, K)
    info[1] = 0.0
    if check_eq:
        w = np.empty(3)
        weight_moment_into(mr, g, R, w)
        res = 0.0
        for p in range(3):
            s = tau_ext[p] + w[p]
            for i in range(m):
                s += J[i, p] * T[i]
            res += s * s
        info[1] = np.sqrt(res)
    return OK


@njit(cache=True)
def all_exact_rotations(Rs):
    """True when every (3, 3) of ``Rs`` is finite with ``||R^T R - I|| <= 1e-12`` and det > 0."""
    for n in range(Rs.shape[0]):
        for i in range(3):
            for j in range(3):
                if not np.isfinite(Rs[n, i, j]):
                    return False
        err, det = rotation_error(Rs[n])
        if err > 1e-12 or det <= 0.0:
            return False
    return True
