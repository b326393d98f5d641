"""``cable_creep`` (a probe outside the vocabulary): rest lengths that grow with tension over time.

A polymer cable under tension creeps: its rest length grows at a rate proportional to its
tension (linear creep, ``dl_i/dt = kappa T_i``). A log records no time, only the order of its rows;
taking one step per row, the rest length of cable ``i`` at row ``k`` of a cycle has grown by
``kappa sum_{j <= k} T_i(j)`` (the sum over the cycle's rows so far: a rig re-tensioned, or its
cables relaxed, between cycles starts each cycle afresh), and its tension falls by ``k_i`` times that.
A cable's creep rate is its length times the material's creep compliance over its section, and its
stiffness ``k_i = E A / L_i``: ``lambda = k_i kappa_i`` is the same for every cable of one material,
the share of its tension a cable loses per row. One parameter ``lambda``
(dimensionless, per row, >= 0): ``T_i(k) -> T_i(k) - lambda sum_{j <= k} T_i(j)``.

Creep is a time-dependent fault, outside the diagnosis's vocabulary: the diagnosis never names it.
It fits this model beside its verdict and warns when the log trends with time (sample order within
each cycle) in a way the verdict only stands in for (:func:`csjm_opt.diagnose.selection.decision`,
``_creep_warning``). A path effect such as friction also makes the rows of a cycle depend on their
order, but through the direction of the last load change (the pose lags behind a rising load and
stays behind a falling one); creep accumulates whichever way the load moves.
"""

from __future__ import annotations

import numpy as np

from .base import Effect

#: Plausible creep: a cable losing up to 5 % of its tension per row (a badly creeping cable).
RANGE_PER_ROW = 0.05


def within_cycle_sum(positions: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The running sum of ``values`` (n, ...) over the rows of each cycle so far.

    ``positions``: each row's place in its cycle (0 = first row; :attr:`Rows.positions
    <csjm_opt.diagnose.fitting.augmented.Rows.positions>`).
    """
    values = np.asarray(values, float)
    total = np.cumsum(values, axis=0)
    start = np.arange(len(values)) - np.asarray(positions, int)   # each row's cycle start
    before = np.zeros_like(values)
    before[1:] = total[:-1]                                       # the sum over the rows before each row
    return total - before[start]


class CableCreep(Effect):
    """Linear creep of every cable: ``T_i(k) -> T_i(k) - lambda sum_{j <= k} T_i(j)`` within a cycle."""

    name = "cable_creep"
    description = "rest length growing with tension over the rows of a cycle (linear creep), tension share per row"

    def __init__(self, n_cables: int = 6):
        self.n_cables = int(n_cables)

    @property
    def param_names(self):
        """``("creep_per_row",)``: ``lambda``, the share of a cable's tension lost per row (per newton-row)."""
        return ("creep_per_row",)

    @property
    def scales(self):
        """A tenth of the plausible range."""
        return np.array([0.1 * RANGE_PER_ROW])

    @property
    def prior_sd(self):
        """Half the plausible range (the range is +-2 sd about no creep)."""
        return np.array([RANGE_PER_ROW / 2])

    def default_ranges(self):
        """Creep lengthens a cable: ``0 <= lambda <= RANGE_PER_ROW``."""
        return {"creep_per_row": (0.0, RANGE_PER_ROW)}

    def adjust_tension(self, ev, stretch, T, p):
        """Each tension less ``lambda`` times its running sum over the row's cycle (never below zero)."""
        return np.maximum(T - float(p[0]) * within_cycle_sum(ev.rows.positions, T), 0.0)

    def describe(self, p):
        """``creep_percent_per_row``: the share of a cable's tension lost per row and newton-row (%)."""
        return {"creep_percent_per_row": 100.0 * float(p[0])}
