"""``tracker_registration``: a constant rotation between the tracker's frame and {B}.

The tracker reports the measured body's orientation in its own frame {T};
when {T} is registered to {B} with a small rotation error ``Q_B = exp(hat(b))``
the log's orientation is ``R_meas = Q_B R`` (``R``: the true pose in {B}).
Optionally (``marker=True``) the marker frame is also rotated against {A} by
``Q_A = exp(hat(a))``: ``R_meas = Q_B R Q_A``. The true pose drives the
cable lengths and the direction of gravity; the F/T moment is unaffected.
Three parameters ``b`` (rad, in {B}), six with ``a`` (rad, in {A}). Over
the small tilts of a load experiment ``a`` and ``b`` are nearly collinear,
so the marker part is off by default.
"""

from __future__ import annotations

import numpy as np

from ... import so3
from .base import Effect

#: Plausible registration error per rotation-vector component (rad): about 3 degrees.
RANGE_RAD = 0.05


class TrackerRegistration(Effect):
    """Rotation vector ``b`` of the tracker frame against {B} (and ``a`` of the markers against {A})."""

    name = "tracker_registration"
    description = "tracker frame rotated against {B} (and markers against {A}): R_meas = Q_B R Q_A"

    def __init__(self, gravity_B_m_per_s2=(0.0, 0.0, -9.81), marker: bool = False, n_cables: int = 6):
        self.n_cables = int(n_cables)
        self.gravity = np.asarray(gravity_B_m_per_s2, float)
        self.marker = bool(marker)

    @property
    def param_names(self):
        """Parameter names of this effect.

        Returns
        -------
        tuple of str
            ``tracker_rot_{x,y,z}_rad`` (in {B}), followed by ``marker_rot_{x,y,z}_rad``
            (in {A}) when ``marker`` is set.
        """
        names = tuple(f"tracker_rot_{a}_rad" for a in "xyz")
        return names + (tuple(f"marker_rot_{a}_rad" for a in "xyz") if self.marker else ())

    @property
    def scales(self):
        """Typical parameter magnitudes (optimiser scaling and ridge prior).

        Returns
        -------
        numpy.ndarray
            5e-3 rad for each rotation-vector component.
        """
        return np.full(self.n_params, 5e-3)

    def default_ranges(self):
        """Plausible ranges: within 0.05 rad (about 3 degrees) per component.

        Returns
        -------
        dict
            Parameter name -> ``(lo, hi)`` (rad).
        """
        return {n: (-RANGE_RAD, RANGE_RAD) for n in self.param_names}

    def adjust_frame(self, ev, p):
        """True body pose ``Q_B^T R_meas`` (``... Q_A^T`` with markers) written to ``ev.R_body``.

        Parameters
        ----------
        ev : Evaluation
            The evaluation being built (:class:`~csjm_opt.diagnose.fitting.augmented.Evaluation`), changed in place.
        p : numpy.ndarray
            ``b`` (rad, in {B}) and, with ``marker``, ``a`` (rad, in {A}).
        """
        R = so3.exp(-np.asarray(p[:3])) @ ev.R_body              # Q_B^T R_meas
        if self.marker:
            R = R @ so3.exp(-np.asarray(p[3:6]))                  # ... Q_A^T
        ev.R_body = R

    def describe(self, p):
        """Physically readable quantities derived from the fitted parameters.

        Parameters
        ----------
        p : numpy.ndarray
            This effect's parameter slice.

        Returns
        -------
        dict
            ``tracker_rotation_deg`` (and ``marker_rotation_deg``): the rotation angles (degrees).
        """
        out = {"tracker_rotation_deg": float(np.degrees(np.linalg.norm(p[:3])))}
        if self.marker:
            out["marker_rotation_deg"] = float(np.degrees(np.linalg.norm(p[3:6])))
        return out



