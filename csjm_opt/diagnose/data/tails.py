"""Tail probabilities of the diagnosis's test statistics, from ``scipy.special``.

The same numbers as ``scipy.stats`` (its distributions call these functions), without importing
``scipy.stats``, which alone costs half a second of every ``csjm diagnose`` start. Checked against
``scipy.stats`` in ``tests/diagnose/data/test_tails.py``.
"""

from __future__ import annotations

import numpy as np
from scipy import special


def chi2_sf(x: float, dof: float) -> float:
    """``P(X > x)`` for ``X ~ chi^2(dof)``."""
    return float(special.chdtrc(dof, x))


def f_sf(x: float, dfn: float, dfd: float) -> float:
    """``P(X > x)`` for ``X ~ F(dfn, dfd)``."""
    return float(special.fdtrc(dfn, dfd, x))


def norm_sf(z: float) -> float:
    """``P(Z > z)`` for a standard normal ``Z``."""
    return float(special.ndtr(-z))


def norm_isf(p: float) -> float:
    """``z`` with ``P(Z > z) = p`` for a standard normal ``Z``."""
    return float(-special.ndtri(p))


def t_greater(d: np.ndarray) -> float:
    """One-sided p-value of the one-sample t-test that the mean of ``d`` is above 0.

    nan where ``d`` has no spread and a zero mean (as ``scipy.stats.ttest_1samp``).
    """
    d = np.asarray(d, float)
    n = d.size
    with np.errstate(divide="ignore", invalid="ignore"):
        t = d.mean() / (d.std(ddof=1) / np.sqrt(n))
    return float(special.stdtr(n - 1, -t))


def linear_trend(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """``(slope, p)`` of the least-squares line of ``y`` on ``x``; ``p`` two-sided for a zero slope.

    As ``scipy.stats.linregress``: a perfect line has ``p = 0``; a constant ``y``, ``p = 1``.
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    n = x.size
    dx, dy = x - x.mean(), y - y.mean()
    sxx, syy, sxy = float(dx @ dx), float(dy @ dy), float(dx @ dy)
    slope = sxy / sxx
    r2 = 0.0 if syy == 0.0 else min(sxy * sxy / (sxx * syy), 1.0)
    if r2 == 1.0:
        return slope, 0.0
    dof = n - 2
    t = np.sqrt(r2 * dof / (1.0 - r2))
    return slope, float(2.0 * special.stdtr(dof, -t))
