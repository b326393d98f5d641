"""``sensor_bias``: a constant moment offset of the F/T reading, in {A}."""

from __future__ import annotations

import numpy as np

from .base import Effect


class SensorBias(Effect):
    """Measured moment = true external moment + ``b`` (3 parameters, N m)."""

    name = "sensor_bias"
    description = "constant F/T moment offset b (N m, in {A}): tau_meas = tau_ext + b"

    @property
    def param_names(self):
        return ("bias_x_Nm", "bias_y_Nm", "bias_z_Nm")

    @property
    def scales(self):
        return np.full(3, 0.05)

    def default_ranges(self):
        """Within 10 % of the F/T sensor's 5 N m moment range."""
        return {n: (-0.5, 0.5) for n in self.param_names}

    def adjust_load(self, ev, p):
        ev.tau_ext_A_Nm = ev.tau_ext_A_Nm - p

    def describe(self, p):
        return {"bias_norm_Nm": float(np.linalg.norm(p))}
