"""``drum_slip`` (a probe outside the vocabulary): cables that slip on their drums above a tension.

A cable wound on a drum (or clamped by a capstan) holds up to a tension ``T_s``; above it, the cable
slips until the excess is relieved, and its rest length grows. Nothing winds it back until the drives
re-home, which a lab does between load cycles. To first order, the rest length of cable ``i`` at row
``k`` of a cycle has grown by ``c_slip`` times the excess ``max(T_i(j) - T_s, 0)`` summed over the
cycle's earlier rows ``j < k`` (a row slips after it settles), and its tension falls by ``k_i`` times
that. Two parameters: ``slip_share = k_i c_slip`` (dimensionless, >= 0; 1 relieves the whole excess at
once) and the threshold ``T_s`` (N): ``T_i(k) -> T_i(k) - slip_share sum_{j < k} max(T_i(j) - T_s, 0)``.

It differs from creep (:mod:`.cable_creep`) in what drives it: creep takes a share of every tension,
row after row, whichever way the load moves; slip takes only the excess over a threshold, so it happens
at a cycle's heaviest rows and stays for the rest of the cycle. Friction holds a pose and gives it back
when the load returns; slip does not give it back within the cycle.

Drum slip is a fault outside the diagnosis's vocabulary: never named. It is fitted beside the verdict like
creep, and a verdict it explains as well carries the warning that the log trends with sample order
within each cycle (:func:`csjm_opt.diagnose.selection.decision`, ``_trend_probe_warning``).
"""

from __future__ import annotations

import numpy as np

from .base import Effect
from .cable_creep import within_cycle_sum

#: Plausible slip: up to the whole excess relieved at once (``slip_share = 1``).
SHARE_RANGE = 1.0
#: Starting thresholds, as shares of the rig's largest planned tension (the threshold is not smooth to fit).
THRESHOLD_STARTS = (0.3, 0.5, 0.7)


class DrumSlip(Effect):
    """Slip above ``T_s``: ``T_i(k) -> T_i(k) - slip_share sum_{j < k} max(T_i(j) - T_s, 0)`` within a cycle."""

    name = "drum_slip"
    description = "cables slipping on their drums above a tension threshold, for the rest of the cycle"

    def __init__(self, n_cables: int = 6, t_max_N: float = 100.0):
        self.n_cables = int(n_cables)
        self.t_max_N = float(t_max_N)

    @property
    def param_names(self):
        """``("slip_share", "slip_threshold_N")``."""
        return ("slip_share", "slip_threshold_N")

    @property
    def scales(self):
        """A tenth of each plausible range."""
        return np.array([0.1 * SHARE_RANGE, 0.1 * self.t_max_N])

    @property
    def prior_sd(self):
        """A ridge prior on the share (half its range); none on the threshold (any threshold is nominal at no slip)."""
        return np.array([SHARE_RANGE / 2, np.inf])

    @property
    def lower_bounds(self):
        """Slip lengthens a cable; a threshold is a tension."""
        return np.zeros(2)

    def default_ranges(self):
        """``0 <= slip_share <= 1``, ``0 <= T_s <= t_max`` (the rig's largest planned tension)."""
        return {"slip_share": (0.0, SHARE_RANGE), "slip_threshold_N": (0.0, self.t_max_N)}

    def x0(self):
        """No slip, the threshold at half the largest planned tension."""
        return np.array([0.0, 0.5 * self.t_max_N])

    def extra_starts(self):
        """Some slip from each of :data:`THRESHOLD_STARTS`."""
        return [np.array([0.3 * SHARE_RANGE, f * self.t_max_N]) for f in THRESHOLD_STARTS]

    def adjust_tension(self, ev, stretch, T, p):
        """Each tension less ``slip_share`` times the excess over ``T_s`` summed over the cycle's earlier rows."""
        excess = np.maximum(T - float(p[1]), 0.0)
        earlier = within_cycle_sum(ev.rows.positions, excess) - excess
        return np.maximum(T - float(p[0]) * earlier, 0.0)

    def describe(self, p):
        """``slip_percent_of_excess`` and ``slip_threshold_N``."""
        return {"slip_percent_of_excess": 100.0 * float(p[0]), "slip_threshold_N": float(p[1])}
