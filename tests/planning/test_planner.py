"""Tension planner: equilibrium, bounds, optimality against independent solvers."""

import numpy as np
import pytest
import qpsolvers
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog, minimize

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.planning.planner import build_tension_qp, feasibility_distance_Nm


def _independent_feasible(J, tau_load, t_min, t_max, margin=1e-3):
    """LP (HiGHS): is there T in [t_min + margin, t_max - margin] with J^T T = -tau_load?"""
    res = linprog(np.zeros(6), A_eq=J.T, b_eq=-tau_load, bounds=[(t_min + margin, t_max - margin)] * 6,
                  method="highs")
    return res.status == 0


def _slsqp(J, tau_load, t_min, t_max, t_ref):
    res = minimize(lambda t: 0.5 * np.sum((t - t_ref) ** 2), t_ref, jac=lambda t: t - t_ref,
                   constraints=[{"type": "eq", "fun": lambda t: J.T @ t + tau_load, "jac": lambda t: J.T}],
                   bounds=[(t_min, t_max)] * 6, method="SLSQP", options={"ftol": 1e-15, "maxiter": 500})
    return res.x


def _check_plan(plan, rig):
    assert plan.equilibrium_residual_Nm <= 1e-8
    assert np.all(plan.tensions_N >= rig.t_min_N - 1e-9)
    assert np.all(plan.tensions_N <= rig.t_max_N + 1e-9)
    assert plan.is_valid()


pose = st.tuples(*[st.floats(-0.35, 0.35)] * 3).map(np.array)
load = st.tuples(*[st.floats(-2.5, 2.5)] * 3).map(np.array)


@given(pose, load)
@settings(max_examples=40, deadline=None)
def test_planned_tensions_hold_the_load_within_bounds_and_are_optimal(rig, model, rotvec, tau):
    R = so3.exp(rotvec)
    J = model.jacobian(R)
    tau_load = tau + model.weight_moment(R)
    assume(_independent_feasible(J, tau_load, rig.t_min_N, rig.t_max_N))
    plan = co.plan_tensions(rig, R, tau, model=model)
    _check_plan(plan, rig)
    reference = _slsqp(J, tau_load, rig.t_min_N, rig.t_max_N, rig.t_mid_N)
    assert np.abs(plan.tensions_N - reference).max() < 1e-5
    other = co.plan_tensions(rig, R, tau, model=model, solver="clarabel")
    assert np.abs(other.tensions_N - plan.tensions_N).max() < 1e-5


def test_active_bounds_case_matches_slsqp(rig, model):
    """A load that drives some cables to a bound: exact KKT point, same as SLSQP."""
    R = so3.exp([0.25, -0.1, 0.05])
    tau = np.array([5.7, -3.6, 1.8])
    plan = co.plan_tensions(rig, R, tau, model=model)
    _check_plan(plan, rig)
    assert plan.active_bounds, "test load should make a bound active"
    J = plan.J
    ref = _slsqp(J, tau + plan.tau_weight_A_Nm, rig.t_min_N, rig.t_max_N, rig.t_mid_N)
    assert np.abs(plan.tensions_N - ref).max() < 1e-5


def test_user_reference_tension_changes_the_optimum_not_the_equilibrium(rig, model):
    R = so3.exp([0.1, 0.05, -0.1])
    low = co.plan_tensions(rig, R, [0.2, 0.1, 0.0], t_ref_N=20.0, model=model)
    high = co.plan_tensions(rig, R, [0.2, 0.1, 0.0], t_ref_N=120.0, model=model)
    _check_plan(low, rig)
    _check_plan(high, rig)
    assert low.tensions_N.mean() < high.tensions_N.mean()
    # the difference of two equilibria lies in the null space of J^T
    assert np.allclose(low.J.T @ (high.tensions_N - low.tensions_N), 0.0, atol=1e-8)


def test_build_tension_qp_is_the_stated_problem(rig, model):
    R = so3.exp([0.2, 0.0, 0.1])
    tau = np.array([0.5, -0.3, 0.2])
    J = model.jacobian(R)
    tau_load = tau + model.weight_moment(R)
    problem = build_tension_qp(J, tau_load, rig.t_min_N, rig.t_max_N, rig.t_mid_N)
    assert isinstance(problem, qpsolvers.Problem)
    assert np.allclose(problem.P.toarray(), np.eye(6))
    assert np.allclose(problem.q, -rig.t_mid_N)
    assert np.allclose(problem.A.toarray(), J.T)
    assert np.allclose(problem.b, -tau_load)
    assert np.all(problem.lb == rig.t_min_N) and np.all(problem.ub == rig.t_max_N)
    # without active bounds the optimum is the projection of t_ref onto the affine set
    t_proj = rig.t_mid_N - J @ np.linalg.solve(J.T @ J, J.T @ rig.t_mid_N + tau_load)
    assert np.all((t_proj > rig.t_min_N) & (t_proj < rig.t_max_N))
    assert np.allclose(co.plan_tensions(rig, R, tau, model=model).tensions_N, t_proj, atol=1e-9)


def test_infeasible_load_raises_with_distance(rig, model):
    R = so3.exp([0.1, 0.0, 0.0])
    tau = np.array([15.0, 0.0, 0.0])
    with pytest.raises(co.InfeasibleLoad) as info:
        co.plan_tensions(rig, R, tau, model=model)
    err = info.value
    assert np.allclose(err.tau_ext, tau) and np.allclose(err.R, R, atol=1e-12)
    # independent distance: minimise ||J^T T + tau_load|| over the box with SLSQP
    J = model.jacobian(R)
    tau_load = tau + model.weight_moment(R)
    res = minimize(lambda t: np.sum((J.T @ t + tau_load) ** 2), rig.t_mid_N, method="SLSQP",
                   bounds=[(rig.t_min_N, rig.t_max_N)] * 6, options={"ftol": 1e-14, "maxiter": 500})
    assert err.distance_Nm == pytest.approx(np.sqrt(res.fun), rel=1e-4)
    assert err.distance_Nm > 1.0
    assert "outside the wrench-feasible set" in str(err)


def test_feasibility_distance_is_zero_inside(rig, model):
    R = np.eye(3)
    J = model.jacobian(R)
    assert feasibility_distance_Nm(J, model.weight_moment(R), rig.t_min_N, rig.t_max_N) < 1e-10


def test_batch_matches_single_and_follows_a_trajectory(rig, model):
    t = np.linspace(0, 1, 300)
    rotvecs = np.column_stack([0.3 * np.sin(2 * np.pi * t), 0.2 * np.cos(2 * np.pi * t), 0.1 * t])
    taus = np.column_stack([2.0 * np.sin(6 * t), -1.5 * np.ones_like(t), 0.5 * np.cos(3 * t)])
    Rs = so3.exp(rotvecs)
    batch = co.plan_tensions_batch(rig, Rs, taus, model=model)
    assert batch.tensions.shape == (300, 6)
    assert batch.equilibrium_residual_Nm.max() <= 1e-8
    assert batch.bound_violation_N.max() <= 1e-9
    for i in (0, 57, 150, 299):
        single = co.plan_tensions(rig, Rs[i], taus[i], model=model)
        assert np.abs(single.tensions_N - batch.tensions_N[i]).max() < 1e-7
    osqp = co.plan_tensions_batch(rig, Rs[:20], taus[:20], solver="osqp", model=model)
    assert np.abs(osqp.tensions_N - batch.tensions_N[:20]).max() < 1e-7


def test_batch_reports_which_pose_is_infeasible(rig, model):
    Rs = so3.exp(np.zeros((5, 3)))
    taus = np.zeros((5, 3))
    taus[3] = [20.0, 0.0, 0.0]
    with pytest.raises(co.InfeasibleLoad, match="pose 3") as info:
        co.plan_tensions_batch(rig, Rs, taus, model=model)
    assert info.value.index == 3


def test_bad_inputs(rig):
    with pytest.raises(co.NotARotation):
        co.plan_tensions(rig, np.ones((3, 3)), np.zeros(3))
    with pytest.raises(co.InvalidInput, match="tau_ext"):
        co.plan_tensions(rig, np.eye(3), [0.0, 1.0])
    with pytest.raises(co.InvalidInput, match="unknown QP solver"):
        co.plan_tensions(rig, np.eye(3), np.zeros(3), solver="nope")


def _independent_lengths(rig, R):
    return np.linalg.norm(rig.base_holes_B_m - rig.platform_holes_A_m @ R.T, axis=1)


def test_plan_rest_lengths_reproduce_the_tensions(rig, model):
    """t = k (c - l) with c written from scratch; l held at R by those tensions is an equilibrium."""
    R = so3.exp([0.15, -0.1, 0.2])
    tau = np.array([0.7, -0.4, 0.2])
    plan = co.plan_tensions(rig, R, tau)
    c = _independent_lengths(rig, R)
    np.testing.assert_allclose(plan.cable_lengths_m, c, atol=1e-15)
    np.testing.assert_allclose(rig.cable_stiffness_N_per_m * (c - plan.rest_lengths_m), plan.tensions_N, atol=1e-9)
    eq = co.solve_equilibrium(rig, plan.rest_lengths_m, tau, R_init=R)   # forward statics, same load
    assert np.linalg.norm(so3.log(R.T @ eq.R)) < 1e-8
    Rs = so3.random_rotations(30, np.random.default_rng(2), max_angle=0.3)
    taus = np.random.default_rng(3).normal(size=(30, 3)) * 0.5
    batch = co.plan_tensions_batch(rig, Rs, taus)
    c = np.array([_independent_lengths(rig, R) for R in Rs])
    np.testing.assert_allclose(batch.cable_lengths_m, c, atol=1e-15)
    np.testing.assert_allclose(rig.cable_stiffness_N_per_m * (c - batch.rest_lengths_m), batch.tensions_N, atol=1e-9)
    np.testing.assert_allclose(batch[4].rest_lengths_m, batch.rest_lengths_m[4])


def _boundary_scale(rig, model, R, direction):
    """Largest s with tau_ext = s * direction feasible at R: an LP (HiGHS), independent of the planner."""
    J = model.casadi("jacobian", R)[0]
    tau_w = model.point_force_moment(R, rig.weight_B_N, rig.com_A_m)[0]
    # variables (T, s): maximise s subject to J^T T + s d = -tau_w, t_min <= T <= t_max
    A_eq = np.hstack([J.T, direction[:, None]])
    res = linprog(np.r_[np.zeros(6), -1.0], A_eq=A_eq, b_eq=-tau_w,
                  bounds=[(rig.t_min_N, rig.t_max_N)] * 6 + [(0, None)], method="highs")
    assert res.status == 0
    return res.x[-1]


@pytest.mark.parametrize("solver", ["active_set", "osqp", "clarabel"])
def test_near_boundary_loads_are_planned_by_every_solver(rig, model, solver):
    if solver not in qpsolvers.available_solvers + ["active_set"]:
        pytest.skip(f"{solver} not installed")
    rng = np.random.default_rng(11)
    R = so3.exp([0.1, -0.05, 0.0])
    for d in [np.array([1.0, 0.0, 0.0]), *rng.normal(size=(3, 3))]:
        d = d / np.linalg.norm(d)
        s = _boundary_scale(rig, model, R, d)
        for frac in (1 - 1e-3, 1 - 1e-6, 1 - 1e-9, 1.0):
            plan = co.plan_tensions(rig, R, frac * s * d, solver=solver)
            _check_plan(plan, rig)
        with pytest.raises(co.InfeasibleLoad) as info:
            co.plan_tensions(rig, R, (1 + 1e-3) * s * d, solver=solver)
        assert info.value.distance_Nm > 1e-8


def test_issue_load_near_boundary_is_held(rig):
    """csjm stiffness --rotvec 0.1 -0.05 0 --tau 10.80221 0 0 was refused 5e-15 N m 'outside'."""
    plan = co.plan_tensions(rig, so3.exp([0.1, -0.05, 0.0]), [10.80221, 0.0, 0.0])
    _check_plan(plan, rig)
