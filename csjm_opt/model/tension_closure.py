"""Tension closure: whether the cables can hold the platform's weight with tensions in bounds.

At a pose ``R`` the cables hold the weight when some ``t`` with
``t_min <= t_i <= t_max`` solves ``J^T t + tau_weight = 0`` ((38), no external
moment): ``-tau_weight`` must lie in the zonotope ``Z = {J^T t : t in box}``.
The facet normals of a zonotope in R^3 are among the cross products
``n = j_i x j_k`` of pairs of its generators (rows of J), and a point ``b`` lies
in ``Z`` iff ``n . b <= h(n)`` for every such ``n`` and ``-n``, where
``h(n) = sum_i max(t_min n.j_i, t_max n.j_i)`` is the support function
(:func:`closure_margin` returns the largest signed distance past a facet plane;
inside iff <= 0). This is the same test as the planner's
``outside_margin`` kernel, written here in numpy so the model layer can refuse
a rig at load without the planner.

**The stated range** of a rig is its zero pose ``R = I`` plus, when the rig
file has ``[workspace] tilt_deg = a``, the tilted poses ``exp(theta [cos phi,
sin phi, 0])`` with ``theta`` in ``{a/2, a}`` and 12 azimuths ``phi``. A rig is
refused (:func:`check_tension_closure`) when at any pose of its stated range
the weight cannot be held: a rig whose cables cannot hold the platform where
its file says it works cannot work.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import RigFileError
from ..so3 import exp as so3_exp
from .cable_terms import geometry, weight_moment

#: Tolerance (N m, relative to the load scale) on the facet margin.
_REL_TOL = 1e-9


def closure_margin(J: np.ndarray, b: np.ndarray, t_min: float, t_max: float) -> float:
    """Largest signed distance (N m) of ``b`` past a facet plane of ``{J^T t : t_min <= t <= t_max}``.

    Parameters
    ----------
    J : ndarray, shape (m, 3)
        Rows ``j_i`` of (38) at the pose.
    b : ndarray, shape (3,)
        The moment the cables must produce (N m).
    t_min, t_max : float
        Tension bounds (N).

    Returns
    -------
    float
        ``<= 0`` (up to round-off) iff ``b`` can be produced; ``inf`` when J has rank < 3
        (no pair of rows spans a facet: nothing but a plane can be produced).
    """
    m = J.shape[0]
    i, k = np.triu_indices(m, 1)
    n = np.cross(J[i], J[k])                                        # (P, 3) candidate facet normals
    norm = np.linalg.norm(n, axis=1)
    scale = np.linalg.norm(J[i], axis=1) * np.linalg.norm(J[k], axis=1)
    keep = norm > 1e-12 * scale
    if not np.any(keep):
        return float("inf")
    n, norm = n[keep], norm[keep]
    worst = -np.inf
    for sign in (1.0, -1.0):
        d = sign * n @ J.T                                          # (P, m)
        h = np.where(d > 0, t_max * d, t_min * d).sum(axis=1)
        worst = max(worst, float(np.max((sign * n @ b - h) / norm)))
    return worst


def stated_range_rotvecs(tilt_deg: float | None) -> np.ndarray:
    """The rotation vectors (rad) of a rig's stated range (module docstring), shape (n, 3)."""
    poses = [np.zeros(3)]
    if tilt_deg:
        phi = np.arange(12) * (np.pi / 6)
        for theta in (0.5 * np.deg2rad(tilt_deg), np.deg2rad(tilt_deg)):
            poses += [theta * np.array([np.cos(p), np.sin(p), 0.0]) for p in phi]
    return np.array(poses)


def check_tension_closure(rig: Any, path: str | None = None) -> None:
    """Refuse a rig whose cables cannot hold its weight somewhere in its stated range.

    Parameters
    ----------
    rig : Rig
        The rig (its ``workspace_tilt_deg`` sets the stated range).
    path : str, optional
        The rig file, named in the error.

    Raises
    ------
    RigFileError
        Naming ``cables.t_max`` (or ``geometry.platform_holes`` for a rank-deficient layout)
        with the pose and by how much (N m) the weight lies outside what the cables can hold.
    """
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    first_moment = rig.platform_mass_kg * np.asarray(rig.com_A_m, float)
    for rotvec in stated_range_rotvecs(rig.workspace_tilt_deg):
        R = so3_exp(rotvec)
        J = geometry(R, A, B)[2]
        b = -weight_moment(R, first_moment, rig.gravity_B_m_per_s2)
        margin = closure_margin(J, b, rig.t_min_N, rig.t_max_N)
        scale = max(1.0, rig.t_max_N * float(np.abs(J).max()))
        if margin == float("inf"):
            raise RigFileError("no tension closure: the cables' moment arms span less than 3 directions at "
                               f"rotvec {np.round(rotvec, 4).tolist()} rad (holes in a degenerate layout)",
                               path, "geometry.platform_holes")
        if margin > _REL_TOL * scale:
            raise RigFileError(
                f"no tension closure: at rotvec {np.round(rotvec, 4).tolist()} rad (stated range: "
                + ("the zero pose" if not rig.workspace_tilt_deg else f"tilts up to {rig.workspace_tilt_deg:g} deg")
                + f") no tensions in [{rig.t_min_N:g}, {rig.t_max_N:g}] N hold the platform's weight "
                f"(short by {margin:.3g} N m); move holes or widen the tension bounds", path, "cables.t_max")
