"""Hole layouts described by their pattern: count, radii, angles, heights, twist, alternation.

A rig file may give its holes as a ``[geometry.pattern]`` table instead of
``platform_holes`` / ``base_holes`` coordinates; :func:`expand_pattern` turns
it into the two (m, 3) arrays, which the rig then checks like coordinates.
The keys (docs/guide/input-files.md prints the same list):

``count`` (required)
    m, the number of cables (4 <= m <= 12).
``platform_radius``, ``base_radius`` (required)
    Radius of the hole circle (m) on the platform {A} and on the base {B}: one
    number, or m numbers (hole by hole).
``platform_height``, ``base_height`` (required)
    z of the holes (m): platform holes in {A} (above O: positive), base holes
    in {B} (below O: negative); one number or m numbers.
``platform_angles_deg`` / ``platform_pair_angle_deg`` (optional, at most one)
    Angular positions of the platform holes (deg, counter-clockwise about z
    from x). ``*_angles_deg``: m explicit angles. ``*_pair_angle_deg``: the
    holes in pairs, pair j centred at ``j * 720/m`` deg, its two holes at the
    centre minus and plus half this angle (the paper's semi-regular hexagon is
    the case m = 6); odd m ends with a single hole (:func:`paired_angles_deg`).
    Neither: evenly spaced, hole i (from 1) at ``(i - 1) * 360/m`` deg.
``base_angles_deg`` / ``base_pair_angle_deg`` (optional, at most one)
    The same for the base holes.
``phase_deg`` (default 0)
    Rotation of the whole layout (both bodies) about z (deg).
``twist_deg`` (default 0)
    Extra rotation of the base holes about z relative to the platform's (deg).
``alternation`` (default 0)
    Zig-zag of the hole heights (m): odd-numbered holes (1, 3, ...) sit
    ``alternation / 2`` higher, even-numbered ones ``alternation / 2`` lower,
    on both bodies (staggers neighbouring cables).
``connect_shift`` (integer, default 0)
    Cable i runs from platform hole i to base hole ``i + connect_shift``
    (cyclically): crossed cabling without renumbering the base.

Cable i always joins row i of the expanded platform and base arrays.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import RigFileError

#: Fewest and most cables a rig may have (3 rotations need m >= 4 pull-only cables; 12 is the tested range).
MIN_CABLES, MAX_CABLES = 4, 12

#: Every key of a ``[geometry.pattern]`` table, with its meaning.
PATTERN_KEYS: dict[str, str] = {
    "count": "number of cables m (4..12)",
    "platform_radius": "platform hole circle radius (m): a number or m numbers",
    "base_radius": "base hole circle radius (m): a number or m numbers",
    "platform_height": "z of the platform holes in {A} (m): a number or m numbers",
    "base_height": "z of the base holes in {B} (m): a number or m numbers",
    "platform_angles_deg": "m explicit platform hole angles (deg)",
    "platform_pair_angle_deg": "platform holes in pairs this central angle apart (deg; odd m: one single)",
    "base_angles_deg": "m explicit base hole angles (deg)",
    "base_pair_angle_deg": "base holes in pairs this central angle apart (deg; odd m: one single)",
    "phase_deg": "rotation of the whole layout about z (deg), default 0",
    "twist_deg": "extra rotation of the base holes about z (deg), default 0",
    "alternation": "height zig-zag (m): odd holes +a/2, even holes -a/2, default 0",
    "connect_shift": "cable i joins base hole i + shift (cyclic), default 0",
}
_REQUIRED = ("count", "platform_radius", "base_radius", "platform_height", "base_height")
_KEY = "geometry.pattern"


def _number(value: Any, key: str, path: str | None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(float(value)):
        raise RigFileError(f"expected a finite number, got {value!r:.60}", path, f"{_KEY}.{key}")
    return float(value)


def _per_hole(value: Any, m: int, key: str, path: str | None) -> np.ndarray:
    if isinstance(value, list):
        if len(value) != m:
            raise RigFileError(f"expected one number or {m} numbers (count = {m}), got {len(value)}",
                               path, f"{_KEY}.{key}")
        return np.array([_number(v, key, path) for v in value])
    return np.full(m, _number(value, key, path))


def _angles_deg(table: dict[str, Any], body: str, m: int, path: str | None) -> np.ndarray:
    explicit, paired = f"{body}_angles_deg", f"{body}_pair_angle_deg"
    if explicit in table and paired in table:
        raise RigFileError(f"give {explicit} or {paired}, not both", path, f"{_KEY}.{paired}")
    if explicit in table:
        if not isinstance(table[explicit], list):
            raise RigFileError(f"expected {m} numbers, got {table[explicit]!r:.60}", path, f"{_KEY}.{explicit}")
        return _per_hole(table[explicit], m, explicit, path)
    if paired in table:
        gamma = _number(table[paired], paired, path)
        if not 0.0 < gamma < 720.0 / m:
            raise RigFileError(f"expected 0 < pair angle < {720.0 / m:g} deg (the pair spacing), got {gamma:g}",
                               path, f"{_KEY}.{paired}")
        return paired_angles_deg(m, gamma)
    return np.arange(m) * (360.0 / m)


def paired_angles_deg(m: int, gamma_deg: float) -> np.ndarray:
    """Angles (deg) of m holes in pairs ``gamma_deg`` apart, pair centres ``720/m`` deg apart.

    Even m: pair j centred at ``j 720/m``, its holes at the centre minus and plus ``gamma/2``.
    Odd m continues the same rule with the last pair incomplete: hole i (from 0) at
    ``(i - 1/2) 360/m -+ (gamma - 360/m) / 2`` (minus for even i), which for even m is the pair
    layout again; consecutive holes are ``gamma`` and ``720/m - gamma`` apart in turn, except the
    last and the first, ``360/m`` apart.

    Parameters
    ----------
    m : int
        Number of holes (4..12).
    gamma_deg : float
        Central angle within a pair (deg), ``0 < gamma < 720/m``.

    Returns
    -------
    ndarray, shape (m,)
    """
    if m % 2 == 0:
        centres = np.arange(m // 2) * (720.0 / m)
        angles = np.empty(m)
        angles[0::2] = centres - gamma_deg / 2
        angles[1::2] = centres + gamma_deg / 2
        return angles
    step = 360.0 / m
    i = np.arange(m)
    return (i - 0.5) * step + np.where(i % 2 == 0, -1.0, 1.0) * (gamma_deg - step) / 2


def expand_pattern(table: Any, path: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Platform and base holes (m, 3) of a ``[geometry.pattern]`` table (module docstring).

    Parameters
    ----------
    table : dict
        The pattern table as read from TOML.
    path : str, optional
        The rig file, named in errors.

    Returns
    -------
    platform_holes_A_m, base_holes_B_m : ndarray, shape (m, 3)
        Hole positions in {A} and {B} (m); cable i joins row i of both.

    Raises
    ------
    RigFileError
        Naming the key: an unknown or missing key, a value of the wrong type or count, a count
        outside 4..12, a pair angle wider than the pair spacing, or both ways of giving angles.
    """
    if not isinstance(table, dict):
        raise RigFileError(f"expected a table, got {type(table).__name__}", path, _KEY)
    for key in table:
        if key not in PATTERN_KEYS:
            raise RigFileError(f"unknown key (expected one of {sorted(PATTERN_KEYS)})", path, f"{_KEY}.{key}")
    for key in _REQUIRED:
        if key not in table:
            raise RigFileError("missing key", path, f"{_KEY}.{key}")
    count = table["count"]
    if isinstance(count, bool) or not isinstance(count, int):
        raise RigFileError(f"expected an integer, got {count!r:.60}", path, f"{_KEY}.count")
    if not MIN_CABLES <= count <= MAX_CABLES:
        raise RigFileError(f"expected {MIN_CABLES} <= count <= {MAX_CABLES} cables, got {count}"
                           + (" (3 rotations need at least 4 pull-only cables)" if count < MIN_CABLES else ""),
                           path, f"{_KEY}.count")
    m = int(count)
    shift = table.get("connect_shift", 0)
    if isinstance(shift, bool) or not isinstance(shift, int):
        raise RigFileError(f"expected an integer, got {shift!r:.60}", path, f"{_KEY}.connect_shift")
    phase = _number(table.get("phase_deg", 0.0), "phase_deg", path)
    twist = _number(table.get("twist_deg", 0.0), "twist_deg", path)
    alternation = _number(table.get("alternation", 0.0), "alternation", path)
    zigzag = np.where(np.arange(m) % 2 == 0, 0.5, -0.5) * alternation
    holes = []
    for body, extra in (("platform", 0.0), ("base", twist)):
        radius = _per_hole(table[f"{body}_radius"], m, f"{body}_radius", path)
        if np.any(radius <= 0):
            raise RigFileError(f"radius must be positive, got {radius.tolist()}", path, f"{_KEY}.{body}_radius")
        height = _per_hole(table[f"{body}_height"], m, f"{body}_height", path) + zigzag
        theta = np.deg2rad(_angles_deg(table, body, m, path) + phase + extra)
        holes.append(np.column_stack([radius * np.cos(theta), radius * np.sin(theta), height]))
    platform, base = holes
    base = np.roll(base, -int(shift), axis=0)
    return platform, base
