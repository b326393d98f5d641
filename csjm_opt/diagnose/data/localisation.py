"""Where the gap lies: residuals broken down by axis, pose, load and branch.

All breakdowns are RMS of ``||zeta||`` (rad) over the rows of a group, for
the residuals before (baseline) and after (selected model), on held-out rows.
Hysteresis: in each cycle every unloading row is paired with the loading row
of nearest measured moment; under noise alone ``E||zeta_up - zeta_down||^2 =
2 floor^2``, so the ratio is tested against chi-square.
"""

from __future__ import annotations

import numpy as np

from .noise import systematic
from .residuals import ResidualTable, rms
from .tails import chi2_sf, f_sf

AXES = ("x", "y", "z")


def _groups(labels: np.ndarray, zeta_b: np.ndarray, zeta_a: np.ndarray, names) -> list[dict]:
    out = []
    for key, name in names:
        m = labels == key
        if m.any():
            out.append({"group": name, "rows": int(m.sum()), "rms_before_rad": rms(zeta_b[m]),
                        "rms_after_rad": rms(zeta_a[m])})
    return out


def _binned(x: np.ndarray, zeta_b, zeta_a, n_bins: int = 4, unit: str = "") -> list[dict]:
    edges = np.unique(np.quantile(x, np.linspace(0, 1, n_bins + 1)))
    if len(edges) < 2:
        edges = np.array([x.min(), x.max() + 1e-12])
    lab = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2)
    names = [(i, f"[{edges[i]:.3g}, {edges[i + 1]:.3g}]{unit}") for i in range(len(edges) - 1)]
    return _groups(lab, zeta_b, zeta_a, names)


def hysteresis(table: ResidualTable, zeta: np.ndarray, floor: float) -> dict:
    """Loading-vs-unloading differences at matched loads, against the noise floor."""
    diffs = []
    for c in np.unique(table.cycle):
        idx = np.flatnonzero(table.cycle == c)
        up, down = idx[table.branch[idx] > 0], idx[table.branch[idx] < 0]
        if len(up) == 0 or len(down) == 0:
            continue
        tau = table.rows.tau_meas_A_Nm
        for i in down:
            j = up[np.argmin(np.linalg.norm(tau[up] - tau[i], axis=1))]
            if np.linalg.norm(tau[j] - tau[i]) < 0.25:
                diffs.append(zeta[j] - zeta[i])
    if not diffs:
        return {"pairs": 0}
    d = np.asarray(diffs)
    stat = float(np.sum(d ** 2) / (2 * floor ** 2)) if floor > 0 else float("inf")
    p = float(chi2_sf(stat, 3 * len(d))) if np.isfinite(stat) else 0.0
    return {"pairs": len(d), "rms_up_minus_down_rad": rms(d), "expected_from_noise_rad": float(np.sqrt(2) * floor),
            "mean_up_minus_down_rad": d.mean(axis=0).tolist(), "p_value": p, "significant": bool(p < 0.01)}


def localise(table: ResidualTable, zeta_before: np.ndarray, zeta_after: np.ndarray, floor: float) -> dict:
    """Tables of where the residual lies (JSON-able)."""
    zb, za = np.asarray(zeta_before), np.asarray(zeta_after)
    tilt, az = table.tilt_rad, table.azimuth_rad
    tau = table.rows.tau_meas_A_Nm
    load = np.linalg.norm(table.tau_load_A_Nm, axis=1)
    dom = np.argmax(np.abs(tau), axis=1)
    dirs = dom * 2 + (tau[np.arange(len(tau)), dom] < 0)
    return {
        "noise_floor_rad": floor,
        "by_axis": {a: {"rms_before_rad": float(np.sqrt(np.mean(zb[:, i] ** 2))),
                        "rms_after_rad": float(np.sqrt(np.mean(za[:, i] ** 2))),
                        "mean_before_rad": float(zb[:, i].mean())} for i, a in enumerate(AXES)},
        "by_tilt": _binned(tilt, zb, za, unit=" rad"),
        "by_azimuth": _groups(((az + np.pi) // (np.pi / 2)).astype(int) % 4, zb, za,
                              [(i, f"[{-180 + 90 * i}, {-90 + 90 * i}] deg") for i in range(4)]),
        "by_load_magnitude": _binned(load, zb, za, unit=" N m"),
        "by_load_direction": _groups(dirs, zb, za, [(2 * i + s, ("+" if s == 0 else "-") + a + " dominant")
                                                    for i, a in enumerate(AXES) for s in (0, 1)]),
        "by_branch": _groups(table.branch, zb, za, [(0, "first row"), (1, "loading"), (-1, "unloading")]),
        "hysteresis_before": hysteresis(table, zb, floor),
        "hysteresis_after": hysteresis(table, za, floor),
        "systematic_before_rad": systematic(rms(zb), floor),
        "systematic_after_rad": systematic(rms(za), floor),
    }


def cycle_features(table: ResidualTable) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per cycle: its rows and regressors ``[1, a, unloading]`` built from row order only.

    ``a`` rises linearly from 0 (first row) to 1 (the cycle's peak) and falls back to 0 at its
    last row. No measured quantity enters (the measured moment carries the same noise as the
    residual, and regressing on it would find that noise), so under noise alone the residual is
    independent of the regressors.
    """
    out = []
    for c in np.unique(table.cycle):
        idx = np.flatnonzero(table.cycle == c)
        m = len(idx)
        br = table.branch[idx]
        peak = int(np.flatnonzero(br >= 0).max()) if np.any(br >= 0) else 0
        pos = np.arange(m)
        a = np.where(pos <= peak, pos / max(peak, 1), (m - 1 - pos) / max(m - 1 - peak, 1))
        out.append((idx, np.column_stack([np.ones(m), a, (br < 0).astype(float)])))
    return out


def remaining_signature(table: ResidualTable, zeta: np.ndarray, floor: float, alpha: float = 0.01,
                        blocks=()) -> dict:
    """Test whether a residual still holds structure within cycles (a level, a load trend, a branch step).

    The residuals are whitened with the instrument model (``table.whiten``); in each cycle they are
    regressed on :func:`cycle_features`; the F-test compares what the regressions explain with what
    they leave, pooled over cycles and axes (unknown common noise scale). On a correctly specified
    model the test rejects at about rate ``alpha`` (a test that can come out false); a leftover
    effect that shifts cycles or follows the load within them makes it reject.

    Held-out residuals of a fitted model also carry its parameters' estimation error, common to
    the rows a fold predicts (it shifts whole cycles). ``blocks`` (``(row indices, covariance)``
    per fold, whitened units per unit noise variance; see
    :attr:`~csjm_opt.diagnose.selection.scoring.CandidateScore.heldout_blocks`) adds that covariance to the
    noise's: the regression is then generalised least squares, fold by fold.

    Returns
    -------
    dict
        ``p_value``, ``significant``, ``alpha``, ``f_stat``, ``dof``, ``systematic_rad``, ``rms_rad``,
        ``test``; ``p_value`` is NaN (not significant) when there are too few rows.
    """
    r = np.einsum("nij,nj->ni", table.whiten, np.asarray(zeta))
    feats = cycle_features(table)
    groups = list(blocks) or [(np.arange(len(r)), None)]
    rss0 = rss1 = 0.0
    p = N = 0
    for idx, P in groups:
        idx = np.asarray(idx)
        pos = np.full(len(r), -1)
        pos[idx] = np.arange(len(idx))               # row -> its place in this group (-1: not in it)
        cols = []
        for rows, X in feats:
            inside = pos[rows] >= 0
            for a in range(3) if inside.any() else ():
                block = np.zeros((3 * len(idx), X.shape[1]))
                block[3 * pos[rows[inside]] + a] = X[inside]
                cols.append(block)
        y = r[idx].ravel()
        X = np.hstack(cols) if cols else np.zeros((y.size, 0))
        if P is not None:
            L = np.linalg.cholesky(np.eye(y.size) + P + 1e-12 * np.eye(y.size))
            y, X = np.linalg.solve(L, y), np.linalg.solve(L, X)
        rank = np.linalg.matrix_rank(X) if X.size else 0
        fit = X @ np.linalg.lstsq(X, y, rcond=None)[0] if rank else np.zeros_like(y)
        rss0 += float(y @ y)
        rss1 += float(np.sum((y - fit) ** 2))
        p += rank
        N += y.size
    out = {"alpha": alpha, "systematic_rad": systematic(rms(zeta), floor), "rms_rad": rms(zeta),
           "test": "F-test of whitened held-out residuals on per-cycle [1, load phase, unloading] regressors "
                   "(row order only) against zero-mean noise plus the fit's prediction error (GLS per fold)"}
    if N - p < 3 or rss1 <= 0:
        return {**out, "p_value": float("nan"), "significant": False, "f_stat": float("nan"), "dof": [p, N - p]}
    F = (rss0 - rss1) / p / (rss1 / (N - p))
    pv = f_sf(F, p, N - p)
    return {**out, "p_value": pv, "significant": bool(pv < alpha), "f_stat": float(F), "dof": [p, N - p]}
