"""Forward statics (csjm_opt/statics.py) and its closed-form terms (csjm_opt/cable_terms.py).

Checked against the CasADi model, an energy written from scratch in
conftest.py, finite differences of solved equilibria, and the docs/conventions.md law
``dtau_load = (K + 1/2 hat(tau_load)) dzeta`` for a moment load.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.model.cable_terms import CableTerms, point_force_terms
from csjm_opt.model.statics import EquilibriumSolver, rest_lengths_for, solve_equilibrium
from tests.conftest import cable_energy, fd_gradient, fd_hessian, rodrigues

ROTVEC = np.array([0.12, -0.07, 0.05])
TAU_EXT = np.array([0.4, -0.3, 0.15])


def hat(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def held_pose(rig, model, rotvec=ROTVEC, tau_ext=TAU_EXT):
    """A pose, the load and rest lengths planned to hold it there."""
    R = rodrigues(rotvec)
    plan = co.plan_tensions(rig, R, tau_ext, model=model)
    return R, rest_lengths_for(rig, R, plan.tensions_N, model)


def residual_independent(rig, model, R, l, tau_ext, forces=()):
    """J^T T + tau_gravity + tau_points + tau_ext, tensions and weight written out here."""
    A, B = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    C = B - A @ R.T
    c = np.linalg.norm(C, axis=1)
    T = np.where(c > l, rig.cable_stiffness_N_per_m * (c - l), 0.0)
    tau = model.jacobian(R).T @ T + tau_ext
    for f, p in [(rig.weight_B_N, rig.com_A_m), *forces]:
        tau = tau + np.cross(p, R.T @ f)
    return tau


# ----------------------------------------------------------------- closed-form terms
def test_cable_terms_match_casadi_model(rig, model):
    terms = CableTerms.from_rig(rig)
    rng = np.random.default_rng(1)
    for R in so3.random_rotations(5, rng, max_angle=0.4):
        T = rng.uniform(5, 150, 6)
        J, K0, G = terms.stiffness_basis(R)
        assert np.allclose(J, model.jacobian(R), atol=1e-14)
        assert np.allclose(K0 + np.einsum("i,ijk->jk", T, G), model.stiffness(R, T), atol=1e-9)
        l = model.rest_lengths(R, T) + rng.uniform(-0.02, 0.02, 6)   # some slack
        K_ref, T_ref, tau_ref, _ = model.stiffness_rest(R, l)
        T_, tau_, K_ = terms.rest_terms(R, l)
        assert np.allclose(T_, T_ref, atol=1e-9) and np.allclose(tau_, tau_ref, atol=1e-10)
        assert np.allclose(K_, K_ref, atol=1e-9)
        tau_w, H_w = point_force_terms(R, rig.weight_B_N[None], np.asarray(rig.com_A_m)[None])
        tau_w_ref, H_w_ref = model.point_force_moment(R, rig.weight_B_N, rig.com_A_m)
        assert np.allclose(tau_w, tau_w_ref, atol=1e-14) and np.allclose(H_w, H_w_ref, atol=1e-14)


def test_cable_stiffness_is_energy_hessian(rig):
    """K(rest) equals the FD Hessian of the cable energy written from scratch."""
    terms = CableTerms.from_rig(rig)
    R = rodrigues(np.array([0.2, 0.1, -0.15]))
    l = terms.geometry(R)[0] - np.linspace(0.003, 0.02, 6)
    _, _, K = terms.rest_terms(R, l)
    H = fd_hessian(lambda z: cable_energy(rig, R @ rodrigues(z), l))
    assert np.allclose(K, H, rtol=1e-5, atol=1e-4)


# ----------------------------------------------------------------- equilibrium
def test_equilibrium_residual_and_pose(rig, model):
    R, l = held_pose(rig, model)
    eq = solve_equilibrium(rig, l, TAU_EXT, model=model)           # cold start from identity
    assert np.linalg.norm(residual_independent(rig, model, eq.R, l, TAU_EXT)) <= 1e-9
    assert eq.residual_Nm <= 1e-9 and eq.stable and eq.is_valid()
    assert so3.angle_between(eq.R, R) < 1e-9                        # returns to the planned pose
    assert np.allclose(eq.K, model.stiffness(eq.R, eq.tensions_N), atol=1e-9)


def _pose_response(rig, model, l, tau_ext, R0, include_weight, h=1e-3):
    """d zeta / d tau_ext (3x3) by central differences of solved equilibria."""
    S = np.zeros((3, 3))
    for j in range(3):
        e = h * np.eye(3)[j]
        Rp = solve_equilibrium(rig, l, tau_ext + e, R_init=R0, include_weight=include_weight, model=model).R
        Rm = solve_equilibrium(rig, l, tau_ext - e, R_init=R0, include_weight=include_weight, model=model).R
        S[:, j] = (so3.log(R0.T @ Rp) - so3.log(R0.T @ Rm)) / (2 * h)
    return S


def test_load_increment_moment_only(rig, model):
    """Without weight: dzeta = (K + 1/2 hat(tau_load))^-1 dtau_load, K from the CasADi model."""
    R, _ = held_pose(rig, model)
    rig0 = rig.replace(platform_mass_kg=0.0)
    plan = co.plan_tensions(rig0, R, TAU_EXT)
    l = rest_lengths_for(rig0, R, plan.tensions_N)
    eq = solve_equilibrium(rig0, l, TAU_EXT, R_init=np.eye(3), include_weight=False)
    K = co.stiffness(rig0, eq.R, eq.tensions_N)                     # CasADi model, independent
    S = _pose_response(rig0, co.Model(rig0), l, TAU_EXT, eq.R, include_weight=False)
    # the cables' restoring moment balances the load: dtau_load = (K + 1/2 hat(tau_load)) dzeta
    # with tau_load = tau_ext; the load pushes, the pose yields: S = (K + 1/2 hat(tau))^-1
    expected = np.linalg.inv(K + 0.5 * hat(TAU_EXT))
    assert np.allclose(S, expected, rtol=1e-5, atol=1e-7)
    assert not np.allclose(S, np.linalg.inv(K), rtol=1e-3, atol=1e-5)  # the 1/2 hat term matters
    assert np.allclose(eq.K_tangent, K + 0.5 * hat(TAU_EXT), atol=1e-9)


def test_load_increment_with_weight(rig, model):
    """With weight: tangent stiffness K + H_weight + 1/2 hat(tau_ext), H from FD of the potential."""
    R, l = held_pose(rig, model)
    eq = solve_equilibrium(rig, l, TAU_EXT, R_init=R, model=model)
    K = model.stiffness(eq.R, eq.tensions_N)
    f, r = rig.weight_B_N, np.asarray(rig.com_A_m)
    H_w = fd_hessian(lambda z: -f @ (eq.R @ rodrigues(z) @ r), h=1e-3)
    H_w = 0.5 * (H_w + H_w.T)
    K_t = K + H_w + 0.5 * hat(TAU_EXT)
    S = _pose_response(rig, model, l, TAU_EXT, eq.R, include_weight=True)
    assert np.allclose(S, np.linalg.inv(K_t), rtol=1e-5, atol=1e-7)
    assert np.allclose(eq.K_tangent, K_t, atol=1e-6)
    # first-order law on a finite small increment
    dtau = np.array([2e-3, -1e-3, 1.5e-3])
    eq2 = solve_equilibrium(rig, l, TAU_EXT + dtau, R_init=eq.R, model=model)
    dzeta = so3.log(eq.R.T @ eq2.R)
    assert np.linalg.norm(dzeta - np.linalg.solve(K_t, dtau)) <= 1e-3 * np.linalg.norm(dzeta)


def test_dead_weight_point_force(rig, model):
    """A dead weight fixed in {B}: residual, energy stationarity and Hessian (conservative case)."""
    R, l = held_pose(rig, model, tau_ext=np.zeros(3))
    force, point = np.array([0.0, 0.0, -6.0]), np.array([0.04, -0.02, 0.06])
    eq = solve_equilibrium(rig, l, np.zeros(3), point_forces=[(force, point)], R_init=R, model=model)
    res = residual_independent(rig, model, eq.R, l, np.zeros(3), forces=[(force, point)])
    assert np.linalg.norm(res) <= 1e-9
    assert so3.angle_between(eq.R, R) > 1e-3                        # the weight moved the pose

    def energy(z):
        Rz = eq.R @ rodrigues(z) if np.any(z) else eq.R
        return (cable_energy(rig, Rz, l) - force @ (Rz @ point)
                - rig.weight_B_N @ (Rz @ np.asarray(rig.com_A_m)))

    assert np.linalg.norm(fd_gradient(energy)) < 1e-6
    H = fd_hessian(energy, h=1e-3)
    assert np.allclose(eq.K_tangent, H, rtol=1e-4, atol=1e-3)
    assert np.all(np.linalg.eigvalsh(H) > 0)


@settings(max_examples=12, deadline=None)
@given(st.lists(st.floats(-0.25, 0.25), min_size=3, max_size=3),
       st.lists(st.floats(-0.8, 0.8), min_size=3, max_size=3))
def test_equilibrium_law_random(rig, model, rotvec, tau):
    try:
        R, l = held_pose(rig, model, np.array(rotvec), np.array(tau))
    except co.InfeasibleLoad:
        return
    eq = solve_equilibrium(rig, l, tau, model=model)
    assert np.linalg.norm(residual_independent(rig, model, eq.R, l, np.array(tau))) <= 1e-9
    assert so3.angle_between(eq.R, R) < 1e-8


def test_solver_object_reuse_matches(rig, model):
    R, l = held_pose(rig, model)
    solver = EquilibriumSolver(rig)
    eq = solver.solve(l, TAU_EXT, np.eye(3))
    assert so3.angle_between(eq.R, R) < 1e-9 and eq.iterations >= 1
    assert solver.solve(l, TAU_EXT, eq.R).iterations == 0            # warm start at the answer


# ----------------------------------------------------------------- failures
def test_cable_slack_beyond_recovery_raises(rig, model):
    R, l = held_pose(rig, model, np.zeros(3), np.zeros(3))
    with pytest.raises(co.NoEquilibrium) as info:
        solve_equilibrium(rig, l + np.array([0.08, 0, 0, 0, 0, 0]), model=model)
    assert info.value.reason == "slack" and info.value.residual_Nm > 1e-3
    with pytest.raises(co.NoEquilibrium) as info:
        solve_equilibrium(rig, l + 0.2, model=model)                 # every cable slack
    assert info.value.reason == "slack"


def test_partly_slack_equilibrium_flagged(rig, model):
    """One cable slack but the other five hold: returned (flagged) unless allow_slack=False."""
    R, l = held_pose(rig, model, np.zeros(3), np.zeros(3))
    l = l + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    l[0] += 0.032
    eq = solve_equilibrium(rig, l, model=model)
    assert eq.slack.any() and eq.residual_Nm <= 1e-9 and eq.stable
    with pytest.raises(co.NoEquilibrium) as info:
        solve_equilibrium(rig, l, model=model, allow_slack=False)
    assert info.value.reason == "slack"


def test_load_beyond_capacity_raises(rig, model):
    R, l = held_pose(rig, model)
    with pytest.raises(co.NoEquilibrium):
        solve_equilibrium(rig, l, np.array([25.0, 0.0, 0.0]), model=model)


def test_bad_rest_lengths_rejected(rig, model):
    with pytest.raises(co.InvalidInput):
        solve_equilibrium(rig, -np.ones(6), model=model)
    with pytest.raises(co.InvalidInput):
        solve_equilibrium(rig, np.ones(5), model=model)


def test_model_of_another_rig_is_not_used(rig):
    """A Model built for a different rig must not leak into the solve."""
    other = rig.replace(cable_stiffness_N_per_m=np.full(6, 3000.0))
    plan = co.plan_tensions(other, np.eye(3), np.zeros(3))
    l = rest_lengths_for(other, np.eye(3), plan.tensions_N)
    eq = solve_equilibrium(other, l, np.zeros(3), model=co.Model(rig))
    assert eq.residual_Nm < 1e-9
    assert np.allclose(eq.R, np.eye(3), atol=1e-9)


def test_stability_check_is_routh_hurwitz_exact():
    """statics._stable (Routh-Hurwitz on det(sI + K_t)) agrees with the eigenvalues of random 3x3 matrices."""
    from csjm_opt.model.statics import _stable

    rng = np.random.default_rng(0)
    for _ in range(3000):
        M = rng.normal(size=(3, 3)) * rng.uniform(0.1, 10.0)
        assert _stable(M) == bool(np.all(np.linalg.eigvals(M).real > 0))
    assert not _stable(np.diag([1.0, 2.0, np.nan]))
