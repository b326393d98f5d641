"""``cable_hardening``: tension grows faster than linearly with stretch.

``T = k e (1 + h e)`` for a taut cable with stretch ``e = c - l`` (m); the
tangent stiffness ``k (1 + 2 h e)`` grows with tension. One shared ``h``
(1/m); the nominal stiffness scale fitted alongside absorbs a mean stiffening.
"""

from __future__ import annotations

import numpy as np

from .base import Effect


class CableHardening(Effect):
    """Quadratic hardening coefficient ``h`` (1/m), shared by the six cables."""

    name = "cable_hardening"
    description = "T = k e (1 + h e): stiffness rising with stretch (h in 1/m)"

    @property
    def param_names(self):
        return ("hardening_per_m",)

    @property
    def scales(self):
        return np.array([10.0])

    def default_ranges(self):
        """Up to 300 /m (stiffness x7 at 10 mm stretch); mild softening (-20 /m) allowed."""
        return {"hardening_per_m": (-20.0, 300.0)}

    def adjust_tension(self, ev, stretch_m, T_N, p):
        return T_N * (1.0 + p[0] * np.maximum(stretch_m, 0.0))

    def describe(self, p):
        return {"stiffness_gain_at_20mm_stretch": float(1 + 2 * p[0] * 0.02)}
