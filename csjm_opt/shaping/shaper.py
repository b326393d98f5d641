"""Stiffness shaping: tensions that hold a load and make K as close as possible to a target.

For fixed cable stiffness ``k`` the stiffness of docs/conventions.md is affine in the
tensions (:mod:`csjm_opt.model.cable_terms`)::

    K(T) = K0 + sum_i t_i G_i,     K0 = J^T diag(k) J,   G_i = Hess(c_i)

and the six cables leave three redundant tension directions (the null space
of ``J^T``). Shaping solves the QP (build, then solve)::

    minimise    sum_k w_k (L_k . vec K(T) - s_k)^2 + rho ||T - t_mid||^2
    subject to  J^T T + tau_load = 0,   tau_load = tau_ext + tau_weight   (in {A})
                t_min <= T <= t_max

Objectives (:mod:`csjm_opt.shaping.objectives`; each a set of linear
functionals ``L_k`` of K with targets ``s_k``; the basis ``K0, G`` and the dense QP are in
:mod:`csjm_opt.shaping.basis`): ``"frobenius"`` (entries of K, elementwise weights ``W`` (3, 3):
``||K - K_target||_W^2 = sum W_ab (K_ab - K_target_ab)^2``), ``"eigen"``
(``u_k^T K u_k`` along the eigenvectors ``u_k`` of ``K_target``, targets its
eigenvalues: shapes the principal stiffnesses, ignores coupling), and
``"directional"`` (``u^T K u`` along given ``directions``, targets
``u^T K_target u``). ``rho`` is a tiny regulariser (``regularization`` times
the mean curvature) toward mid-range tensions, which only breaks ties.

:func:`build_shaping_qp` returns the :class:`qpsolvers.Problem`;
:func:`shape_stiffness` solves it (OSQP by default, polished to round-off by
the exact active-set solver of :mod:`csjm_opt.planning.dense_qp`, or ``"active_set"``
alone) and returns a self-checking :class:`ShapingResult`. :class:`Shaper`
is the allocation-light form for control loops (no qpsolvers round trip,
basis reused while the pose does not change, active set warm-started).
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
import qpsolvers
from scipy import sparse

from .._validate import as_array, as_rotation, as_vector3
from ..errors import InfeasibleLoad, InvalidInput, SolverError
from ..model import statics_kernels
from ..model.cable_terms import point_force_terms
from ..model.numeric import Model
from ..model.rig import Rig
from ..planning import dense_qp as dense_qp
from ..planning import kernels as _qp_kernels
from ..planning.planner import feasibility_distance_Nm
from . import shaping_kernels
from .basis import REGULARIZATION, StiffnessBasis, _terms, qp_matrices, stiffness_basis  # noqa: F401 (re-export)
from .objectives import OBJECTIVES, StiffnessObjective, make_objective  # noqa: F401 (re-export)
from .result import ShapingResult


def build_shaping_qp(rig: Rig, R: np.ndarray, tau_ext_A_Nm: np.ndarray, K_target: np.ndarray,
                     weights: np.ndarray | None = None, objective: str = "frobenius",
                     directions: np.ndarray | None = None,
                     regularization: float = REGULARIZATION) -> qpsolvers.Problem:
    """The shaping QP at ``R`` under ``tau_ext`` as a :class:`qpsolvers.Problem`, without solving it.

    Parameters
    ----------
    rig, R, tau_ext_A_Nm, K_target, weights, objective, directions, regularization
        As in :func:`shape_stiffness`.

    Returns
    -------
    qpsolvers.Problem
        ``min 1/2 T^T P T + q^T T`` subject to ``J^T T = -tau_load`` and
        ``t_min <= T <= t_max``; inspect it or solve it with any qpsolvers backend.

    Raises
    ------
    NotARotation
        If ``R`` is not a rotation.
    InvalidInput
        If an argument has the wrong shape, is not finite, or names an unknown objective.
    """
    R = as_rotation(R)
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    obj = make_objective(K_target, weights, objective, directions)
    P, q, A, b = qp_matrices(stiffness_basis(rig, R), tau_ext, obj, rig.t_mid_N, regularization)
    return qpsolvers.Problem(P=sparse.csc_matrix(P), q=q, A=sparse.csc_matrix(A), b=b,
                             lb=np.full(rig.n_cables, rig.t_min_N), ub=np.full(rig.n_cables, rig.t_max_N))


# --------------------------------------------------------------------- solve
class Shaper:
    """Reusable shaping solver for one rig (control loops).

    Keeps the stiffness basis while the pose is unchanged and warm-starts the
    exact active-set solver from the previous active set. Inputs are trusted.
    With ``compiled`` (default) the basis, the QP matrices and the primal-dual
    active-set iterations run in :mod:`csjm_opt.planning.kernels` (numba); the
    numpy solver of :mod:`csjm_opt.planning.dense_qp` (with its finite primal
    active-set fallback) takes over whenever they do not settle.
    """

    def __init__(self, rig: Rig, regularization: float = REGULARIZATION, compiled: bool = True):
        self.rig = rig
        self.regularization = regularization
        self.compiled = compiled
        m = rig.n_cables
        self._lo, self._hi = np.full(m, rig.t_min_N), np.full(m, rig.t_max_N)
        self._basis: StiffnessBasis | None = None
        self._active = (np.zeros(m, bool), np.zeros(m, bool))
        terms = _terms(rig)
        self._geom = (terms.A, terms.B, terms.k)
        self._weight = (rig.weight_B_N[None], np.asarray(rig.com_A_m, float)[None])

    def basis(self, R: np.ndarray) -> StiffnessBasis:
        """The stiffness basis ``K(T) = K0 + sum_i T_i G_i`` at ``R`` (cached for the last pose).

        Parameters
        ----------
        R : ndarray, shape (3, 3)
            Orientation of {A} in {B} (trusted: validate user input first).

        Returns
        -------
        StiffnessBasis
            ``K0``, ``G``, ``J`` and the weight moment at ``R``.
        """
        if self._basis is None or not np.array_equal(self._basis.R, R):
            R = np.array(R, float)
            if self.compiled:
                J, K0, G = statics_kernels.stiffness_basis(*self._geom, R)
                self._basis = StiffnessBasis(R, J, K0, G, point_force_terms(R, *self._weight)[0])
            else:
                self._basis = stiffness_basis(self.rig, R)
        return self._basis

    def solve(self, R: np.ndarray, tau_ext: np.ndarray, objective: StiffnessObjective,
              x0: np.ndarray | None = None) -> tuple[np.ndarray, StiffnessBasis, dense_qp.DenseQPResult]:
        """Solve the shaping QP at ``R`` under ``tau_ext`` (the fast path of a control loop).

        Parameters
        ----------
        R : ndarray, shape (3, 3)
            Orientation of {A} in {B} (trusted).
        tau_ext : ndarray, shape (3,)
            External moment in {A} (N m).
        objective : StiffnessObjective
            From :func:`~csjm_opt.shaping.objectives.make_objective`.
        x0 : ndarray, shape (m,), optional
            Tensions whose active bounds start the active-set method (warm start).

        Returns
        -------
        T : ndarray, shape (m,)
            Shaped tensions (N).
        basis : StiffnessBasis
            The basis used.
        result : DenseQPResult
            The QP solution with its active set and KKT data.

        Raises
        ------
        InfeasibleLoad
            If no tensions within the bounds hold the load.
        SolverError
            If the active-set method does not settle.
        """
        basis = self.basis(R)
        if x0 is not None:
            tol = 1e-5 * max(1.0, self.rig.t_max_N)
            self._active = (x0 <= self.rig.t_min_N + tol, x0 >= self.rig.t_max_N - tol)
        if self.compiled:
            P, q, A, b = shaping_kernels.shaping_qp(basis.G, basis.K0, objective.L, objective.s, objective.w, basis.J,
                                                 tau_ext + basis.tau_weight_A_Nm, self.rig.t_mid_N,
                                                 self.regularization)
            x, nu, z, lower, upper, it, status = _qp_kernels.pdas(P, q, A, b, self._lo, self._hi,
                                                                   self._active[0].copy(), self._active[1].copy(),
                                                                   8, 1e-10)
            if status == 0:
                self._active = (lower, upper)
                return x, basis, dense_qp.DenseQPResult(x, nu, z, lower, upper, it, "pdas", True)
        else:
            P, q, A, b = qp_matrices(basis, tau_ext, objective, self.rig.t_mid_N, self.regularization)
        res = dense_qp.solve(P, q, A, b, self._lo, self._hi, *self._active)
        if not res.converged or res.kkt_error(P, q, A, b, self._lo, self._hi) > 1e-6 * max(1.0, np.abs(q).max()):
            dist = feasibility_distance_Nm(basis.J, -b, self.rig.t_min_N, self.rig.t_max_N)
            if dist > 1e-8:
                raise InfeasibleLoad(f"load tau_ext={np.round(tau_ext, 4).tolist()} N m cannot be held at this "
                                     f"pose with {self.rig.t_min_N:g} N <= t <= {self.rig.t_max_N:g} N: it lies "
                                     f"{dist:.3g} N m outside the wrench-feasible set", R, tau_ext, dist)
            raise SolverError("shaping QP: active-set solver did not converge", "dense_qp")
        self._active = (res.lower, res.upper)
        return res.x, basis, res


def shape_stiffness(rig: Rig, R: np.ndarray, tau_ext_A_Nm: np.ndarray, K_target: np.ndarray,
                    weights: np.ndarray | None = None, objective: str = "frobenius",
                    directions: np.ndarray | None = None, solver: str = "osqp",
                    regularization: float = REGULARIZATION, exact_tol: float = 1e-6,
                    model: Model | None = None) -> ShapingResult:
    """Tensions within the bounds that hold the load at ``R`` and bring K closest to ``K_target``.

    Parameters
    ----------
    rig : Rig
        The rig.
    R : ndarray, shape (3, 3)
        Orientation of {A} in {B}.
    tau_ext_A_Nm : array_like, shape (3,)
        External moment in {A} (N m), platform weight excluded.
    K_target : array_like, shape (3, 3)
        Target stiffness (N m/rad, load convention); symmetrised.
    weights : array_like, optional
        ``"frobenius"``: (3, 3) elementwise weights; ``"eigen"``: 3 weights of the principal
        stiffnesses; ``"directional"``: one weight per direction.
    objective : {"frobenius", "eigen", "directional"}, optional
        What "closest" means (see :mod:`csjm_opt.shaping.objectives`).
    directions : array_like, shape (m, 3), optional
        Directions in {A} for ``objective="directional"``.
    solver : str, optional
        A qpsolvers backend (``"osqp"``, ``"clarabel"``, ...) whose answer is polished exactly by
        the active-set method, or ``"active_set"`` alone.
    regularization : float, optional
        Weight of a small pull toward mid-range tensions (makes the QP strictly convex).
    exact_tol : float, optional
        Residual (N m/rad) below which the target counts as reached.
    model : Model, optional
        A numeric model of ``rig`` to reuse.

    Returns
    -------
    ShapingResult
        Tensions, achieved K (CasADi model), weighted residual, ``exact`` (target reached) and the
        active bounds; the result checks its equilibrium and bounds (``is_valid()``).

    Raises
    ------
    NotARotation
        If ``R`` is not a rotation.
    InvalidInput
        If an argument has the wrong shape, is not finite, or names an unknown objective or solver.
    InfeasibleLoad
        If no tensions within the bounds hold the load.
    SolverError
        If the QP solver fails or its polished answer fails the checks.
    """
    model = model or Model(rig)
    R = as_rotation(R)
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    obj = make_objective(K_target, weights, objective, directions)
    shaper = Shaper(rig, regularization)
    x0 = None
    if solver != "active_set":
        x0 = _solve_qpsolvers(build_shaping_qp(rig, R, tau_ext, K_target, weights, objective, directions,
                                               regularization), solver)
    T, basis, res = shaper.solve(R, tau_ext, obj, x0)
    P, q, A, b = qp_matrices(basis, tau_ext, obj, rig.t_mid_N, regularization)
    Kt = as_array(K_target, (3, 3), "K_target")
    result = ShapingResult(T, model.stiffness(R, T), 0.5 * (Kt + Kt.T), obj, R, tau_ext,
                           model.weight_moment(R), model.jacobian(R), rig.t_min_N,
                           rig.t_max_N, solver, exact_tol, res.kkt_error(P, q, A, b, shaper._lo, shaper._hi))
    if not result.is_valid():
        raise SolverError(f"shaped tensions fail their check: equilibrium residual "
                          f"{result.equilibrium_residual_Nm:.3g} N m, bound violation "
                          f"{result.bound_violation_N:.3g} N", solver)
    return result


def _solve_qpsolvers(problem: qpsolvers.Problem, solver: str) -> np.ndarray | None:
    if solver not in qpsolvers.available_solvers:
        raise InvalidInput(f"unknown QP solver {solver!r}; installed: "
                           f"{', '.join(qpsolvers.available_solvers)} (or 'active_set')", "solver")
    opts: dict[str, Any]
    opts = {"eps_abs": 1e-10, "eps_rel": 1e-10, "verbose": False, "max_iter": 20000} if solver == "osqp" else {}
    try:
        with warnings.catch_warnings():  # solver chatter (status warnings) is reported by our own checks
            warnings.simplefilter("ignore")
            sol = qpsolvers.solve_problem(problem, solver=solver, **opts)
    except Exception as exc:  # noqa: BLE001 - backend errors are wrapped, never leaked
        raise SolverError(f"{solver} failed: {exc}", solver) from exc
    return sol.x if sol.found and sol.x is not None else None

