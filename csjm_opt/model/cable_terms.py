"""The batched numpy reference of the cable physics: geometry, J (38), weight moment, K.

This is the one place the closed-form physics is written in numpy. The
compiled fast paths (:mod:`csjm_opt.model.kernels`, numba) compute the same
quantities and are tested against these functions and against the CasADi
model (:mod:`csjm_opt.model.casadi_model`, the symbolic reference and the
code-generation path); ``tests/test_cable_terms.py`` and
``tests/model/test_stiffness_kernel.py`` do it, together with a finite-difference
Hessian of the cable energy.

Every function takes one pose ``R`` (3, 3) or a stack (..., 3, 3); hole
arrays ``A`` (m, 3) in {A} and ``B`` (m, 3) in {B}, or per-pose (..., m, 3).
With ``c_i = |b_i - R a_i|``, ``u_i = R^T (b_i - R a_i) / c_i`` (in {A}) and
``j_i = a_i x u_i`` (row i of J, (38); ``dc = -J dzeta``), the Levi-Civita
(geodesic) Hessian of a cable length in body coordinates ``R exp(hat(zeta))``
is::

    Hess(c_i) = (|a_i|^2 I - a_i a_i^T - j_i j_i^T) / c_i
                - 1/2 (u_i a_i^T + a_i u_i^T) + (u_i . a_i) I

so the cable energy ``Phi = sum 1/2 k_i (c_i - l_i)^2`` has Hessian (the
corrected (45), docs/conventions.md load convention)::

    K = sum_{i taut} k_i j_i j_i^T + sum_i t_i Hess(c_i).

A **slack** cable (``t_i <= 0`` when tensions are given, ``c_i <= l_i`` when
rest lengths are given) stores no energy nearby and contributes nothing to
K, neither ``k_i j_i j_i^T`` nor the tension term.

A force ``f`` fixed in {B} at platform point ``r`` (in {A}), such as the
weight ``m g`` at the centre of mass, has moment ``r x R^T f`` and energy
Hessian ``(f_A . r) I - 1/2 (f_A r^T + r f_A^T)``.
"""

from __future__ import annotations

import numpy as np

_EYE = np.eye(3)

__all__ = ["CableTerms", "cable_lengths", "geometry", "length_hessians", "point_force_terms",
           "stiffness", "stiffness_from_rest", "weight_moment"]


_NEXT, _LAST = np.array([1, 2, 0]), np.array([2, 0, 1])


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product along the last axis, the leading axes broadcast (cheaper than np.cross for small arrays).

    Component ``k`` is ``a[k+1] b[k+2] - a[k+2] b[k+1]`` (indices mod 3): the three components in one
    product of index-rotated copies (``take``: four small copies instead of nine slices).
    """
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.take(_NEXT, -1) * b.take(_LAST, -1) - a.take(_LAST, -1) * b.take(_NEXT, -1)


def geometry(R: np.ndarray, A_m: np.ndarray, B_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cable lengths ``c`` (..., m), unit vectors ``u`` in {A} (..., m, 3) and J (..., m, 3).

    Parameters
    ----------
    R : (..., 3, 3) orientation of {A} in {B}.
    A_m, B_m : (m, 3) or (..., m, 3) platform holes in {A}, base holes in {B} (m).
    """
    v = np.asarray(B_m) @ R - A_m                       # rows R^T b_i - a_i: cable vectors in {A}
    c = np.sqrt(np.einsum("...ij,...ij->...i", v, v))
    U = v / c[..., None]
    return c, U, _cross(np.asarray(A_m, float), U)


def cable_lengths(R: np.ndarray, A_m: np.ndarray, B_m: np.ndarray) -> np.ndarray:
    """Cable lengths ``|b_i - R a_i|`` (..., m), m."""
    return geometry(R, A_m, B_m)[0]


def length_hessians(A_m: np.ndarray, c: np.ndarray, U: np.ndarray, J: np.ndarray) -> np.ndarray:
    """``Hess(c_i)`` (..., m, 3, 3): the stiffness basis ``dK/dt_i`` (module docstring)."""
    A = np.broadcast_to(A_m, U.shape)
    aa = A[..., :, None] * A[..., None, :]
    jj = J[..., :, None] * J[..., None, :]
    ua = U[..., :, None] * A[..., None, :]
    a2 = np.einsum("...ij,...ij->...i", A, A)
    ua_dot = np.einsum("...ij,...ij->...i", U, A)
    return ((a2[..., None, None] * _EYE - aa - jj) / c[..., None, None]
            - 0.5 * (ua + np.swapaxes(ua, -1, -2)) + ua_dot[..., None, None] * _EYE)


def _stiffness_from(A_m, k, c, U, J, T) -> np.ndarray:
    taut = T > 0
    k_eff = np.where(taut, k, 0.0)
    t_eff = np.where(taut, T, 0.0)
    K0 = np.einsum("...i,...ij,...ik->...jk", k_eff, J, J)
    return K0 + np.einsum("...i,...ijk->...jk", t_eff, length_hessians(A_m, c, U, J))


def stiffness(R: np.ndarray, tensions_N: np.ndarray, A_m: np.ndarray, B_m: np.ndarray,
              k_N_per_m: np.ndarray) -> np.ndarray:
    """K (..., 3, 3), N m/rad, for tensions (..., m); cables with ``t_i <= 0`` are slack.

    Parameters
    ----------
    R : (..., 3, 3) poses.
    tensions_N : (..., m) cable tensions.
    A_m, B_m : hole arrays (see :func:`geometry`).
    k_N_per_m : (m,) cable-plus-drive stiffness.

    Returns
    -------
    K : (..., 3, 3), symmetric, the Levi-Civita Hessian of the cable energy.
    """
    c, U, J = geometry(R, A_m, B_m)
    return _stiffness_from(A_m, np.asarray(k_N_per_m, float), c, U, J, np.asarray(tensions_N, float))


def stiffness_from_rest(R: np.ndarray, rest_lengths_m: np.ndarray, A_m: np.ndarray, B_m: np.ndarray,
                        k_N_per_m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """K, tensions ``t = k (c - l)`` (0 when ``c <= l``) and the cables' moment ``J^T t``.

    Returns
    -------
    K : (..., 3, 3); tensions : (..., m); tau_cables_A_Nm : (..., 3).
    """
    c, U, J = geometry(R, A_m, B_m)
    k = np.asarray(k_N_per_m, float)
    T = np.maximum(k * (c - rest_lengths_m), 0.0)
    return _stiffness_from(A_m, k, c, U, J, T), T, np.einsum("...ij,...i->...j", J, T)


def weight_moment(R: np.ndarray, first_moment_A_kgm: np.ndarray, gravity_B: np.ndarray) -> np.ndarray:
    """Moment of the weight about O in {A}: ``(m r) x (R^T g)`` (N m), (..., 3)."""
    g_A = np.einsum("...ji,...j->...i", R, gravity_B)
    return _cross(np.asarray(first_moment_A_kgm, float), g_A)


def point_force_terms(R: np.ndarray, F_B: np.ndarray, P_A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Summed moment (in {A}) and energy Hessian of forces ``F_B`` (n, 3) at points ``P_A`` (n, 3)."""
    F_A = F_B @ R                                                       # rows R^T f
    tau = _cross(P_A, F_A).sum(axis=0)
    fr = F_A.T @ P_A                                                    # sum f r^T
    return tau, np.trace(fr) * _EYE - 0.5 * (fr + fr.T)


class CableTerms:
    """The reference functions bound to one rig: ``A`` (m, 3) in {A}, ``B`` (m, 3) in {B}, ``k`` (m,).

    Kept for the statics and controller code that evaluates one pose at a
    time; every method is a call of the module functions above.
    """

    def __init__(self, platform_holes_A_m: np.ndarray, base_holes_B_m: np.ndarray,
                 cable_stiffness_N_per_m: np.ndarray):
        self.A = np.array(platform_holes_A_m, float)
        self.B = np.array(base_holes_B_m, float)
        self.k = np.array(cable_stiffness_N_per_m, float)

    @classmethod
    def from_rig(cls, rig) -> "CableTerms":
        """The terms of a :class:`~csjm_opt.model.rig.Rig`."""
        return cls(rig.platform_holes_A_m, rig.base_holes_B_m, rig.cable_stiffness_N_per_m)

    def geometry(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cable lengths ``c`` (m,), unit vectors ``u`` in {A} (m, 3) and J (m, 3)."""
        return geometry(R, self.A, self.B)

    def length_hessians(self, c: np.ndarray, U: np.ndarray, J: np.ndarray) -> np.ndarray:
        """``Hess(c_i)`` (m, 3, 3), the stiffness basis ``G_i = dK/dt_i``."""
        return length_hessians(self.A, c, U, J)

    def stiffness_basis(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(J, K0, G)`` with ``K(T) = K0 + sum_i T_i G_i`` (all taut); K0 = J^T diag(k) J."""
        c, U, J = self.geometry(R)
        return J, (J.T * self.k) @ J, self.length_hessians(c, U, J)

    def stiffness(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """K (docs/conventions.md load convention) for tensions T at R (``t_i <= 0``: slack)."""
        return stiffness(R, T, self.A, self.B, self.k)

    def rest_terms(self, R: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For rest lengths ``l``: tensions T (0 when slack), cable moment J^T T, K (slack k -> 0)."""
        K, T, tau = stiffness_from_rest(R, l, self.A, self.B, self.k)
        return T, tau, K
