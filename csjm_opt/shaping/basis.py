"""The affine stiffness basis ``K(T) = K0 + sum_i T_i G_i`` at a pose, and the dense shaping QP."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from ..model.cable_terms import CableTerms, point_force_terms
from ..model.rig import Rig
from .objectives import StiffnessObjective

#: Default tie-breaking regulariser, relative to the mean curvature of the objective.
REGULARIZATION = 1e-10


@dataclasses.dataclass(frozen=True, eq=False)
class StiffnessBasis:
    """``K(T) = K0 + sum_i T_i G_i`` at one pose, with J and the weight moment there."""

    R: np.ndarray             # (3, 3)
    J: np.ndarray             # (m, 3)
    K0: np.ndarray            # (3, 3) N m/rad, J^T diag(k) J
    G: np.ndarray             # (m, 3, 3) m, dK/dt_i
    tau_weight_A_Nm: np.ndarray  # (3,)

    def K(self, tensions_N: np.ndarray) -> np.ndarray:
        """The stiffness at these tensions, ``K0 + sum_i T_i G_i`` (N m/rad).

        Parameters
        ----------
        tensions_N : (m,) array
            Cable tensions (N).

        Returns
        -------
        (3, 3) array
            K (N m/rad).
        """
        return self.K0 + np.einsum("i,ijk->jk", tensions_N, self.G)


@functools.lru_cache(maxsize=64)
def _terms(rig: Rig) -> CableTerms:
    return CableTerms.from_rig(rig)


def stiffness_basis(rig: Rig, R: np.ndarray) -> StiffnessBasis:
    """``J, K0, G`` and the weight moment at ``R`` (closed form; trusted ``R``)."""
    J, K0, G = _terms(rig).stiffness_basis(R)
    tau_w, _ = point_force_terms(R, rig.weight_B_N[None], np.asarray(rig.com_A_m)[None])
    return StiffnessBasis(R, J, K0, G, tau_w)


def qp_matrices(basis: StiffnessBasis, tau_ext: np.ndarray, objective: StiffnessObjective,
                t_mid: np.ndarray, regularization: float = REGULARIZATION):
    """Dense ``P, q, A, b`` of the shaping QP (``1/2 x^T P x + q^T x``, ``A x = b``)."""
    m = basis.G.shape[0]                                          # cables
    M = objective.L @ basis.G.reshape(m, 9).T                     # (rows of L, m)
    d = objective.s - objective.L @ basis.K0.reshape(9)
    MW = M.T * objective.w
    H = MW @ M
    curvature = float(np.trace(H)) / m
    rho = regularization * (curvature if curvature > 1e-300 else 1.0)   # all-zero weights: regulariser only
    P = 2.0 * (H + rho * np.eye(m))
    q = -2.0 * (MW @ d + rho * t_mid)
    return P, q, basis.J.T, -(tau_ext + basis.tau_weight_A_Nm)
