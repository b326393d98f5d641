"""Tension planner: tensions that hold a pose under a load (paper (38)).

Build, then solve (pink's ``build_ik``/``solve_ik``):
:func:`build_tension_qp` returns a :class:`qpsolvers.Problem` a test can
inspect without a solver; :func:`plan_tensions` solves it and returns a
self-checking :class:`TensionPlan`. By default the QP is solved exactly by the
compiled primal-dual active set method (:mod:`csjm_opt.planning._kernels`), with OSQP
through qpsolvers as the fallback; any qpsolvers backend can be chosen, and
its answer is then polished to round-off by the same active set method. (The
default is not OSQP because qpsolvers' set-up alone costs ~0.5 ms a pose,
several times scipy SLSQP; see docs/guide/planning.md.) The QP::

    minimise    1/2 ||T - T_ref||^2
    subject to  J^T T + tau_load = 0,   tau_load = tau_ext + tau_weight  (in {A})
                t_min <= T <= t_max

A load outside the wrench-feasible set raises :class:`InfeasibleLoad` with
the distance ``min ||J^T T + tau_load||`` over the tension box.
"""

from __future__ import annotations

import dataclasses
import warnings
from typing import Any

import numpy as np
import numpy.typing as npt
import qpsolvers
from scipy import sparse
from scipy.optimize import lsq_linear

from . import _kernels as kernels
from ..errors import InfeasibleLoad, InvalidInput, SolverError
from ..model.numeric import Model
from ..model.rig import Rig
from .._validate import as_array, as_rotation, as_rotations, as_vector3

#: Equilibrium residual (N m) above which a load is reported infeasible.
FEASIBILITY_TOL_NM = 1e-8


@dataclasses.dataclass(frozen=True, eq=False)
class TensionPlan:
    """Tensions for one pose and load; checks itself (qpsolvers ``Solution`` style)."""

    tensions_N: np.ndarray          # (6,)
    R: np.ndarray                   # (3, 3) orientation of {A} in {B}
    tau_ext_A_Nm: np.ndarray        # (3,) external moment, {A}
    tau_weight_A_Nm: np.ndarray     # (3,) platform weight moment, {A}
    J: np.ndarray                   # (6, 3) Jacobian (38) at R
    t_min_N: float
    t_max_N: float
    t_ref_N: np.ndarray             # (6,) reference tensions of the objective
    solver: str

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (docs/conventions.md name)."""
        return self.tensions_N

    @property
    def tau_load_A_Nm(self) -> np.ndarray:
        """Total load moment ``tau_ext + tau_weight`` in {A} (the paper's W)."""
        return self.tau_ext_A_Nm + self.tau_weight_A_Nm

    @property
    def equilibrium_residual_Nm(self) -> float:
        """``||J^T T + tau_load||`` (N m)."""
        return float(np.linalg.norm(self.J.T @ self.tensions_N + self.tau_load_A_Nm))

    @property
    def bound_margins_N(self) -> np.ndarray:
        """Per cable ``min(T - t_min, t_max - T)`` (N); negative means violated."""
        return np.minimum(self.tensions_N - self.t_min_N, self.t_max_N - self.tensions_N)

    @property
    def bound_violation_N(self) -> float:
        """Largest bound violation (N), 0 when within bounds."""
        return float(max(0.0, -np.min(self.bound_margins_N)))

    @property
    def active_bounds(self) -> list[str]:
        """Cables at a bound, e.g. ``["t3=t_min", "t5=t_max"]``."""
        tol = 1e-7 * max(1.0, self.t_max_N)
        out = []
        for i, t in enumerate(self.tensions_N):
            if abs(t - self.t_min_N) <= tol:
                out.append(f"t{i + 1}=t_min")
            elif abs(t - self.t_max_N) <= tol:
                out.append(f"t{i + 1}=t_max")
        return out

    def is_valid(self, eq_tol_Nm: float = 1e-8, bound_tol_N: float = 1e-9) -> bool:
        """Equilibrium and bounds hold within the given tolerances."""
        return self.equilibrium_residual_Nm <= eq_tol_Nm and self.bound_violation_N <= bound_tol_N


@dataclasses.dataclass(frozen=True, eq=False)
class TensionPlanBatch:
    """Tensions for many poses: arrays with a leading axis ``n``."""

    tensions_N: np.ndarray          # (n, 6)
    R: np.ndarray                   # (n, 3, 3)
    tau_ext_A_Nm: np.ndarray        # (n, 3)
    tau_weight_A_Nm: np.ndarray     # (n, 3)
    J: np.ndarray                   # (n, 6, 3)
    t_min_N: float
    t_max_N: float
    solver: str
    fallbacks: int                  # rows solved by the general QP solver instead

    @property
    def tensions(self) -> np.ndarray:
        return self.tensions_N

    def __len__(self) -> int:
        return self.tensions_N.shape[0]

    @property
    def equilibrium_residual_Nm(self) -> np.ndarray:
        """Per pose ``||J^T T + tau_load||`` (N m), shape (n,)."""
        tau = np.einsum("nij,ni->nj", self.J, self.tensions_N)
        return np.linalg.norm(tau + self.tau_ext_A_Nm + self.tau_weight_A_Nm, axis=1)

    @property
    def bound_violation_N(self) -> np.ndarray:
        """Per pose largest bound violation (N), shape (n,)."""
        margin = np.minimum(self.tensions_N - self.t_min_N, self.t_max_N - self.tensions_N)
        return np.maximum(0.0, -margin.min(axis=1))

    def __getitem__(self, i: int) -> TensionPlan:
        return TensionPlan(self.tensions_N[i], self.R[i], self.tau_ext_A_Nm[i],
                           self.tau_weight_A_Nm[i], self.J[i], self.t_min_N, self.t_max_N,
                           np.full(6, np.nan), self.solver)


# --------------------------------------------------------------------- build
def build_tension_qp(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float, t_max_N: float,
                     t_ref_N: np.ndarray) -> qpsolvers.Problem:
    """The tension QP as a :class:`qpsolvers.Problem` (dense), solver-free."""
    return qpsolvers.Problem(P=sparse.identity(6, format="csc"), q=-np.asarray(t_ref_N, float),
                             A=sparse.csc_matrix(J.T), b=-np.asarray(tau_load_A_Nm, float),
                             lb=np.full(6, t_min_N), ub=np.full(6, t_max_N))


def build_tension_qp_for(rig: Rig, R: np.ndarray, tau_ext_A_Nm: np.ndarray,
                         t_ref_N: np.ndarray | None = None,
                         model: Model | None = None) -> qpsolvers.Problem:
    """The tension QP of ``rig`` at pose ``R`` under ``tau_ext`` (validated inputs)."""
    model = model or Model(rig)
    R = as_rotation(R)
    tau_ext = as_vector3(tau_ext_A_Nm, "tau_ext")
    tau_load = tau_ext + model.weight_moment(R)
    return build_tension_qp(model.jacobian(R), tau_load, rig.t_min_N, rig.t_max_N,
                            _t_ref(rig, t_ref_N))


# --------------------------------------------------------------------- solve
#: Solver names besides the qpsolvers backends: "auto" (exact active set,
#: compiled, with OSQP through qpsolvers as fallback) and "active_set" (no fallback).
SOLVERS = ("auto", "active_set")


def plan_tensions(rig: Rig, R: np.ndarray, tau_ext_A_Nm: npt.ArrayLike = (0.0, 0.0, 0.0),
                  t_ref_N: np.ndarray | None = None, solver: str = "auto",
                  model: Model | None = None) -> TensionPlan:
    """Tensions that hold ``tau_ext`` (N m, {A}) at ``R``, closest to ``t_ref`` (N).

    ``solver``: ``"auto"`` (default) solves the QP exactly by the compiled
    active-set method and falls back to OSQP through qpsolvers if that does not
    settle; any installed qpsolvers backend (``"osqp"``, ``"clarabel"``, ...)
    solves :func:`build_tension_qp` with it and polishes the result exactly.
    ``model`` is accepted for symmetry with other functions and not needed.
    """
    R = _rotation(R)
    tau_ext = _vector3(tau_ext_A_Nm, "tau_ext")
    t_ref = _t_ref(rig, t_ref_N)
    _check_solver(solver)
    J, tau_w = np.empty((6, 3)), np.empty(3)
    kernels.jacobian_into(rig.platform_holes_A_m, rig.base_holes_B_m, R, J)
    kernels.weight_moment_into(rig.platform_mass_kg, rig.com_A_m, rig.gravity_B_m_per_s2, R, tau_w)
    b = -(tau_ext + tau_w)
    lower, upper, T = np.zeros(6, np.bool_), np.zeros(6, np.bool_), np.empty(6)
    status = kernels.NOT_CONVERGED
    used = solver
    if solver in SOLVERS:
        status = kernels.solve_one(J, b, t_ref, rig.t_min_N, rig.t_max_N, lower, upper, T, 40)
        used = "active_set"
    if status != kernels.OK and solver != "active_set":
        backend = "osqp" if solver in SOLVERS else solver
        x = _solve_qp(build_tension_qp(J, -b, rig.t_min_N, rig.t_max_N, t_ref), backend)
        if x is not None:  # polish exactly, warm-started from the backend's active set
            tol = 1e-5 * max(1.0, rig.t_max_N)
            lower, upper = x <= rig.t_min_N + tol, x >= rig.t_max_N - tol
            status = kernels.solve_one(J, b, t_ref, rig.t_min_N, rig.t_max_N, lower, upper, T, 40)
            used = backend
    plan = TensionPlan(T, R, tau_ext, tau_w, J, rig.t_min_N, rig.t_max_N, t_ref, used)
    if status == kernels.OK and plan.is_valid(FEASIBILITY_TOL_NM, 1e-9):
        return plan
    raise _infeasible(J, -b, rig, R, tau_ext)


def plan_tensions_batch(rig: Rig, Rs: np.ndarray, taus_A_Nm: np.ndarray | None = None,
                        t_ref_N: np.ndarray | None = None, solver: str = "auto",
                        model: Model | None = None) -> TensionPlanBatch:
    """Plan tensions for ``n`` poses ``Rs`` (n, 3, 3) under loads ``taus`` (n, 3) N m.

    Poses are solved in order, each warm-started from the previous pose's
    active set (as along a trajectory), in one compiled loop. Rows that do not
    settle, and all rows for a qpsolvers backend, go through
    :func:`plan_tensions` one by one. ``t_ref_N`` is a scalar, (6,) or (n, 6).
    """
    Rs = as_rotations(Rs, "Rs")
    n = Rs.shape[0]
    taus = np.zeros((n, 3)) if taus_A_Nm is None else as_array(taus_A_Nm, (n, 3), "taus")
    t_ref = _t_ref_batch(rig, t_ref_N, n)
    _check_solver(solver)
    T, J, tau_w = np.zeros((n, 6)), np.empty((n, 6, 3)), np.empty((n, 3))
    status = np.full(n, kernels.NOT_CONVERGED, np.int64)
    if solver in SOLVERS:
        kernels.plan_batch(rig.platform_holes_A_m, rig.base_holes_B_m, rig.platform_mass_kg,
                           rig.com_A_m, rig.gravity_B_m_per_s2, Rs, taus, t_ref, rig.t_min_N,
                           rig.t_max_N, 40, T, J, tau_w, status)
    todo = np.flatnonzero(status != kernels.OK)
    for i in todo:
        try:
            plan = plan_tensions(rig, Rs[i], taus[i], t_ref[i], "auto" if solver in SOLVERS else solver)
        except InfeasibleLoad as exc:
            raise InfeasibleLoad(f"pose {i}: {exc}", Rs[i], taus[i], exc.distance_Nm, index=int(i)) from exc
        T[i], J[i], tau_w[i] = plan.tensions_N, plan.J, plan.tau_weight_A_Nm
    batch = TensionPlanBatch(T, Rs, taus, tau_w, J, rig.t_min_N, rig.t_max_N, solver, int(todo.size))
    bad = (batch.equilibrium_residual_Nm > FEASIBILITY_TOL_NM) | (batch.bound_violation_N > 1e-9)
    if np.any(bad):
        k = int(np.argmax(bad))
        raise _infeasible(J[k], taus[k] + tau_w[k], rig, Rs[k], taus[k], index=k)
    return batch


def feasibility_distance_Nm(J: np.ndarray, tau_load_A_Nm: np.ndarray, t_min_N: float,
                            t_max_N: float) -> float:
    """``min ||J^T T + tau_load||`` over ``t_min <= T <= t_max`` (bounded least squares)."""
    res = lsq_linear(J.T, -np.asarray(tau_load_A_Nm, float), bounds=(t_min_N, t_max_N),
                     method="bvls", tol=1e-14)
    return float(np.linalg.norm(J.T @ res.x + tau_load_A_Nm))


# --------------------------------------------------------------------- helpers
def _t_ref(rig: Rig, t_ref_N: np.ndarray | None) -> np.ndarray:
    if t_ref_N is None:
        return rig.t_mid_N
    t_ref = np.asarray(t_ref_N, float)
    if t_ref.shape == ():
        t_ref = np.full(6, float(t_ref))
    return as_array(t_ref, (6,), "t_ref")


def _t_ref_batch(rig: Rig, t_ref_N: np.ndarray | None, n: int) -> np.ndarray:
    if t_ref_N is not None and np.ndim(t_ref_N) == 2:
        return np.ascontiguousarray(as_array(t_ref_N, (n, 6), "t_ref"))
    return np.ascontiguousarray(np.broadcast_to(_t_ref(rig, t_ref_N), (n, 6)))


def _rotation(R: np.ndarray) -> np.ndarray:
    """Fast path of :func:`as_rotation` for exact rotations (the common case)."""
    arr = np.asarray(R, dtype=np.float64)
    if arr.shape == (3, 3) and arr.flags.c_contiguous:
        err, det = kernels.rotation_error(arr)
        if err < 1e-12 and det > 0:
            return arr
    return as_rotation(R)


def _vector3(v: npt.ArrayLike, name: str) -> np.ndarray:
    arr = np.asarray(v, dtype=np.float64) if not isinstance(v, str) else None
    if arr is not None and arr.shape == (3,) and np.isfinite(arr).all():
        return arr
    return as_vector3(v, name)


def _check_solver(solver: str) -> None:
    if solver not in SOLVERS and solver not in qpsolvers.available_solvers:
        raise InvalidInput(f"unknown QP solver {solver!r}; choose from "
                           f"{', '.join(SOLVERS + tuple(qpsolvers.available_solvers))}", "solver")


def _solve_qp(problem: qpsolvers.Problem, solver: str) -> np.ndarray | None:
    opts: dict[str, Any]
    opts = {"eps_abs": 1e-9, "eps_rel": 1e-9, "verbose": False} if solver == "osqp" else {}  # we polish ourselves
    try:
        with warnings.catch_warnings():  # infeasibility is reported by InfeasibleLoad instead
            warnings.simplefilter("ignore")
            sol = qpsolvers.solve_problem(problem, solver=solver, **opts)
    except Exception as exc:  # noqa: BLE001 - backend errors are wrapped, never leaked
        raise SolverError(f"{solver} failed: {exc}", solver) from exc
    return sol.x if sol.found and sol.x is not None else None


def _infeasible(J: np.ndarray, tau_load: np.ndarray, rig: Rig, R: np.ndarray, tau_ext: np.ndarray,
                index: int | None = None) -> InfeasibleLoad:
    dist = feasibility_distance_Nm(J, tau_load, rig.t_min_N, rig.t_max_N)
    where = f"pose {index}: " if index is not None else ""
    return InfeasibleLoad(
        f"{where}load tau_ext={np.round(tau_ext, 4).tolist()} N m cannot be held at this pose "
        f"with {rig.t_min_N:g} N <= t <= {rig.t_max_N:g} N: it lies {dist:.3g} N m outside the "
        f"wrench-feasible set", R, tau_ext, dist, index)
