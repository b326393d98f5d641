"""SO(3) helpers: laws and closed forms."""

import casadi as ca
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from csjm_opt import so3
from tests.conftest import rodrigues

vec3 = st.tuples(*[st.floats(-3.0, 3.0)] * 3).map(np.array)


@given(vec3, vec3)
@settings(max_examples=60, deadline=None)
def test_hat_is_cross_product(w, v):
    assert np.allclose(so3.hat(w) @ v, np.cross(w, v))
    assert np.allclose(so3.vee(so3.hat(w)), w)


@given(vec3)
@settings(max_examples=60, deadline=None)
def test_exp_matches_rodrigues_and_is_a_rotation(w):
    R = so3.exp(w)
    assert np.allclose(R, rodrigues(w), atol=1e-12)
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.isclose(np.linalg.det(R), 1.0)


@given(vec3, vec3, vec3)
@settings(max_examples=40, deadline=None)
def test_group_axioms(a, b, c):
    A, B, C = so3.exp(a), so3.exp(b), so3.exp(c)
    assert np.allclose((A @ B) @ C, A @ (B @ C))          # associativity
    assert np.allclose(A @ so3.exp(-a), np.eye(3))        # inverse
    assert np.allclose(so3.exp(np.zeros(3)) @ A, A)       # identity
    assert np.allclose(so3.exp(0.3 * a) @ so3.exp(0.7 * a), A)  # one-parameter subgroup


def test_log_inverts_exp_everywhere_including_near_zero_and_pi():
    rng = np.random.default_rng(0)
    axes = rng.normal(size=(2000, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate([rng.uniform(0, np.pi, 1000), np.logspace(-12, -3, 500),
                             np.pi - np.logspace(-9, -2, 500)])
    w = axes * angles[:, None]
    assert np.abs(so3.log(so3.exp(w)) - w).max() < 1e-9
    assert np.all(np.isfinite(so3.log(np.eye(3))))
    assert np.allclose(so3.log(np.eye(3)), 0.0)


def test_exp_derivative_at_zero_is_hat():
    w = np.array([0.3, -0.2, 0.5])
    h = 1e-6
    d = (so3.exp(h * w) - so3.exp(-h * w)) / (2 * h)
    assert np.allclose(d, so3.hat(w), atol=1e-9)


def test_casadi_versions_match_numpy():
    x = ca.SX.sym("x", 3)
    f = ca.Function("f", [x], [so3.exp(x), so3.vee(so3.hat(x))])
    for w in (np.array([0.4, -1.1, 0.2]), np.zeros(3), np.array([1e-9, 0, 0])):
        R, v = f(w)
        assert np.allclose(np.array(R), so3.exp(w), atol=1e-12)
        assert np.allclose(np.array(v).ravel(), w)
        assert np.all(np.isfinite(np.array(R)))


def test_casadi_log_matches_numpy_including_near_zero_and_pi():
    X = ca.SX.sym("R", 3, 3)
    f = ca.Function("log", [X], [so3.log(X)])
    rng = np.random.default_rng(2)
    for angle in (0.0, 1e-9, 1e-4, 0.7, 2.5, np.pi - 1e-5, np.pi - 1e-2):
        axis = rng.normal(size=3)
        w = angle * axis / np.linalg.norm(axis)
        assert np.allclose(np.array(f(so3.exp(w))).ravel(), w, atol=1e-9)


def test_batched_shapes_and_angle_between():
    rng = np.random.default_rng(1)
    Rs = so3.random_rotations(50, rng, max_angle=1.0)
    assert Rs.shape == (50, 3, 3)
    w = so3.log(Rs)
    assert np.all(np.linalg.norm(w, axis=1) <= 1.0 + 1e-12)
    d = so3.angle_between(Rs[:-1], Rs[1:])
    expected = [np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)) for a, b in zip(Rs[:-1], Rs[1:])]
    assert np.allclose(d, expected, atol=1e-7)


def test_exp_with_and_without_small_angles_in_the_batch_agree_row_by_row():
    """A batch with a zero angle takes the Taylor branch: every other row is what it is in a batch without one."""
    w = np.random.default_rng(3).normal(size=(5, 3)) * 0.3
    mixed = so3.exp(np.r_[w, np.zeros((1, 3))])
    np.testing.assert_array_equal(mixed[:5], so3.exp(w))
    np.testing.assert_array_equal(mixed[5], np.eye(3))
