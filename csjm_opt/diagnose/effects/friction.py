"""``friction``: Coulomb (capstan) friction of the cables at the base guide holes.

Where a cable slides through its guide hole, the tension on the platform side
is the drive-side tension times ``exp(+mu_beta)`` when the cable is drawn out
towards the platform (its length ``c_i`` grows) and ``exp(-mu_beta)`` when it
is pulled back, so the platform feels a tension *band* that depends on the
direction of motion: path-dependent, and the order of rows within a cycle
matters (loading and unloading branches differ: hysteresis).

The sliding direction of each cable in each row, ``s_i in {-1, 0, +1}``, is
taken from the row sequence of its cycle (``ev.slip_sign``; 0 for the first
row of a cycle, whose state is unknown). Six parameters ``mu_beta_i >= 0``.
"""

from __future__ import annotations

import numpy as np

from .base import Effect


class Friction(Effect):
    """Capstan factor ``mu_i beta_i`` (dimensionless) of each cable's guide hole."""

    name = "friction"
    description = "capstan friction at guide holes: T_platform = T_drive exp(mu_beta_i s_i), s_i = sliding direction"

    @property
    def param_names(self):
        return tuple(f"mu_beta_{i + 1}" for i in range(6))

    @property
    def scales(self):
        return np.full(6, 0.05)

    @property
    def lower_bounds(self):
        return np.zeros(6)

    def adjust_tension(self, ev, stretch_m, T_N, p):
        return T_N * np.exp(ev.slip_sign * p)

    def describe(self, p):
        return {"tension_band_percent": (100 * (np.exp(np.asarray(p)) - 1)).tolist()}
