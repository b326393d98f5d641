"""Compiled (numba) cable physics for stacks of poses: ``*_many`` (serial) and ``*_many_par``.

Each ``*_many`` loops the one-pose kernels of :mod:`csjm_opt.model._pose_kernels`
over poses; each ``*_many_par`` runs its serial twin on chunks of poses in
parallel (``prange``), for large batches called from the main thread (see
:func:`csjm_opt.model.numeric.parallel_ok`). Re-exported by
:mod:`csjm_opt.model.kernels`. Compiled on first use and cached on disk
(``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ._pose_kernels import geometry_into, rest_terms_into, stiffness_from_geometry_into, weight_moment_into


# ------------------------------------------------------------------ many poses
@njit(cache=True)
def geometry_many(A, B, Rs, c, J):
    """Lengths ``c`` (n, m) and J (n, m, 3) for poses ``Rs`` (n, 3, 3)."""
    U = np.empty((A.shape[0], 3))
    for n in range(Rs.shape[0]):
        geometry_into(A, B, Rs[n], c[n], U, J[n])


@njit(cache=True)
def weight_moment_many(mr, g, Rs, out):
    """Weight moments (n, 3) for poses ``Rs``."""
    for n in range(Rs.shape[0]):
        weight_moment_into(mr, g, Rs[n], out[n])


@njit(cache=True)
def stiffness_many(A, B, k, Rs, Ts, Ks):
    """K (n, 3, 3) for poses ``Rs`` (n, 3, 3) and tensions ``Ts`` (n, m)."""
    m = A.shape[0]
    c = np.empty(m)
    U = np.empty((m, 3))
    J = np.empty((m, 3))
    for n in range(Rs.shape[0]):
        geometry_into(A, B, Rs[n], c, U, J)
        stiffness_from_geometry_into(A, k, c, U, J, Ts[n], Ks[n])


@njit(cache=True)
def rest_terms_many(A, B, k, Rs, ls, Ks, Ts, taus):
    """:func:`rest_terms_into` for every pose; ``ls`` (n, m)."""
    for n in range(Rs.shape[0]):
        rest_terms_into(A, B, k, Rs[n], ls[n], Ks[n], Ts[n], taus[n])


@njit(cache=True)
def stiffness_basis_many(A, B, k, Rs, K0, G):
    """``K(T) = K0 + sum_i T_i G_i`` (all cables taut): K0 (n, 3, 3), G (n, m, 3, 3)."""
    m = A.shape[0]
    c = np.empty(m)
    U = np.empty((m, 3))
    J = np.empty((m, 3))
    e = np.zeros(m)
    zero_k = np.zeros(m)
    for n in range(Rs.shape[0]):
        geometry_into(A, B, Rs[n], c, U, J)
        # K0 = J^T diag(k) J; G_i = Hess(c_i) = K of cable i alone at unit tension and zero stiffness
        for p in range(3):
            for q in range(3):
                s = 0.0
                for i in range(m):
                    s += k[i] * J[i, p] * J[i, q]
                K0[n, p, q] = s
        for i in range(m):
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
