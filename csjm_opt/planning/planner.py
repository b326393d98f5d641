"""Tension planner: tensions that hold a pose under a load (paper (38)).

Build, then solve (pink's ``build_ik``/``solve_ik``):
:func:`build_tension_qp` returns a :class:`qpsolvers.Problem` a test can
inspect without a solver; :func:`plan_tensions` solves it and returns a
self-checking :class:`TensionPlan` (:mod:`csjm_opt.planning.plans`) that also
carries the cable and rest lengths. By default the QP is solved exactly by the
compiled primal-dual active set method (:mod:`csjm_opt.planning.kernels`), with
a finite primal active-set method (:mod:`csjm_opt.planning.dense_qp`) as the
fallback near the boundary of the feasible set; any qpsolvers backend can be
chosen, and its answer is then polished to round-off from its active set and
checked. (OSQP alone is not exact: it refuses loads up to ~1e-3 N m inside
the feasible set; its set-up also costs ~0.5 ms a pose.) The QP::

    minimise    1/2 ||T - T_ref||^2
    subject to  J^T T + tau_load = 0,   tau_load = tau_ext + tau_weight  (in {A})
                t_min <= T <= t_max

A load more than ``FEASIBILITY_TOL_NM`` outside the wrench-feasible set raises
:class:`InfeasibleLoad` with the distance ``min ||J^T T + tau_load||`` over the
tension box; a load within that tolerance always gets a plan.
"""

from __future__ import annotations

import warnings
from typing import TYPE_CHECKING, Any, NoReturn

import numba
import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_array, as_rotation, as_vector3
from ..errors import InfeasibleLoad, InvalidInput, SolverError
from ..model.numeric import Model, as_rotations_fast, model_for, parallel_ok
from ..model.rig import Rig
from . import dense_qp as dense_qp
from . import kernels as kernels
from .plans import TensionPlan, TensionPlanBatch

if TYPE_CHECKING:        # qpsolvers and SciPy load only on the paths that use them (csjm plan needs neither)
    import qpsolvers

__all__ = ["FEASIBILITY_TOL_NM", "SOLVERS", "TensionPlan", "TensionPlanBatch", "build_tension_qp",
           "build_tension_qp_for", "feasibility_distance_Nm", "plan_tensions", "plan_tensions_batch"]

#: Equilibrium residual (N m) above which a load is reported infeasible.
FEASIBILITY_TOL_NM = 1e-8


# --------------------------------------------------------------------- build
def build_tension_qp(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float, t_max_N: float,
                     t_ref_N: np.ndarray) -> qpsolvers.Problem:
    """The tension QP as a :class:`qpsolvers.Problem` (dense), solver-free."""
    import qpsolvers
    from scipy import sparse

    n_cab = J.shape[0]
    return qpsolvers.Problem(P=sparse.identity(n_cab, format="csc"), q=-np.asarray(t_ref_N, float),
                             A=sparse.csc_matrix(J.T), b=-np.asarray(tau_load_A_Nm, float),
                             lb=np.full(n_cab, t_min_N), ub=np.full(n_cab, t_max_N))


def build_tension_qp_for(rig: Rig, R: np.ndarray, tau_ext_A_Nm: np.ndarray,
                         t_ref_N: np.ndarray | None = None,
                         model: Model | None = None) -> qpsolvers.Problem:
    """The tension QP of ``rig`` at pose ``R`` under ``tau_ext`` (validated inputs)."""
    model = model_for(rig, model)
    R = as_rotation(R)
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    _, J, tau_w = model.pose_terms(R)
    return build_tension_qp(J, tau_ext + tau_w, rig.t_min_N, rig.t_max_N,
                            _t_ref(rig, t_ref_N))


# --------------------------------------------------------------------- solve
#: Solver names besides the qpsolvers backends: "active_set" (default: the compiled
#: exact method, then a finite primal active-set method), "auto" (the same, kept as an alias).
SOLVERS = ("active_set", "auto")


def plan_tensions(rig: Rig, R: np.ndarray, tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0),
                  t_ref_N: np.ndarray | None = None, solver: str = "active_set",
                  model: Model | None = None) -> TensionPlan:
    """Tensions that hold ``tau_ext`` (N m, {A}) at ``R``, closest to ``t_ref`` (N).

    Parameters
    ----------
    rig : the rig.
    R : (3, 3) orientation of {A} in {B}.
    tau_ext_A_Nm : (3,) external moment in {A}, weight excluded.
    t_ref_N : reference tensions of the objective (scalar or (m,); default mid-range).
    solver : ``"active_set"`` (default) solves the QP exactly by the compiled
        primal-dual active-set method; if that does not settle (near the
        boundary of the feasible set, where few tensions hold the load) a
        finite primal active-set method from a feasible point takes over. Any
        installed qpsolvers backend (``"osqp"``, ``"clarabel"``, ...) solves
        :func:`build_tension_qp` instead; its answer is polished exactly from
        its active set and checked, with the same fallback.
    model : a :class:`Model` of ``rig`` to reuse (optional).

    Returns
    -------
    TensionPlan : with ``rest_lengths_m`` and ``cable_lengths_m``.

    Raises
    ------
    InfeasibleLoad : only when the load lies more than ``FEASIBILITY_TOL_NM``
        outside the wrench-feasible set (``distance_Nm`` says how far).
    """
    _check_solver(solver)
    m = model_for(rig, model)
    R_arr, tau_ext = np.asarray(R, dtype=np.float64), np.asarray(tau_ext_A_Nm, dtype=np.float64)
    t_ref = m.t_mid if t_ref_N is None else _t_ref(rig, t_ref_N)
    if R_arr.shape != (3, 3) or tau_ext.shape != (3,):  # the validators say what is wrong
        R_arr, tau_ext = as_rotation(R), as_vector3(tau_ext_A_Nm, "tau_ext")
    n_cab = m.A.shape[0]
    T, J, tau_w, c, l, info = (np.empty(n_cab), np.empty((n_cab, 3)), np.empty(3), np.empty(n_cab),
                               np.empty(n_cab), np.empty(2))
    default = solver in SOLVERS
    args = (m.A, m.B, m.k, m.first_moment_A_kgm, m.g)
    tail = (rig.t_min_N, rig.t_max_N, 40 if default else 0, T, J, tau_w, c, l, info)
    status = kernels.plan_one(*args, R_arr, tau_ext, t_ref, *tail)
    if status == kernels.BAD_INPUT:  # not a rotation to round-off, or not finite: validate, re-orthonormalise
        R_arr, tau_ext = as_rotation(R), as_vector3(tau_ext_A_Nm, "tau_ext")
        status = kernels.plan_one(*args, R_arr, tau_ext, t_ref, *tail)
    used = "active_set"
    if status != kernels.OK:
        b = -(tau_ext + tau_w)
        T, used = _solve_hard(J, b, t_ref, rig, R_arr, tau_ext, None if default else solver)
        l = c - T / m.k
        info[0], info[1] = np.linalg.norm(J.T @ T - b), max(0.0, float(np.max(np.maximum(rig.t_min_N - T,
                                                                                           T - rig.t_max_N))))
    plan = TensionPlan(T, R_arr, tau_ext, tau_w, J, rig.t_min_N, rig.t_max_N, t_ref, used, c, l)
    if info[0] > FEASIBILITY_TOL_NM or info[1] > 1e-9:  # cannot happen unless a solver misbehaves
        raise SolverError(f"{used}: tension plan fails its own check (residual {info[0]:.3g} N m, "
                          f"bound violation {info[1]:.3g} N)", used)
    return plan


def plan_tensions_batch(rig: Rig, Rs: np.ndarray, taus_A_Nm: np.ndarray | None = None,
                        t_ref_N: np.ndarray | None = None, solver: str = "active_set",
                        model: Model | None = None) -> TensionPlanBatch:
    """Plan tensions for ``n`` poses ``Rs`` (n, 3, 3) under loads ``taus`` (n, 3) N m.

    Poses are solved in order, each warm-started from the previous pose's
    active set (as along a trajectory), in one compiled loop that also gives
    cable and rest lengths. Rows that do not settle, and all rows for a
    qpsolvers backend, go through :func:`plan_tensions` one by one.

    Parameters
    ----------
    rig, solver, model : as in :func:`plan_tensions`.
    Rs : (n, 3, 3) orientations.
    taus_A_Nm : (n, 3) external moments (default zero).
    t_ref_N : scalar, (m,) or (n, m) reference tensions.

    Returns
    -------
    TensionPlanBatch

    Raises
    ------
    InfeasibleLoad : for the first pose whose load is infeasible (``index`` set).
    """
    Rs = as_rotations_fast(Rs, "Rs")
    n = Rs.shape[0]
    taus = np.zeros((n, 3)) if taus_A_Nm is None else as_array(taus_A_Nm, (n, 3), "taus")
    t_ref = _t_ref_batch(rig, t_ref_N, n)
    _check_solver(solver)
    m = model_for(rig, model)
    n_cab = m.A.shape[0]
    T, J, tau_w = np.zeros((n, n_cab)), np.empty((n, n_cab, 3)), np.empty((n, 3))
    c, l = np.empty((n, n_cab)), np.empty((n, n_cab))
    status = np.full(n, kernels.NOT_CONVERGED, np.int64)
    args = (m.A, m.B, m.k, m.first_moment_A_kgm, m.g, Rs, taus, t_ref, rig.t_min_N, rig.t_max_N,
            40 if solver in SOLVERS else 0, T, J, tau_w, c, l, status)
    if parallel_ok(n):  # consecutive chunks, one per thread, each warm-started along its poses
        kernels.plan_batch_par(*args, numba.get_num_threads())
    else:
        kernels.plan_batch(*args)
    todo = np.flatnonzero(status != kernels.OK)
    for i in todo:
        try:
            plan = plan_tensions(rig, Rs[i], taus[i], t_ref[i], solver, m)
        except InfeasibleLoad as exc:
            raise InfeasibleLoad(f"pose {i}: {exc}", Rs[i], taus[i], exc.distance_Nm, index=int(i)) from exc
        T[i], l[i] = plan.tensions_N, plan.rest_lengths_m
    return TensionPlanBatch(T, Rs, taus, tau_w, J, rig.t_min_N, rig.t_max_N, solver, int(todo.size), c, l)


def _solve_hard(J: np.ndarray, b: np.ndarray, t_ref: np.ndarray, rig: Rig, R: np.ndarray,
                tau_ext: np.ndarray, backend: str | None) -> tuple[np.ndarray, str]:
    """Tensions when the compiled active set did not settle (or another solver was asked for).

    Order: the backend (if any), polished exactly from its active set; the
    dense primal active-set method from a feasible point (finite); the
    bounded least-squares point when the load is within ``FEASIBILITY_TOL_NM``
    of the feasible set. Raises :class:`InfeasibleLoad` only when it is not.
    """
    lo, hi = rig.t_min_N, rig.t_max_N
    n_cab = J.shape[0]
    if kernels.outside_margin(np.ascontiguousarray(J, dtype=float), b, float(lo), float(hi)) > FEASIBILITY_TOL_NM:
        # past a facet plane: no solver can hold it
        _raise_infeasible(J, b, lo, hi, R, tau_ext)
    if backend is not None:
        x = _solve_qp(build_tension_qp(J, -b, lo, hi, t_ref), backend)
        if x is not None:
            tol = 1e-5 * max(1.0, hi)
            lower, upper = x <= lo + tol, x >= hi - tol
            T = np.empty(n_cab)
            if kernels.solve_one(J, b, t_ref, lo, hi, lower, upper, T, 40) == kernels.OK \
                    and _holds(J, b, T, lo, hi):
                return T, backend
    res = dense_qp.solve(np.eye(n_cab), -t_ref, np.ascontiguousarray(J.T), b, np.full(n_cab, lo),
                         np.full(n_cab, hi))
    T = np.clip(res.x, lo, hi)
    if res.converged and _holds(J, b, T, lo, hi):
        return T, "active_set" if backend is None else f"{backend}+active_set"
    T, dist = _nearest_feasible(J, -b, lo, hi)
    if dist <= FEASIBILITY_TOL_NM:
        return T, "bvls"
    _raise_infeasible(J, b, lo, hi, R, tau_ext)


def _raise_infeasible(J: np.ndarray, b: np.ndarray, lo: float, hi: float, R: np.ndarray,
                      tau_ext: np.ndarray) -> NoReturn:
    dist = _nearest_feasible(J, -b, lo, hi)[1]
    raise InfeasibleLoad(
        f"load tau_ext={np.round(tau_ext, 4).tolist()} N m cannot be held at this pose "
        f"with {lo:g} N <= t <= {hi:g} N: it lies {dist:.3g} N m outside the "
        f"wrench-feasible set", R, tau_ext, dist)


def _holds(J: np.ndarray, b: np.ndarray, T: np.ndarray, lo: float, hi: float) -> bool:
    return bool(np.linalg.norm(J.T @ T - b) <= FEASIBILITY_TOL_NM and T.min() >= lo - 1e-9 and T.max() <= hi + 1e-9)


def _nearest_feasible(J: np.ndarray, tau_load: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, float]:
    J = np.ascontiguousarray(J, dtype=float)
    b = -np.asarray(tau_load, float)
    if kernels.outside_margin(J, b, float(lo), float(hi)) > 0.0:   # outside: nearest point on a face, exact
        T = np.empty(J.shape[0])
        return T, float(kernels.boundary_distance(J, b, float(lo), float(hi), T))
    from scipy.optimize import lsq_linear

    res = lsq_linear(J.T, b, bounds=(lo, hi), method="bvls", tol=1e-14)
    T = np.clip(res.x, lo, hi)
    return T, float(np.linalg.norm(J.T @ T - b))


def feasibility_distance_Nm(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float,
                            t_max_N: float) -> float:
    """``min ||J^T T + tau_load||`` over ``t_min <= T <= t_max`` (bounded least squares), N m."""
    return _nearest_feasible(J, tau_load_A_Nm, t_min_N, t_max_N)[1]


# --------------------------------------------------------------------- helpers
def _t_ref(rig: Rig, t_ref_N: np.ndarray | None) -> np.ndarray:
    if t_ref_N is None:
        return rig.t_mid_N
    t_ref = np.asarray(t_ref_N, float)
    if t_ref.shape == ():
        t_ref = np.full(rig.n_cables, float(t_ref))
    return as_array(t_ref, (rig.n_cables,), "t_ref")


def _t_ref_batch(rig: Rig, t_ref_N: np.ndarray | None, n: int) -> np.ndarray:
    if t_ref_N is not None and np.ndim(t_ref_N) == 2:
        return np.ascontiguousarray(as_array(t_ref_N, (n, rig.n_cables), "t_ref"))
    return np.ascontiguousarray(np.broadcast_to(_t_ref(rig, t_ref_N), (n, rig.n_cables)))


def _check_solver(solver: str) -> None:
    if solver in SOLVERS:
        return
    import qpsolvers

    if solver not in qpsolvers.available_solvers:
        raise InvalidInput(f"unknown QP solver {solver!r}; choose from "
                           f"{', '.join(SOLVERS + tuple(qpsolvers.available_solvers))}", "solver")


def _solve_qp(problem: qpsolvers.Problem, solver: str) -> np.ndarray | None:
    import qpsolvers

    opts: dict[str, Any] = {"eps_abs": 1e-9, "eps_rel": 1e-9, "verbose": False} if solver == "osqp" else {}
    try:
        with warnings.catch_warnings():  # infeasibility is reported by InfeasibleLoad instead
            warnings.simplefilter("ignore")
            sol = qpsolvers.solve_problem(problem, solver=solver, **opts)
    except Exception as exc:
        raise SolverError(f"{solver} failed: {exc}", solver) from exc
    return sol.x if sol.found and sol.x is not None else None
