"""Exact solver for small dense QPs with equality and box constraints.

Solves::

    minimise    1/2 x^T P x + q^T x          (P symmetric positive definite)
    subject to  A x = b                       (A: m x n, full row rank)
                lo <= x <= hi

for the handful of variables of a stiffness-shaping problem (n = m, the cable count), fast
enough for a 1 kHz loop and exact to round-off (it also polishes the answer
of an iterative solver such as OSQP). Two methods:

1. Primal-dual active set (Hintermueller, Ito & Kunisch 2002), warm-started
   from a guessed active set (the previous solution along a trajectory):
   usually one or two KKT solves, compiled (:func:`csjm_opt.planning.kernels.pdas`).
   It can cycle for a general ``P``, so
2. if it does not settle in a few iterations, the primal active-set method
   (Nocedal & Wright, Numerical Optimization, Alg. 16.3) from a feasible
   point, which terminates finitely.

Every result's KKT conditions are checked (:meth:`DenseQPResult.kkt_error`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from . import kernels as kernels
from .active_set import solve as _project_box_eq


@dataclasses.dataclass(frozen=True, eq=False)
class DenseQPResult:
    """Solution ``x``, equality multipliers ``nu`` and bound multipliers ``z``.

    Stationarity: ``P x + q + A^T nu = z`` with ``z >= 0`` at lower bounds,
    ``z <= 0`` at upper bounds, ``z = 0`` for free variables.
    """

    x: np.ndarray
    nu: np.ndarray
    z: np.ndarray
    lower: np.ndarray       # (n,) bool, at lower bound
    upper: np.ndarray       # (n,) bool, at upper bound
    iterations: int
    method: str             # "pdas" or "primal"
    converged: bool

    def kkt_error(self, P: np.ndarray, q: np.ndarray, A: np.ndarray, b: np.ndarray,
                  lo: np.ndarray, hi: np.ndarray) -> float:
        """Largest violation of primal feasibility, stationarity and dual signs."""
        x, z = self.x, self.z
        stat = P @ x + q + A.T @ self.nu - z
        free = ~(self.lower | self.upper)
        viol = [np.abs(A @ x - b).max(initial=0.0), np.maximum(lo - x, 0).max(initial=0.0),
                np.maximum(x - hi, 0).max(initial=0.0), np.abs(stat).max(initial=0.0),
                np.abs(z[free]).max(initial=0.0), np.maximum(-z[self.lower], 0).max(initial=0.0),
                np.maximum(z[self.upper], 0).max(initial=0.0)]
        return float(max(viol))


def solve(P: np.ndarray, q: np.ndarray, A: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray,
          lower0: np.ndarray | None = None, upper0: np.ndarray | None = None,
          max_pdas: int = 8, max_primal: int = 60, tol: float = 1e-10) -> DenseQPResult:
    """Solve the QP exactly; ``lower0``/``upper0`` (n,) bool warm-start the active set."""
    n = q.size
    lower = np.zeros(n, bool) if lower0 is None else np.array(lower0, bool)
    upper = np.zeros(n, bool) if upper0 is None else np.array(upper0, bool) & ~lower
    scale_x = max(1.0, float(np.max(np.abs(hi))))
    scale_g = max(1.0, float(np.abs(P).max()) * scale_x, float(np.abs(q).max()))
    x, nu, z, lower, upper, it, status = kernels.pdas(
        np.ascontiguousarray(P, float), np.ascontiguousarray(q, float), np.ascontiguousarray(A, float),
        np.ascontiguousarray(b, float), np.ascontiguousarray(lo, float), np.ascontiguousarray(hi, float),
        lower, upper, max_pdas, tol)
    if status == 0:
        res = DenseQPResult(x, nu, np.where(lower | upper, z, 0.0), lower.copy(), upper.copy(), it, "pdas", True)
        if res.kkt_error(P, q, A, b, lo, hi) <= 1e-8 * scale_g:
            return res
    return _primal_active_set(P, q, A, b, lo, hi, max_primal, tol)


def _kkt(P, q, A, b, lo, hi, lower, upper):
    """Solve for free variables with the active ones fixed; ``None`` if singular."""
    fixed = lower | upper
    free = ~fixed
    x = np.where(lower, lo, np.where(upper, hi, 0.0))
    F = np.flatnonzero(free)
    m = A.shape[0]
    AF = A[:, F]
    if F.size < m:
        return None
    KKT = np.zeros((F.size + m, F.size + m))
    KKT[:F.size, :F.size] = P[np.ix_(F, F)]
    KKT[:F.size, F.size:] = AF.T
    KKT[F.size:, :F.size] = AF
    rhs = np.concatenate([-q[F] - P[F] @ x, b - A @ x])
    try:
        sol = np.linalg.solve(KKT, rhs)
    except np.linalg.LinAlgError:
        return None
    if not np.all(np.isfinite(sol)) or np.abs(sol).max() > 1e12 * max(1.0, np.abs(rhs).max()):
        return None
    x[F] = sol[:F.size]
    nu = sol[F.size:]
    z = P @ x + q + A.T @ nu
    return x, nu, z


def _feasible_point(A, b, lo, hi) -> np.ndarray | None:
    """A point of ``{A x = b, lo <= x <= hi}``: projection of the box centre, else an LP."""
    if A.shape[0] == 3 and A.shape[1] >= 4 and np.ptp(lo) == 0 and np.ptp(hi) == 0:
        proj = _project_box_eq(A[None], b[None], (0.5 * (lo + hi))[None], lo[0], hi[0])
        if proj.converged[0]:
            return proj.t[0].copy()
    from scipy.optimize import linprog  # only near the boundary of the feasible set

    res = linprog(np.zeros(A.shape[1]), A_eq=A, b_eq=b, bounds=list(zip(lo, hi)), method="highs")
    return res.x if res.status == 0 else None


def _primal_active_set(P, q, A, b, lo, hi, max_iter, tol) -> DenseQPResult:
    """Nocedal & Wright Alg. 16.3 from a feasible point (projection of the box centre)."""
    n = q.size
    x = _feasible_point(A, b, lo, hi)
    if x is None:
        return DenseQPResult(np.clip(np.zeros(n), lo, hi), np.zeros(A.shape[0]), np.zeros(n),
                             np.zeros(n, bool), np.zeros(n, bool), 0, "primal", False)
    eps = tol * max(1.0, float(np.max(np.abs(hi))))
    lower, upper = x <= lo + eps, x >= hi - eps
    x = np.clip(x, lo, hi)
    nu, z = np.zeros(A.shape[0]), np.zeros(n)
    it = 0
    for it in range(1, max_iter + 1):
        sol = _kkt(P, q, A, b, lo, hi, lower, upper)
        if sol is None:  # too many bounds in the working set: drop the last added
            idx = np.flatnonzero(lower | upper)
            lower[idx[-1]] = upper[idx[-1]] = False
            continue
        x_new, nu, z = sol
        p = x_new - x
        if np.max(np.abs(p)) <= eps:
            zW = np.where(lower, z, np.where(upper, -z, np.inf))
            j = int(np.argmin(zW))
            if zW[j] >= -1e-12 * max(1.0, np.abs(z).max()):
                return DenseQPResult(x, nu, np.where(lower | upper, z, 0.0), lower, upper, it, "primal", True)
            lower[j] = upper[j] = False
            continue
        alpha, block, at_upper = 1.0, -1, False
        for i in map(int, np.flatnonzero(~(lower | upper))):
            if p[i] < 0 and (lo[i] - x[i]) / p[i] < alpha:
                alpha, block, at_upper = (lo[i] - x[i]) / p[i], i, False
            elif p[i] > 0 and (hi[i] - x[i]) / p[i] < alpha:
                alpha, block, at_upper = (hi[i] - x[i]) / p[i], i, True
        x = x + max(alpha, 0.0) * p
        if block >= 0:
            x[block] = hi[block] if at_upper else lo[block]
            (upper if at_upper else lower)[block] = True
    return DenseQPResult(x, nu, np.where(lower | upper, z, 0.0), lower, upper, it, "primal", False)
