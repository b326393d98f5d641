"""Why an optimisation is infeasible: the binding constraint and the orientation where it binds."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...errors import InfeasibleRequirement
from .settings import OptimiseSettings
from .shaping import shaping_rows


def violation(settings: OptimiseSettings, angles: np.ndarray, pb: Any, x: np.ndarray, sol: Any) -> tuple:
    """The most violated constraint at IPOPT's last point.

    Parameters
    ----------
    settings : OptimiseSettings
    angles : ndarray, shape (N, 3)
        The problem's orientations at range scale 1 (rad).
    pb : Problem
    x : ndarray
        IPOPT's last point.
    sol : dict
        IPOPT's output (``g``).

    Returns
    -------
    tuple
        (constraint name, (tilt, azimuth, torsion) in deg or None, violation).
    """
    g = np.array(sol["g"]).ravel()
    viol = np.maximum(pb.lbg - g, 0.0) + np.maximum(g - pb.ubg, 0.0)
    k = int(np.argmax(viol))
    n_cab = pb.n_cables
    names = _pose_names(settings, n_cab)
    rows = shaping_rows(n_cab)
    per = len(names)
    n_pose = per * pb.n_slots
    scale = settings.requirements.range_scale if settings.objective != "range" else float(x[pb.objective_index])
    n_shaping = rows * pb.n_slots if "shaping" in (settings.objective, settings.pareto_with) else 0
    if k < n_pose or k >= len(g) - n_shaping:
        o, c = divmod(k, per) if k < n_pose else divmod(k - (len(g) - n_shaping), rows)
        a = (angles[o] if o < angles.shape[0] else np.zeros(3)) * np.array([scale, 1.0, scale])
        name = names[c] if k < n_pose else ("shaping range (smallest LP range about " + "xyz"[c - rows + 3]
                                            + ")" if c >= rows - 3 else "tensions of the shaping range")
        return name, tuple(math.degrees(v) for v in a), float(viol[k])
    return "hole spacing or cable contact", None, float(viol[k])


def _pose_names(settings: OptimiseSettings, n_cables: int = 6) -> list[str]:
    n_l, m = np.asarray(settings.requirements.loads).shape[0], n_cables
    names = ["tension range of load 1 (lower bound)"] * m + ["tension range of load 1 (upper bound)"] * m
    names += ["stiffness (smallest eigenvalue of K)"] * 7
    for k in range(2, n_l + 1):
        names += [f"tension range of load {k}"] * (2 * m) + [f"equilibrium of load {k}"] * 3
    if settings.requirements.max_exit_angle_deg < 180:
        names += ["exit angle at a platform hole"] * m + ["exit angle at a base hole"] * m
    return names


def infeasible(info: tuple | None) -> InfeasibleRequirement:
    """The error for :func:`violation`'s finding.

    Parameters
    ----------
    info : tuple or None

    Returns
    -------
    InfeasibleRequirement
    """
    if info is None:
        return InfeasibleRequirement("no design within the bounds meets the requirements", "unknown")
    name, angles, amount = info
    where = "" if angles is None else \
        f" at tilt {angles[0]:.1f} deg, azimuth {angles[1]:.1f} deg, torsion {angles[2]:.1f} deg"
    return InfeasibleRequirement(f"no design within the bounds meets the requirements: {name} binds{where} "
                                 "(the binding constraint at the best point IPOPT found)", name, angles)
