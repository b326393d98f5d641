"""Random rigs with scattered holes: off their hexagons by at most the radius, still valid."""

import dataclasses

import numpy as np

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
