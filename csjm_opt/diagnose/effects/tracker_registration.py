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

    def __init__(self, gravity_B_m_per_s2=(0.0, 0.0, -9.81), marker: bool = False):
        self.gravity = np.asarray(gravity_B_m_per_s2, float)
        self.marker = bool(marker)

    @property
    def param_names(self):
        names = tuple(f"tracker_rot_{a}_rad" for a in "xyz")
        return names + (tuple(f"marker_rot_{a}_rad" for a in "xyz") if self.marker else ())

    @property
    def scales(self):
        return np.full(self.n_params, 5e-3)

    def default_ranges(self):
        return {n: (-RANGE_RAD, RANGE_RAD) for n in self.param_names}

    def adjust_frame(self, ev, p):
        R = so3.exp(-np.asarray(p[:3])) @ ev.R_body              # Q_B^T R_meas
        if self.marker:
            R = R @ so3.exp(-np.asarray(p[3:6]))                  # ... Q_A^T
        ev.R_body = R

    def describe(self, p):
        out = {"tracker_rotation_deg": float(np.degrees(np.linalg.norm(p[:3])))}
        if self.marker:
            out["marker_rotation_deg"] = float(np.degrees(np.linalg.norm(p[3:6])))
        return out



