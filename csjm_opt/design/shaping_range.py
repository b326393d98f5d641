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
needs, and tests/test_design_metrics.py checks the two agree.
"""

from __future__ import annotations

import itertools

import numpy as np

_BASES = np.array(list(itertools.combinations(range(6), 3)))          # (20, 3)
_NONBASIC = np.array([[i for i in range(6) if i not in b] for b in _BASES])  # (20, 3)
_PATTERNS = np.array(list(itertools.product((0, 1), repeat=3)), float)  # (8, 3)

#: Unit directions in {A}: bending about x, bending about y, torsion about z (platform axis).
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def vertices(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float, t_max_N: float,
             tol_N: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """All basic solutions of P: tensions (n, 160, 6) and validity mask (n, 160)."""
    J = np.asarray(J, float)
    n = J.shape[0]
    w = -np.asarray(tau_load_A_Nm, float)                                   # (n, 3)
    t_nb = t_min_N + _PATTERNS * (t_max_N - t_min_N)                        # (8, 3)
    A_b = np.swapaxes(J[:, _BASES, :], -1, -2)                              # (n, 20, 3, 3)
    A_nb = np.swapaxes(J[:, _NONBASIC, :], -1, -2)                          # (n, 20, 3, 3)
    rhs = w[:, None, None, :] - np.einsum("nbij,pj->nbpi", A_nb, t_nb)      # (n, 20, 8, 3)
    det = np.linalg.det(A_b)
    scale = np.prod(np.linalg.norm(A_b, axis=-2), axis=-1)
    regular = np.abs(det) > 1e-10 * np.maximum(scale, 1e-300)
    A_safe = np.where(regular[..., None, None], A_b, np.eye(3))
    t_b = np.linalg.solve(A_safe[:, :, None], rhs[..., None])[..., 0]      # (n, 20, 8, 3)
    ok = regular[:, :, None] & np.all((t_b >= t_min_N - tol_N) & (t_b <= t_max_N + tol_N), axis=-1)
    T = np.empty((n, 20, 8, 6))
    for k in range(3):  # advanced indices (base, cable) split by a slice put their axis first
        T[:, np.arange(20), :, _BASES[:, k]] = t_b[..., k].transpose(1, 0, 2)
        T[:, np.arange(20), :, _NONBASIC[:, k]] = np.broadcast_to(t_nb[:, k], (20, n, 8))
    return T.reshape(n, 160, 6), ok.reshape(n, 160)


def directional_stiffness_range(J: np.ndarray, tau_load_A_Nm: np.ndarray, K0: np.ndarray,
                                K_per_N: np.ndarray, t_min_N: float, t_max_N: float,
                                directions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Min and max of ``u^T K(T) u`` over feasible tensions, per pose and direction.

    ``K0`` (n, 3, 3) is K at zero tension, ``K_per_N`` (n, 6, 3, 3) the change
    of K per newton of cable i, ``directions`` (d, 3) unit vectors in {A}.
    Returns ``(lo, hi)``, each (n, d), N m/rad; NaN where P is empty.
    """
    U = np.asarray(directions, float)
    T, ok = vertices(J, tau_load_A_Nm, t_min_N, t_max_N)
    c0 = np.einsum("dj,njk,dk->nd", U, K0, U)
    ci = np.einsum("dj,nijk,dk->nid", U, K_per_N, U)
    values = c0[:, None, :] + np.einsum("nvi,nid->nvd", T, ci)              # (n, 160, d)
    lo = np.where(ok[..., None], values, np.inf).min(axis=1)
    hi = np.where(ok[..., None], values, -np.inf).max(axis=1)
    empty = ~ok.any(axis=1)
    lo[empty] = np.nan
    hi[empty] = np.nan
    return lo, hi
