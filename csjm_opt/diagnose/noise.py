"""Noise floor estimated from the data, without trusting any effect model.

Within one cycle the rest lengths are fixed and only the load changes, so a
smooth systematic residual is close to affine in the load, with a step
between the loading and unloading branches (hysteresis). Fitting
``zeta ~ a + B s + d [unloading] + B' s [unloading] + e [first row]`` per cycle (each branch its own
slope, and the first row its own offset: dry friction with memory bends the branches apart and
shifts the row where the previous cycle's state enters), where ``s`` are the measured
moment's coordinates along the directions in which the cycle's load really
varies (principal directions with spread well above the F/T noise: regressing
on pure-noise directions would absorb the noise the floor is meant to measure), and pooling the residual
sums of squares over cycles and axes (with their degrees of freedom) gives
``E||zeta_noise||^2``; its square root is the noise floor (rad): the held-out
RMS a perfect model would still show.
"""

from __future__ import annotations

import numpy as np

from .residuals import ResidualTable

#: A load direction counts as varied within a cycle when its RMS spread exceeds this (N m).
LOAD_SPREAD_NM = 0.2


def noise_floor(table: ResidualTable, zeta: np.ndarray | None = None) -> tuple[float, int]:
    """``(floor_rad, degrees_of_freedom)``; ``(nan, 0)`` when no cycle has spare rows."""
    zeta = table.zeta_rad if zeta is None else zeta
    rss, dof = 0.0, 0
    for c in np.unique(table.cycle):
        idx = np.flatnonzero(table.cycle == c)
        m = len(idx)
        tau = table.rows.tau_meas_A_Nm[idx]
        down = (table.branch[idx] < 0).astype(float)
        cols = [np.ones(m)]
        centred = tau - tau.mean(axis=0)
        _, sv, Vt = np.linalg.svd(centred, full_matrices=False)
        loads = []
        for k in range(len(sv)):
            if sv[k] / np.sqrt(m) > LOAD_SPREAD_NM and m - len(cols) >= 3:
                loads.append(centred @ Vt[k])
                cols.append(loads[-1])
        if m - len(cols) >= 3 and 2 <= down.sum() <= m - 2:
            cols.append(down)
            for s_k in loads:          # each branch its own slope: friction makes them differ
                if m - len(cols) >= 3:
                    cols.append(s_k * down)
        if m - len(cols) >= 3:         # the first row: where friction carried from the last cycle shows
            cols.append((np.arange(m) == 0).astype(float))
        X = np.column_stack(cols)
        rank = np.linalg.matrix_rank(X)
        if m - rank < 1:
            continue
        coef, *_ = np.linalg.lstsq(X, zeta[idx], rcond=None)
        rss += float(np.sum((zeta[idx] - X @ coef) ** 2))
        dof += m - rank
    if dof == 0:
        return float("nan"), 0
    return float(np.sqrt(rss / dof)), dof


def systematic(rms_rad: float, floor_rad: float) -> float:
    """Systematic part of an RMS gap: ``sqrt(max(rms^2 - floor^2, 0))``."""
    return float(np.sqrt(max(rms_rad ** 2 - floor_rad ** 2, 0.0)))
