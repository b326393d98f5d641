"""Parametric hole geometry: paper dimensions, equivalent parametrisations, validation."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.design import design_holes, design_rig
from csjm_opt.design.geometry import cable_clearance_m, chords_from_circle
from csjm_opt.errors import DesignError


def _chord(holes: np.ndarray, i: int, j: int) -> float:
    return float(np.linalg.norm(holes[i - 1] - holes[j - 1]))


def test_default_design_has_the_papers_section_iv_a_dimensions():
    rig = design_rig({})
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    # Section IV-A: A1A2 = A3A4 = A5A6 = 0.010, A2A3 = A4A5 = A6A1 = 0.095 (m) ...
    for (i, j), d in {(1, 2): 0.010, (3, 4): 0.010, (5, 6): 0.010,
                      (2, 3): 0.095, (4, 5): 0.095, (6, 1): 0.095}.items():
        assert _chord(A, i, j) == pytest.approx(d, abs=1e-12)
    # ... B1B2 = 0.128, B2B3 = 0.005; OO_A = OO_B = 0.08 m (platform above O, base below)
    for (i, j), d in {(1, 2): 0.128, (3, 4): 0.128, (5, 6): 0.128,
                      (2, 3): 0.005, (4, 5): 0.005, (6, 1): 0.005}.items():
        assert _chord(B, i, j) == pytest.approx(d, abs=1e-12)
    np.testing.assert_allclose(A[:, 2], 0.08)
    np.testing.assert_allclose(B[:, 2], -0.08)
    assert rig.platform_mass_kg * 9.81 == pytest.approx(4.82, abs=5e-3)   # G = 4.82 N


def test_radius_and_gamma_give_the_same_hexagon_as_chords():
    r, gamma = 0.07, 30.0
    d12, d23 = chords_from_circle(r, gamma)
    # closed form: chord = 2 r sin(central angle / 2), central angles gamma and 120 - gamma
    assert d12 == pytest.approx(2 * r * np.sin(np.radians(15)))
    assert d23 == pytest.approx(2 * r * np.sin(np.radians(45)))
    by_circle = design_holes({"platform_radius_m": r, "platform_gamma_deg": gamma})[0]
    by_chords = design_holes({"platform_d12_m": d12, "platform_d23_m": d23})[0]
    np.testing.assert_allclose(by_circle, by_chords, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(by_circle[:, :2], axis=1), r)


def test_theta0_rotates_and_offsets_move_single_holes():
    A0 = design_holes({})[0]
    A = design_holes({"platform_theta0_deg": 90.0, "A3_dz_m": 0.004, "A3_dx_m": -0.001})[0]
    rot = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])
    expected = A0 @ rot.T
    expected[2] += [-0.001, 0.0, 0.004]
    np.testing.assert_allclose(A, expected, atol=1e-12)


def test_free_hole_coordinates_replace_the_hexagon():
    rng = np.random.default_rng(3)
    holes = np.column_stack([0.06 * np.cos(np.arange(6)), 0.06 * np.sin(np.arange(6)), np.full(6, 0.07)])
    holes += rng.normal(scale=1e-3, size=(6, 3))
    rig = design_rig({"platform_holes": holes.tolist()})
    np.testing.assert_array_equal(rig.platform_holes_A_m, holes)


def test_clearance_is_the_distance_from_o_to_the_cable_segment():
    A = np.array([[0.05, 0.0, 0.08]] * 6)
    B = np.array([[-0.05, 0.0, -0.08]] * 6)       # the segment passes through O
    np.testing.assert_allclose(cable_clearance_m(A, B), 0.0, atol=1e-15)
    B2 = np.array([[0.05, 0.0, -0.08]] * 6)       # vertical line x = 0.05
    np.testing.assert_allclose(cable_clearance_m(A, B2), 0.05)


@pytest.mark.parametrize("params, key", [
    ({"platform_d12_m": 0.0005}, "platform_holes"),               # coincident holes
    ({"A1_dx_m": -0.0577, "A1_dy_m": 0.005, "B1_dx_m": -0.0398, "B1_dy_m": 0.064}, "holes"),  # cable 1 through O
    ({"platform_radius_m": 0.05}, "platform_radius_m"),           # gamma missing
    ({"platform_radius_m": 0.05, "platform_gamma_deg": 20.0, "platform_d12_m": 0.01}, "platform_radius_m"),
    ({"platform_gamma_deg": 130.0, "platform_radius_m": 0.05}, "platform_radius_m"),
    ({"oo_a_m": -0.01}, "oo_a_m"),
    ({"t_min_N": 200.0}, "t_min_N"),
    ({"cable_stiffness_N_per_m": 0.0}, "cable_stiffness_N_per_m"),
    ({"platform_radius": 0.05}, "platform_radius"),               # unknown name
    ({"oo_b_m": "0.08"}, "oo_b_m"),
    ({"base_holes": [[0, 0, 0]] * 5}, "base_holes"),
])
def test_invalid_designs_name_the_parameter(params, key):
    with pytest.raises(DesignError) as info:
        design_rig(params)
    assert info.value.key == key
    assert f"[{key}]" in str(info.value)
