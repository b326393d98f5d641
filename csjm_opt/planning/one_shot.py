"""One tension plan without the compiled kernels: the start-up path of ``csjm plan``.

The compiled planner (:func:`csjm_opt.planning.planner.plan_tensions`) plans a
pose in ~5 us, but its first call in a process loads numba and its cached
machine code, about one second. A command that plans one pose and exits pays
that second for a 50 us job. :func:`plan_tensions_uncompiled` solves the same
QP::

    minimise    1/2 ||T - T_ref||^2
    subject to  J^T T + tau_load = 0,   t_min <= T <= t_max

by the same primal-dual active set method (Hintermueller, Ito & Kunisch 2002;
see :mod:`csjm_opt.planning.active_set`) written in NumPy over the m cables,
with the geometry and weight moment from the NumPy reference
(:mod:`csjm_opt.model.cable_terms`). It imports neither numba nor SciPy.
When the method does not settle (near the boundary of the feasible set, where
few tensions hold the load) or an input needs validating, it hands the pose to
the compiled planner, which has the finite fallbacks and the infeasibility
report; so its answers are the compiled planner's to round-off
(``tests/planning/test_one_shot.py`` checks it, and both against an
independent QP solver).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..model import cable_terms
from ..model.rig import Rig
from .plans import TensionPlan

__all__ = ["plan_tensions_uncompiled"]

#: Iterations of the active-set method before the compiled planner takes over (as the compiled kernel).
MAX_ITER = 40


def solve_active_set(J: np.ndarray, b: np.ndarray, t_ref: np.ndarray, lo: float, hi: float,
                     max_iter: int = MAX_ITER) -> np.ndarray | None:
    """``argmin 1/2||t - t_ref||^2`` s.t. ``J^T t = b``, ``lo <= t <= hi``; ``None`` if it does not settle.

    Parameters
    ----------
    J : (m, 3) Jacobian (38); b : (3,) required cable moment (N m); t_ref : (m,) N; lo, hi : bounds (N).
    """
    eps = 1e-10 * max(1.0, abs(hi))
    lower = np.zeros(J.shape[0], bool)
    upper = np.zeros(J.shape[0], bool)
    for _ in range(max_iter):
        free = ~(lower | upper)
        fixed_t = np.where(lower, lo, hi)
        M = J[free].T @ J[free]
        rhs = b - J[~free].T @ fixed_t[~free] - J[free].T @ t_ref[free]
        tr = np.trace(M) / 3.0
        if tr <= 0.0 or abs(np.linalg.det(M)) < 1e-12 * tr**3:
            return None
        lam = np.linalg.solve(M, rhs)
        t_free = t_ref + J @ lam                 # stationarity of the free tensions
        t = np.where(free, t_free, fixed_t)
        # multipliers of active bounds: z = t - t_ref - J lam (>= 0 at lower, <= 0 at upper)
        release_lower = lower & (t - t_free < -eps)
        release_upper = upper & (t - t_free > eps)
        hit_lower = free & (t < lo - eps)
        hit_upper = free & (t > hi + eps)
        if not (release_lower.any() or release_upper.any() or hit_lower.any() or hit_upper.any()):
            return t
        lower = (lower & ~release_lower) | hit_lower
        upper = (upper & ~release_upper) | hit_upper
    return None


def plan_tensions_uncompiled(rig: Rig, R: np.ndarray, tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0),
                             t_ref_N: ArrayLike | None = None) -> TensionPlan:
    """Tensions that hold ``tau_ext`` (N m, {A}) at ``R``, closest to ``t_ref`` (N), without numba.

    The same plan as :func:`csjm_opt.planning.planner.plan_tensions` with its
    default solver (to round-off), for one pose in a process that has not
    loaded the compiled kernels. Poses the NumPy method cannot settle, and
    inputs that need validating, go to the compiled planner.

    Raises
    ------
    InfeasibleLoad : as the compiled planner, for a load outside the wrench-feasible set.
    """
    R_arr = np.asarray(R, dtype=np.float64)
    tau_ext = np.asarray(tau_ext_A_Nm, dtype=np.float64)
    n_cab = rig.n_cables
    t_ref = rig.t_mid_N if t_ref_N is None else np.asarray(t_ref_N, float)
    if t_ref.shape == ():
        t_ref = np.full(n_cab, float(t_ref))
    ok_input = (t_ref.shape == (n_cab,) and R_arr.shape == (3, 3) and tau_ext.shape == (3,)
                and np.all(np.isfinite(R_arr)) and np.all(np.isfinite(tau_ext)) and np.all(np.isfinite(t_ref))
                and np.abs(R_arr.T @ R_arr - np.eye(3)).max() <= 1e-12 and np.linalg.det(R_arr) > 0.0)
    if ok_input:
        A, B = rig.platform_holes_A_m, rig.base_holes_B_m
        c, _, J = cable_terms.geometry(R_arr, A, B)
        tau_w = cable_terms.weight_moment(R_arr, rig.platform_mass_kg * np.asarray(rig.com_A_m, float),
                                          np.asarray(rig.gravity_B_m_per_s2, float))
        T = solve_active_set(J, -(tau_ext + tau_w), t_ref, rig.t_min_N, rig.t_max_N)
        if T is not None:
            plan = TensionPlan(T, R_arr, tau_ext, tau_w, J, rig.t_min_N, rig.t_max_N, np.array(t_ref, float),
                               "active_set", c, c - T / rig.cable_stiffness_N_per_m)
            if plan.is_valid():   # the compiled planner's own check: equilibrium to 1e-8 N m, bounds to 1e-9 N
                return plan
    from .planner import plan_tensions  # the compiled planner: validation, fallbacks, infeasibility

    return plan_tensions(rig, R, tau_ext_A_Nm, None if t_ref_N is None else np.asarray(t_ref_N, float))

