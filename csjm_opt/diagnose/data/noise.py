"""Noise floor estimated from the data, without trusting any effect model.

Within one cycle the rest lengths are fixed and only the load changes, so a
smooth systematic residual is close to affine in the load, with a step
between the loading and unloading branches (hysteresis). Fitting
``zeta ~ a + B s + d [unloading] + B' s [unloading] + e [first row]`` per cycle (each branch its own
slope, and the first row its own offset: dry friction with memory bends the branches apart and
shifts the row where the previous cycle's state enters), where ``s`` are the measured
moment's coordinates along the directions in which the cycle's load really
varies (principal directions with spread well above the F/T noise: regressing
on pure-noise directions would absorb the noise the floor is meant to measure).

The regression is weighted by the instrument model's shape (generalised least squares on
whitened residuals ``W_i zeta_i``, :attr:`ResidualTable.whiten`): the noise is far from
equal across a cycle (on a soft rig whose pose noise comes from the F/T sensor, a cycle's
first and last rows, at the lowest load, carry 2-3x the noise of its middle rows), and an
unweighted fit spends its per-row parameters (the first row's own offset, the branch
slopes) on exactly those rows and underestimates the floor (by about 1.6x on such a rig,
which then left a correct model "unexplained"). Pooling the whitened residual sums of squares over
cycles (with their degrees of freedom) gives the noise scale ``s`` relative to the
instrument model, and the floor is ``s`` times the instrument model's floor
(:attr:`ResidualTable.instrument_floor_rad`): the held-out RMS a perfect model would still show.
"""

from __future__ import annotations

import numpy as np

from .residuals import ResidualTable

#: A load direction counts as varied within a cycle when its RMS spread exceeds this (N m).
LOAD_SPREAD_NM = 0.2


def noise_floor(table: ResidualTable, zeta: np.ndarray | None = None) -> tuple[float, int]:
    """``(floor_rad, degrees_of_freedom)``; ``(nan, 0)`` when no cycle has spare rows."""
    zeta = table.zeta_rad if zeta is None else zeta
    W = table.whiten
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
        # whitened design: row i, axis a of the coefficient block of regressor k -> W_i[:, a] x_k[i]
        Xw = np.einsum("iab,ik->iakb", W[idx], X).reshape(3 * m, 3 * X.shape[1])
        yw = np.einsum("iab,ib->ia", W[idx], zeta[idx]).reshape(3 * m)
        coef, *_ = np.linalg.lstsq(Xw, yw, rcond=None)
        rss += float(np.sum((yw - Xw @ coef) ** 2))
        dof += m - rank
    if dof == 0:
        return float("nan"), 0
    return float(np.sqrt(rss / (3 * dof))) * table.instrument_floor_rad, dof


def systematic(rms_rad: float, floor_rad: float) -> float:
    """Systematic part of an RMS gap: ``sqrt(max(rms^2 - floor^2, 0))``."""
    return float(np.sqrt(max(rms_rad ** 2 - floor_rad ** 2, 0.0)))


def combine_scales(s1: float, dof1: float, s2: float, dof2: float) -> float:
    """Noise level from two estimates: pooled when they agree, else the smaller one.

    Each estimate has relative sd ``sqrt(2/dof)`` in variance; they are pooled when they
    agree within 2.5 sd, else the smaller is kept (a misfit only inflates an estimate).
    """
    if not np.isfinite(s1) or dof1 <= 0:
        return s2
    v1, v2 = s1 ** 2, s2 ** 2
    sd = np.hypot(v1 * np.sqrt(2 / dof1), v2 * np.sqrt(2 / max(dof2, 1)))
    if abs(v1 - v2) <= 2.5 * sd:
        return float(np.sqrt((v1 * dof1 + v2 * dof2) / (dof1 + dof2)))
    return float(min(s1, s2))
