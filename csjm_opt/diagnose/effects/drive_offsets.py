"""``drive_offsets``: each cable's actual rest length off the commanded one by a constant.

A drive is homed (its encoder zeroed) to within some fraction of a millimetre; after that the
rest length it realises is ``l_i + d_i`` for the commanded ``l_i``, the same offset ``d_i`` on
every row (m parameters, m the rig's cable count). The common part of the offsets is the
nuisance ``dl_common_m`` every model carries (a pretension error); the effect is what the
cables do *differently*. The tension law becomes ``T_i = k_i (c_i - l_i - d_i)``.

Prior: a zero-mean Gaussian of sd ``RANGE_M / 2`` per drive (the plausible range +-``RANGE_M``
is +-2 sd), carried by the fit as a ridge (``prior_sd``), so the direction shared with the
nuisance stays well posed. A base hole moved along its cable changes that cable's length by
about the same amount at every pose: drive offsets are, to first order, m of the 6 m
hole-offset directions, and the evidence (:mod:`csjm_opt.diagnose.evidence`) prefers the m
numbers when they explain the log as well.
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot

#: Plausible homing error of one drive (m): a few tenths of a mm is typical, 2 mm a badly homed drive.
RANGE_M = 2e-3


class DriveOffsets(Effect):
    """A constant rest-length offset per cable (m)."""

    name = "drive_offsets"
    description = "constant rest-length offset d_i per drive (homing / encoder zero error), m: l_i -> l_i + d_i"

    def __init__(self, n_cables: int = 6, prior_sd_m: float = RANGE_M / 2):
        self.n_cables = int(n_cables)
        self.prior_sd_m = float(prior_sd_m)

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``drive_offset{i}_m`` for cables ``i = 1..m`` (m).
        """
        return tuple(f"drive_offset{i + 1}_m" for i in range(self.n_cables))

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling).

        Returns
        -------
        numpy.ndarray
            2e-4 m per drive.
        """
        return np.full(self.n_cables, 2e-4)

    @property
    def prior_sd(self):
        """Standard deviation of the zero-mean Gaussian prior of each offset (m).

        Returns
        -------
        numpy.ndarray
            ``prior_sd_m`` per drive.
        """
        return np.full(self.n_cables, self.prior_sd_m)

    def default_ranges(self):
        """Within +-2 mm per drive."""
        return {n: (-RANGE_M, RANGE_M) for n in self.param_names}

    def adjust_rest(self, ev, p):
        """Add the offsets to the rest lengths ``ev.rest_lengths_m`` (n, m).

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            Offsets ``d_i`` (m), shape (m,).
        """
        ev.rest_lengths_m = ev.rest_lengths_m + np.asarray(p)[None, :]

    def d_adjust_rest(self, ev, p, cols, d_rest):
        """Tangent of :meth:`adjust_rest`: each cable's rest length moves by one on its offset's column."""
        return d_rest + one_hot(cols, d_rest.shape[-1])[None]

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``drive_offset_mm``: each offset (mm); ``relative_offset_mm``: each offset minus their mean
            (the part the common pretension offset cannot take).
        """
        p = np.asarray(p, float)
        return {"drive_offset_mm": (1e3 * p).tolist(), "relative_offset_mm": (1e3 * (p - p.mean())).tolist()}
