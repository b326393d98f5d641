"""Semi-regular hexagon hole layouts (paper Section II and IV-A).

A semi-regular hexagon has alternating chords: holes 1-2, 3-4, 5-6 are one
chord ``d12`` apart and holes 2-3, 4-5, 6-1 another ``d23``. All six lie on a
circle of radius ``r`` at height ``z``; hole ``2m+1`` sits at angle
``theta0 + 120 m - gamma/2`` and hole ``2m+2`` at ``theta0 + 120 m + gamma/2``
(degrees, counter-clockwise about z), where ``gamma`` is the central angle of
chord 1-2. Platform and base use the same rule, so cable i joins hole i of
each, exactly as the paper labels them.
"""

from __future__ import annotations

import numpy as np

from ..errors import InvalidInput

#: Paper Section IV-A: A1A2 = 0.010 m, A2A3 = 0.095 m; B1B2 = 0.128 m, B2B3 = 0.005 m;
#: OO_A = OO_B = 0.08 m (platform above O, base below O).
PAPER_PLATFORM_CHORDS_M = (0.010, 0.095)
PAPER_BASE_CHORDS_M = (0.128, 0.005)
PAPER_OO_A_M = 0.08
PAPER_OO_B_M = 0.08


def circle_from_chords(d12_m: float, d23_m: float) -> tuple[float, float]:
    """Radius (m) and central angle gamma (rad) of chord 1-2 for chords d12, d23.

    Solves ``d12 = 2 r sin(gamma/2)``, ``d23 = 2 r sin(pi/3 - gamma/2)``.
    """
    if not (d12_m > 0 and d23_m > 0):
        raise InvalidInput(f"chords must be positive, got d12={d12_m}, d23={d23_m}", "chords")

    def ratio_gap(gamma: float) -> float:
        return d12_m * np.sin(np.pi / 3 - gamma / 2) - d23_m * np.sin(gamma / 2)

    # The closed form is tan(gamma/2) = d12 sin(pi/3) / (d23 + d12 cos(pi/3)); the root is found with
    # brentq as in every earlier release so that designs keep their numbers to the last bit.
    from scipy.optimize import brentq  # here, not at import: scipy.optimize costs ~0.4 s

    gamma = brentq(ratio_gap, 0.0, 2 * np.pi / 3, xtol=1e-15)
    radius = d12_m / (2 * np.sin(gamma / 2))
    return float(radius), float(gamma)


def hexagon_holes(d12_m: float, d23_m: float, z_m: float, theta0_deg: float = 0.0) -> np.ndarray:
    """(6, 3) hole positions of a semi-regular hexagon, ordered 1..6."""
    radius, gamma = circle_from_chords(d12_m, d23_m)
    base = np.deg2rad(theta0_deg) + np.deg2rad(120.0) * np.arange(3)
    angles = np.empty(6)
    angles[0::2] = base - gamma / 2
    angles[1::2] = base + gamma / 2
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.full(6, z_m)])


#: The paper rig's holes (m) as :func:`hexagon_holes` gives them for the chords above, written out so that
#: building the paper rig needs no root finder (the planner's command starts without SciPy's optimisers);
#: ``tests/model/test_hexagon_chords.py`` checks them against the chord solution bit for bit.
PAPER_PLATFORM_HOLES_A_M = (
    (0.05773502691896258, -0.005, 0.08),
    (0.05773502691896258, 0.005, 0.08),
    (-0.024537386440559077, 0.05250000000000001, 0.08),
    (-0.033197640478403484, 0.04750000000000001, 0.08),
    (-0.0331976404784035, -0.0475, 0.08),
    (-0.024537386440559136, -0.05249999999999999, 0.08))
PAPER_BASE_HOLES_B_M = (
    (0.03983716857408418, -0.064, -0.08),
    (0.03983716857408418, 0.064, -0.08),
    (0.035507041555161996, 0.06649999999999999, -0.08),
    (-0.07534421012924616, 0.0025000000000000235, -0.08),
    (-0.07534421012924616, -0.002499999999999971, -0.08),
    (0.03550704155516195, -0.06650000000000002, -0.08))


def paper_holes() -> tuple[np.ndarray, np.ndarray]:
    """Platform holes A_i in {A} and base holes B_i in {B} of the paper's rig (m)."""
    return np.array(PAPER_PLATFORM_HOLES_A_M), np.array(PAPER_BASE_HOLES_B_M)
