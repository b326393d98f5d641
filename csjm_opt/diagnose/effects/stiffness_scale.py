"""``stiffness_scale``: every cable stiffness off by one common factor.

``k_i -> s k_i`` with ``s = exp(log_k_scale)`` (one parameter): a cable batch
or drive stiffness different from the rig file's. Until it had a name it
was folded into the nominal refit; now the nominal refit keeps only the
common rest-length offset (pretension) and a stiffness error is named.
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot

#: Plausible common stiffness factor (the prior's +-2 sd of its log); also the sensor gain's, its look-alike.
FACTOR_RANGE = (0.5, 2.0)


class StiffnessScale(Effect):
    """Common cable stiffness factor ``s = exp(log_k_scale)``."""

    name = "stiffness_scale"
    description = "all cable stiffnesses scaled by a common factor s = exp(log_k_scale)"

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``("log_k_scale",)``: the log of the common stiffness factor.
        """
        return ("log_k_scale",)

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            ``[0.05]`` (log factor, dimensionless).
        """
        return np.array([0.05])

    @property
    def lower_bounds(self):
        """Lower bound of ``log_k_scale`` for the optimiser.

        Returns
        -------
        numpy.ndarray
            ``[-2.0]`` (factor ``exp(-2)``).
        """
        return np.array([-2.0])

    @property
    def upper_bounds(self):
        """Upper bound of ``log_k_scale`` for the optimiser.

        Returns
        -------
        numpy.ndarray
            ``[2.0]`` (factor ``exp(2)``).
        """
        return np.array([2.0])

    def default_ranges(self):
        """A factor within :data:`FACTOR_RANGE` (0.5 to 2)."""
        return {"log_k_scale": tuple(float(np.log(f)) for f in FACTOR_RANGE)}

    def adjust_tension(self, ev, stretch_m, T_N, p):
        """Tensions scaled by the common stiffness factor ``s = exp(log_k_scale)``.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`).
        stretch_m : numpy.ndarray
            Cable stretch ``e = c - l`` (m), shape (n, m).
        T_N : numpy.ndarray
            Tensions from the tension law so far (N), shape (n, m).
        p : numpy.ndarray
            ``[log_k_scale]`` (dimensionless).

        Returns
        -------
        numpy.ndarray
            The changed tensions (N), shape (n, m).
        """
        return T_N * np.exp(p[0])

    def d_adjust_tension(self, ev, stretch_m, d_stretch, T_N, d_T, T_out_N, p, cols):
        """Tangent of :meth:`adjust_tension`: ``s dT + s T d(log_k_scale)``."""
        return d_T * np.exp(p[0]) + T_out_N[..., None] * one_hot(cols, d_T.shape[-1])[0]

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``stiffness_factor``: ``s = exp(log_k_scale)``.
        """
        return {"stiffness_factor": float(np.exp(p[0]))}
