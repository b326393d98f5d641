"""``sensor_gain``: the force/torque sensor's moment reading scaled about its true value.

A calibration (or units, or lever-arm) error of the F/T sensor scales what it reports:
``tau_meas = G tau_ext`` with ``G = diag(g)`` in the sensor's axes ({A}, the reading being
transformed per (55)). Two variants, chosen by the data (:data:`~csjm_opt.diagnose.fitting.model_fits.VARIANTS`):

* ``axes="common"``: one gain ``g = exp(log_gain)`` on every axis (1 parameter);
* ``axes="per_axis"``: a gain per axis ``g_j = exp(log_gain_j)`` (3 parameters).

The model's external moment is ``tau_ext = G^-1 tau_meas``. The platform's own weight does not
pass through the sensor, so a gain differs from a common cable stiffness error
(``stiffness_scale``, which scales the cables' answer to the weight as well): the two look alike
on a log whose load moments dwarf the weight's, and the verdict then names both.

Prior: ``log g`` Gaussian, the plausible gains ``GAIN_RANGE`` being its +-2 sd: the same prior as
``stiffness_scale``'s factor. A stiffness scale ``s`` with first moment ``mr`` balances every row as a gain
``s`` with first moment ``mr / s`` (tests/diagnose/effects/test_look_alikes.py), so on a log with a mass
change the two pairs fit alike and only the priors choose: with the same prior on the shared factor the
choice falls to the first moment's prior (the smaller change of the platform's weight), not to which
factor was given the narrower range. (With gains in [0.6, 1.4], narrower than the stiffness factor's [0.5, 2],
every such tie went to the gain: three stiffness-scale + mass logs of the loop study and one validation log.)
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot
from .stiffness_scale import FACTOR_RANGE

#: Plausible gain of the moment reading (true moment -> logged moment): the stiffness factor's range, its look-alike.
GAIN_RANGE = FACTOR_RANGE
AXES = ("common", "per_axis")


class SensorGain(Effect):
    """Gain of the F/T moment reading, common or per axis (``log_gain``)."""

    name = "sensor_gain"
    description = "F/T moment reading scaled by a gain g (common or per axis of {A}): tau_meas = g tau_ext"

    def __init__(self, axes: str = "common", n_cables: int = 6):
        self.n_cables = int(n_cables)
        if axes not in AXES:
            raise ValueError(f"axes must be one of {AXES}, got {axes!r}")
        self.axes = axes

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``("log_gain",)`` (common) or ``log_gain_{x,y,z}`` (per axis); dimensionless.
        """
        return ("log_gain",) if self.axes == "common" else tuple(f"log_gain_{a}" for a in "xyz")

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling).

        Returns
        -------
        numpy.ndarray
            0.05 per log gain.
        """
        return np.full(self.n_params, 0.05)

    @property
    def lower_bounds(self):
        """Lower bounds of the log gains for the optimiser.

        Returns
        -------
        numpy.ndarray
            ``-2`` (a gain of ``exp(-2)``).
        """
        return np.full(self.n_params, -2.0)

    @property
    def upper_bounds(self):
        """Upper bounds of the log gains for the optimiser.

        Returns
        -------
        numpy.ndarray
            ``2`` (a gain of ``exp(2)``).
        """
        return np.full(self.n_params, 2.0)

    def default_ranges(self):
        """Gains within :data:`GAIN_RANGE`."""
        lo, hi = (float(np.log(g)) for g in GAIN_RANGE)
        return {n: (lo, hi) for n in self.param_names}

    def gains(self, p: np.ndarray) -> np.ndarray:
        """The gain of each axis (3,) from the parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        numpy.ndarray
        """
        return np.broadcast_to(np.exp(np.asarray(p, float)), (3,)).copy()

    def adjust_load(self, ev, p):
        """The true external moment ``G^-1 tau_meas`` from the reading ``ev.tau_ext_A_Nm`` (N m, in {A}).

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            The log gains.
        """
        ev.tau_ext_A_Nm = ev.tau_ext_A_Nm / self.gains(p)

    def d_adjust_load(self, ev, p, cols, d_tau, d_first):
        """Tangents of :meth:`adjust_load`: ``d(tau / g) = d tau / g - (tau / g) d log g``."""
        g = self.gains(p)
        axis_col = np.repeat(cols[:1], 3) if self.axes == "common" else np.asarray(cols)
        dlog = one_hot(axis_col, d_tau.shape[-1])                              # (3, P)
        return d_tau / g[None, :, None] - (ev.tau_ext_A_Nm / g)[..., None] * dlog[None], d_first

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``axes`` and ``gain`` per axis (logged / true moment).
        """
        return {"axes": self.axes, "gain": self.gains(p).tolist()}
