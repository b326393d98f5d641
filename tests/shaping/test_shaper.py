"""Stiffness shaping (csjm_opt/shaping.py): reachable targets recovered, unreachable ones optimal.

Independent references: the CasADi model's K (not the closed-form basis the
shaper uses), scipy SLSQP on the same objective written out here.
"""

from __future__ import annotations

import numpy as np
import pytest
import qpsolvers
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import minimize

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.shaping.shaper import build_shaping_qp, make_objective, shape_stiffness, stiffness_basis

R_POSE = so3.exp(np.array([0.1, -0.05, 0.02]))
TAU = np.array([0.3, -0.2, 0.1])


def null_space(J):
    return np.linalg.svd(J.T)[2][3:].T              # (6, 3), J^T N = 0


def feasible_tensions(rig, model, R, tau, move):
    """Planned tensions moved along the null space of J^T, clipped into the bounds by scaling."""
    plan = co.plan_tensions(rig, R, tau, model=model)
    step = null_space(model.jacobian(R)) @ np.asarray(move, float)
    s = 1.0
    for i in range(6):
        if step[i] > 0:
            s = min(s, 0.9 * (rig.t_max_N - plan.tensions_N[i]) / step[i])
        elif step[i] < 0:
            s = min(s, 0.9 * (rig.t_min_N - plan.tensions_N[i]) / step[i])
    return plan.tensions_N + s * step


def slsqp_shaping(rig, model, R, tau, K_target, W=None):
    """Independent solver: SLSQP on sum W (K(T) - K_target)^2 with K from the CasADi model."""
    W = np.ones((3, 3)) if W is None else W
    J = model.jacobian(R)
    tau_load = tau + model.weight_moment(R)
    basis_T = np.eye(6)
    K0 = model.casadi("stiffness", R, np.zeros(6))[0]                 # all cables taut (CasADi)
    G = np.array([model.casadi("stiffness", R, e)[0] - K0 for e in basis_T])  # K affine in T (checked below)

    def f(T):
        E = K0 + np.einsum("i,ijk->jk", T, G) - K_target
        return float(np.sum(W * E * E))

    def grad(T):
        E = K0 + np.einsum("i,ijk->jk", T, G) - K_target
        return 2 * np.einsum("jk,ijk->i", W * E, G)

    best = None
    for t0 in (rig.t_mid_N, co.plan_tensions(rig, R, tau, model=model).tensions_N):
        res = minimize(f, t0, jac=grad, method="SLSQP", bounds=[(rig.t_min_N, rig.t_max_N)] * 6,
                       constraints=[{"type": "eq", "fun": lambda T: J.T @ T + tau_load, "jac": lambda T: J.T}],
                       options={"ftol": 1e-15, "maxiter": 1000})
        if best is None or res.fun < best.fun:
            best = res
    return best


def test_basis_matches_casadi_and_is_affine(rig, model):
    basis = stiffness_basis(rig, R_POSE)
    rng = np.random.default_rng(3)
    for _ in range(3):
        T = rng.uniform(5, 150, 6)
        assert np.allclose(basis.K(T), model.stiffness(R_POSE, T), atol=1e-9)
    T1, T2 = rng.uniform(5, 150, (2, 6))
    # affinity of the CasADi model itself: K(a T1 + (1-a) T2) = a K(T1) + (1-a) K(T2)
    a = 0.3
    assert np.allclose(model.stiffness(R_POSE, a * T1 + (1 - a) * T2),
                       a * model.stiffness(R_POSE, T1) + (1 - a) * model.stiffness(R_POSE, T2), atol=1e-9)
    assert np.allclose(basis.tau_weight_A_Nm, model.weight_moment(R_POSE), atol=1e-14)


def test_build_shaping_qp_structure(rig, model):
    K_target = np.diag([20.0, 15.0, 25.0])
    prob = build_shaping_qp(rig, R_POSE, TAU, K_target)
    assert isinstance(prob, qpsolvers.Problem)
    P = prob.P.toarray()
    assert np.allclose(P, P.T) and np.all(np.linalg.eigvalsh(P) > 0)
    assert np.allclose(prob.A.toarray(), model.jacobian(R_POSE).T, atol=1e-14)
    assert np.allclose(prob.b, -(TAU + model.weight_moment(R_POSE)), atol=1e-14)
    assert np.all(prob.lb == rig.t_min_N) and np.all(prob.ub == rig.t_max_N)
    # the QP objective equals the Frobenius objective (up to the tiny regulariser and a constant)
    T1, T2 = np.full(6, 60.0), np.full(6, 90.0)
    qp = [0.5 * T @ P @ T + prob.q @ T for T in (T1, T2)]
    fro = [np.sum((model.stiffness(R_POSE, T) - K_target) ** 2) for T in (T1, T2)]
    assert np.isclose(qp[1] - qp[0], fro[1] - fro[0], rtol=1e-6)


@pytest.mark.parametrize("solver", ["osqp", "clarabel", "active_set"])
def test_reachable_target_recovered(rig, model, solver):
    T_true = feasible_tensions(rig, model, R_POSE, TAU, [25.0, -15.0, 20.0])
    K_target = model.stiffness(R_POSE, T_true)
    res = shape_stiffness(rig, R_POSE, TAU, K_target, solver=solver, model=model)
    assert np.abs(res.K - K_target).max() <= 1e-6
    assert res.exact and res.residual <= 1e-6
    assert np.allclose(res.tensions, T_true, atol=1e-4)       # the map T -> K is injective here
    assert res.equilibrium_residual_Nm <= 1e-9 and res.is_valid()
    assert np.linalg.norm(model.jacobian(R_POSE).T @ res.tensions + TAU + model.weight_moment(R_POSE)) <= 1e-9


@settings(max_examples=8, deadline=None)
@given(st.lists(st.floats(-40, 40), min_size=3, max_size=3))
def test_reachable_targets_property(rig, model, move):
    T_true = feasible_tensions(rig, model, R_POSE, TAU, move)
    K_target = model.stiffness(R_POSE, T_true)
    res = shape_stiffness(rig, R_POSE, TAU, K_target, solver="active_set", model=model)
    assert np.abs(res.K - K_target).max() <= 1e-6 and res.exact


def test_reachable_target_at_bounds(rig, model):
    """A target built from tensions on a bound: recovered, and that bound reported active."""
    from csjm_opt.shaping.reachable import feasible_vertices

    J = model.jacobian(R_POSE)
    V = feasible_vertices(J, TAU + model.weight_moment(R_POSE), rig.t_min_N, rig.t_max_N)
    T_true = 0.8 * V[0] + 0.2 * V[1] if np.sum(np.isclose(V[0], V[1])) >= 1 else V[0]
    K_target = model.stiffness(R_POSE, T_true)
    res = shape_stiffness(rig, R_POSE, TAU, K_target, model=model)
    assert np.abs(res.K - K_target).max() <= 1e-6 and res.exact
    at_bound = np.isclose(T_true, rig.t_min_N) | np.isclose(T_true, rig.t_max_N)
    assert len(res.active_bounds) == int(at_bound.sum()) >= 1


@pytest.mark.parametrize("W", [np.ones((3, 3)), np.array([[4.0, 1, 1], [1, 1, 0.5], [1, 0.5, 2]])])
def test_unreachable_target_is_constrained_optimum(rig, model, W):
    K_target = np.diag([40.0, 10.0, 25.0])
    res = shape_stiffness(rig, R_POSE, TAU, K_target, weights=W, model=model)
    assert not res.exact and res.residual > 1.0
    ref = slsqp_shaping(rig, model, R_POSE, TAU, K_target, W)
    f_ours = float(np.sum(W * (res.K - K_target) ** 2))
    assert f_ours <= ref.fun + 1e-7 * max(1.0, ref.fun)
    assert np.isclose(res.residual, np.sqrt(ref.fun), rtol=1e-6)
    assert np.allclose(res.tensions, ref.x, atol=1e-3)
    assert res.is_valid()


def test_unreachable_target_with_active_bounds(rig, model):
    """Very stiff or very soft target: tensions pushed to a bound; optimum still matches SLSQP.

    (Here the geometric term sum t_i Hess(c_i) softens the joint: the stiff target drives
    tensions to t_min, the soft one to t_max.)"""
    K_target = 80.0 * np.eye(3)
    res = shape_stiffness(rig, R_POSE, TAU, K_target, model=model)
    assert any("t_min" in b for b in res.active_bounds) and not res.exact
    soft = shape_stiffness(rig, R_POSE, TAU, 2.0 * np.eye(3), model=model)
    assert any("t_max" in b for b in soft.active_bounds) and not soft.exact
    ref = slsqp_shaping(rig, model, R_POSE, TAU, K_target)
    assert res.residual ** 2 <= ref.fun + 1e-7 * ref.fun


def test_eigen_and_directional_objectives(rig, model):
    T_true = feasible_tensions(rig, model, R_POSE, TAU, [-20.0, 10.0, 30.0])
    K_target = model.stiffness(R_POSE, T_true)
    res = shape_stiffness(rig, R_POSE, TAU, K_target, objective="eigen", model=model)
    lam, U = np.linalg.eigh(K_target)
    assert np.allclose(np.einsum("ik,ij,jk->k", U, res.K, U), lam, atol=1e-6) and res.exact
    u = np.array([[1.0, 0.0, 0.0]])
    res = shape_stiffness(rig, R_POSE, TAU, 35.0 * np.eye(3), objective="directional", directions=u, model=model)
    rs_hi = co_directional_max(rig, model, u[0])
    assert np.isclose(u[0] @ res.K @ u[0], min(35.0, rs_hi), atol=1e-6)


def co_directional_max(rig, model, u):
    """max u^T K u over feasible tensions by SLSQP (independent of the shaper)."""
    J = model.jacobian(R_POSE)
    tau_load = TAU + model.weight_moment(R_POSE)
    f = lambda T: -u @ model.stiffness(R_POSE, T) @ u                 # noqa: E731
    res = minimize(f, co.plan_tensions(rig, R_POSE, TAU, model=model).tensions_N, method="SLSQP",
                   bounds=[(rig.t_min_N, rig.t_max_N)] * 6,
                   constraints=[{"type": "eq", "fun": lambda T: J.T @ T + tau_load}], options={"ftol": 1e-14})
    return -res.fun


def test_zero_weights_fall_back_to_mid_range(rig, model):
    """With every weight zero only the regulariser remains: the plan closest to mid-range."""
    res = shape_stiffness(rig, R_POSE, TAU, np.eye(3), weights=np.zeros((3, 3)), model=model)
    plan = co.plan_tensions(rig, R_POSE, TAU, model=model)
    assert np.allclose(res.tensions, plan.tensions_N, atol=1e-6)


def test_infeasible_load_raises(rig, model):
    with pytest.raises(co.InfeasibleLoad):
        shape_stiffness(rig, R_POSE, np.array([30.0, 0, 0]), np.eye(3) * 20, model=model)
    with pytest.raises(co.InfeasibleLoad):
        shape_stiffness(rig, R_POSE, np.array([30.0, 0, 0]), np.eye(3) * 20, solver="active_set", model=model)


def test_bad_inputs(rig, model):
    with pytest.raises(co.InvalidInput):
        shape_stiffness(rig, R_POSE, TAU, np.eye(2), model=model)
    with pytest.raises(co.InvalidInput):
        shape_stiffness(rig, R_POSE, TAU, np.eye(3), objective="nuclear", model=model)
    with pytest.raises(co.InvalidInput):
        shape_stiffness(rig, R_POSE, TAU, np.eye(3), weights=-np.ones((3, 3)), model=model)
    with pytest.raises(co.InvalidInput):
        make_objective(np.eye(3), objective="directional")
    with pytest.raises(co.NotARotation):
        shape_stiffness(rig, 2 * np.eye(3), TAU, np.eye(3), model=model)
    with pytest.raises(co.InvalidInput):
        shape_stiffness(rig, R_POSE, TAU, np.eye(3), solver="nope", model=model)


def test_result_as_dict_is_json(rig, model):
    import json

    res = shape_stiffness(rig, R_POSE, TAU, np.eye(3) * 20, model=model)
    d = json.loads(json.dumps(res.as_dict()))
    assert d["exact"] is False and len(d["tensions_N"]) == 6
