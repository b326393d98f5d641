"""Cable quantities written out cable by cable, for checking effects against (not the package's kinematics)."""

from __future__ import annotations

import numpy as np


def tensions_by_hand(rig, R, rest):
    """Tension (n, m) N of every cable at poses ``R`` (n, 3, 3), rest lengths ``rest`` (n, m): ``k (l - l0)^+``."""
    A, B = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    k = np.asarray(rig.cable_stiffness_N_per_m)
    return np.array([[ki * max(np.linalg.norm(b - Ri @ a) - l0, 0.0) for a, b, ki, l0 in zip(A, B, k, li)]
                     for Ri, li in zip(R, rest)])
