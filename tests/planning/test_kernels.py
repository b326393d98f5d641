"""Compiled kernels agree with the CasADi reference model and the batched solver."""

import numpy as np

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.planning import active_set as active_set
from csjm_opt.planning import kernels as kernels


def test_planner_kernel_matches_casadi_model(rig, model):
    """plan_one's J, weight moment, cable and rest lengths against the CasADi model."""
    rng = np.random.default_rng(3)
    Rs = so3.random_rotations(20, rng, max_angle=0.6)
    for R in Rs:
        tau = rng.normal(size=3) * 0.3
        T, J, w, c, l, info = np.empty(6), np.empty((6, 3)), np.empty(3), np.empty(6), np.empty(6), np.empty(2)
        status = kernels.plan_one(model.A, model.B, model.k, model.first_moment_A_kgm, model.g, R, tau,
                                  rig.t_mid_N, rig.t_min_N, rig.t_max_N, 40, T, J, w, c, l, info)
        assert status == kernels.OK and info[0] < 1e-12 and info[1] <= 0.0
        (J_ref,) = model.casadi("jacobian", R)
        (c_ref,) = model.casadi("cable_lengths", R)
        tau_w_ref, _ = model.point_force_moment(R, rig.weight_B_N, rig.com_A_m)
        np.testing.assert_allclose(J, J_ref, atol=1e-14)
        np.testing.assert_allclose(c, c_ref, atol=1e-15)
        np.testing.assert_allclose(w, tau_w_ref, atol=1e-14)
        (T_back,) = model.casadi("tensions_from_rest", R, l)
        np.testing.assert_allclose(T_back, T, atol=1e-9)   # t = k (c - l) reproduces the plan


def test_rotation_error_kernel():
    R = so3.exp([0.3, 0.2, -0.1])
    err, det = kernels.rotation_error(R)
    assert err < 1e-14 and abs(det - 1) < 1e-14
    err, det = kernels.rotation_error(2 * R)
    assert np.isclose(err, np.linalg.norm(4 * np.eye(3) - np.eye(3))) and np.isclose(det, 8.0)


def test_batched_active_set_warm_start_gives_the_same_answer(rig, model):
    rng = np.random.default_rng(4)
    Rs = so3.random_rotations(50, rng, max_angle=0.3)
    taus = rng.normal(size=(50, 3)) * 1.5
    J = model.jacobian(Rs)
    b = -(taus + model.weight_moment(Rs))
    cold = active_set.solve(np.swapaxes(J, 1, 2), b, np.full((50, 6), 77.5), rig.t_min_N, rig.t_max_N)
    warm = active_set.solve(np.swapaxes(J, 1, 2), b, np.full((50, 6), 77.5), rig.t_min_N, rig.t_max_N,
                            lower0=cold.lower, upper0=cold.upper)
    ok = cold.converged & warm.converged
    assert ok.mean() > 0.5
    assert np.allclose(cold.t[ok], warm.t[ok], atol=1e-9)
    for i in np.flatnonzero(ok)[:10]:
        assert np.allclose(co.plan_tensions(rig, Rs[i], taus[i]).tensions_N, cold.t[i], atol=1e-9)
