"""CasADi model: J, cable moment and K against finite differences of the energy.

The references here are written from scratch in numpy (tests/conftest.py):
cable lengths ``|b - R a|`` and the energy ``sum 1/2 k (c - l)^2``, differenced
on SO(3) along ``R exp(hat(zeta))``. Nothing is taken from the package's model.
"""

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import so3
from csjm_opt._validate import as_rotation
from tests.conftest import R0_CORRECTED, cable_energy, fd_gradient, fd_hessian, rodrigues


def _cable_lengths(rig, R):
    return np.linalg.norm(rig.base_holes_B_m - rig.platform_holes_A_m @ R.T, axis=1)


def _random_loaded_poses(rig, model, n, seed):
    """Random tilted poses, each with a random load and tensions planned for it."""
    rng = np.random.default_rng(seed)
    out = []
    while len(out) < n:
        R = rodrigues(rng.normal(size=3) * 0.25)
        tau = rng.normal(size=3) * 0.8
        try:
            plan = co.plan_tensions(rig, R, tau, model=model)
        except co.InfeasibleLoad:
            continue
        out.append((R, plan.tensions_N))
    return out


def test_jacobian_matches_finite_differences_of_cable_lengths(rig, model):
    for R, _ in _random_loaded_poses(rig, model, 5, seed=1):
        J = model.jacobian(R)
        h = 1e-7
        dc = np.column_stack([(_cable_lengths(rig, R @ rodrigues(h * e))
                               - _cable_lengths(rig, R @ rodrigues(-h * e))) / (2 * h) for e in np.eye(3)])
        assert np.allclose(dc, -J, atol=1e-8)  # (40): dc = -J dzeta


def test_cable_moment_is_minus_energy_gradient(rig, model):
    for R, T in _random_loaded_poses(rig, model, 5, seed=2):
        l = _cable_lengths(rig, R) - T / rig.cable_stiffness_N_per_m
        grad = fd_gradient(lambda z: cable_energy(rig, R @ rodrigues(z), l))
        assert np.allclose(model.cable_moment(R, T), -grad, atol=1e-6)  # erratum 2: tau = -dPhi


def test_stiffness_is_levi_civita_hessian_of_cable_energy(rig, model):
    for R, T in _random_loaded_poses(rig, model, 8, seed=3):
        l = _cable_lengths(rig, R) - T / rig.cable_stiffness_N_per_m
        H = fd_hessian(lambda z: cable_energy(rig, R @ rodrigues(z), l))
        K = co.stiffness(rig, R, T, model=model)
        assert np.linalg.norm(K - H) / np.linalg.norm(H) < 1e-5
        assert np.abs(K - K.T).max() < 1e-9
        K45 = np.array(model.functions["stiffness_paper"](
            R, T, rig.cable_stiffness_N_per_m, rig.platform_holes_A_m.T, rig.base_holes_B_m.T))
        assert np.linalg.norm(K45 + H) / np.linalg.norm(H) < 1e-5    # corrected (45) = -Hessian


def test_stiffness_from_rest_lengths_matches_hessian_and_tensions(rig, model):
    for R, T in _random_loaded_poses(rig, model, 3, seed=4):
        l = _cable_lengths(rig, R) - T / rig.cable_stiffness_N_per_m
        K, T_rest, tau, energy = model.stiffness_rest(R, l)
        assert np.allclose(T_rest, T, atol=1e-9)
        assert energy == pytest.approx(cable_energy(rig, R, l), rel=1e-12)
        H = fd_hessian(lambda z: cable_energy(rig, R @ rodrigues(z), l))
        assert np.linalg.norm(K - H) / np.linalg.norm(H) < 1e-5


def test_slack_cable_contributes_nothing(rig, model):
    R = rodrigues(np.array([0.1, -0.05, 0.2]))
    l = _cable_lengths(rig, R) - 0.01
    l[2] += 0.02  # cable 3 slack by 1 cm
    K, T, _, _ = model.stiffness_rest(R, l)
    assert T[2] == 0.0
    H = fd_hessian(lambda z: cable_energy(rig, R @ rodrigues(z), l), h=1e-5)
    assert np.linalg.norm(K - H) / np.linalg.norm(H) < 1e-5


def test_printed_structure_constants_give_asymmetric_stiffness(rig, model):
    """Erratum 1: with gamma = +-2 as printed in (31), (45) is not symmetric at a loaded pose."""
    (R, T), = _random_loaded_poses(rig, model, 1, seed=5)
    args = (R, T, rig.cable_stiffness_N_per_m, rig.platform_holes_A_m.T, rig.base_holes_B_m.T)
    K_printed = np.array(model.functions["stiffness_paper_as_printed"](*args))
    K_corrected = np.array(model.functions["stiffness_paper"](*args))
    tau = model.cable_moment(R, T)
    asym = K_printed - K_printed.T
    assert np.abs(asym).max() > 1e-3
    assert np.allclose(asym, -so3.hat(tau), atol=1e-9)   # the extra -1/2 hat(tau) on each side
    assert np.abs(K_corrected - K_corrected.T).max() < 1e-9


def test_batch_evaluation_equals_single(rig, model):
    poses = _random_loaded_poses(rig, model, 6, seed=6)
    Rs = np.stack([p[0] for p in poses])
    Ts = np.stack([p[1] for p in poses])
    Ks = co.stiffness_batch(rig, Rs, Ts, model=model)
    Js = model.jacobian(Rs)
    for i in range(len(poses)):
        assert np.allclose(Ks[i], model.stiffness(Rs[i], Ts[i]), atol=1e-12)
        assert np.allclose(Js[i], model.jacobian(Rs[i]), atol=1e-15)
    assert np.allclose(model.cable_lengths(Rs), [_cable_lengths(rig, R) for R in Rs])


def test_weight_moment_and_hessian_from_gravity_potential(rig, model):
    m, r, g = rig.platform_mass_kg, rig.com_A_m, rig.gravity_B_m_per_s2
    R = as_rotation(R0_CORRECTED)
    V = lambda z: -m * g @ (R @ rodrigues(z) @ r)  # noqa: E731
    tau, H = model.point_force_moment(R, m * g, r)
    assert np.allclose(tau, -fd_gradient(V), atol=1e-8)
    assert np.allclose(H, fd_hessian(V), atol=1e-6)
    # Section IV-A: G = 4.82 N at r_G = (0, 0, 0.081) m
    assert np.linalg.norm(rig.weight_B_N) == pytest.approx(4.82, abs=5e-3)


def test_stiffness_rejects_bad_input(rig):
    with pytest.raises(co.NotARotation):
        co.stiffness(rig, 1.1 * np.eye(3), np.ones(6))
    with pytest.raises(co.InvalidInput, match="tensions"):
        co.stiffness(rig, np.eye(3), np.ones(5))


def test_compiled_model_gives_the_same_numbers(rig, model):
    Rs = so3.random_rotations(5, np.random.default_rng(9), max_angle=0.3)
    T = np.full((5, 6), 60.0)
    fast = co.Model(rig, compiled=True)
    assert np.allclose(fast.stiffness(Rs, T), model.stiffness(Rs, T), atol=1e-10)
