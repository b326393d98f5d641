"""Orientation sampling: rotations, ranges, Haar uniformity, reproducibility."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from csjm_opt import so3
from csjm_opt.design import OrientationSampling, tilt_torsion_angles, tilt_torsion_rotations
from csjm_opt.errors import DesignError


def test_samples_are_rotations_within_the_tilt_and_torsion_range():
    s = OrientationSampling(n=500, max_tilt_deg=40.0, max_torsion_deg=25.0)
    R = s.rotations()
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    tilt = np.degrees(np.arccos(np.clip(R[:, 2, 2], -1, 1)))   # angle between z_A and z_B
    assert tilt.max() <= 40.0 + 1e-9
    _, _, torsion = tilt_torsion_angles(R)
    assert np.degrees(np.abs(torsion)).max() <= 25.0 + 1e-9


def test_tilt_torsion_definition_and_inverse():
    rng = np.random.default_rng(0)
    tilt, az, tor = rng.uniform(0.01, 1.5, 50), rng.uniform(-3, 3, 50), rng.uniform(-1.5, 1.5, 50)
    R = tilt_torsion_rotations(tilt, az, tor)
    # Rz(phi) Ry(theta) Rz(-phi) Rz(sigma) from so3.exp, independently
    ez, ey = np.array([0, 0, 1.0]), np.array([0, 1.0, 0])
    for k in range(5):
        ref = (so3.exp(az[k] * ez) @ so3.exp(tilt[k] * ey) @ so3.exp(-az[k] * ez) @ so3.exp(tor[k] * ez))
        np.testing.assert_allclose(R[k], ref, atol=1e-12)
    back = tilt_torsion_angles(R)
    np.testing.assert_allclose(back[0], tilt, atol=1e-9)
    np.testing.assert_allclose(np.angle(np.exp(1j * (back[1] - az))), 0, atol=1e-9)
    np.testing.assert_allclose(back[2], tor, atol=1e-9)
    t0 = tilt_torsion_angles(tilt_torsion_rotations(np.zeros(1), np.ones(1), np.full(1, 0.3)))
    np.testing.assert_allclose([t0[0][0], t0[2][0]], [0.0, 0.3], atol=1e-12)


@pytest.mark.parametrize("method", ["halton", "random"])
def test_full_range_is_haar_uniform(method):
    # Haar measure: rotation angle w has CDF (w - sin w) / pi on [0, pi].
    R = OrientationSampling(n=3000, max_tilt_deg=180.0, max_torsion_deg=180.0, method=method).rotations()
    angle = np.linalg.norm(so3.log(R), axis=1)
    assert stats.kstest(angle, lambda w: (w - np.sin(w)) / np.pi).pvalue > 0.01
    # axes isotropic: mean of the axis-angle vector direction ~ 0
    assert np.abs(np.mean(so3.log(R) / angle[:, None], axis=0)).max() < 0.06


def test_tilt_is_area_uniform_on_the_cap():
    s = OrientationSampling(n=4000, max_tilt_deg=60.0, max_torsion_deg=10.0, method="random", seed=5)
    tilt = s.angles()[0]
    cdf = lambda t: (1 - np.cos(t)) / (1 - np.cos(np.radians(60)))  # noqa: E731
    assert stats.kstest(tilt, cdf).pvalue > 0.01


def test_sampling_is_reproducible_and_halton_is_nested():
    a = OrientationSampling(n=100, seed=7).rotations()
    b = OrientationSampling(n=100, seed=7).rotations()
    c = OrientationSampling(n=400, seed=7).rotations()
    np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(c[:100], a, atol=1e-15)
    assert not np.allclose(OrientationSampling(n=100, seed=8).rotations(), a)


@pytest.mark.parametrize("kwargs, key", [({"n": 0}, "orientations"), ({"max_tilt_deg": 0.0}, "max_tilt_deg"),
                                         ({"max_torsion_deg": -1.0}, "max_torsion_deg"),
                                         ({"method": "sobol"}, "method")])
def test_bad_sampling_names_the_key(kwargs, key):
    with pytest.raises(DesignError) as info:
        OrientationSampling(**kwargs)
    assert info.value.key == key
