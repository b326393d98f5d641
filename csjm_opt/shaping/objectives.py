"""Objectives of stiffness shaping: sets of linear functionals of K with targets and weights.

Every objective has the form ``sum_k w_k (L_k . vec K - s_k)^2`` with rows
``L_k`` (9,) acting on ``vec K`` (row-major), so that with ``K`` affine in the
tensions it is a convex quadratic in the tensions (:mod:`csjm_opt.shaping.shaper`):

* ``"frobenius"``: the entries of K; ``weights`` (3, 3) elementwise,
  ``||K - K_target||_W^2 = sum_ab W_ab (K_ab - K_target_ab)^2``;
* ``"eigen"``: ``u_k^T K u_k`` along the eigenvectors ``u_k`` of ``K_target``
  with its eigenvalues as targets (principal stiffnesses; coupling ignored),
  ``weights`` (3,). For repeated eigenvalues the eigenvectors are not unique
  and the basis ``numpy.linalg.eigh`` returns is used: prefer ``"frobenius"``
  for (nearly) isotropic targets;
* ``"directional"``: ``u^T K u`` along given unit ``directions`` (n, 3) with
  targets ``u^T K_target u``, ``weights`` (n,).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .._limits import check_array
from .._validate import as_array
from ..errors import InvalidInput

OBJECTIVES = ("frobenius", "eigen", "directional")


@dataclasses.dataclass(frozen=True, eq=False)
class StiffnessObjective:
    """``sum_k w_k (L_k . vec K - s_k)^2``: functionals ``L`` (m, 9), targets ``s`` (m,), weights ``w``."""

    name: str
    L: np.ndarray
    s: np.ndarray
    w: np.ndarray

    def residual(self, K: np.ndarray) -> float:
        """Weighted residual ``sqrt(sum w_k (L_k . vec K - s_k)^2)`` (N m/rad)."""
        e = self.L @ K.reshape(9) - self.s
        return float(np.sqrt(np.sum(self.w * e * e)))


def make_objective(K_target: np.ndarray, weights: np.ndarray | None = None, objective: str = "frobenius",
                   directions: np.ndarray | None = None) -> StiffnessObjective:
    """Objective of the given kind for ``K_target`` (3, 3); see the module docstring for ``weights``."""
    if objective not in OBJECTIVES:
        raise InvalidInput(f"objective must be one of {', '.join(OBJECTIVES)}, got {objective!r}", "objective")
    Kt = as_array(K_target, (3, 3), "K_target")
    check_array(Kt, "stiffness_Nm_per_rad", "K_target", lambda msg: InvalidInput(msg, "K_target"))
    Kt = 0.5 * (Kt + Kt.T)
    if objective == "frobenius":
        W = np.ones((3, 3)) if weights is None else as_array(weights, (3, 3), "weights")
        if np.any(W < 0):
            raise InvalidInput("weights must be >= 0", "weights")
        return StiffnessObjective("frobenius", np.eye(9), Kt.reshape(9), 0.5 * (W + W.T).reshape(9))
    if objective == "eigen":
        lam, U = np.linalg.eigh(Kt)
        U = U.T
    else:
        if directions is None:
            raise InvalidInput("objective='directional' needs directions (n, 3)", "directions")
        U = as_array(np.atleast_2d(directions), (None, 3), "directions")
        norms = np.linalg.norm(U, axis=1)
        if np.any(norms < 1e-12):
            raise InvalidInput("directions must be non-zero", "directions")
        U = U / norms[:, None]
        lam = np.einsum("ki,ij,kj->k", U, Kt, U)
    w = np.ones(len(U)) if weights is None else as_array(np.ravel(weights), (len(U),), "weights")
    if np.any(w < 0):
        raise InvalidInput("weights must be >= 0", "weights")
    return StiffnessObjective(objective, np.einsum("ki,kj->kij", U, U).reshape(len(U), 9), lam, w)
