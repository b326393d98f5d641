"""CasADi symbolic model of the CSJM: cable geometry, Jacobian (38), stiffness (45).

All functions are named ``casadi.Function`` objects with named inputs, so
callers use names, not positions. Geometry is an input, not a constant, so the
same functions serve fitted or perturbed rigs.

Inputs (shapes):
    R  (3, 3)  orientation of {A} in {B}
    A  (3, m)  platform holes A_i in {A} (columns), m
    B  (3, m)  base holes B_i in {B} (columns), m
    T  (m, 1)  cable tensions, N
    l  (m, 1)  rest lengths (cable plus drive), m
    k  (m, 1)  cable-plus-drive stiffness, N/m

(m cables: :func:`build_functions` builds one set per cable count.)

Conventions (docs/conventions.md, errata 1-2):
    * ``J`` (m, 3) has rows ``a_i x (R^T u_i)`` in {A}, (38); ``dc = -J dzeta`` (40).
    * ``J^T T`` is the cables' moment on the platform in {A}, ``= -dPhi``.
    * ``stiffness`` is the load-convention K of docs/conventions.md,
      ``K = J^T Kdiag J - D + 1/2 hat(J^T T)`` with ``D = d(J^T T)/dzeta`` at
      fixed T: the Levi-Civita Hessian of ``Phi = sum 1/2 k (c - l)^2``.
    * ``stiffness_paper`` is (45) with the corrected structure constants (31),
      ``D - J^T Kdiag J - 1/2 hat(J^T T) = -K``; ``stiffness_paper_as_printed``
      keeps the printed +-2 constants (``- hat(J^T T)``), kept only to document
      the erratum: it is not symmetric.
"""

from __future__ import annotations

import functools

import casadi as ca

from .. import so3

__all__ = ["build_functions"]


def _cable_terms(R: ca.SX, A: ca.SX, B: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """Cable vectors in {B} (3 x m), lengths (m x 1), and J (m x 3)."""
    C = B - R @ A                                   # c_i = b_i - R a_i, in {B}
    lengths = ca.sqrt(ca.sum1(C * C)).T             # (m, 1)
    U_A = R.T @ C / ca.repmat(lengths.T, 3, 1)      # u_i expressed in {A}
    J = ca.horzcat(*[ca.cross(A[:, i], U_A[:, i]) for i in range(A.shape[1])]).T  # (m, 3)
    return C, lengths, J


def _stiffness_parts(R: ca.SX, T: ca.SX, k: ca.SX, A: ca.SX, B: ca.SX) -> dict[str, ca.SX]:
    """J, tau = J^T T, and D = d(J^T T)/dzeta at fixed T, zeta = 0 (45)."""
    zeta = ca.SX.sym("zeta", 3)
    # R(zeta) = R (I + hat zeta) agrees with R exp(hat zeta) to first order,
    # which is all a first derivative at zeta = 0 sees.
    _, _, J_z = _cable_terms(R @ (ca.DM.eye(3) + so3.hat(zeta)), A, B)
    tau_z = J_z.T @ T
    D = ca.substitute(ca.jacobian(tau_z, zeta), zeta, ca.DM.zeros(3))
    _, lengths, J = _cable_terms(R, A, B)
    tau = J.T @ T
    JtKJ = J.T @ ca.diag(k) @ J
    return {"J": J, "lengths": lengths, "tau": tau, "D": D, "JtKJ": JtKJ}


@functools.cache
def build_functions(n_cables: int = 6) -> dict[str, ca.Function]:
    """All model functions for ``n_cables`` cables, built once per process and count (on first use)."""
    R = ca.SX.sym("R", 3, 3)
    A = ca.SX.sym("A", 3, n_cables)
    B = ca.SX.sym("B", 3, n_cables)
    T = ca.SX.sym("T", n_cables)
    l = ca.SX.sym("l", n_cables)
    k = ca.SX.sym("k", n_cables)
    m = ca.SX.sym("m")
    r = ca.SX.sym("r", 3)
    g = ca.SX.sym("g", 3)

    C, lengths, J = _cable_terms(R, A, B)
    parts = _stiffness_parts(R, T, k, A, B)
    K = parts["JtKJ"] - parts["D"] + 0.5 * so3.hat(parts["tau"])
    K = 0.5 * (K + K.T)  # exact in exact arithmetic (erratum 1); removes round-off
    K45 = parts["D"] - parts["JtKJ"] - 0.5 * so3.hat(parts["tau"])
    K45_printed = parts["D"] - parts["JtKJ"] - so3.hat(parts["tau"])

    # Rest-length form: t = k (c - l) for c > l, else 0 (a slack cable adds no stiffness).
    taut = lengths > l
    T_rest = ca.if_else(taut, k * (lengths - l), 0)
    k_eff = ca.if_else(taut, k, 0)
    rest = _stiffness_parts(R, T_rest, k_eff, A, B)
    K_rest = rest["JtKJ"] - rest["D"] + 0.5 * so3.hat(rest["tau"])
    K_rest = 0.5 * (K_rest + K_rest.T)
    energy = 0.5 * ca.sum1(k_eff * (lengths - l) ** 2)

    # Weight-like load: force m g (in {B}) at r (in {A}); V = -m g . (R r).
    g_A = R.T @ g
    tau_w = m * ca.cross(r, g_A)
    H_w = m * (ca.dot(g_A, r) * ca.DM.eye(3) - 0.5 * (g_A @ r.T + r @ g_A.T))

    f = ca.Function
    return {
        "cable_vectors": f("cable_vectors", [R, A, B], [C], ["R", "A", "B"], ["C_B"]),
        "cable_lengths": f("cable_lengths", [R, A, B], [lengths], ["R", "A", "B"], ["c"]),
        "jacobian": f("jacobian", [R, A, B], [J], ["R", "A", "B"], ["J"]),
        "cable_moment": f("cable_moment", [R, T, A, B], [J.T @ T], ["R", "T", "A", "B"], ["tau_A"]),
        "stiffness": f("stiffness", [R, T, k, A, B], [K], ["R", "T", "k", "A", "B"], ["K"]),
        "stiffness_paper": f("stiffness_paper", [R, T, k, A, B], [K45],
                             ["R", "T", "k", "A", "B"], ["K45"]),
        "stiffness_paper_as_printed": f("stiffness_paper_as_printed", [R, T, k, A, B], [K45_printed],
                                        ["R", "T", "k", "A", "B"], ["K45_printed"]),
        "tensions_from_rest": f("tensions_from_rest", [R, l, k, A, B], [T_rest],
                                ["R", "l", "k", "A", "B"], ["T"]),
        "stiffness_rest": f("stiffness_rest", [R, l, k, A, B], [K_rest, T_rest, rest["tau"], energy],
                            ["R", "l", "k", "A", "B"], ["K", "T", "tau_A", "energy"]),
        "weight_moment": f("weight_moment", [R, m, r, g], [tau_w, H_w],
                           ["R", "m", "r", "g"], ["tau_A", "hessian"]),
    }
