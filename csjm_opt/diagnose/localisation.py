"""Where the gap lies: residuals broken down by axis, pose, load and branch.

All breakdowns are RMS of ``||zeta||`` (rad) over the rows of a group, for
the residuals before (baseline) and after (selected model), on held-out rows.
Hysteresis: in each cycle every unloading row is paired with the loading row
of nearest measured moment; under noise alone ``E||zeta_up - zeta_down||^2 =
2 floor^2``, so the ratio is tested against chi-square.
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from .noise import systematic
from .residuals import ResidualTable, rms

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
    p = float(stats.chi2.sf(stat, 3 * len(d))) if np.isfinite(stat) else 0.0
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


def signature_features(table: ResidualTable) -> np.ndarray:
    """Regressors a leftover effect would correlate with: load, branch, gravity direction."""
    tilt, az = table.tilt_rad, table.azimuth_rad
    return np.column_stack([np.ones(len(table)), table.rows.tau_meas_A_Nm, (table.branch < 0).astype(float),
                            tilt * np.cos(az), tilt * np.sin(az)])


def remaining_signature(table: ResidualTable, zeta: np.ndarray, floor: float, alpha: float = 0.01) -> dict:
    """Does the residual left after the selected model still correlate with load, branch or pose?

    F-test of ``zeta ~ features`` (per axis, pooled) against zero-mean noise.
    """
    X = signature_features(table)
    coef, *_ = np.linalg.lstsq(X, zeta, rcond=None)
    rss1 = float(np.sum((zeta - X @ coef) ** 2))
    rss0 = float(np.sum(zeta ** 2))
    p = 3 * X.shape[1]
    N = zeta.size
    if N - p < 1 or rss1 <= 0:
        return {"p_value": float("nan"), "significant": False}
    F = (rss0 - rss1) / p / (rss1 / (N - p))
    pv = float(stats.f.sf(F, p, N - p))
    return {"p_value": pv, "significant": bool(pv < alpha), "alpha": alpha,
            "systematic_rad": systematic(rms(zeta), floor), "rms_rad": rms(zeta),
            "test": "F-test of residual on [1, tau_meas, unloading, tilt*cos(az), tilt*sin(az)]"}
