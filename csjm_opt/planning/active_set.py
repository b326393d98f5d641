"""Exact solver for the tension QP by the primal-dual active set method.

Solves, for each of ``n`` problems::

    minimise    1/2 ||t - t_ref||^2
    subject to  A t = b            (A = J^T, 3 x m: equilibrium)
                lo <= t <= hi      (tension bounds)

by the primal-dual active set method (Hintermueller, Ito & Kunisch, SIAM J.
Optim. 13(3), 2002): guess which bounds are active, solve the equality-
constrained KKT system exactly, update the guess from primal violations and
multiplier signs, repeat until the guess is stable. The answer is exact to
round-off, so it also polishes the output of OSQP. Rows that do not settle
(``converged`` False) are left to the caller. The loops run compiled in
:mod:`csjm_opt.planning.kernels`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from . import kernels as kernels


@dataclasses.dataclass
class ActiveSetResult:
    """Per-row result: ``t`` (n, m), ``converged`` (n,), ``lower``/``upper`` active masks (n, m)."""

    t: np.ndarray
    converged: np.ndarray
    lower: np.ndarray
    upper: np.ndarray


def solve(A: np.ndarray, b: np.ndarray, t_ref: np.ndarray, lo: float, hi: float,
          lower0: np.ndarray | None = None, upper0: np.ndarray | None = None,
          max_iter: int = 40) -> ActiveSetResult:
    """Solve ``n`` problems; ``A`` is (n, 3, m), ``b`` (n, 3), ``t_ref`` (n, m).

    ``lower0``/``upper0`` (n, m) bool warm-start the active sets.
    """
    n = t_ref.shape[0]
    J = np.ascontiguousarray(np.swapaxes(A, 1, 2), dtype=np.float64)
    n_cab = J.shape[1]
    lower = np.zeros((n, n_cab), np.bool_) if lower0 is None else np.array(lower0, np.bool_)
    upper = np.zeros((n, n_cab), np.bool_) if upper0 is None else np.array(upper0, np.bool_) & ~lower
    T = np.zeros((n, n_cab))
    status = np.zeros(n, np.int64)
    kernels.solve_rows(J, np.ascontiguousarray(b, dtype=np.float64),
                       np.ascontiguousarray(np.broadcast_to(t_ref, (n, n_cab)), dtype=np.float64),
                       float(lo), float(hi), lower, upper, max_iter, T, status)
    return ActiveSetResult(t=T, converged=status == kernels.OK, lower=lower, upper=upper)
