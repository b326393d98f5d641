"""Random rigs with scattered holes: off their hexagons by at most the radius, still valid."""

import dataclasses

import numpy as np
import pytest

from csjm_opt.testbed.rigs import RigRanges, draw_rig, random_rig


def test_no_scatter_draws_the_same_rigs_as_before():
    a = draw_rig(np.random.default_rng(3))
    b = draw_rig(np.random.default_rng(3), RigRanges(hole_scatter_m=0.0))
    assert np.array_equal(a.platform_holes_A_m, b.platform_holes_A_m)
    assert np.array_equal(a.base_holes_B_m, b.base_holes_B_m)


def test_scatter_moves_every_hole_within_the_radius():
    ranges = RigRanges(hole_scatter_m=0.008)
    plain, scattered = draw_rig(np.random.default_rng(5)), draw_rig(np.random.default_rng(5), ranges)
    for field in ("platform_holes_A_m", "base_holes_B_m"):
        d = np.linalg.norm(getattr(scattered, field) - getattr(plain, field), axis=1)
        assert np.all(d > 0.0) and np.all(d <= 0.008)
    # the draws after the holes differ (the stream moved on), but the hexagon draws are the same
    assert dataclasses.replace(ranges, hole_scatter_m=0.0) == RigRanges()


def test_scattered_random_rig_holds_its_experiment_and_breaks_the_symmetry():
    rig, _ = random_rig(np.random.default_rng(11), RigRanges(hole_scatter_m=0.008))
    radii = np.linalg.norm(rig.platform_holes_A_m[:, :2], axis=1)
    assert np.ptp(radii) > 1e-4            # a hexagon has all its holes on one circle


@pytest.mark.parametrize("m", [4, 5, 8, 12])
def test_random_rigs_of_m_cables_keep_the_hexagons_circles_and_pair_fractions(m):
    """m holes on the circles the chords give (closed form), pairs at the hexagon's fraction of the spacing."""
    rng, rng6 = np.random.default_rng(m), np.random.default_rng(m)
    rig, hexagon = draw_rig(rng, RigRanges(n_cables=m)), draw_rig(rng6)
    assert rig.n_cables == m and rig.platform_holes_A_m.shape == rig.base_holes_B_m.shape == (m, 3)
    assert np.asarray(rig.cable_stiffness_N_per_m).shape == (m,)
    for body in ("platform_holes_A_m", "base_holes_B_m"):
        h, h6 = getattr(rig, body), getattr(hexagon, body)
        # tan(gamma / 2) = d12 sin 60 / (d23 + d12 cos 60) for the hexagon's own chords
        d12, d23 = np.linalg.norm(h6[1] - h6[0]), np.linalg.norm(h6[2] - h6[1])
        gamma6 = 2 * np.arctan2(d12 * np.sin(np.pi / 3), d23 + d12 * np.cos(np.pi / 3))
        radius = d12 / (2 * np.sin(gamma6 / 2))
        assert np.allclose(np.linalg.norm(h[:, :2], axis=1), radius, rtol=1e-12)
        assert np.allclose(h[:, 2], h6[0, 2])
        if m % 2 == 0:
            gamma = np.arccos(np.clip(h[0, :2] @ h[1, :2] / radius ** 2, -1, 1))
            assert gamma == pytest.approx(gamma6 * 6 / m, rel=1e-9)


@pytest.mark.parametrize("m", [4, 5, 8, 12])
def test_random_rigs_of_m_cables_hold_their_experiment(m):
    from csjm_opt.testbed.cycles import design_cycles

    rig, _ = random_rig(np.random.default_rng(m), RigRanges(n_cables=m))
    assert rig.n_cables == m
    assert len(design_cycles(rig, 2, np.random.default_rng(0))) == 2
