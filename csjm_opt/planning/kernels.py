"""Compiled (numba) active-set QP kernels of the planner, one pose or many.

The physics (cable geometry, J (38), weight moment) comes from the model
layer's kernels (:mod:`csjm_opt.model.kernels`); this module holds the
solvers:

* :func:`solve_one`: the tension QP ``min 1/2||t - t_ref||^2, J^T t = b,
  lo <= t <= hi`` by the primal-dual active set method (see
  :mod:`csjm_opt.planning.active_set`), specialised to the identity Hessian
  and three equality rows (3x3 Cramer solves, no allocation);
* :func:`plan_one` / :func:`plan_batch`: geometry + weight + QP + rest lengths
  for one pose, or for many in order, each warm-started from the previous
  pose's active set;
* :func:`pdas`: the same method for a general dense QP (symmetric positive
  definite ``P``), used by stiffness shaping (:mod:`csjm_opt.planning.dense_qp`
  adds a finite primal active-set fallback). It is not used for the tension QP:
  the specialised solver is ~4x faster there (benchmarks/bench_planner.py).

``tests/planning/test_kernels.py`` checks them against the CasADi model and SLSQP.
Compiled on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from ..model.kernels import det3 as _det3
from ..model.kernels import geometry_into, rotation_error, weight_moment_into

#: Status codes of :func:`solve_one`.
OK, SINGULAR, NOT_CONVERGED, BAD_INPUT = 0, 1, 2, 3


@njit(cache=True)
def solve_one(J, b, t_ref, lo, hi, lower, upper, t, max_iter):
    """Exact solution of min 1/2||t - t_ref||^2, J^T t = b, lo <= t <= hi.

    ``J`` is (m, 3) for m cables; ``lower``/``upper`` (bool, m) are the warm-start
    active sets and are updated in place; ``t`` (m,) receives the solution.
    Returns a status code. Work per iteration: O(m) (a 3x3 system).
    """
    n_cab = J.shape[0]
    scale = max(1.0, abs(hi))
    eps = 1e-10 * scale
    M = np.empty((3, 3))
    rhs = np.empty(3)
    lam = np.empty(3)
    for _ in range(max_iter):
        M[:] = 0.0
        rhs[:] = b
        for i in range(n_cab):
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
        for i in range(n_cab):
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
def _rest_lengths(k, c, T, l):
    for i in range(k.shape[0]):
        l[i] = c[i] - T[i] / k[i]


@njit(cache=True)
def plan_one(A, B, k, mr, g, R, tau_ext, t_ref, lo, hi, max_iter, T, J, tau_w, c, l, info):
    """Plan one pose cold: J, weight moment, the QP, cable and rest lengths. Returns a status.

    BAD_INPUT when ``R`` is not a rotation to 1e-12 or an input is not finite
    (the caller validates and calls again). ``info`` (2,) receives the
    equilibrium residual ``||J^T T + tau_load||`` (N m) and the largest bound
    violation (N) of the answer.
    """
    for p in range(3):
        if not np.isfinite(tau_ext[p]):
            return BAD_INPUT
        for q in range(3):
            if not np.isfinite(R[p, q]):
                return BAD_INPUT
    n_cab = A.shape[0]
    for i in range(n_cab):
        if not np.isfinite(t_ref[i]):
            return BAD_INPUT
    err, det = rotation_error(R)
    if err > 1e-12 or det <= 0.0:
        return BAD_INPUT
    U = np.empty((n_cab, 3))
    geometry_into(A, B, R, c, U, J)
    weight_moment_into(mr, g, R, tau_w)
    b = np.empty(3)
    for p in range(3):
        b[p] = -(tau_ext[p] + tau_w[p])
    lower = np.zeros(n_cab, dtype=np.bool_)
    upper = np.zeros(n_cab, dtype=np.bool_)
    status = solve_one(J, b, t_ref, lo, hi, lower, upper, T, max_iter)
    _rest_lengths(k, c, T, l)
    res = 0.0
    for p in range(3):
        r = -b[p]
        for i in range(n_cab):
            r += J[i, p] * T[i]
        res += r * r
    viol = 0.0
    for i in range(n_cab):
        viol = max(viol, lo - T[i], T[i] - hi)
    info[0] = np.sqrt(res)
    info[1] = viol
    return status


@njit(cache=True)
def plan_batch(A, B, k, mr, g, Rs, taus, t_ref, lo, hi, max_iter, T, J_out, tau_w_out, c_out, l_out, status):
    """Plan ``n`` poses in order, each warm-started from the previous active set."""
    n = Rs.shape[0]
    n_cab = A.shape[0]
    lower = np.zeros(n_cab, dtype=np.bool_)
    upper = np.zeros(n_cab, dtype=np.bool_)
    b = np.empty(3)
    U = np.empty((n_cab, 3))
    for s in range(n):
        geometry_into(A, B, Rs[s], c_out[s], U, J_out[s])
        weight_moment_into(mr, g, Rs[s], tau_w_out[s])
        for p in range(3):
            b[p] = -(taus[s, p] + tau_w_out[s, p])
        status[s] = solve_one(J_out[s], b, t_ref[s], lo, hi, lower, upper, T[s], max_iter)
        if status[s] != OK:  # cold restart once before giving up on this pose
            lower[:] = False
            upper[:] = False
            status[s] = solve_one(J_out[s], b, t_ref[s], lo, hi, lower, upper, T[s], max_iter)
            if status[s] != OK:
                lower[:] = False
                upper[:] = False
        _rest_lengths(k, c_out[s], T[s], l_out[s])


@njit(cache=True, parallel=True)
def plan_batch_par(A, B, k, mr, g, Rs, taus, t_ref, lo, hi, max_iter, T, J_out, tau_w_out, c_out, l_out,
                   status, n_chunks):
    """:func:`plan_batch` on ``n_chunks`` consecutive chunks in parallel (warm starts within a chunk)."""
    n = Rs.shape[0]
    for ch in prange(n_chunks):
        s = ch * n // n_chunks
        e = (ch + 1) * n // n_chunks
        plan_batch(A, B, k, mr, g, Rs[s:e], taus[s:e], t_ref[s:e], lo, hi, max_iter, T[s:e], J_out[s:e],
                   tau_w_out[s:e], c_out[s:e], l_out[s:e], status[s:e])


@njit(cache=True)
def solve_rows(J, b, t_ref, lo, hi, lower, upper, max_iter, T, status):
    """:func:`solve_one` for each row independently (sets updated in place)."""
    for k in range(J.shape[0]):
        status[k] = solve_one(J[k], b[k], t_ref[k], lo, hi, lower[k], upper[k], T[k], max_iter)


@njit(cache=True)
def pdas(P, q, A, b, lo, hi, lower, upper, max_iter, tol):
    """Primal-dual active set for a dense QP ``min 1/2 x^T P x + q^T x, A x = b, lo <= x <= hi``.

    Returns ``(x, nu, z, lower, upper, iterations, status)``; status 0 settled,
    1 singular KKT, 2 not settled (callers fall back to :mod:`csjm_opt.planning.dense_qp`).
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
def outside_margin(J, b, lo, hi):
    """Largest signed distance (N m) of ``b`` past a facet plane of the zonotope ``{J^T t}``.

    The zonotope of the box ``lo <= t <= hi`` under ``J^T`` (``J`` is m x 3) has its
    facet normals among the m (m - 1) / 2 cross products of pairs of rows of ``J``; ``b``
    can be held iff the margin is ``<= 0`` (up to round-off). Degenerate pairs
    (parallel rows) are skipped.
    """
    n_cab = J.shape[0]
    worst = -np.inf
    for i in range(n_cab):
        for j in range(i + 1, n_cab):
            gi, gj = J[i], J[j]
            n0 = gi[1] * gj[2] - gi[2] * gj[1]
            n1 = gi[2] * gj[0] - gi[0] * gj[2]
            n2 = gi[0] * gj[1] - gi[1] * gj[0]
            nn = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
            if not nn > 1e-12 * np.sqrt((gi @ gi) * (gj @ gj)):
                continue
            for s in (-1.0, 1.0):
                h = 0.0
                for k in range(n_cab):     # support function h(u) = sum_k max(lo u.g_k, hi u.g_k)
                    d = s * (n0 * J[k, 0] + n1 * J[k, 1] + n2 * J[k, 2])
                    h += hi * d if d > 0.0 else lo * d
                m = (s * (n0 * b[0] + n1 * b[1] + n2 * b[2]) - h) / nn
                if m > worst:
                    worst = m
    return worst


@njit(cache=True)
def _clamp(x, lo, hi):
    return lo if x < lo else (hi if x > hi else x)


@njit(cache=True)
def boundary_distance(J, b, lo, hi, t):
    """``min |J^T t - b|`` over the faces of dimension <= 2 of the box (N m); ``t`` gets the minimiser.

    For a load outside the zonotope ``{J^T t : lo <= t <= hi}`` the nearest
    point lies on its boundary, which is made of such faces: m (m - 1) / 2 pairs of free
    cables x 2^(m - 2) assignments of the others to their bounds (15 x 16 for m = 6), each a
    two-variable box least squares solved in closed form (interior stationary
    point if inside the square, else the four edges' clamped minimisers). For a
    load inside, this is the distance to the boundary, not zero: test with
    :func:`outside_margin` first. The generated C planner does the same.
    """
    n_cab = J.shape[0]
    best = np.inf
    r0 = np.empty(3)
    xs = np.empty(4)
    ys = np.empty(4)
    for i in range(n_cab):
        for j in range(i + 1, n_cab):
            gi, gj = J[i], J[j]
            a, c, bb = gi @ gi, gj @ gj, gi @ gj
            det = a * c - bb * bb
            inv_a = 1.0 / a if a > 0.0 else 0.0
            inv_c = 1.0 / c if c > 0.0 else 0.0
            inv_det = 1.0 / det if det > 1e-12 * a * c else 0.0
            for mask in range(1 << (n_cab - 2)):     # the other cables at lo (bit 0) or hi (bit 1)
                r0[:] = -b
                bit = 0
                for k in range(n_cab):
                    if k == i or k == j:
                        continue
                    tk = hi if (mask >> bit) & 1 else lo
                    bit += 1
                    r0 += tk * J[k]
                p, q = gi @ r0, gj @ r0
                n_cand = 4
                xs[0], ys[0] = lo, _clamp(-(q + bb * lo) * inv_c, lo, hi)
                xs[1], ys[1] = hi, _clamp(-(q + bb * hi) * inv_c, lo, hi)
                ys[2], xs[2] = lo, _clamp(-(p + bb * lo) * inv_a, lo, hi)
                ys[3], xs[3] = hi, _clamp(-(p + bb * hi) * inv_a, lo, hi)
                if inv_det > 0.0:
                    x = (-p * c + q * bb) * inv_det
                    y = (-q * a + p * bb) * inv_det
                    if lo <= x <= hi and lo <= y <= hi:
                        xs[0], ys[0], n_cand = x, y, 1
                for e in range(n_cand):
                    d = 0.0
                    for m in range(3):
                        v = r0[m] + xs[e] * gi[m] + ys[e] * gj[m]
                        d += v * v
                    if d < best:
                        best = d
                        bit = 0
                        for k in range(n_cab):
                            if k == i:
                                t[k] = xs[e]
                            elif k == j:
                                t[k] = ys[e]
                            else:
                                t[k] = hi if (mask >> bit) & 1 else lo
                                bit += 1
    return np.sqrt(best)
