"""Does the residual trend with time? A check for faults outside the vocabulary that drift.

Cable creep and a drifting sensor bias change the rig over the log's time order; no effect of the
vocabulary does (every one is constant in time, or follows the loading path). A model fitted to
such a log leaves a residual whose *cycle means* move steadily with the sample order.

The test regresses, per component, the cycle means of a residual (rad) on the cycle's position in
the log (rows are in time order), with the scatter of the cycle means about the line as the noise
(``C - 2`` degrees of freedom for ``C`` cycles): a per-cycle misfit that does not follow the time
order (a pose-dependent one) is noise to it, not a trend. The smallest p-value of the three
components, times three (Bonferroni), is the test's p-value. A trend is reported when it is
significant and *material*: its change over the log is at least ``share`` noise floors.
"""

from __future__ import annotations

import numpy as np

from .tails import linear_trend


def time_trend(zeta_rad: np.ndarray, cycle: np.ndarray, floor_rad: float, alpha: float = 0.01,
               share: float = 0.5) -> dict:
    """Linear trend of the cycle means of a residual over the log's time order.

    Parameters
    ----------
    zeta_rad : numpy.ndarray
        Residuals (n, 3), rows in time order.
    cycle : numpy.ndarray
        Cycle ids (n,); rows of a cycle consecutive.
    floor_rad : float
        The noise floor the change is measured against (rad).
    alpha : float, optional
        Level of the test.
    share : float, optional
        Change over the log, in floors, that makes a trend material.

    Returns
    -------
    dict
        ``p_value``, ``change_rad`` (the fitted change from the first cycle to the last, per
        component), ``cycles``, ``trends`` (significant and material).
    """
    zeta = np.asarray(zeta_rad, float)
    cycle = np.asarray(cycle)
    first = np.r_[True, cycle[1:] != cycle[:-1]]
    run = np.cumsum(first) - 1                    # cycles in time order (an id that comes back is a new cycle)
    C = int(run.max(initial=-1)) + 1
    out = {"p_value": 1.0, "change_rad": [0.0, 0.0, 0.0], "cycles": C, "trends": False}
    if C < 4:
        return out
    means = np.stack([zeta[run == c].mean(axis=0) for c in range(C)])
    t = np.arange(C, dtype=float)
    p, change = [], []
    for j in range(3):
        slope, pv = linear_trend(t, means[:, j])
        p.append(pv if np.isfinite(pv) else 1.0)
        change.append(float(slope * (C - 1)))
    p_value = float(min(1.0, 3.0 * min(p)))
    material = float(np.max(np.abs(change))) >= share * float(floor_rad)
    return {"p_value": p_value, "change_rad": change, "cycles": C, "trends": bool(p_value < alpha and material)}
