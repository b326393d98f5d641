"""The semi-regular hexagon's circle from its two chords, in closed form, satisfies both chord equations."""

import numpy as np

from csjm_opt.model.hexagon import circle_from_chords


def test_circle_from_chords_satisfies_both_chord_equations():
    rng = np.random.default_rng(3)
    for d12, d23 in [(0.010, 0.095), (0.128, 0.005), *rng.uniform(1e-3, 0.2, (50, 2))]:
        r, gamma = circle_from_chords(d12, d23)
        assert 0 < gamma < 2 * np.pi / 3
        assert abs(2 * r * np.sin(gamma / 2) - d12) < 1e-15
        assert abs(2 * r * np.sin(np.pi / 3 - gamma / 2) - d23) < 1e-15
