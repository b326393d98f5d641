"""``sensor_bias``: a constant moment offset of the F/T reading, in {A}."""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot


class SensorBias(Effect):
    """Measured moment = true external moment + ``b`` (3 parameters, N m)."""

    name = "sensor_bias"
    description = "constant F/T moment offset b (N m, in {A}): tau_meas = tau_ext + b"

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            The three bias components ``bias_{x,y,z}_Nm`` (N m, in {A}).
        """
        return ("bias_x_Nm", "bias_y_Nm", "bias_z_Nm")

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            0.05 N m for each component.
        """
        return np.full(3, 0.05)

    def default_ranges(self):
        """Within 10 % of the F/T sensor's 5 N m moment range."""
        return {n: (-0.5, 0.5) for n in self.param_names}

    def adjust_load(self, ev, p):
        """Subtract the bias ``b`` from the measured external moment ``ev.tau_ext_A_Nm`` (N m, in {A}).

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            The bias ``b`` (N m, in {A}), shape (3,).
        """
        ev.tau_ext_A_Nm = ev.tau_ext_A_Nm - p

    def d_adjust_load(self, ev, p, cols, d_tau, d_first):
        """Tangents of :meth:`adjust_load`: ``-1`` on each axis's own column."""
        return d_tau - one_hot(cols, d_tau.shape[-1])[None], d_first

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``bias_norm_Nm``: the bias magnitude ``|b|`` (N m).
        """
        return {"bias_norm_Nm": float(np.linalg.norm(p))}
