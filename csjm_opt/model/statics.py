"""Forward statics: the equilibrium orientation for given rest lengths and loads.

Given commanded rest lengths ``l`` (m) and a load, find ``R`` with::

    J^T T(R, l) + tau_weight(R) + tau_points(R) + tau_ext = 0      (in {A})

where ``T = k (c - l)`` for taut cables (0 for slack ones), ``tau_ext`` is a
moment fixed in {A} and ``tau_points`` comes from dead-weight forces fixed in
{B} applied at platform points. Newton's method on SO(3),
``R <- R exp(hat(step))``, with the exact tangent stiffness

    K_t = -d(residual)/dzeta = H_cable + H_points - 1/2 hat(tau_cable + tau_points)

(``H`` are Levi-Civita energy Hessians; the weight is one of the point
forces; ``H_cable - 1/2 hat(tau_cable)`` is :attr:`Equilibrium.K`, the cable
stiffness of docs/conventions.md), damped by a cap on the step length and a backtracking
line search on the residual. If Newton from ``R_init`` stalls, the external
load is applied in increments (load continuation), each step warm-started
from the last. If that fails too, or ends on an unstable equilibrium (a
saddle), an energy descent on SO(3) from ``R_init`` follows the overdamped
motion of the platform to where it settles (:mod:`csjm_opt.model._descent`;
slack cables carry nothing, the Hessian is checked at the answer), or finds
that it falls over. Every result carries its residual: a result is returned only
when ``||residual|| <= tol_Nm`` and the equilibrium is stable (all eigenvalues
of ``K_t`` with positive real part); otherwise :class:`NoEquilibrium` says
why (``"slack"``: too few taut cables to hold the load; ``"diverged"``: no
convergence; ``"unstable"``: converged to an unstable equilibrium with all
cables taut; an unstable one with slack cables counts as ``"slack"``).

The Newton terms are evaluated in closed form (:mod:`csjm_opt.model.cable_terms`,
checked against the CasADi model in the tests); by default the Newton loop
runs compiled (:mod:`csjm_opt.model.statics_kernels`, numba), ``compiled=False``
runs the numpy reference. Cheap enough for a 1 kHz simulation loop.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import numpy.typing as npt

from .._validate import as_array, as_rotation, as_vector3
from ..errors import InvalidInput, NoEquilibrium
from . import statics_kernels
from ._statics_newton import (
    MAX_EXCURSION_RAD,
    PointForce,
    _Evaluator,
    _newton,
    _stable,
    cable_terms_for,
)
from .equilibrium import Equilibrium
from .numeric import Model
from .rig import Rig

__all__ = ["Equilibrium", "EquilibriumSolver", "MAX_EXCURSION_RAD", "PointForce", "cable_terms_for",
           "rest_lengths_for", "solve_equilibrium"]


# ------------------------------------------------------------------ solver
class EquilibriumSolver:
    """Forward statics of one rig under fixed point forces; reuse it along a trajectory.

    Inputs of :meth:`solve` are trusted (validated by :func:`solve_equilibrium`),
    so a simulation loop pays only for the Newton iterations. Options as in
    :func:`solve_equilibrium`.
    """

    def __init__(self, rig: Rig, point_forces: Sequence[PointForce] = (), include_weight: bool = True,
                 tol_Nm: float = 1e-11, max_iter: int = 100, max_step_rad: float = 0.25,
                 allow_slack: bool = True, continuation_steps: int = 8, compiled: bool = True,
                 globalise: bool = True):
        forces = list(point_forces)
        if include_weight and rig.platform_mass_kg > 0:
            forces.append((rig.weight_B_N, np.asarray(rig.com_A_m, float)))
        self.rig = rig
        self._evaluate = _Evaluator(rig, forces)
        self.tol_Nm, self.max_iter, self.max_step_rad = tol_Nm, max_iter, max_step_rad
        self.allow_slack, self.continuation_steps = allow_slack, continuation_steps
        self.compiled, self.globalise = compiled, globalise
        terms = cable_terms_for(rig)
        self._kernel_args = (terms.A, terms.B, terms.k, self._evaluate._F, self._evaluate._P)

    def _newton(self, l: np.ndarray, R0: np.ndarray, tau_ext: np.ndarray):
        if not self.compiled:
            return _newton(self._evaluate, l, R0, tau_ext, self.tol_Nm, self.max_iter, self.max_step_rad)
        R, *terms, it, ok = statics_kernels.newton(
            *self._kernel_args, np.ascontiguousarray(R0, dtype=np.float64), np.ascontiguousarray(l, dtype=np.float64),
            np.ascontiguousarray(tau_ext, dtype=np.float64), self.tol_Nm, self.max_iter, self.max_step_rad,
            MAX_EXCURSION_RAD)
        return (R, tuple(terms), it), bool(ok)

    def solve(self, l: np.ndarray, tau_ext: np.ndarray, R_init: np.ndarray) -> Equilibrium:
        """Equilibrium for rest lengths ``l`` (m,) and moment ``tau_ext`` (3,) from ``R_init``."""
        state, ok = self._newton(l, R_init, tau_ext)
        if not ok and self.continuation_steps > 0 and np.any(tau_ext):
            # load continuation: equilibrium without tau_ext first, then increments
            R = R_init
            for s in np.linspace(0.0, 1.0, self.continuation_steps + 1):
                state, ok = self._newton(l, R, s * tau_ext)
                if not ok:
                    break
                R = state[0]
        stable = ok and _stable(state[1][2])
        if self.globalise and not stable:
            # plain Newton failed or found a saddle: energy descent from the start (model/_descent.py)
            from . import _descent

            state, status = _descent.descend(self._evaluate, cable_terms_for(self.rig), self._evaluate._F,
                                             self._evaluate._P, l, R_init, tau_ext, self.tol_Nm,
                                             max_step_rad=self.max_step_rad)
            ok, stable = status in ("ok", "unstable"), status == "ok"
            if status == "fell":
                R, (g, *_, T, _, _), it = state
                raise NoEquilibrium(f"no equilibrium within {np.degrees(_descent.FALL_ANGLE_RAD):.0f} deg of the "
                                    f"start: the platform falls over ({int(np.sum(T <= 0))} slack cables)",
                                    "slack" if np.any(T <= 0) else "diverged", float(np.linalg.norm(g)))
        R, (g, K, K_t, T, tau_c, tau_p), it = state
        best = float(np.linalg.norm(g))
        n_slack = int(np.sum(T <= 0))
        if not ok:
            reason = "slack" if n_slack else "diverged"
            raise NoEquilibrium(f"no equilibrium found: residual {best:.3g} N m after {it} Newton steps "
                                f"({n_slack} slack cables)", reason, best)
        eq = Equilibrium(R, l, T, tau_ext, tau_c, tau_p, K, K_t, it)
        if not stable:
            raise NoEquilibrium(f"equilibrium found is unstable: tangent stiffness eigenvalues "
                                f"{np.round(np.linalg.eigvals(K_t).real, 4).tolist()} N m/rad "
                                f"({n_slack} slack cables)", "slack" if n_slack else "unstable", best)
        if n_slack and not self.allow_slack:
            raise NoEquilibrium(f"equilibrium has {n_slack} slack cable(s) "
                                f"({', '.join(f'l{i + 1}' for i in np.flatnonzero(T <= 0))}) and "
                                f"allow_slack=False", "slack", best)
        return eq


def solve_equilibrium(rig: Rig, rest_lengths_m: np.ndarray, tau_ext_A_Nm: npt.ArrayLike = (0.0, 0.0, 0.0),
                      point_forces: Sequence[PointForce] = (), R_init: np.ndarray | None = None,
                      include_weight: bool = True, model: Model | None = None, tol_Nm: float = 1e-11,
                      max_iter: int = 100, max_step_rad: float = 0.25, allow_slack: bool = True,
                      continuation_steps: int = 8, verify_tol_Nm: float = 1e-9,
                      compiled: bool = True, globalise: bool = True) -> Equilibrium:
    """Equilibrium of ``rig`` with rest lengths ``l`` (m) under the given loads.

    ``tau_ext_A_Nm`` is a moment fixed in {A}; ``point_forces`` are
    ``(force_B_N, point_A_m)`` pairs (dead weights fixed in {B}); the
    platform's weight is added unless ``include_weight=False``. ``R_init`` is
    the starting orientation (identity by default; pass the previous pose to
    warm-start). With ``allow_slack=False`` an equilibrium with a slack cable
    raises :class:`NoEquilibrium` (``reason="slack"``). ``continuation_steps``
    load increments are tried when plain Newton fails (0 disables); if that
    fails too or ends on an unstable equilibrium, ``globalise=True`` runs the
    energy descent of :mod:`csjm_opt.model._descent` from ``R_init`` (it
    finds the stable equilibrium a heavily damped platform settles in, and
    raises ``NoEquilibrium`` when the platform falls over, i.e. leaves the
    90 degree ball around ``R_init``). The result
    is verified with the CasADi model (``model``): its residual
    ``||J^T T + tau_load||`` must be below ``verify_tol_Nm``.
    """
    model = model if model is not None and model.rig is rig else Model(rig)
    l = as_array(rest_lengths_m, (rig.n_cables,), "rest_lengths")
    if np.any(l <= 0):
        raise InvalidInput(f"rest lengths must be positive, got {np.round(l, 6).tolist()} m", "rest_lengths")
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    R0 = np.eye(3) if R_init is None else as_rotation(R_init, "R_init")
    forces = [(as_vector3(f, "force_B"), as_vector3(p, "point_A")) for f, p in point_forces]
    solver = EquilibriumSolver(rig, forces, include_weight, tol_Nm, max_iter, max_step_rad,
                               allow_slack, continuation_steps, compiled, globalise)
    eq = solver.solve(l, tau_ext, R0)
    # independent check with the CasADi model
    T = model.tensions_from_rest(eq.R, l)
    tau = model.cable_moment(eq.R, T) + tau_ext
    tau += sum((model.point_force_moment(eq.R, f, p)[0] for f, p in forces), np.zeros(3))
    if include_weight and rig.platform_mass_kg > 0:
        tau += model.weight_moment(eq.R)
    residual = float(np.linalg.norm(tau))
    if not residual <= max(verify_tol_Nm, tol_Nm):
        raise NoEquilibrium(f"equilibrium residual {residual:.3g} N m (CasADi model) exceeds "
                            f"{verify_tol_Nm:g} N m", "diverged", residual)
    return eq


def rest_lengths_for(rig: Rig, R: np.ndarray, tensions_N: np.ndarray, model: Model | None = None) -> np.ndarray:
    """Rest lengths ``l = c(R) - T / k`` that give tensions ``T`` at ``R`` (m)."""
    model = model if model is not None and model.rig is rig else Model(rig)
    return model.rest_lengths(as_rotation(R), as_array(tensions_N, (rig.n_cables,), "tensions"))
