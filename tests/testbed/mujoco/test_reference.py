"""Statics and stiffness against MuJoCo (an independent engine model of the rig: csjm_opt.testbed.mujoco.reference)."""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
import csjm_opt.testbed.mujoco.reference as ref
from csjm_opt import so3
from csjm_opt.model.perturbation import stiffness_from_engine


def _angle(Ra, Rb):
    return float(np.linalg.norm(so3.log(Ra.T @ Rb)))


def _cases(n, seed, rotvec_max=0.3, tau_max=0.4):
    rng = np.random.default_rng(seed)
    return [(so3.exp(rng.uniform(-rotvec_max, rotvec_max, 3)), rng.uniform(-tau_max, tau_max, 3))
            for _ in range(n)]


def _hat(w):
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def test_settling_reproduces_planned_pose_and_tensions(rig):
    """20 poses and loads: MuJoCo settles (from a nudge) at the planned pose and tensions."""
    worst_pose, worst_T = 0.0, 0.0
    for R, tau in _cases(20, seed=1):
        plan = co.plan_tensions(rig, R, tau)
        l = co.rest_lengths_for(rig, R, plan.tensions_N)
        R_mj, T_mj, settled = ref.settle(rig, l, R, tau, nudge=[0.02, -0.015, 0.01])
        assert settled
        worst_pose = max(worst_pose, _angle(R, R_mj))
        worst_T = max(worst_T, float(np.abs(T_mj - plan.tensions_N).max()))
    assert worst_pose <= 1e-9
    assert worst_T <= 1e-6


@pytest.mark.parametrize("load_fixed_in", ["A", "B"])
def test_perturbation_stiffness_matches_K(rig, load_fixed_in):
    """-dQ/dzeta in MuJoCo = K + H_weight +- 1/2 hat(tau_ext); K from co.stiffness and Equilibrium.K."""
    for R, tau in _cases(4, seed=2, tau_max=0.6):
        plan = co.plan_tensions(rig, R, tau)
        l = co.rest_lengths_for(rig, R, plan.tensions_N)
        K_meas, Q0 = ref.measured_stiffness(rig, l, R, tau, world_fixed=load_fixed_in == "B")
        assert np.abs(Q0).max() < 1e-10                      # the planned pose is an equilibrium in MuJoCo
        K = co.stiffness(rig, R, plan.tensions_N)
        eq = co.solve_equilibrium(rig, l, tau, R_init=R)
        # weight Hessian written out here: f_A = R^T m g at r = COM
        f_A, r = R.T @ (rig.platform_mass_kg * rig.gravity_B_m_per_s2), rig.com_A_m
        H_w = (f_A @ r) * np.eye(3) - 0.5 * (np.outer(f_A, r) + np.outer(r, f_A))
        s = 1.0 if load_fixed_in == "A" else -1.0
        K_engine = K_meas - H_w - 0.5 * s * _hat(tau)
        scale = np.abs(K).max()
        assert np.abs(K_engine - K).max() <= 1e-5 * scale
        assert np.abs(K_engine - eq.K).max() <= 1e-5 * scale
        assert np.abs(stiffness_from_engine(rig, R, K_meas, tau, load_fixed_in) - K).max() <= 1e-5 * scale
        # the uncorrected measurement is not K (the correction matters)
        assert np.abs(K_meas - K).max() > 1e-3 * scale


def test_perturbation_stiffness_with_slack_cable(rig):
    """An equilibrium with one slack cable, settled in MuJoCo: K at MuJoCo's pose and tensions matches."""
    R0, tau = so3.exp([0.05, -0.04, 0.02]), np.array([0.1, -0.1, 0.05])
    plan = co.plan_tensions(rig, R0, tau)
    l = co.rest_lengths_for(rig, R0, plan.tensions_N)
    l[2] += 0.03
    R_mj, T_mj, settled = ref.settle(rig, l, R0, tau)
    assert settled and np.sum(T_mj == 0.0) == 1
    K_meas, _ = ref.measured_stiffness(rig, l, R_mj, tau)
    K_engine = stiffness_from_engine(rig, R_mj, K_meas, tau)
    eq = co.solve_equilibrium(rig, l, tau, R_init=R0)
    scale = np.abs(eq.K).max()
    assert _angle(eq.R, R_mj) <= 1e-9
    assert np.abs(K_engine - eq.K).max() <= 1e-5 * scale
    assert np.abs(K_engine - co.Model(rig).stiffness_rest(R_mj, l)[0]).max() <= 1e-5 * scale


def test_co_stiffness_counts_slack_cable_as_nothing(rig):
    """co.stiffness with MuJoCo's tensions (one exactly zero) matches MuJoCo's K at a slack equilibrium."""
    R0, tau = so3.exp([0.05, -0.04, 0.02]), np.array([0.1, -0.1, 0.05])
    l = co.rest_lengths_for(rig, R0, co.plan_tensions(rig, R0, tau).tensions_N)
    l[2] += 0.03
    R_mj, T_mj, settled = ref.settle(rig, l, R0, tau)
    assert settled and np.sum(T_mj == 0.0) == 1
    K_engine = stiffness_from_engine(rig, R_mj, ref.measured_stiffness(rig, l, R_mj, tau)[0], tau)
    scale = np.abs(K_engine).max()
    assert np.abs(K_engine - co.stiffness(rig, R_mj, T_mj, check_bounds=False)).max() <= 1e-5 * scale
    assert np.abs(K_engine - co.stiffness(rig, R_mj, rest_lengths_m=l)).max() <= 1e-5 * scale


def test_lengthened_cable_settles_where_statics_finds_it(rig):
    """40 cases, one cable lengthened by 10-50 mm: MuJoCo settles -> statics finds the same pose;
    MuJoCo falls over (ends > 90 deg from the start) -> statics raises NoEquilibrium."""
    rng = np.random.default_rng(3)
    found = fell = plain_newton_misses = 0
    for R, tau in _cases(40, seed=4, rotvec_max=0.25, tau_max=0.3):
        l = co.rest_lengths_for(rig, R, co.plan_tensions(rig, R, tau).tensions_N)
        l[rng.integers(6)] += rng.uniform(0.010, 0.050)
        R_mj, T_mj, settled = ref.settle(rig, l, R, tau)
        if settled and _angle(R, R_mj) < 0.5 * np.pi:
            eq = co.solve_equilibrium(rig, l, tau, R_init=R)
            assert _angle(eq.R, R_mj) <= 1e-6
            found += 1
            try:
                plain = co.solve_equilibrium(rig, l, tau, R_init=R, globalise=False)
                plain_newton_misses += _angle(plain.R, R_mj) > 1e-6
            except co.NoEquilibrium:
                plain_newton_misses += 1
        else:
            assert _angle(R, R_mj) > 0.5 * np.pi
            with pytest.raises(co.NoEquilibrium):
                co.solve_equilibrium(rig, l, tau, R_init=R)
            fell += 1
    assert found >= 20 and fell >= 3          # both kinds are exercised
    assert plain_newton_misses >= 1           # and the globalisation is what finds some of them
