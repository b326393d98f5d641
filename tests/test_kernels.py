"""Compiled kernels agree with the CasADi reference model and the batched solver."""

import numpy as np

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.planning import _active_set as active_set
from csjm_opt.planning import _kernels as kernels


def test_kernel_jacobian_and_weight_match_casadi_model(rig, model):
    Rs = so3.random_rotations(20, np.random.default_rng(3), max_angle=0.6)
    for R in Rs:
        J = np.empty((6, 3))
        kernels.jacobian_into(rig.platform_holes_A_m, rig.base_holes_B_m, R, J)
        assert np.allclose(J, model.jacobian(R), atol=1e-14)
        w = np.empty(3)
        kernels.weight_moment_into(rig.platform_mass_kg, rig.com_A_m, rig.gravity_B_m_per_s2, R, w)
        assert np.allclose(w, model.weight_moment(R), atol=1e-14)


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
