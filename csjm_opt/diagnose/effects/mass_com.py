"""``mass_com``: error of the platform's mass and centre of mass.

Moment data see the weight only through its first mass moment
``m r`` (kg m, in {A}): ``tau_w = (m r) x (R^T g)``. Mass and the centre of
mass along ``r`` are therefore not separately identifiable; the effect fits
the first-moment error ``d(m r)`` (3 parameters) and reports what it implies
for the centre of mass at the rig file's mass.
"""

from __future__ import annotations

import numpy as np

from .base import Effect, one_hot


class MassCom(Effect):
    """First mass moment error ``d(m r)`` (kg m, in {A})."""

    name = "mass_com"
    description = "platform mass / centre-of-mass error, fitted as the first mass moment m r (kg m)"

    def __init__(self, mass_kg: float = 0.4913, n_cables: int = 6):
        self.n_cables = int(n_cables)
        self.mass_kg = float(mass_kg)

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            The first-moment error components ``dmr_{x,y,z}_kgm`` (kg m, in {A}).
        """
        return ("dmr_x_kgm", "dmr_y_kgm", "dmr_z_kgm")

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            2e-3 kg m for each component.
        """
        return np.full(3, 2e-3)

    def default_ranges(self):
        """``|d(m r)| <= 0.1 kg x nominal mass`` per axis: a 10 cm centre-of-mass shift at nominal mass."""
        lim = 0.1 * max(self.mass_kg, 0.05)
        return {n: (-lim, lim) for n in self.param_names}

    def adjust_load(self, ev, p):
        """Add the first-moment error ``d(m r)`` to ``ev.first_moment_A_kgm`` (kg m, in {A}).

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            The first-moment error ``d(m r)`` (kg m, in {A}), shape (3,).
        """
        ev.first_moment_A_kgm = ev.first_moment_A_kgm + p

    def d_adjust_load(self, ev, p, cols, d_tau, d_first):
        """Tangents of :meth:`adjust_load`: the first moment moves by one on each component's column."""
        return d_tau, d_first + one_hot(cols, d_first.shape[-1])

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``com_shift_at_nominal_mass_m``: ``d(m r) / m`` (m, in {A}) at the rig file's mass, with a
            note that mass and centre of mass are confounded; empty if the mass is not positive.
        """
        if self.mass_kg <= 0:
            return {}
        return {"com_shift_at_nominal_mass_m": (np.asarray(p) / self.mass_kg).tolist(),
                "note": "mass and com are confounded in moment data; only m*r is identified"}
