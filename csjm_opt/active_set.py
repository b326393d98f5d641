"""Batched exact solver for the tension QP (primal-dual active set).

Solves, for each of ``n`` problems at once (numpy, no Python loop over poses)::

    minimise    1/2 ||t - t_ref||^2
    subject to  A t = b            (A = J^T, 3 x 6: equilibrium)
                lo <= t <= hi      (tension bounds)

by the primal-dual active set method (Hintermueller, Ito & Kunisch, SIAM J.
Optim. 13(3), 2002): guess which bounds are active, solve the equality-
constrained KKT system exactly, update the guess from primal violations and
multiplier signs, repeat until the guess is stable. The answer is exact to
round-off, so it also serves as the polishing step after OSQP. Rows that do
not converge are reported so the caller can fall back to a general solver.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass
class ActiveSetResult:
    """Per-row result: ``t`` (n, 6), ``converged`` (n,), ``lower``/``upper`` active masks."""

    t: np.ndarray
    lam: np.ndarray
    converged: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    iterations: int


def solve(A: np.ndarray, b: np.ndarray, t_ref: np.ndarray, lo: np.ndarray, hi: np.ndarray,
          lower0: np.ndarray | None = None, upper0: np.ndarray | None = None,
          max_iter: int = 40, tol: float = 1e-10) -> ActiveSetResult:
    """Solve the batch; ``lower0``/``upper0`` warm-start the active sets (n, 6) bool."""
    n, m = t_ref.shape
    lo = np.broadcast_to(lo, (n, m))
    hi = np.broadcast_to(hi, (n, m))
    lower = np.zeros((n, m), bool) if lower0 is None else lower0.copy()
    upper = np.zeros((n, m), bool) if upper0 is None else upper0.copy()
    upper &= ~lower
    scale = max(1.0, float(np.max(np.abs(hi))))
    converged = np.zeros(n, bool)
    t = t_ref.copy()
    lam = np.zeros((n, A.shape[1]))
    it = 0
    for it in range(1, max_iter + 1):
        t, lam, ok = _kkt(A, b, t_ref, lo, hi, lower, upper)
        # KKT: t - t_ref - A^T lam = nu_lo - nu_hi with nu_lo, nu_hi >= 0 on their bounds.
        grad = t - t_ref - np.einsum("nij,ni->nj", A, lam)
        free = ~(lower | upper)
        eps = tol * scale
        new_lower = (lower & (grad >= -eps)) | (free & (t < lo - eps))
        new_upper = (upper & (grad <= eps)) | (free & (t > hi + eps))
        new_upper &= ~new_lower
        stable = ok & np.all(new_lower == lower, axis=1) & np.all(new_upper == upper, axis=1)
        converged = stable
        if np.all(converged):
            break
        lower = np.where(converged[:, None], lower, new_lower)
        upper = np.where(converged[:, None], upper, new_upper)
    return ActiveSetResult(t=t, lam=lam, converged=converged, lower=lower, upper=upper, iterations=it)


def _kkt(A: np.ndarray, b: np.ndarray, t_ref: np.ndarray, lo: np.ndarray, hi: np.ndarray,
         lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact solution of the KKT system for fixed active sets.

    Free tensions are ``t_ref + (A^T lam)``; fixed ones sit on their bound;
    ``lam`` solves ``(A_F A_F^T) lam = b - A t_fixed - A_F t_ref_F``.
    """
    free = ~(lower | upper)
    fixed = np.where(lower, lo, 0.0) + np.where(upper, hi, 0.0)
    AF = A * free[:, None, :]
    M = AF @ np.swapaxes(AF, 1, 2)                     # (n, 3, 3)
    rhs = b - np.einsum("nij,nj->ni", A, fixed) - np.einsum("nij,nj->ni", AF, t_ref)
    # Rank check: fewer than three free directions cannot meet equilibrium in general.
    cond_ok = np.linalg.cond(M) < 1e12
    M_safe = np.where(cond_ok[:, None, None], M, np.eye(M.shape[1]))
    lam = np.linalg.solve(M_safe, rhs[..., None])[..., 0]
    t = np.where(free, t_ref + np.einsum("nij,ni->nj", A, lam), fixed)
    return t, lam, cond_ok
