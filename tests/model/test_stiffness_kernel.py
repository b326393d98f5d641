"""Compiled stiffness kernels against the numpy reference, the CasADi model and the energy Hessian.

Three references the kernels did not produce: the numpy reference
(csjm_opt.model.cable_terms, a separate implementation of the closed form),
the CasADi model (symbolic differentiation of J^T T) and finite differences
of the cable energy written from scratch in tests/conftest.py.
"""

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt.model import cable_terms as reference
from csjm_opt.model import kernels as kernels
from csjm_opt.model.joint_stiffness import is_stable
from tests.conftest import cable_energy, fd_hessian, rodrigues

REL = 1e-12


def _random_rig(rng: np.random.Generator) -> co.Rig:
    """The paper rig with every hole moved by up to 1 cm and random cable stiffness."""
    base = co.paper_rig()
    return base.replace(platform_holes_A_m=base.platform_holes_A_m + rng.uniform(-0.01, 0.01, (6, 3)),
                        base_holes_B_m=base.base_holes_B_m + rng.uniform(-0.01, 0.01, (6, 3)),
                        cable_stiffness_N_per_m=rng.uniform(1000, 9000, 6))


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(np.abs(b).max(), 1e-300))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kernel_equals_numpy_reference_and_casadi(seed):
    rng = np.random.default_rng(seed)
    rig = _random_rig(rng)
    model = co.Model(rig)
    n = 64
    Rs = co.so3.random_rotations(n, rng, max_angle=0.6)
    Ts = rng.uniform(rig.t_min_N, rig.t_max_N, (n, 6))
    K_ref = reference.stiffness(Rs, Ts, rig.platform_holes_A_m, rig.base_holes_B_m, rig.cable_stiffness_N_per_m)
    (K_cas,) = model.casadi("stiffness", Rs, Ts)
    K_serial = np.empty((n, 3, 3))
    kernels.stiffness_many(model.A, model.B, model.k, Rs, Ts, K_serial)
    K_par = np.empty((n, 3, 3))
    kernels.stiffness_many_par(model.A, model.B, model.k, Rs, Ts, K_par)
    assert _rel(K_ref, K_cas) < REL
    for K in (K_serial, K_par, model.stiffness(Rs, Ts), co.stiffness_batch(rig, Rs, Ts)):
        assert _rel(K, K_cas) < REL
    for i in range(0, n, 8):  # one pose at a time, through the public checked function
        assert _rel(co.stiffness(rig, Rs[i], Ts[i]), K_cas[i]) < REL
    # geometry and weight moment of the same kernels against CasADi
    c, J = model.geometry(Rs)
    assert _rel(J, model.casadi("jacobian", Rs)[0]) < REL
    assert _rel(c, model.casadi("cable_lengths", Rs)[0]) < REL
    tau_w_cas, _ = model.point_force_moment(Rs, rig.weight_B_N, rig.com_A_m)
    assert np.abs(model.weight_moment(Rs) - tau_w_cas).max() < 1e-14


def test_stiffness_basis_is_affine_decomposition():
    rig = co.paper_rig()
    model = co.Model(rig)
    rng = np.random.default_rng(5)
    Rs = co.so3.random_rotations(10, rng, max_angle=0.4)
    Ts = rng.uniform(5, 150, (10, 6))
    K0, G = model.stiffness_basis(Rs)
    (K_cas,) = model.casadi("stiffness", Rs, Ts)
    assert _rel(K0 + np.einsum("ni,nijk->njk", Ts, G), K_cas) < REL


def test_kernel_is_energy_hessian_at_loaded_poses():
    rig = co.paper_rig()
    model = co.Model(rig)
    rng = np.random.default_rng(7)
    for _ in range(4):
        R = rodrigues(rng.normal(size=3) * 0.3)
        T = rng.uniform(5, 150, 6)
        l = np.linalg.norm(rig.base_holes_B_m - rig.platform_holes_A_m @ R.T, axis=1) - T / rig.cable_stiffness_N_per_m
        H = fd_hessian(lambda z: cable_energy(rig, R @ rodrigues(z), l))
        K = model.stiffness(R, T)
        assert np.linalg.norm(K - H) / np.linalg.norm(H) < 1e-5


def test_slack_cables_contribute_nothing():
    """Cables 2 and 5 slack (rest length beyond the cable): K is the energy Hessian of the rest."""
    rig = co.paper_rig()
    model = co.Model(rig)
    R = rodrigues(np.array([0.1, -0.2, 0.05]))
    c = np.linalg.norm(rig.base_holes_B_m - rig.platform_holes_A_m @ R.T, axis=1)
    l = c - np.array([40.0, 60.0, 80.0, 30.0, 50.0, 70.0]) / rig.cable_stiffness_N_per_m
    l[[1, 4]] = c[[1, 4]] + 0.002                       # 2 mm of slack
    H = fd_hessian(lambda z: cable_energy(rig, R @ rodrigues(z), l))
    K_rest = co.stiffness(rig, R, rest_lengths_m=l)
    assert np.linalg.norm(K_rest - H) / np.linalg.norm(H) < 1e-5
    T = np.maximum(rig.cable_stiffness_N_per_m * (c - l), 0.0)
    assert T[1] == 0.0 and T[4] == 0.0
    K_t = co.stiffness(rig, R, T)                        # t <= 0 marks a slack cable (not out of bounds)
    assert _rel(K_t, K_rest) < REL
    # the CasADi rest-length form agrees, and its all-taut form does not (k j j^T of the slack cables)
    K_cas_rest = model.casadi("stiffness_rest", R, l)[0]
    assert _rel(K_rest, K_cas_rest) < REL
    assert _rel(model.casadi("stiffness", R, T)[0], K_rest) > 1e-3


def test_stiffness_checks_its_tensions(rig):
    R = co.so3.exp([0.1, -0.05, 0.0])
    tau = np.array([0.5, -0.2, 0.1])
    plan = co.plan_tensions(rig, R, tau)
    co.stiffness(rig, R, plan.tensions_N, tau_ext_A_Nm=tau)            # consistent: fine
    with pytest.raises(co.InconsistentTensions) as info:
        co.stiffness(rig, R, plan.tensions_N, tau_ext_A_Nm=tau + [0.1, 0.0, 0.0])
    assert info.value.reason == "equilibrium" and info.value.value == pytest.approx(0.1, rel=1e-6)
    with pytest.raises(co.InconsistentTensions) as info:
        co.stiffness(rig, R, np.full(6, 1000.0))
    assert info.value.reason == "bounds" and info.value.value == pytest.approx(850.0)
    # outside the bounds on purpose: K is returned, and it is not positive definite (unstable)
    K = co.stiffness(rig, R, np.full(6, 1000.0), check_bounds=False)
    assert not is_stable(K)
    assert np.linalg.eigvalsh(K)[0] < -100
    with pytest.raises(co.InvalidInput):
        co.stiffness(rig, R, np.full(6, np.nan))
    with pytest.raises(co.NotARotation):
        co.stiffness(rig, 1.1 * np.eye(3), np.full(6, 50.0))
    with pytest.raises(co.InconsistentTensions):
        co.stiffness_batch(rig, R[None], np.full((1, 6), 2.0))
    with pytest.raises(co.InconsistentTensions):            # taut below t_min
        co.stiffness(rig, R, np.array([2.0, 50, 50, 50, 50, 50]))
    co.stiffness_batch(rig, R[None], np.array([[0.0, 50, 50, 50, 50, 50]]))   # slack: accepted


def test_nearly_orthogonal_rotation_is_accepted_like_the_validator(rig):
    R = co.so3.exp([0.2, 0.1, 0.0])
    R_noisy = R + 1e-6
    K = co.stiffness(rig, R_noisy, np.full(6, 50.0))
    from csjm_opt._validate import as_rotation
    R_fixed = as_rotation(R_noisy)
    assert _rel(K, co.Model(rig).casadi("stiffness", R_fixed, np.full(6, 50.0))[0]) < REL


@pytest.mark.parametrize("a_shape, b_shape", [((6, 3), (4, 6, 3)), ((3,), (5, 3)), ((2, 1, 3), (1, 4, 3))])
def test_the_references_cross_product_is_numpys(a_shape, b_shape):
    """The reference's cross product (index-rotated copies) against numpy's, broadcast over the leading axes."""
    rng = np.random.default_rng(4)
    a, b = rng.normal(size=a_shape), rng.normal(size=b_shape)
    np.testing.assert_allclose(reference._cross(a, b), np.cross(a, b), rtol=0, atol=1e-15)
