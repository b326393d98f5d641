"""Boundary validators."""

import numpy as np
import pytest

from csjm_opt import InvalidInput, NotARotation, so3
from csjm_opt._validate import as_rotation, as_rotations, as_vector3
from tests.conftest import R0_CORRECTED


def test_printed_R0_is_rejected_with_measured_error():
    R0_printed = R0_CORRECTED.copy()
    R0_printed[2, 1] = 0.300  # as printed in Table 3 (errata item 3)
    with pytest.raises(NotARotation) as info:
        as_rotation(R0_printed)
    expected = np.linalg.norm(R0_printed.T @ R0_printed - np.eye(3))
    assert info.value.orthogonality_error == pytest.approx(expected)
    assert 0.75 < info.value.orthogonality_error < 0.85          # errata: 0.81
    assert f"{expected:.3g}" in str(info.value)


def test_corrected_R0_is_accepted_and_orthonormalised():
    R = as_rotation(R0_CORRECTED)
    assert np.linalg.norm(R0_CORRECTED.T @ R0_CORRECTED - np.eye(3)) < 2e-3  # errata: 1e-3
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.abs(R - R0_CORRECTED).max() < 2e-3


def test_reflection_and_bad_shapes_rejected():
    with pytest.raises(NotARotation, match="det"):
        as_rotation(np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(InvalidInput, match=r"expected shape \(3, 3\)"):
        as_rotation(np.eye(2))
    with pytest.raises(InvalidInput, match="finite"):
        as_vector3([0.0, np.nan, 1.0], "tau")
    with pytest.raises(InvalidInput, match="numbers"):
        as_vector3(["a", "b", "c"], "tau")
    Rs = np.stack([np.eye(3), 2 * np.eye(3)])
    with pytest.raises(NotARotation, match=r"Rs\[1\]"):
        as_rotations(Rs)
    assert as_rotations(so3.exp(np.zeros((4, 3)))).shape == (4, 3, 3)
