"""Range of directional stiffness reachable by shaping the tensions (an exact batched LP).

At a fixed pose and load, the tensions that hold the load form the polytope
``P = {T : J^T T = -tau_load, t_min <= T <= t_max}`` (6 unknowns, 3
equalities: a 3-dimensional polytope). The stiffness is affine in the
tensions, ``K(T) = K0 + sum_i T_i K_i`` (``K = J^T Kdiag J - D(T) + 1/2
hat(J^T T)``, csjm_opt.model.casadi_model), so the directional stiffness
``u^T K(T) u`` along a unit vector ``u`` is linear in T, and its range over P
is a pair of linear programs. Their optima lie at vertices of P, i.e. basic
feasible solutions: 3 basic tensions solved from the equilibrium with the
other 3 at a bound (20 bases x 8 bound patterns = 160 candidates per pose).
Enumerating them all, in numpy, solves every LP of a batch exactly and at
once; it also certifies feasibility (P is empty iff no candidate is valid).

It answers "what stiffness range can shaping reach here", not "which
tensions give this K" (that is :func:`csjm_opt.shaping.shaper.shape_stiffness`).
:func:`csjm_opt.shaping.reachable.directional_range` solves the same LPs one pose at a
time with HiGHS; this batched form is what a sweep over thousands of poses
needs, and tests/design/test_metrics.py checks the two agree.
"""

from __future__ import annotations

import functools
import itertools

import numpy as np
from numba import njit


@functools.cache
def _tables(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bases (3 basic cables), their non-basic cables and the 2^(m - 3) bound patterns of m cables.

    Shapes (C(m, 3), 3), (C(m, 3), m - 3), (2^(m - 3), m - 3): (20, 3), (20, 3), (8, 3) for m = 6.
    """
    bases = np.array(list(itertools.combinations(range(m), 3)), dtype=np.int64)
    nonbasic = np.array([[i for i in range(m) if i not in b] for b in bases], dtype=np.int64).reshape(len(bases), m - 3)
    patterns = np.array(list(itertools.product((0, 1), repeat=m - 3)), float).reshape(-1, m - 3)
    return bases, nonbasic, patterns

#: Unit directions in {A}: bending about x, bending about y, torsion about z (platform axis).
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def vertices(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float, t_max_N: float,
             tol_N: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """All basic solutions of P: tensions (n, V, m) and validity mask (n, V); V = 160 for m = 6."""
    J = np.asarray(J, float)
    n, m = J.shape[0], J.shape[1]
    bases, nonbasic, patterns = _tables(m)
    nb, npat = len(bases), len(patterns)
    w = -np.asarray(tau_load_A_Nm, float)                                   # (n, 3)
    t_nb = t_min_N + patterns * (t_max_N - t_min_N)                         # (8, 3) for m = 6
    A_b = np.swapaxes(J[:, bases, :], -1, -2)                               # (n, 20, 3, 3)
    A_nb = np.swapaxes(J[:, nonbasic, :], -1, -2)                           # (n, 20, 3, m - 3)
    rhs = w[:, None, None, :] - np.einsum("nbij,pj->nbpi", A_nb, t_nb)      # (n, 20, 8, 3)
    with np.errstate(divide="ignore", invalid="ignore"):   # singular bases are masked just below
        det = np.linalg.det(A_b)
    scale = np.prod(np.linalg.norm(A_b, axis=-2), axis=-1)
    regular = np.abs(det) > 1e-10 * np.maximum(scale, 1e-300)
    A_safe = np.where(regular[..., None, None], A_b, np.eye(3))
    t_b = np.linalg.solve(A_safe[:, :, None], rhs[..., None])[..., 0]      # (n, 20, 8, 3)
    ok = regular[:, :, None] & np.all((t_b >= t_min_N - tol_N) & (t_b <= t_max_N + tol_N), axis=-1)
    T = np.empty((n, nb, npat, m))
    for k in range(3):  # advanced indices (base, cable) split by a slice put their axis first
        T[:, np.arange(nb), :, bases[:, k]] = t_b[..., k].transpose(1, 0, 2)
    for k in range(m - 3):
        T[:, np.arange(nb), :, nonbasic[:, k]] = np.broadcast_to(t_nb[:, k], (nb, n, npat))
    return T.reshape(n, nb * npat, m), ok.reshape(n, nb * npat)


def directional_stiffness_range(J: np.ndarray, tau_load_A_Nm: np.ndarray, K0: np.ndarray,
                                K_per_N: np.ndarray, t_min_N: float, t_max_N: float,
                                directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Min and max of ``u^T K(T) u`` over feasible tensions, per pose and direction.

    ``K0`` (n, 3, 3) is K at zero tension, ``K_per_N`` (n, m, 3, 3) the change
    of K per newton of cable i, ``directions`` (d, 3) unit vectors in {A}.
    Returns ``(lo, hi)``, each (n, d), N m/rad; NaN where P is empty.
    """
    U = np.asarray(directions, float)
    c0 = np.einsum("dj,njk,dk->nd", U, K0, U)
    ci = np.ascontiguousarray(np.einsum("dj,nijk,dk->nid", U, K_per_N, U))
    lo = np.empty(c0.shape)
    hi = np.empty(c0.shape)
    J = np.ascontiguousarray(J, dtype=np.float64)
    w = -np.ascontiguousarray(tau_load_A_Nm, dtype=np.float64)
    m = np.shape(J)[1]
    if m <= EXHAUSTIVE_MAX_CABLES:
        _range_kernel(J, w, float(t_min_N), float(t_max_N), 1e-9, *_tables(m), c0, ci, lo, hi)
    else:
        _range_kernel_dual(J, w, float(t_min_N), float(t_max_N), 1e-9, _tables(m)[0], c0, ci, lo, hi)
    return lo, hi


#: Largest cable count whose range enumerates every basic solution (C(m, 3) 2^(m - 3) per pose); above it
#: each basis gives one candidate per direction and sense, its non-basic tensions on the bounds its reduced
#: costs choose (dual feasible), so a primal-feasible candidate is optimal: C(m, 3) per direction and sense.
EXHAUSTIVE_MAX_CABLES = 6


def directional_stiffness_range_reference(J: np.ndarray, tau_load_A_Nm: np.ndarray, K0: np.ndarray,
                                          K_per_N: np.ndarray, t_min_N: float, t_max_N: float,
                                          directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`directional_stiffness_range` from :func:`vertices` in numpy (the kernel's test reference)."""
    U = np.asarray(directions, float)
    T, ok = vertices(J, tau_load_A_Nm, t_min_N, t_max_N)
    c0 = np.einsum("dj,njk,dk->nd", U, K0, U)
    ci = np.einsum("dj,nijk,dk->nid", U, K_per_N, U)
    values = c0[:, None, :] + np.einsum("nvi,nid->nvd", T, ci)              # (n, V, d)
    lo = np.where(ok[..., None], values, np.inf).min(axis=1)
    hi = np.where(ok[..., None], values, -np.inf).max(axis=1)
    empty = ~ok.any(axis=1)
    lo[empty] = np.nan
    hi[empty] = np.nan
    return lo, hi


@njit(cache=True)
def _solve3(M, rhs, transpose):
    """``M x = rhs`` (or ``M^T x = rhs``) for a 3 x 3 matrix, LU with partial pivoting."""
    A = np.empty((3, 3))
    for p in range(3):
        for k in range(3):
            A[p, k] = M[k, p] if transpose else M[p, k]
    x = rhs.copy()
    for col in range(3):
        piv = col
        for row in range(col + 1, 3):
            if abs(A[row, col]) > abs(A[piv, col]):
                piv = row
        if piv != col:
            for k in range(3):
                A[col, k], A[piv, k] = A[piv, k], A[col, k]
            x[col], x[piv] = x[piv], x[col]
        for row in range(col + 1, 3):
            f = A[row, col] / A[col, col]
            for k in range(col, 3):
                A[row, k] -= f * A[col, k]
            x[row] -= f * x[col]
    for col in range(2, -1, -1):
        s = x[col]
        for k in range(col + 1, 3):
            s -= A[col, k] * x[k]
        x[col] = s / A[col, col]
    return x


@njit(cache=True)
def _basis_matrix(J, n, bases, b, M):
    """``M[p, k] = J[n, bases[b, k], p]`` (J_B^T); False when the basis is singular relative to its rows' lengths."""
    scale = 1.0
    for k in range(3):
        i = bases[b, k]
        scale *= np.sqrt(J[n, i, 0] ** 2 + J[n, i, 1] ** 2 + J[n, i, 2] ** 2)
    for p in range(3):
        for k in range(3):
            M[p, k] = J[n, bases[b, k], p]
    det = (M[0, 0] * (M[1, 1] * M[2, 2] - M[1, 2] * M[2, 1])
           - M[0, 1] * (M[1, 0] * M[2, 2] - M[1, 2] * M[2, 0])
           + M[0, 2] * (M[1, 0] * M[2, 1] - M[1, 1] * M[2, 0]))
    return abs(det) > 1e-10 * max(scale, 1e-300)


@njit(cache=True)
def _range_kernel_dual(J, w, t_min, t_max, tol, bases, c0, ci, lo, hi):
    """Per pose, basis, direction and sense: the dual-feasible basic solution; min/max over the primal-feasible ones.

    For the basis B (3 cables) the multipliers y solve ``J_B y = c_B`` (c: the direction's K per newton); a
    non-basic cable's reduced cost ``c_i - J_i . y`` puts it on t_min (minimum: positive cost) or t_max, and
    the basic tensions close the equilibrium. Such a solution within the box is optimal (LP duality); every
    other candidate is a feasible point, so it never undercuts the minimum (overshoots the maximum).
    """
    n_dir = c0.shape[1]
    n_cab = J.shape[1]
    M = np.empty((3, 3))
    cb = np.empty(3)
    r = np.empty(3)
    T = np.empty(n_cab)
    in_basis = np.zeros(n_cab, np.bool_)
    for n in range(J.shape[0]):
        for d in range(n_dir):
            lo[n, d] = np.inf
            hi[n, d] = -np.inf
        for b in range(bases.shape[0]):
            if not _basis_matrix(J, n, bases, b, M):
                continue
            for k in range(3):
                in_basis[bases[b, k]] = True
            for d in range(n_dir):
                for k in range(3):
                    cb[k] = ci[n, bases[b, k], d]
                y = _solve3(M, cb, True)                      # J_B y = c_B, J_B = M^T
                for sense in range(2):                         # 0: minimum, 1: maximum
                    for p in range(3):
                        r[p] = w[n, p]
                    for i in range(n_cab):
                        if in_basis[i]:
                            continue
                        red = ci[n, i, d] - (J[n, i, 0] * y[0] + J[n, i, 1] * y[1] + J[n, i, 2] * y[2])
                        t_i = t_min if (red > 0) == (sense == 0) else t_max
                        T[i] = t_i
                        for p in range(3):
                            r[p] -= J[n, i, p] * t_i
                    x = _solve3(M, r, False)
                    ok = True
                    for k in range(3):
                        if not (x[k] >= t_min - tol and x[k] <= t_max + tol):
                            ok = False
                        T[bases[b, k]] = x[k]
                    if not ok:
                        continue
                    v = c0[n, d]
                    for i in range(n_cab):
                        v += T[i] * ci[n, i, d]
                    if sense == 0:
                        lo[n, d] = min(lo[n, d], v)
                    else:
                        hi[n, d] = max(hi[n, d], v)
            for k in range(3):
                in_basis[bases[b, k]] = False
        for d in range(n_dir):
            if lo[n, d] == np.inf or hi[n, d] == -np.inf:
                lo[n, d] = np.nan
                hi[n, d] = np.nan


@njit(cache=True)
def _range_kernel(J, w, t_min, t_max, tol, bases, nonbasic, patterns, c0, ci, lo, hi):
    """Per pose: every basic solution (3 basic tensions by LU with partial pivoting), min/max of c0 + T.ci."""
    n_dir = c0.shape[1]
    M = np.empty((3, 3))
    r = np.empty(3)
    n_cab = J.shape[1]
    n_nb = nonbasic.shape[1]
    T = np.empty(n_cab)
    for n in range(J.shape[0]):
        for d in range(n_dir):
            lo[n, d] = np.inf
            hi[n, d] = -np.inf
        found = False
        for b in range(bases.shape[0]):
            if not _basis_matrix(J, n, bases, b, M):
                continue
            for q in range(patterns.shape[0]):
                for p in range(3):
                    s = w[n, p]
                    for k in range(n_nb):
                        t_nb = t_min + patterns[q, k] * (t_max - t_min)
                        T[nonbasic[b, k]] = t_nb
                        s -= J[n, nonbasic[b, k], p] * t_nb
                    r[p] = s
                x = _solve3(M, r, False)                  # the same LU with partial pivoting
                ok = True
                for k in range(3):
                    if not (x[k] >= t_min - tol and x[k] <= t_max + tol):
                        ok = False
                    T[bases[b, k]] = x[k]
                if not ok:
                    continue
                found = True
                for d in range(n_dir):
                    v = c0[n, d]
                    for i in range(n_cab):
                        v += T[i] * ci[n, i, d]
                    lo[n, d] = min(lo[n, d], v)
                    hi[n, d] = max(hi[n, d], v)
        if not found:
            for d in range(n_dir):
                lo[n, d] = np.nan
                hi[n, d] = np.nan
