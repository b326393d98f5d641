"""Parametric hole geometry of a CSJM design, validated, turned into a :class:`Rig`.

A design is a flat mapping of named parameters (the vocabulary is
:data:`PARAMETERS`; every value has SI units or degrees as its name says).
Unspecified parameters take the paper's Section IV-A values, so ``{}`` is the
paper's design. Each body (platform {A}, base {B}) is either

* a semi-regular hexagon (:mod:`csjm_opt.model.hexagon`): chords ``*_d12_m`` and
  ``*_d23_m``, or equivalently circle radius ``*_radius_m`` and central angle
  ``*_gamma_deg`` of chord 1-2 (give one pair, not both), rotated by
  ``*_theta0_deg`` about z, at height ``+oo_a_m`` (platform, above O) or
  ``-oo_b_m`` (base, below O); or
* free coordinates ``platform_holes`` / ``base_holes`` (m [x, y, z] rows, m).

``n_cables`` (default 6) sets m, the number of cables (4..12; a sweep axis like any
other). For m != 6 a body's holes form pairs: pair j centred at
``theta0 + j * 720/m`` deg, its holes ``gamma`` apart, on the circle of radius
``*_radius_m`` (or of chords ``*_d12_m`` within a pair and ``*_d23_m`` between
pairs); m = 6 is the semi-regular hexagon. Odd m continues the rule with a last,
single hole (:func:`csjm_opt.model.hole_pattern.paired_angles_deg`), the layout of
a rig file's ``*_pair_angle_deg``.

Per-hole offsets ``A{i}_d{x,y,z}_m`` / ``B{i}_d{x,y,z}_m`` (i = 1..m, m) are
added to either, so a sweep can move single holes. Rig scalars
``cable_stiffness_N_per_m``, ``t_min_N``, ``t_max_N``, ``platform_mass_kg``,
``com_z_m`` complete the rig.

Validation (:func:`check_holes`): holes on one body at least
``min_hole_spacing_m`` apart, every cable at the home pose (R = I) passing at
least ``min_cable_clearance_m`` from the joint centre O (a cable through O has
no moment arm), cables of non-zero length.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import DesignError, InvalidInput
from ..model import hexagon
from ..model.cable_terms import cable_lengths
from ..model.hole_pattern import paired_angles_deg
from ..model.rig import PAPER_CABLE_STIFFNESS_N_PER_M, PAPER_COM_A_M, PAPER_MASS_KG, Rig, paper_rig

_BODIES = {"platform": "A", "base": "B"}
_SCALARS = {
    "platform_d12_m": "platform chord A1A2 = A3A4 = A5A6 (m)",
    "platform_d23_m": "platform chord A2A3 = A4A5 = A6A1 (m)",
    "platform_radius_m": "platform hole circle radius (m), with platform_gamma_deg",
    "platform_gamma_deg": "central angle of platform chord A1A2 (deg), with platform_radius_m",
    "platform_theta0_deg": "rotation of the platform hexagon about z (deg)",
    "base_d12_m": "base chord B1B2 = B3B4 = B5B6 (m)",
    "base_d23_m": "base chord B2B3 = B4B5 = B6B1 (m)",
    "base_radius_m": "base hole circle radius (m), with base_gamma_deg",
    "base_gamma_deg": "central angle of base chord B1B2 (deg), with base_radius_m",
    "base_theta0_deg": "rotation of the base hexagon about z (deg)",
    "oo_a_m": "height of the platform holes above O, OO_A (m)",
    "oo_b_m": "depth of the base holes below O, OO_B (m)",
    "cable_stiffness_N_per_m": "stiffness of each cable with its drive (N/m)",
    "t_min_N": "lower tension bound (N)",
    "t_max_N": "upper tension bound (N)",
    "platform_mass_kg": "moving platform mass (kg)",
    "com_z_m": "height of the platform's centre of mass above O, in {A} (m)",
    "n_cables": "number of cables m (4..12; m != 6: holes in pairs, odd m one single; default 6)",
}
_OFFSETS = {f"{body}{i}_d{axis}_m": f"offset of hole {body}{i} along {axis} (m)"
            for body in "AB" for i in range(1, 13) for axis in "xyz"}
_ARRAYS = {"platform_holes": "free platform holes A_i in {A}, m [x, y, z] rows (m)",
           "base_holes": "free base holes B_i in {B}, m [x, y, z] rows (m)"}
#: Every design parameter, with its meaning and unit.
PARAMETERS: dict[str, str] = {**_SCALARS, **_OFFSETS, **_ARRAYS}
#: Parameters that take a single number (everything but the free hole arrays).
SCALAR_PARAMETERS = frozenset(_SCALARS) | frozenset(_OFFSETS)

PAPER_DESIGN: dict[str, float] = {
    "platform_d12_m": hexagon.PAPER_PLATFORM_CHORDS_M[0],
    "platform_d23_m": hexagon.PAPER_PLATFORM_CHORDS_M[1],
    "platform_theta0_deg": 0.0,
    "base_d12_m": hexagon.PAPER_BASE_CHORDS_M[0],
    "base_d23_m": hexagon.PAPER_BASE_CHORDS_M[1],
    "base_theta0_deg": 0.0,
    "oo_a_m": hexagon.PAPER_OO_A_M,
    "oo_b_m": hexagon.PAPER_OO_B_M,
    "cable_stiffness_N_per_m": PAPER_CABLE_STIFFNESS_N_PER_M,
    "t_min_N": 5.0,
    "t_max_N": 150.0,
    "platform_mass_kg": PAPER_MASS_KG,
    "com_z_m": PAPER_COM_A_M[2],
}


@dataclasses.dataclass(frozen=True)
class GeometryLimits:
    """Thresholds of :func:`check_holes` (m)."""

    min_hole_spacing_m: float = 1e-3
    min_cable_clearance_m: float = 5e-3


def chords_from_circle(radius_m: float, gamma_deg: float) -> tuple[float, float]:
    """Chords (d12, d23) of a semi-regular hexagon on a circle; inverse of ``circle_from_chords``."""
    if not (radius_m > 0 and 0 < gamma_deg < 120):
        raise InvalidInput(f"need radius > 0 and 0 < gamma < 120 deg, got {radius_m}, {gamma_deg}",
                           "radius/gamma")
    half = math.radians(gamma_deg) / 2
    return 2 * radius_m * math.sin(half), 2 * radius_m * math.sin(math.pi / 3 - half)


def design_holes(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Platform and base holes of a design, not yet checked.

    Parameters
    ----------
    params : mapping of str to value
        Design parameters (names in :data:`PARAMETERS`); anything missing takes the paper's value.

    Returns
    -------
    platform_A_m : ndarray, shape (m, 3)
        Platform holes in {A} (m).
    base_B_m : ndarray, shape (m, 3)
        Base holes in {B} (m).

    Raises
    ------
    DesignError
        If a parameter is unknown, not a finite number, or no semi-regular hexagon has the given
        chords.
    """
    _check_names(params)
    p = {**PAPER_DESIGN, **params}
    m = _n_cables(params)
    holes = []
    for body, letter in _BODIES.items():
        if f"{body}_holes" in params:
            xyz = _as_holes(params[f"{body}_holes"], f"{body}_holes", m)
        else:
            height_key = "oo_a_m" if body == "platform" else "oo_b_m"
            height = _number(p, height_key)
            if not height > 0:
                raise DesignError(f"must be > 0, got {height}", height_key)
            z = height if body == "platform" else -height
            if m == 6:
                d12, d23 = _chords(body, params)
                try:
                    xyz = hexagon.hexagon_holes(d12, d23, z_m=z, theta0_deg=_number(p, f"{body}_theta0_deg"))
                except (InvalidInput, ValueError) as exc:
                    raise DesignError(f"no semi-regular hexagon with chords {d12:g}, {d23:g}: {exc}",
                                      f"{body}_d12_m") from exc
            else:
                xyz = _pair_holes(body, params, m, z, _number(p, f"{body}_theta0_deg"))
        xyz = xyz.copy()
        for key in params:
            if key[:1] == letter and key in _OFFSETS and int(key[1:].split("_")[0]) > m:
                raise DesignError(f"offset of hole {key[1:].split('_')[0]}, but the design has {m} cables", key)
        for i in range(m):
            for j, axis in enumerate("xyz"):
                key = f"{letter}{i + 1}_d{axis}_m"
                if key in params:
                    xyz[i, j] += _number(params, key)
        holes.append(xyz)
    return holes[0], holes[1]


def check_holes(platform_A_m: np.ndarray, base_B_m: np.ndarray,
                limits: GeometryLimits = GeometryLimits()) -> None:
    """Check that the holes make a usable joint (see the module docstring).

    Parameters
    ----------
    platform_A_m : ndarray, shape (m, 3)
        Platform holes in {A} (m).
    base_B_m : ndarray, shape (m, 3)
        Base holes in {B} (m).
    limits : GeometryLimits, optional
        Smallest hole spacing and cable clearance from O.

    Returns
    -------
    None

    Raises
    ------
    DesignError
        If a coordinate is not finite, two holes of a body are closer than
        ``limits.min_hole_spacing_m``, or a cable passes closer than
        ``limits.min_cable_clearance_m`` to O at the home pose.
    """
    for name, holes in (("platform_holes", platform_A_m), ("base_holes", base_B_m)):
        if not np.all(np.isfinite(holes)):
            raise DesignError("hole coordinates must be finite", name)
        gaps = np.where(np.eye(len(holes), dtype=bool), np.inf,
                        np.linalg.norm(holes[:, None] - holes[None], axis=-1))
        i, j = np.unravel_index(np.argmin(gaps), gaps.shape)
        if gaps[i, j] < limits.min_hole_spacing_m:
            raise DesignError(f"holes {i + 1} and {j + 1} are {gaps[i, j] * 1e3:.3g} mm apart "
                              f"(minimum {limits.min_hole_spacing_m * 1e3:g} mm)", name)
    clearance = cable_clearance_m(platform_A_m, base_B_m)
    lengths = cable_lengths(np.eye(3), platform_A_m, base_B_m)
    if np.min(lengths) < limits.min_hole_spacing_m:
        k = int(np.argmin(lengths))
        raise DesignError(f"cable {k + 1} has length {lengths[k]:.3g} m at the home pose", "holes")
    if np.min(clearance) < limits.min_cable_clearance_m:
        k = int(np.argmin(clearance))
        raise DesignError(f"cable {k + 1} passes {clearance[k] * 1e3:.3g} mm from the joint centre O "
                          f"at the home pose (minimum {limits.min_cable_clearance_m * 1e3:g} mm)", "holes")


def cable_clearance_m(platform_A_m: np.ndarray, base_B_m: np.ndarray) -> np.ndarray:
    """Distance (m) from O to each cable segment A_i B_i at the home pose R = I, shape (m,)."""
    d = base_B_m - platform_A_m
    s = np.clip(-np.sum(platform_A_m * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300), 0, 1)
    return np.linalg.norm(platform_A_m + s[:, None] * d, axis=1)


def design_rig(params: Mapping[str, Any] | None = None,
               limits: GeometryLimits = GeometryLimits()) -> Rig:
    """The validated :class:`~csjm_opt.model.rig.Rig` of a design.

    Parameters
    ----------
    params : mapping of str to value, optional
        Design parameters (names in :data:`PARAMETERS`: hexagon chords or radius and angle,
        heights, per-hole offsets, free hole coordinates, cable and platform values); ``None`` or
        ``{}`` gives the paper's rig.
    limits : GeometryLimits, optional
        Smallest hole spacing and cable clearance from O.

    Returns
    -------
    Rig
        The rig of the design.

    Raises
    ------
    DesignError
        If a parameter is unknown or invalid, or the holes fail :func:`check_holes` (naming the key).
    """
    params = dict(params or {})
    platform, base = design_holes(params)
    check_holes(platform, base, limits)
    p = {**PAPER_DESIGN, **params}
    k = _number(p, "cable_stiffness_N_per_m")
    if not k > 0:
        raise DesignError(f"must be > 0, got {k}", "cable_stiffness_N_per_m")
    t_min, t_max = _number(p, "t_min_N"), _number(p, "t_max_N")
    if not 0 <= t_min < t_max:
        raise DesignError(f"need 0 <= t_min_N < t_max_N, got {t_min}, {t_max}", "t_min_N")
    mass = _number(p, "platform_mass_kg")
    if not mass >= 0:
        raise DesignError(f"must be >= 0, got {mass}", "platform_mass_kg")
    return paper_rig().replace(platform_holes_A_m=platform, base_holes_B_m=base,
                               cable_stiffness_N_per_m=np.full(len(platform), k), t_min_N=t_min, t_max_N=t_max,
                               platform_mass_kg=mass,
                               com_A_m=np.array([0.0, 0.0, _number(p, "com_z_m")]))


# ------------------------------------------------------------------ helpers
def _check_names(params: Mapping[str, Any]) -> None:
    for key in params:
        if key not in PARAMETERS:
            raise DesignError("unknown design parameter (see csjm_opt.design.PARAMETERS)", key)
    for body in _BODIES:
        chords = {f"{body}_d12_m", f"{body}_d23_m"} & set(params)
        circle = {f"{body}_radius_m", f"{body}_gamma_deg"} & set(params)
        if chords and circle:
            raise DesignError("give chords or radius and gamma, not both", sorted(circle)[-1])
        if len(circle) == 1:
            missing = ({f"{body}_radius_m", f"{body}_gamma_deg"} - circle).pop()
            raise DesignError(f"needs {missing} as well", circle.pop())


def _chords(body: str, params: Mapping[str, Any]) -> tuple[float, float]:
    if f"{body}_radius_m" in params:
        r, g = _number(params, f"{body}_radius_m"), _number(params, f"{body}_gamma_deg")
        try:
            return chords_from_circle(r, g)
        except InvalidInput as exc:
            raise DesignError(str(exc), f"{body}_radius_m") from exc
    p = {**PAPER_DESIGN, **params}
    d12, d23 = _number(p, f"{body}_d12_m"), _number(p, f"{body}_d23_m")
    for key, value in ((f"{body}_d12_m", d12), (f"{body}_d23_m", d23)):
        if not value > 0:
            raise DesignError(f"must be > 0, got {value}", key)
    return d12, d23


def _number(params: Mapping[str, Any], key: str) -> float:
    value = params[key]
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise DesignError(f"expected a number, got {value!r:.40}", key)
    if not math.isfinite(float(value)):
        raise DesignError(f"expected a finite number, got {value}", key)
    return float(value)


def _n_cables(params: Mapping[str, Any]) -> int:
    """m: ``n_cables`` when given, else the rows of free hole coordinates of both bodies, else 6."""
    if "n_cables" in params:
        value = _number(params, "n_cables")
        if value != int(value) or not 4 <= value <= 12:
            raise DesignError(f"expected an integer from 4 to 12, got {value:g}", "n_cables")
        return int(value)
    if "platform_holes" in params and "base_holes" in params and np.ndim(params["platform_holes"]) == 2:
        return int(np.shape(params["platform_holes"])[0])
    return 6


def pair_circle_from_chords(d12_m: float, d23_m: float, n_cables: int) -> tuple[float, float]:
    """Circle radius (m) and pair angle gamma (rad) of m/2 hole pairs with chords d12 (in a pair) and d23 (between).

    The pair centres are 720/m deg apart, so ``d12 = 2 r sin(gamma / 2)`` and
    ``d23 = 2 r sin((720/m deg - gamma) / 2)``; gamma is the root of their ratio (m = 6: the
    semi-regular hexagon of :func:`csjm_opt.model.hexagon.circle_from_chords`).

    Parameters
    ----------
    d12_m, d23_m : float
        Chords (m), both > 0.
    n_cables : int
        m.

    Returns
    -------
    radius_m, gamma_rad : float
    """
    from scipy.optimize import brentq

    spacing = 4.0 * math.pi / n_cables
    gamma = brentq(lambda g: d12_m * math.sin((spacing - g) / 2) - d23_m * math.sin(g / 2), 0.0, spacing,
                   xtol=1e-15)
    return d12_m / (2 * math.sin(gamma / 2)), gamma


def _pair_holes(body: str, params: Mapping[str, Any], m: int, z: float, theta0_deg: float) -> np.ndarray:
    """M holes in m/2 pairs on a circle (module docstring), from radius and gamma or from chords."""
    spacing = 4.0 * math.pi / m                               # angle between pair centres (rad)
    if f"{body}_radius_m" in params:
        radius, gamma = _number(params, f"{body}_radius_m"), math.radians(_number(params, f"{body}_gamma_deg"))
        if not (radius > 0 and 0 < gamma < spacing):
            raise DesignError(f"need radius > 0 and 0 < gamma < {math.degrees(spacing):g} deg for {m} cables, "
                              f"got {radius:g}, {math.degrees(gamma):g}", f"{body}_radius_m")
    else:
        radius, gamma = pair_circle_from_chords(*_chords(body, params), m)
    if m % 2:      # the pairs continued, the last one a single hole (hole_pattern.paired_angles_deg)
        angles = math.radians(theta0_deg) + np.radians(paired_angles_deg(m, math.degrees(gamma)))
    else:
        centres = math.radians(theta0_deg) + spacing * np.arange(m // 2)
        angles = np.empty(m)
        angles[0::2], angles[1::2] = centres - gamma / 2, centres + gamma / 2
    return np.column_stack([radius * np.cos(angles), radius * np.sin(angles), np.full(m, z)])


def _as_holes(value: Any, key: str, m: int = 6) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DesignError(f"expected {m} [x, y, z] rows of numbers: {exc}", key) from exc
    if arr.shape != (m, 3):
        raise DesignError(f"expected shape ({m}, 3), got {arr.shape}", key)
    if not np.all(np.isfinite(arr)):
        raise DesignError("expected finite numbers", key)
    return arr
