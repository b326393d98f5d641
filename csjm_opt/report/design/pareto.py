"""Pareto front and layers of designs scored by two maximised quantities."""

from __future__ import annotations

import numpy as np


def pareto_mask(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Designs that no other design beats in both ``x`` and ``y`` (both maximised).

    Parameters
    ----------
    x, y : (n,) arrays

    Returns
    -------
    (n,) bool array
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    better_eq = (x[None, :] >= x[:, None]) & (y[None, :] >= y[:, None])
    strictly = (x[None, :] > x[:, None]) | (y[None, :] > y[:, None])
    return ~np.any(better_eq & strictly, axis=1)


def pareto_layers(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Layer of each design: 1 for the Pareto front, 2 for the front of the rest, and so on."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    layer = np.zeros(len(x), int)
    k = 0
    while np.any(layer == 0):
        k += 1
        left = np.flatnonzero(layer == 0)
        layer[left[pareto_mask(x[left], y[left])]] = k
    return layer
