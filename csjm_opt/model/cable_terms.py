"""Closed-form cable terms in numpy, for the inner loops (statics, shaping).

The CasADi model (:mod:`csjm_opt.model.casadi_model`) is the reference; these are
the same quantities in closed form, about 3x cheaper per call from Python,
used where one evaluation runs thousands of times (forward statics, the
closed-loop simulation, stiffness shaping). ``tests/test_statics.py`` checks
them against the CasADi model and against finite differences.

With ``c_i = |b_i - R a_i|``, ``u_i = R^T (b_i - R a_i) / c_i`` (in {A}) and
``j_i = a_i x u_i`` (row i of J, (38)), the Levi-Civita (geodesic) Hessian of
a cable length in body coordinates ``R exp(hat(zeta))`` is::

    Hess(c_i) = (|a_i|^2 I - a_i a_i^T - j_i j_i^T) / c_i
                - 1/2 (u_i a_i^T + a_i u_i^T) + (u_i . a_i) I

so the cable energy ``Phi = sum 1/2 k_i (c_i - l_i)^2`` has Hessian
``K = sum_i k_i j_i j_i^T + sum_i t_i Hess(c_i)``: the docs/conventions.md stiffness,
affine in the tensions ``t_i`` for fixed ``k`` (slack cables: ``k_i -> 0``).
A force ``f`` fixed in {B} at platform point ``r`` (in {A}) has moment
``r x R^T f`` and energy Hessian ``(f_A . r) I - 1/2 (f_A r^T + r f_A^T)``.
"""

from __future__ import annotations

import numpy as np

_EYE = np.eye(3)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (n, 3) arrays (cheaper than np.cross for small n)."""
    a0, a1, a2 = a[:, 0], a[:, 1], a[:, 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    return np.stack((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0), axis=1)


class CableTerms:
    """Geometry of one rig as arrays: ``A`` (6, 3) in {A}, ``B`` (6, 3) in {B}, ``k`` (6,)."""

    def __init__(self, platform_holes_A_m: np.ndarray, base_holes_B_m: np.ndarray,
                 cable_stiffness_N_per_m: np.ndarray):
        self.A = np.array(platform_holes_A_m, float)
        self.B = np.array(base_holes_B_m, float)
        self.k = np.array(cable_stiffness_N_per_m, float)
        self._aa = np.einsum("ij,ik->ijk", self.A, self.A)              # a a^T
        self._a2 = np.einsum("ij,ij->i", self.A, self.A)                # |a|^2

    @classmethod
    def from_rig(cls, rig) -> "CableTerms":
        return cls(rig.platform_holes_A_m, rig.base_holes_B_m, rig.cable_stiffness_N_per_m)

    def geometry(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cable lengths ``c`` (6,), unit vectors ``u`` in {A} (6, 3) and J (6, 3)."""
        C_A = self.B @ R - self.A                                       # rows R^T b_i - a_i
        c = np.sqrt(np.einsum("ij,ij->i", C_A, C_A))
        U = C_A / c[:, None]
        return c, U, _cross(self.A, U)

    def length_hessians(self, c: np.ndarray, U: np.ndarray, J: np.ndarray) -> np.ndarray:
        """``Hess(c_i)`` (6, 3, 3), the stiffness basis ``G_i = dK/dt_i``."""
        jj = np.einsum("ij,ik->ijk", J, J)
        ua = np.einsum("ij,ik->ijk", U, self.A)
        ua_dot = np.einsum("ij,ij->i", U, self.A)
        return ((self._a2[:, None, None] * _EYE - self._aa - jj) / c[:, None, None]
                - 0.5 * (ua + ua.transpose(0, 2, 1)) + ua_dot[:, None, None] * _EYE)

    def stiffness_basis(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(J, K0, G)`` with ``K(T) = K0 + sum_i T_i G_i``; K0 = J^T diag(k) J."""
        c, U, J = self.geometry(R)
        return J, (J.T * self.k) @ J, self.length_hessians(c, U, J)

    def stiffness(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """K (load convention of docs/conventions.md) for tensions T at R (all cables taut, stiffness k)."""
        J, K0, G = self.stiffness_basis(R)
        return K0 + np.einsum("i,ijk->jk", T, G)

    def rest_terms(self, R: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For rest lengths ``l``: tensions T (0 when slack), cable moment J^T T, K (slack k -> 0)."""
        c, U, J = self.geometry(R)
        stretch = c - l
        taut = stretch > 0
        k_eff = np.where(taut, self.k, 0.0)
        T = np.where(taut, self.k * stretch, 0.0)
        K = (J.T * k_eff) @ J + np.einsum("i,ijk->jk", T, self.length_hessians(c, U, J))
        return T, J.T @ T, K


def point_force_terms(R: np.ndarray, F_B: np.ndarray, P_A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Summed moment (in {A}) and energy Hessian of forces ``F_B`` (n, 3) at points ``P_A`` (n, 3)."""
    F_A = F_B @ R                                                       # rows R^T f
    tau = _cross(P_A, F_A).sum(axis=0)
    fr = F_A.T @ P_A                                                    # sum f r^T
    return tau, np.trace(fr) * _EYE - 0.5 * (fr + fr.T)
