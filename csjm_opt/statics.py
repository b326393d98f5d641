"""Forward statics: the equilibrium orientation for given rest lengths and loads.

Given commanded rest lengths ``l`` (m) and a load, find ``R`` with::

    J^T T(R, l) + tau_weight(R) + tau_points(R) + tau_ext = 0      (in {A})

where ``T = k (c - l)`` for taut cables, ``tau_ext`` is a moment fixed in {A}
and ``tau_points`` comes from dead-weight forces fixed in {B} applied at
platform points. Newton's method on SO(3) with the exact tangent stiffness

    K_t = H_cable + H_points - 1/2 hat(tau_cable + tau_points)

(``H`` are Levi-Civita energy Hessians; the weight is one of the point forces),
damped by a trust region on the step length and a backtracking line search on
the residual. Every result carries its residual; a result is returned only
when the residual is below ``tol_Nm`` and the equilibrium is stable (all
eigenvalues of ``K_t`` with positive real part), else :class:`NoEquilibrium`.
"""

from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np

from . import so3
from .errors import NoEquilibrium
from .model import Model
from .rig import Rig
from .validate import as_array, as_rotation, as_vector3

PointForce = tuple[np.ndarray, np.ndarray]  # (force in {B}, N; point in {A}, m)


@dataclasses.dataclass(frozen=True, eq=False)
class Equilibrium:
    """A static equilibrium found by :func:`solve_equilibrium`."""

    R: np.ndarray                   # (3, 3) orientation of {A} in {B}
    rest_lengths_m: np.ndarray      # (6,)
    tensions_N: np.ndarray          # (6,)
    tau_ext_A_Nm: np.ndarray        # (3,) external moment fixed in {A}
    tau_cable_A_Nm: np.ndarray      # (3,) J^T T
    tau_points_A_Nm: np.ndarray     # (3,) weight plus dead-weight forces
    K: np.ndarray                   # (3, 3) cable stiffness (SPEC.md convention) at R
    K_tangent: np.ndarray           # (3, 3) tangent stiffness of the whole loaded system
    iterations: int

    @property
    def tau_load_A_Nm(self) -> np.ndarray:
        """Total load on the platform (external plus weight/point forces), {A}."""
        return self.tau_ext_A_Nm + self.tau_points_A_Nm

    @property
    def residual_Nm(self) -> float:
        """``||J^T T + tau_load||`` (N m)."""
        return float(np.linalg.norm(self.tau_cable_A_Nm + self.tau_load_A_Nm))

    @property
    def slack(self) -> np.ndarray:
        """Mask of slack cables (zero tension)."""
        return self.tensions_N <= 0.0

    @property
    def stable(self) -> bool:
        return bool(np.all(np.linalg.eigvals(self.K_tangent).real > 0))


def solve_equilibrium(rig: Rig, rest_lengths_m: np.ndarray, tau_ext_A_Nm: np.ndarray = (0.0, 0.0, 0.0),
                      point_forces: Sequence[PointForce] = (), R_init: np.ndarray | None = None,
                      include_weight: bool = True, model: Model | None = None, tol_Nm: float = 1e-11,
                      max_iter: int = 100, max_step_rad: float = 0.25) -> Equilibrium:
    """Equilibrium of ``rig`` with rest lengths ``l`` under the given loads.

    ``point_forces`` are ``(force_B_N, point_A_m)`` pairs (dead weights fixed in
    {B}); the platform's weight is added unless ``include_weight=False``.
    ``R_init`` is the starting orientation (identity by default).
    """
    model = model or Model(rig)
    l = as_array(rest_lengths_m, (6,), "rest_lengths")
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    R = np.eye(3) if R_init is None else as_rotation(R_init, "R_init")
    forces = [(as_vector3(f, "force_B"), as_vector3(p, "point_A")) for f, p in point_forces]
    if include_weight and rig.platform_mass_kg > 0:
        forces.append((rig.weight_B_N, np.asarray(rig.com_A_m)))

    def evaluate(R: np.ndarray):
        K, T, tau_c, _ = model.stiffness_rest(R, l)
        tau_p, H_p = np.zeros(3), np.zeros((3, 3))
        for f, p in forces:
            t, H = model.point_force_moment(R, f, p)
            tau_p, H_p = tau_p + t, H_p + H
        g = tau_c + tau_p + tau_ext
        K_t = K + H_p - 0.5 * so3.hat(tau_c + tau_p)
        return g, K, K_t, T, tau_c, tau_p

    g, K, K_t, T, tau_c, tau_p = evaluate(R)
    best = float(np.linalg.norm(g))
    it = 0
    for it in range(1, max_iter + 1):
        if best <= tol_Nm:
            break
        step = _newton_step(K_t, g, max_step_rad)
        alpha, improved = 1.0, False
        for _ in range(30):
            R_try = R @ so3.exp(alpha * step)
            out = evaluate(R_try)
            norm = float(np.linalg.norm(out[0]))
            if norm < best or norm <= tol_Nm:
                R, (g, K, K_t, T, tau_c, tau_p), best, improved = R_try, out, norm, True
                break
            alpha *= 0.5
        if not improved:
            break
    if best > tol_Nm:
        reason = "slack" if np.any(T <= 0) else "diverged"
        raise NoEquilibrium(f"no equilibrium found: residual {best:.3g} N m after {it} Newton steps "
                            f"({int(np.sum(T <= 0))} slack cables)", reason, best)
    eq = Equilibrium(R, l, T, tau_ext, tau_c, tau_p, K, K_t, it)
    if not eq.stable:
        raise NoEquilibrium(f"equilibrium found is unstable: tangent stiffness eigenvalues "
                            f"{np.round(np.linalg.eigvals(K_t).real, 4).tolist()} N m/rad "
                            f"({int(eq.slack.sum())} slack cables)", "unstable", best)
    return eq


def _newton_step(K_t: np.ndarray, g: np.ndarray, max_step_rad: float) -> np.ndarray:
    """Solve ``K_t step = g`` (g + dg/dzeta step = 0, dg/dzeta = -K_t), regularised and capped."""
    try:
        step = np.linalg.solve(K_t, g)
        if not np.all(np.isfinite(step)) or np.dot(step, g) <= 0 and np.linalg.cond(K_t) > 1e10:
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        S = 0.5 * (K_t + K_t.T)
        mu = max(0.0, -np.min(np.linalg.eigvalsh(S))) + 1e-3 * max(1.0, np.abs(S).max())
        step = np.linalg.solve(S + mu * np.eye(3), g)
    norm = np.linalg.norm(step)
    return step if norm <= max_step_rad else step * (max_step_rad / norm)


def rest_lengths_for(rig: Rig, R: np.ndarray, tensions_N: np.ndarray, model: Model | None = None) -> np.ndarray:
    """Rest lengths ``l = c(R) - T / k`` that give tensions ``T`` at ``R`` (m)."""
    model = model or Model(rig)
    return model.rest_lengths(as_rotation(R), as_array(tensions_N, (6,), "tensions"))
