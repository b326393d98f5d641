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
runs compiled (:mod:`csjm_opt.control._loop_kernels`, numba), ``compiled=False``
runs the numpy reference. Cheap enough for a 1 kHz simulation loop.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Sequence

import numpy as np
import numpy.typing as npt

from .. import so3
from .cable_terms import CableTerms, point_force_terms
from ..errors import InvalidInput, NoEquilibrium
from .numeric import Model
from .rig import Rig
from .._validate import as_array, as_rotation, as_vector3

PointForce = tuple[np.ndarray, np.ndarray]  # (force in {B}, N; point in {A}, m)

#: Largest rotation (rad) away from the start before a Newton run is called diverged.
MAX_EXCURSION_RAD = 2.5


@dataclasses.dataclass(frozen=True, eq=False)
class Equilibrium:
    """A static equilibrium found by :func:`solve_equilibrium` (checks itself)."""

    R: np.ndarray                   # (3, 3) orientation of {A} in {B}
    rest_lengths_m: np.ndarray      # (6,)
    tensions_N: np.ndarray          # (6,)
    tau_ext_A_Nm: np.ndarray        # (3,) external moment fixed in {A}
    tau_cable_A_Nm: np.ndarray      # (3,) J^T T
    tau_points_A_Nm: np.ndarray     # (3,) weight plus dead-weight forces
    K: np.ndarray                   # (3, 3) cable stiffness (convention of docs/conventions.md) at R
    K_tangent: np.ndarray           # (3, 3) tangent stiffness of the whole loaded system
    iterations: int

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (docs/conventions.md name)."""
        return self.tensions_N

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
        """All eigenvalues of the tangent stiffness have positive real part."""
        return bool(np.all(np.linalg.eigvals(self.K_tangent).real > 0))

    def is_valid(self, tol_Nm: float = 1e-9) -> bool:
        """Residual within ``tol_Nm`` and stable."""
        return self.residual_Nm <= tol_Nm and self.stable


# ------------------------------------------------------------------ terms
@functools.lru_cache(maxsize=64)
def cable_terms_for(rig: Rig) -> CableTerms:
    """Closed-form cable terms of ``rig`` (cached per rig object)."""
    return CableTerms.from_rig(rig)


class _Evaluator:
    """All Newton terms at a pose, closed form (checked against the CasADi model in the tests)."""

    def __init__(self, rig: Rig, forces: list[PointForce]):
        self._terms = cable_terms_for(rig)
        self._F = np.array([f for f, _ in forces], float).reshape(-1, 3)
        self._P = np.array([p for _, p in forces], float).reshape(-1, 3)

    def __call__(self, R: np.ndarray, l: np.ndarray, tau_ext: np.ndarray):
        T, tau_c, K = self._terms.rest_terms(R, l)
        tau_p, H_p = point_force_terms(R, self._F, self._P)
        g = tau_c + tau_p + tau_ext
        K_t = K + H_p - 0.5 * so3.hat(tau_c + tau_p)
        return g, K, K_t, T, tau_c, tau_p


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
        from ..control import _loop_kernels as loop_kernels

        R, *terms, it, ok = loop_kernels.newton(
            *self._kernel_args, np.ascontiguousarray(R0, dtype=np.float64), np.ascontiguousarray(l, dtype=np.float64),
            np.ascontiguousarray(tau_ext, dtype=np.float64), self.tol_Nm, self.max_iter, self.max_step_rad,
            MAX_EXCURSION_RAD)
        return (R, tuple(terms), it), bool(ok)

    def solve(self, l: np.ndarray, tau_ext: np.ndarray, R_init: np.ndarray) -> Equilibrium:
        """Equilibrium for rest lengths ``l`` (6,) and moment ``tau_ext`` (3,) from ``R_init``."""
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


def _stable(K_t: np.ndarray) -> bool:
    """All eigenvalues of the 3x3 ``K_t`` have positive real part (Routh-Hurwitz on ``det(s I + K_t)``)."""
    if not np.all(np.isfinite(K_t)):
        return False
    tr = K_t[0, 0] + K_t[1, 1] + K_t[2, 2]
    m2 = (K_t[0, 0] * K_t[1, 1] - K_t[0, 1] * K_t[1, 0] + K_t[0, 0] * K_t[2, 2] - K_t[0, 2] * K_t[2, 0]
          + K_t[1, 1] * K_t[2, 2] - K_t[1, 2] * K_t[2, 1])
    det = float(np.linalg.det(K_t))
    return bool(tr > 0 and det > 0 and tr * m2 > det)


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
    l = as_array(rest_lengths_m, (6,), "rest_lengths")
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


def _newton(evaluate: _Evaluator, l: np.ndarray, R0: np.ndarray, tau_ext: np.ndarray, tol_Nm: float,
            max_iter: int, max_step_rad: float):
    """Damped Newton from ``R0``; returns ``((R, terms, iterations), converged)``."""
    R = R0
    terms = evaluate(R, l, tau_ext)
    best = float(np.linalg.norm(terms[0]))
    it = 0
    for it in range(1, max_iter + 1):
        if best <= tol_Nm:
            it -= 1
            break
        g, _, K_t = terms[0], terms[1], terms[2]
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(K_t))):
            return (R, terms, it), False
        step = _newton_step(K_t, g, max_step_rad)
        alpha, improved = 1.0, False
        for _ in range(30):
            R_try = R @ so3.exp(alpha * step)
            out = evaluate(R_try, l, tau_ext)
            norm = float(np.linalg.norm(out[0]))
            if norm < best or norm <= tol_Nm:
                R, terms, best, improved = R_try, out, norm, True
                break
            alpha *= 0.5
        if not improved or _angle(R0, R) > MAX_EXCURSION_RAD:
            return (R, terms, it), False
    return (R, terms, it), best <= tol_Nm


def _angle(R0: np.ndarray, R: np.ndarray) -> float:
    """Rotation angle of ``R0^T R`` (rad), from the trace."""
    return float(np.arccos(np.clip(0.5 * (np.sum(R0 * R) - 1.0), -1.0, 1.0)))


def _newton_step(K_t: np.ndarray, g: np.ndarray, max_step_rad: float) -> np.ndarray:
    """Solve ``K_t step = g`` (g + dg/dzeta step = 0, dg/dzeta = -K_t), regularised and capped."""
    try:
        step = np.linalg.solve(K_t, g)
        if not np.all(np.isfinite(step)) or (np.dot(step, g) <= 0 and np.linalg.cond(K_t) > 1e10):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        S = 0.5 * (K_t + K_t.T)
        mu = max(0.0, -np.min(np.linalg.eigvalsh(S))) + 1e-3 * max(1.0, np.abs(S).max())
        step = np.linalg.solve(S + mu * np.eye(3), g)
    norm = np.linalg.norm(step)
    return step if norm <= max_step_rad else step * (max_step_rad / norm)


def rest_lengths_for(rig: Rig, R: np.ndarray, tensions_N: np.ndarray, model: Model | None = None) -> np.ndarray:
    """Rest lengths ``l = c(R) - T / k`` that give tensions ``T`` at ``R`` (m)."""
    model = model if model is not None and model.rig is rig else Model(rig)
    return model.rest_lengths(as_rotation(R), as_array(tensions_N, (6,), "tensions"))
