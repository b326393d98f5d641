"""Cable contacts of the optimisation: which cable pairs (and cable-link pairs) the next solve must keep apart."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..clearance import cable_ends_B_m, cable_pairs, point_segment_distance, segment_distance
from ..sampling import tilt_torsion_rotations
from .problem import Contact
from .settings import OptimiseSettings

#: Extra distance (m) within which a cable pair or cable and link become a contact constraint.
CONTACT_BUFFER_M = 0.005
#: Orientations per cable pair (or cable and link part) kept as contact constraints in a round.
CONTACTS_PER_PAIR = 4


def contacts_near(settings: OptimiseSettings, rig: Any, angles: np.ndarray, scale: float) -> list[Contact]:
    """Cable pairs and cable-link pairs closer than the requirement plus a buffer, at their closest points.

    Per pair (or cable and link part) the :data:`CONTACTS_PER_PAIR` orientations where they come closest.

    Parameters
    ----------
    settings : OptimiseSettings
    rig : Rig
        The current design.
    angles : ndarray, shape (N, 3)
        The problem's orientations at range scale 1 (rad).
    scale : float
        The range scale they are taken at.

    Returns
    -------
    list of Contact
    """
    req, link = settings.requirements, settings.link
    Rs = tilt_torsion_rotations(angles[:, 0] * scale, angles[:, 1], angles[:, 2] * scale)
    top, bottom = cable_ends_B_m(rig, Rs)
    pairs = cable_pairs(rig.n_cables)
    i, j = pairs[:, 0], pairs[:, 1]
    out: list[Contact] = []

    def closest(gap: np.ndarray, limit: float, make: Any) -> None:
        for col in range(gap.shape[1]):
            rows = np.flatnonzero(gap[:, col] < limit)
            out.extend(make(int(o), col) for o in rows[np.argsort(gap[rows, col])][:CONTACTS_PER_PAIR])

    d, s, t = segment_distance(top[:, i], bottom[:, i], top[:, j], bottom[:, j])
    closest(d, req.min_cable_distance_m + CONTACT_BUFFER_M,
            lambda o, p: Contact(o, "pair", int(i[p]), int(j[p]), float(s[o, p]), float(t[o, p])))
    r0, r1 = link.rod_ends_B_m
    d2, s2, t2 = segment_distance(top, bottom, r0, r1)
    closest(d2 - link.rod_radius_m, req.min_link_clearance_m + CONTACT_BUFFER_M,
            lambda o, c: Contact(o, "rod", c, -1, float(s2[o, c]), float(t2[o, c])))
    ball = point_segment_distance(np.zeros(3), top, bottom)
    u = bottom - top
    s_ball = np.clip(-np.einsum("nki,nki->nk", top, u) / np.einsum("nki,nki->nk", u, u), 0.0, 1.0)
    closest(ball - link.ball_radius_m, req.min_link_clearance_m + CONTACT_BUFFER_M,
            lambda o, c: Contact(o, "ball", c, -1, float(s_ball[o, c]), 0.0))
    return out
