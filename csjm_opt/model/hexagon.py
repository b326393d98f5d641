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

    # d12 sin(pi/3 - x) = d23 sin(x), x = gamma/2  <=>  tan(x) = d12 sin(pi/3) / (d23 + d12 cos(pi/3))
    gamma = 2.0 * float(np.arctan2(d12_m * np.sin(np.pi / 3), d23_m + d12_m * np.cos(np.pi / 3)))
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


def paper_holes() -> tuple[np.ndarray, np.ndarray]:
    """Platform holes A_i in {A} and base holes B_i in {B} of the paper's rig (m)."""
    platform = hexagon_holes(*PAPER_PLATFORM_CHORDS_M, z_m=PAPER_OO_A_M)
    base = hexagon_holes(*PAPER_BASE_CHORDS_M, z_m=-PAPER_OO_B_M)
    return platform, base
