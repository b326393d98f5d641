"""Cable interference over orientations: cable-cable distances, clearance from the link, exit angles.

At an orientation R, cable i is the straight segment from the platform hole
``R a_i`` to the base hole ``b_i`` (both in {B}). This module gives, exactly
and vectorised over orientations:

* the **cable-cable distance** of each of the 15 pairs: the minimum distance
  between the two segments (:func:`segment_distance`, the closed-form closest
  points of two segments, clamped to their ends);
* the **link clearance** of each cable: the distance from the segment to the
  rod (a capsule: segment-segment distance minus the rod radius) and to the
  ball at O (point-segment distance minus the ball radius), the smaller of the
  two (:class:`csjm_opt.model.link.Link`; negative when the cable cuts it);
* the **exit angle** at each hole: the angle between the cable and the hole's
  axis, the z axis of its body (0 when the cable leaves the hole straight
  along the axis). A hole drilled along z guides the cable up to some angle;
  beyond it the cable rubs the hole's edge.

The summary :class:`Interference` keeps the worst value of each over the
orientations and where it occurs.
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from ..model.link import Link
from ..model.rig import Rig


def cable_pairs(n_cables: int) -> np.ndarray:
    """The m (m - 1) / 2 cable pairs (0-based, i < j), in the order of the ``pair`` axis."""
    return np.array(list(itertools.combinations(range(n_cables), 2)), dtype=np.int64).reshape(-1, 2)


#: The 15 cable pairs of a six-cable rig.
PAIRS = cable_pairs(6)


def segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray,
                     q1: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Minimum distance between segments ``p0 p1`` and ``q0 q1`` (broadcast over leading axes).

    Closed form (closest points of the two lines, clamped to the segments and
    re-projected; Ericson, *Real-Time Collision Detection*, 5.1.9). A segment
    of zero length is a point.

    Parameters
    ----------
    p0, p1, q0, q1 : array_like, shape (..., 3)
        End points (m).

    Returns
    -------
    distance : ndarray, shape (...)
        The minimum distance (m).
    s, t : ndarray, shape (...)
        Parameters in [0, 1] of the closest points ``p0 + s (p1 - p0)`` and ``q0 + t (q1 - q0)``.
    """
    p0, p1, q0, q1 = np.broadcast_arrays(*(np.asarray(x, float) for x in (p0, p1, q0, q1)))
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a = np.einsum("...i,...i", d1, d1)
    e = np.einsum("...i,...i", d2, d2)
    b = np.einsum("...i,...i", d1, d2)
    c = np.einsum("...i,...i", d1, r)
    f = np.einsum("...i,...i", d2, r)
    tiny = 1e-300
    a_ok, e_ok = a > tiny, e > tiny
    denom = a * e - b * b
    general = denom > 1e-14 * np.maximum(a * e, tiny)  # not parallel
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(general, np.clip((b * f - c * e) / np.where(general, denom, 1.0), 0.0, 1.0), 0.0)
        t = np.where(e_ok, (b * s + f) / np.where(e_ok, e, 1.0), 0.0)
        # t outside [0, 1]: clamp it and recompute s for that end of q
        t_low, t_high = t < 0.0, t > 1.0
        s = np.where(t_low, np.clip(-c / np.where(a_ok, a, 1.0), 0.0, 1.0), s)
        s = np.where(t_high, np.clip((b - c) / np.where(a_ok, a, 1.0), 0.0, 1.0), s)
        t = np.clip(t, 0.0, 1.0)
        # degenerate segments: a point against a segment
        s = np.where(a_ok, s, 0.0)
        t = np.where(a_ok, t, np.where(e_ok, np.clip(f / np.where(e_ok, e, 1.0), 0.0, 1.0), 0.0))
        s = np.where(a_ok & ~e_ok, np.clip(-c / np.where(a_ok, a, 1.0), 0.0, 1.0), s)
    gap = (p0 + s[..., None] * d1) - (q0 + t[..., None] * d2)
    return np.linalg.norm(gap, axis=-1), s, t


def point_segment_distance(point: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Distance from a point to the segment ``q0 q1`` (broadcast over leading axes).

    Parameters
    ----------
    point, q0, q1 : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (...)
    """
    point, q0, q1 = np.broadcast_arrays(*(np.asarray(x, float) for x in (point, q0, q1)))
    d = q1 - q0
    dd = np.einsum("...i,...i", d, d)
    t = np.clip(np.einsum("...i,...i", point - q0, d) / np.maximum(dd, 1e-300), 0.0, 1.0)
    return np.linalg.norm(point - q0 - t[..., None] * d, axis=-1)


def cable_ends_B_m(rig: Rig, Rs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Platform-hole and base-hole ends of every cable in {B} at each orientation.

    Parameters
    ----------
    rig : Rig
    Rs : ndarray, shape (n, 3, 3)

    Returns
    -------
    top, bottom : ndarray, shape (n, m, 3)
        ``R a_i`` and ``b_i`` (m).
    """
    Rs = np.asarray(Rs, float)
    top = np.einsum("nij,kj->nki", Rs, rig.platform_holes_A_m)
    bottom = np.broadcast_to(rig.base_holes_B_m, top.shape)
    return top, bottom


@dataclasses.dataclass(frozen=True, eq=False)
class PoseInterference:
    """Per-orientation interference arrays (n orientations)."""

    cable_distance_m: np.ndarray    # (n, m (m - 1) / 2) per pair of cable_pairs(m)
    link_clearance_m: np.ndarray    # (n, m) per cable (negative: the cable cuts the link)
    exit_angle_deg: np.ndarray      # (n, m, 2) per cable, at its platform hole and its base hole


def pose_interference(rig: Rig, Rs: np.ndarray, link: Link | None = None) -> PoseInterference:
    """Cable-cable distances, link clearances and exit angles at each orientation.

    Parameters
    ----------
    rig : Rig
        The design (its ``link``, or the documented default).
    Rs : ndarray, shape (n, 3, 3)
        Orientations of {A} in {B}.
    link : Link, optional
        Overrides the rig's link.

    Returns
    -------
    PoseInterference
    """
    link = link or rig.link_or_default
    top, bottom = cable_ends_B_m(rig, Rs)
    pairs = cable_pairs(rig.n_cables)
    i, j = pairs[:, 0], pairs[:, 1]
    cc, _, _ = segment_distance(top[:, i], bottom[:, i], top[:, j], bottom[:, j])
    r0, r1 = link.rod_ends_B_m
    rod, _, _ = segment_distance(top, bottom, r0, r1)
    ball = point_segment_distance(np.zeros(3), top, bottom)
    clearance = np.minimum(rod - link.rod_radius_m, ball - link.ball_radius_m)
    u = bottom - top                                     # along the cable, platform to base, in {B}
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    z_A = np.asarray(Rs, float)[:, :, 2]                 # platform axis in {B}
    cos_top = -np.einsum("nki,ni->nk", u, z_A)           # leaves the platform downwards
    cos_bottom = u[..., 2] * -1.0                        # leaves the base upwards (+z_B)
    angles = np.degrees(np.arccos(np.clip(np.stack([cos_top, cos_bottom], axis=-1), -1.0, 1.0)))
    return PoseInterference(cable_distance_m=cc, link_clearance_m=clearance, exit_angle_deg=angles)


@dataclasses.dataclass(frozen=True)
class Interference:
    """Worst interference over a set of orientations, and where (index into the set)."""

    min_cable_distance_m: float
    min_cable_distance_pair: tuple[int, int]      # 1-based cable numbers
    min_cable_distance_at: int
    min_link_clearance_m: float
    min_link_clearance_cable: int                 # 1-based
    min_link_clearance_at: int
    max_exit_angle_deg: float
    max_exit_angle_at: int

    def as_dict(self) -> dict[str, object]:
        """JSON-able dict of the fields.

        Returns
        -------
        dict
        """
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in dataclasses.asdict(self).items()}


def interference(rig: Rig, Rs: np.ndarray, link: Link | None = None) -> Interference:
    """The worst cable-cable distance, link clearance and exit angle over orientations.

    Parameters
    ----------
    rig : Rig
        The design.
    Rs : ndarray, shape (n, 3, 3)
        Orientations (n >= 1).
    link : Link, optional
        Overrides the rig's link.

    Returns
    -------
    Interference
    """
    p = pose_interference(rig, Rs, link)
    n_cc = int(np.argmin(p.cable_distance_m))
    at_cc, pair = divmod(n_cc, p.cable_distance_m.shape[1])
    n_lk = int(np.argmin(p.link_clearance_m))
    at_lk, cable = divmod(n_lk, rig.n_cables)
    pairs = cable_pairs(rig.n_cables)
    flat = p.exit_angle_deg.reshape(len(p.exit_angle_deg), -1)
    at_ex = int(np.argmax(flat.max(axis=1)))
    return Interference(
        min_cable_distance_m=float(p.cable_distance_m.flat[n_cc]),
        min_cable_distance_pair=(int(pairs[pair, 0]) + 1, int(pairs[pair, 1]) + 1),
        min_cable_distance_at=int(at_cc),
        min_link_clearance_m=float(p.link_clearance_m.flat[n_lk]), min_link_clearance_cable=int(cable) + 1,
        min_link_clearance_at=int(at_lk),
        max_exit_angle_deg=float(flat[at_ex].max()), max_exit_angle_at=at_ex)
