"""``stiffness_scale``: every cable stiffness off by one common factor.

``k_i -> s k_i`` with ``s = exp(log_k_scale)`` (one parameter): a cable batch
or drive stiffness different from the rig file's. Until it had a name it
was folded into the nominal refit; now the nominal refit keeps only the
common rest-length offset (pretension) and a stiffness error is named.
"""

from __future__ import annotations

import numpy as np

from .base import Effect


class StiffnessScale(Effect):
    """Common cable stiffness factor ``s = exp(log_k_scale)``."""

    name = "stiffness_scale"
    description = "all cable stiffnesses scaled by a common factor s = exp(log_k_scale)"

    @property
    def param_names(self):
        return ("log_k_scale",)

    @property
    def scales(self):
        return np.array([0.05])

    @property
    def lower_bounds(self):
        return np.array([-2.0])

    @property
    def upper_bounds(self):
        return np.array([2.0])

    def default_ranges(self):
        """A factor between 0.5 and 2."""
        return {"log_k_scale": (float(np.log(0.5)), float(np.log(2.0)))}

    def adjust_tension(self, ev, stretch_m, T_N, p):
        return T_N * np.exp(p[0])

    def describe(self, p):
        return {"stiffness_factor": float(np.exp(p[0]))}
