"""Compiled (numba) cable physics: geometry, J (38), weight moment, K, one pose or many.

The same closed forms as the numpy reference :mod:`csjm_opt.model.cable_terms`
(read its docstring for the formulas), written as loops that allocate
nothing: ``*_into`` functions write into arrays the caller owns, so a
controller can call them every step at a cost of ~1 us. The ``*_many``
functions loop over poses; their ``*_many_par`` twins do the same in
parallel (``prange``, ``NUMBA_NUM_THREADS`` threads), for large batches
called from the main thread (the workqueue threading layer must not be
entered from two threads at once; see :func:`csjm_opt.model.numeric.parallel_ok`).
``tests/test_stiffness_kernel.py`` checks every kernel against the numpy reference,
the CasADi model and a finite-difference energy Hessian.
Compiled on first use and cached on disk (``cache=True``).

Argument names: ``A`` (6, 3) platform holes in {A}, ``B`` (6, 3) base holes
in {B}, ``k`` (6,) cable stiffness, ``m r`` the first moment of the platform's
mass (kg m) in {A} and ``g`` gravity in {B}; ``R`` (3, 3) or ``Rs`` (n, 3, 3).
"""

from __future__ import annotations

import os

import numba
import numpy as np
from numba import njit, prange

# The parallel kernels run in processes that a sweep may fork; GNU OpenMP aborts
# on fork(), the workqueue layer does not (set NUMBA_THREADING_LAYER to override).
if "NUMBA_THREADING_LAYER" not in os.environ:
    numba.config.THREADING_LAYER = "workqueue"  # type: ignore[attr-defined]

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
    """Cable lengths ``c`` (6,), unit vectors ``U`` in {A} (6, 3), J (6, 3) of (38)."""
    for i in range(6):
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
    for i in range(6):
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
    """K at one pose for tensions ``T`` (6,) into ``K`` (3, 3)."""
    c = np.empty(6)
    U = np.empty((6, 3))
    J = np.empty((6, 3))
    geometry_into(A, B, R, c, U, J)
    stiffness_from_geometry_into(A, k, c, U, J, T, K)


@njit(cache=True)
def rest_terms_into(A, B, k, R, l, K, T, tau):
    """For rest lengths ``l``: tensions ``T = k (c - l)``, 0 when slack; ``tau = J^T T``; K."""
    c = np.empty(6)
    U = np.empty((6, 3))
    J = np.empty((6, 3))
    geometry_into(A, B, R, c, U, J)
    for i in range(6):
        s = c[i] - l[i]
        T[i] = k[i] * s if s > 0.0 else 0.0
    for p in range(3):
        tau[p] = J[0, p] * T[0] + J[1, p] * T[1] + J[2, p] * T[2] + J[3, p] * T[3] + J[4, p] * T[4] \
            + J[5, p] * T[5]
    stiffness_from_geometry_into(A, k, c, U, J, T, K)


@njit(cache=True)
def pose_terms_into(A, B, mr, g, R, c, J, tau_w):
    """What a controller needs per step without K: lengths, J and the weight moment."""
    U = np.empty((6, 3))
    geometry_into(A, B, R, c, U, J)
    weight_moment_into(mr, g, R, tau_w)


@njit(cache=True)
def checked_stiffness_into(A, B, k, mr, g, R, T, t_lo, t_hi, tau_ext, check_eq, rot_tol, K, info):
    """K with the checks of :func:`csjm_opt.model.stiffness.stiffness`, in one call.

    Returns a status code; ``info`` (2,) receives the largest bound violation
    (N) and the equilibrium residual ``||J^T T + tau_ext + tau_w||`` (N m, when
    ``check_eq``) of the taut cables (``T_i > 0``; slack ones are exempt). Bounds are not checked
    when ``t_lo > t_hi``.
    """
    for i in range(3):
        for j in range(3):
            if not np.isfinite(R[i, j]):
                return NON_FINITE
    viol = 0.0
    for i in range(6):
        if not np.isfinite(T[i]):
            return NON_FINITE
        if t_lo <= t_hi and T[i] > 0.0:            # t <= 0: a slack cable, not a bound violation
            viol = max(viol, t_lo - T[i], T[i] - t_hi)
    info[0] = viol
    err, det = rotation_error(R)
    if err > rot_tol or det <= 0.0:
        return NOT_A_ROTATION
    c = np.empty(6)
    U = np.empty((6, 3))
    J = np.empty((6, 3))
    geometry_into(A, B, R, c, U, J)
    stiffness_from_geometry_into(A, k, c, U, J, T, K)
    info[1] = 0.0
    if check_eq:
        w = np.empty(3)
        weight_moment_into(mr, g, R, w)
        res = 0.0
        for p in range(3):
            s = tau_ext[p] + w[p]
            for i in range(6):
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


# ------------------------------------------------------------------ many poses
@njit(cache=True)
def geometry_many(A, B, Rs, c, J):
    """Lengths ``c`` (n, 6) and J (n, 6, 3) for poses ``Rs`` (n, 3, 3)."""
    U = np.empty((6, 3))
    for n in range(Rs.shape[0]):
        geometry_into(A, B, Rs[n], c[n], U, J[n])


@njit(cache=True)
def weight_moment_many(mr, g, Rs, out):
    """Weight moments (n, 3) for poses ``Rs``."""
    for n in range(Rs.shape[0]):
        weight_moment_into(mr, g, Rs[n], out[n])


@njit(cache=True)
def stiffness_many(A, B, k, Rs, Ts, Ks):
    """K (n, 3, 3) for poses ``Rs`` (n, 3, 3) and tensions ``Ts`` (n, 6)."""
    c = np.empty(6)
    U = np.empty((6, 3))
    J = np.empty((6, 3))
    for n in range(Rs.shape[0]):
        geometry_into(A, B, Rs[n], c, U, J)
        stiffness_from_geometry_into(A, k, c, U, J, Ts[n], Ks[n])


@njit(cache=True)
def rest_terms_many(A, B, k, Rs, ls, Ks, Ts, taus):
    """:func:`rest_terms_into` for every pose; ``ls`` (n, 6)."""
    for n in range(Rs.shape[0]):
        rest_terms_into(A, B, k, Rs[n], ls[n], Ks[n], Ts[n], taus[n])


@njit(cache=True)
def stiffness_basis_many(A, B, k, Rs, K0, G):
    """``K(T) = K0 + sum_i T_i G_i`` (all cables taut): K0 (n, 3, 3), G (n, 6, 3, 3)."""
    c = np.empty(6)
    U = np.empty((6, 3))
    J = np.empty((6, 3))
    e = np.zeros(6)
    zero_k = np.zeros(6)
    for n in range(Rs.shape[0]):
        geometry_into(A, B, Rs[n], c, U, J)
        # K0 = J^T diag(k) J; G_i = Hess(c_i) = K of cable i alone at unit tension and zero stiffness
        for p in range(3):
            for q in range(3):
                s = 0.0
                for i in range(6):
                    s += k[i] * J[i, p] * J[i, q]
                K0[n, p, q] = s
        for i in range(6):
            e[i] = 1.0
            stiffness_from_geometry_into(A, zero_k, c, U, J, e, G[n, i])
            e[i] = 0.0


# ------------------------------------------------- many poses, parallel (main thread)
# Each runs its serial twin on consecutive chunks of poses, one chunk per prange iteration.
_CHUNKS = 64


@njit(cache=True, parallel=True)
def geometry_many_par(A, B, Rs, c, J):
    """:func:`geometry_many` in parallel."""
    n = Rs.shape[0]
    for ch in prange(_CHUNKS):
        s, e = ch * n // _CHUNKS, (ch + 1) * n // _CHUNKS
        geometry_many(A, B, Rs[s:e], c[s:e], J[s:e])


@njit(cache=True, parallel=True)
def weight_moment_many_par(mr, g, Rs, out):
    """:func:`weight_moment_many` in parallel."""
    n = Rs.shape[0]
    for ch in prange(_CHUNKS):
        s, e = ch * n // _CHUNKS, (ch + 1) * n // _CHUNKS
        weight_moment_many(mr, g, Rs[s:e], out[s:e])


@njit(cache=True, parallel=True)
def stiffness_many_par(A, B, k, Rs, Ts, Ks):
    """:func:`stiffness_many` in parallel."""
    n = Rs.shape[0]
    for ch in prange(_CHUNKS):
        s, e = ch * n // _CHUNKS, (ch + 1) * n // _CHUNKS
        stiffness_many(A, B, k, Rs[s:e], Ts[s:e], Ks[s:e])


@njit(cache=True, parallel=True)
def rest_terms_many_par(A, B, k, Rs, ls, Ks, Ts, taus):
    """:func:`rest_terms_many` in parallel."""
    n = Rs.shape[0]
    for ch in prange(_CHUNKS):
        s, e = ch * n // _CHUNKS, (ch + 1) * n // _CHUNKS
        rest_terms_many(A, B, k, Rs[s:e], ls[s:e], Ks[s:e], Ts[s:e], taus[s:e])


@njit(cache=True, parallel=True)
def stiffness_basis_many_par(A, B, k, Rs, K0, G):
    """:func:`stiffness_basis_many` in parallel."""
    n = Rs.shape[0]
    for ch in prange(_CHUNKS):
        s, e = ch * n // _CHUNKS, (ch + 1) * n // _CHUNKS
        stiffness_basis_many(A, B, k, Rs[s:e], K0[s:e], G[s:e])
