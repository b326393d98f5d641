"""Exact, vectorised wrench feasibility: whether a load lies inside the available moment set.

At a pose with Jacobian ``J`` (6, 3), the moments the cables can exert with
tensions in the box ``[t_min, t_max]^6`` form the zonotope::

    Z = { J^T T : t_min <= T <= t_max } = J^T t_mid + sum_i [-h, h] g_i,
    g_i = J[i] (row i),  t_mid = (t_min + t_max) / 2,  h = (t_max - t_min) / 2.

A load ``tau_load`` (in {A}, weight included) can be held iff
``w = -tau_load`` lies in Z (equilibrium ``J^T T + tau_load = 0``). A
full-dimensional zonotope in R^3 is the intersection of the slabs whose
normals are the cross products ``n = g_a x g_b`` of generator pairs (every
facet is spanned by two generators, and every slab ``|n.(w - c)| <= h sum_i
|n.g_i|`` is supporting), so 15 slab tests per pose decide feasibility
exactly, with no iteration and no solver. For unit normals, the smallest
slack is the distance from ``w`` to the boundary of Z when ``w`` is inside:
the *wrench margin* (N m), known in the cable-robot literature as the
capacity margin. Outside Z it is negative (its magnitude is then a lower
bound on the distance). A Jacobian of rank < 3 gives ``-inf``.
"""

from __future__ import annotations

import itertools

import numpy as np
from numba import njit


def _pairs(m: int) -> np.ndarray:
    """Index pairs (i < j) of m cables, (m (m - 1) / 2, 2): the candidate facet normals j_i x j_k."""
    return np.array(list(itertools.combinations(range(m), 2)), dtype=np.int64).reshape(-1, 2)

#: Relative flatness below which the moment set counts as rank deficient (J of rank < 3).
RANK_TOL = 1e-9


def wrench_margin_Nm(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float,
                     t_max_N: float) -> np.ndarray:
    """Signed distance (N m) of ``-tau_load`` inside the available moment zonotope.

    ``J`` is (n, m_c, 3) for m_c cables; ``tau_load_A_Nm`` is (n, 3) or (n, m, 3) for ``m``
    loads per pose. Returns (n,) or (n, m). Feasible iff the result is >= 0
    (use a small negative tolerance for round-off). Compiled
    (:func:`_margin_kernel`); :func:`wrench_margin_reference` is the same
    computation in numpy, kept as the test reference.
    """
    J = np.ascontiguousarray(J, dtype=np.float64)
    tau = np.asarray(tau_load_A_Nm, float)
    single = tau.ndim == 2
    tau = np.ascontiguousarray(tau[:, None, :] if single else tau)
    out = np.empty(tau.shape[:2])
    _margin_kernel(J, tau, float(t_min_N), float(t_max_N), RANK_TOL, _pairs(J.shape[1]), out)
    return out[:, 0] if single else out


@njit(cache=True)
def _margin_kernel(J, tau, t_min, t_max, rank_tol, pairs, out):
    h = 0.5 * (t_max - t_min)
    mid = 0.5 * (t_min + t_max)
    n_loads = tau.shape[1]
    n_cab = J.shape[1]
    n_pairs = pairs.shape[0]
    unit = np.empty((n_pairs, 3))
    width = np.empty(n_pairs)
    valid = np.empty(n_pairs, np.bool_)
    for n in range(J.shape[0]):
        G = J[n]
        g_max = 0.0
        c0 = c1 = c2 = 0.0
        for i in range(n_cab):
            g_max = max(g_max, np.sqrt(G[i, 0] ** 2 + G[i, 1] ** 2 + G[i, 2] ** 2))
            c0 += G[i, 0]
            c1 += G[i, 1]
            c2 += G[i, 2]
        c0, c1, c2 = mid * c0, mid * c1, mid * c2
        w_max = 0.0
        for p in range(n_pairs):
            a, b = pairs[p, 0], pairs[p, 1]
            n0 = G[a, 1] * G[b, 2] - G[a, 2] * G[b, 1]
            n1 = G[a, 2] * G[b, 0] - G[a, 0] * G[b, 2]
            n2 = G[a, 0] * G[b, 1] - G[a, 1] * G[b, 0]
            norm = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
            scale = np.sqrt(G[a, 0] ** 2 + G[a, 1] ** 2 + G[a, 2] ** 2) \
                * np.sqrt(G[b, 0] ** 2 + G[b, 1] ** 2 + G[b, 2] ** 2)
            valid[p] = norm > 1e-12 * max(scale, 1e-300)
            if valid[p]:
                unit[p, 0], unit[p, 1], unit[p, 2] = n0 / norm, n1 / norm, n2 / norm
                w = 0.0
                for i in range(n_cab):
                    w += abs(unit[p, 0] * G[i, 0] + unit[p, 1] * G[i, 1] + unit[p, 2] * G[i, 2])
                width[p] = w
                w_max = max(w_max, w)
        flat = w_max <= rank_tol * max(g_max, 1e-300)
        for m in range(n_loads):
            if flat:
                out[n, m] = -np.inf
                continue
            d0 = -tau[n, m, 0] - c0
            d1 = -tau[n, m, 1] - c1
            d2 = -tau[n, m, 2] - c2
            best = np.inf
            for p in range(n_pairs):
                if valid[p]:
                    off = d0 * unit[p, 0] + d1 * unit[p, 1] + d2 * unit[p, 2]
                    best = min(best, h * width[p] - abs(off))
            out[n, m] = best


def wrench_margin_reference(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float,
                            t_max_N: float) -> np.ndarray:
    """:func:`wrench_margin_Nm` in vectorised numpy (the reference the kernel is tested against)."""
    J = np.asarray(J, float)
    tau = np.asarray(tau_load_A_Nm, float)
    single = tau.ndim == 2
    if single:
        tau = tau[:, None, :]
    pairs = _pairs(J.shape[1])
    g_a, g_b = J[:, pairs[:, 0]], J[:, pairs[:, 1]]
    normals = np.cross(g_a, g_b)                                           # (n, 15, 3)
    norms = np.linalg.norm(normals, axis=-1)
    scale = np.linalg.norm(g_a, axis=-1) * np.linalg.norm(g_b, axis=-1)
    valid = norms > 1e-12 * np.maximum(scale, 1e-300)
    unit = normals / np.where(valid, norms, 1.0)[..., None]
    h = 0.5 * (t_max_N - t_min_N)
    width = np.abs(unit @ np.swapaxes(J, 1, 2)).sum(axis=-1)              # (n, 15): sum_i |n.g_i|
    centre = 0.5 * (t_min_N + t_max_N) * J.sum(axis=1)                     # J^T t_mid, (n, 3)
    offset = (-tau - centre[:, None, :]) @ np.swapaxes(unit, 1, 2)         # (n, m, 15)
    slack = np.where(valid[:, None, :], h * width[:, None, :] - np.abs(offset), np.inf)
    margin = slack.min(axis=-1)
    # rank < 3: every valid normal is the one plane normal and no generator leaves the plane
    g_max = np.linalg.norm(J, axis=-1).max(axis=-1)
    flat = np.where(valid, width, 0.0).max(axis=-1) <= RANK_TOL * np.maximum(g_max, 1e-300)
    margin = np.where(flat[:, None], -np.inf, margin)
    return margin[:, 0] if single else margin


def feasible(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float, t_max_N: float,
             tol_Nm: float = 1e-9) -> np.ndarray:
    """Boolean verdict of :func:`wrench_margin_Nm` (``margin >= -tol_Nm``)."""
    return wrench_margin_Nm(J, tau_load_A_Nm, t_min_N, t_max_N) >= -tol_Nm
