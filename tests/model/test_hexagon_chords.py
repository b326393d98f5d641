"""The semi-regular hexagon's circle from its two chords satisfies both chord equations and the closed form."""

import numpy as np

from csjm_opt.model import hexagon
from csjm_opt.model.hexagon import circle_from_chords


def test_circle_from_chords_satisfies_both_chord_equations():
    rng = np.random.default_rng(3)
    for d12, d23 in [(0.010, 0.095), (0.128, 0.005), *rng.uniform(1e-3, 0.2, (50, 2))]:
        r, gamma = circle_from_chords(d12, d23)
        assert 0 < gamma < 2 * np.pi / 3
        assert abs(2 * r * np.sin(gamma / 2) - d12) < 1e-15
        assert abs(2 * r * np.sin(np.pi / 3 - gamma / 2) - d23) < 1e-15


def test_circle_from_chords_matches_the_closed_form():
    for d12, d23 in [(0.010, 0.095), (0.128, 0.005), (0.05, 0.05)]:
        _, gamma = circle_from_chords(d12, d23)
        closed = 2.0 * np.arctan2(d12 * np.sin(np.pi / 3), d23 + d12 * np.cos(np.pi / 3))
        assert abs(gamma - closed) < 1e-14


def test_paper_holes_are_the_chord_solution_bit_for_bit():
    A, B = hexagon.paper_holes()
    assert np.array_equal(A, hexagon.hexagon_holes(*hexagon.PAPER_PLATFORM_CHORDS_M, z_m=hexagon.PAPER_OO_A_M))
    assert np.array_equal(B, hexagon.hexagon_holes(*hexagon.PAPER_BASE_CHORDS_M, z_m=-hexagon.PAPER_OO_B_M))
