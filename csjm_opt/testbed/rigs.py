"""Random rigs: the testbed's statistics over rigs unlike the paper's.

:class:`RigRanges` states the ranges every quantity is drawn from (uniform
unless said otherwise); :func:`random_rig` draws a rig and its instrument
noise and *validates that the rig holds its experiment*: the nominal planner
finds tensions at the reference poses and the nominal response of every
load cycle keeps each cable taut and within its tension bounds (the check of
:func:`csjm_opt.testbed.cycles.design_cycles`). Rigs that fail are redrawn.

=======================  ==================================================
cable count              ``n_cables`` (m, default 6, 4 to 12)
platform holes           semi-regular hexagon, chords d12 in [5, 30] mm,
                         d23 in [70, 120] mm, height OO_A in [50, 110] mm
base holes               semi-regular hexagon, chords d12 in [90, 150] mm,
                         d23 in [3, 30] mm, height -OO_B, OO_B in
                         [50, 110] mm, turned by [-10, 10] deg
m other than 6           the hexagons' circles, heights and turn as
                         drawn above, the holes laid out for m by
                         :func:`pattern_holes` (pairs for even m, the
                         same relative twist for odd m)
cable stiffness          common k in [2000, 10000] N/m, each cable x
                         U(0.9, 1.1)
tension range            t_min in [3, 8] N, t_max in [100, 200] N
mass, centre of mass     [0.25, 1.0] kg; com z in [30, 120] mm, x, y in
                         [-10, 10] mm
instrument noise         the paper's F/T and tracker sigmas, each times
                         a factor in [0.6, 1.6] (drawn independently)
scattered holes          optional (``hole_scatter_m > 0``): every hole
                         moved off its hexagon by a vector drawn
                         uniformly in a ball of that radius (in the
                         hole circle's plane for x, y and along z), so
                         the rig has no symmetry left
=======================  ==================================================
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import CsjmError
from ..measurement.instruments import InstrumentNoise
from ..model.hexagon import hexagon_holes
from ..model.rig import Rig
from .cycles import design_cycles

Range = tuple[float, float]


@dataclasses.dataclass(frozen=True)
class RigRanges:
    """Ranges of the random rigs (SI units; see the module table)."""

    platform_d12_m: Range = (0.005, 0.030)
    platform_d23_m: Range = (0.070, 0.120)
    platform_height_m: Range = (0.050, 0.110)
    base_d12_m: Range = (0.090, 0.150)
    base_d23_m: Range = (0.003, 0.030)
    base_depth_m: Range = (0.050, 0.110)
    base_turn_deg: Range = (-10.0, 10.0)
    stiffness_N_per_m: Range = (2000.0, 10000.0)
    stiffness_spread: float = 0.1
    t_min_N: Range = (3.0, 8.0)
    t_max_N: Range = (100.0, 200.0)
    mass_kg: Range = (0.25, 1.0)
    com_z_m: Range = (0.030, 0.120)
    com_xy_m: float = 0.010
    noise_factor: Range = (0.6, 1.6)
    hole_scatter_m: float = 0.0
    n_cables: int = 6


def _u(rng: np.random.Generator, r: Range) -> float:
    return float(rng.uniform(*r))


def pattern_holes(m: int, platform: np.ndarray, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Holes of an m-cable rig (m, 3) laid out like the two semi-regular hexagons ``platform``, ``base``.

    Each hexagon gives its circle (radius, height), its pair's central angle ``gamma`` and its
    turn (the angle of its first pair's centre). Even m: m/2 pairs centred ``j 720/m`` deg
    (plus the turn), each pair's central angle the fraction ``gamma / 120 deg`` of the pair
    spacing ``720/m`` (m = 6 gives the hexagons back). Odd m (no pairs): platform holes evenly
    spaced, hole i (from 0) at ``i 360/m``, base hole i turned from it by ``-+ (f_base -
    f_platform) 360/m`` (minus for even i), the same relative twist as a pair's two cables.

    Parameters
    ----------
    m : int
        Number of cables (4 to 12).
    platform, base : ndarray, shape (6, 3)
        Semi-regular hexagons in {A} and {B} (:func:`csjm_opt.model.hexagon.hexagon_holes`).

    Returns
    -------
    platform_holes_A_m, base_holes_B_m : ndarray, shape (m, 3)
    """
    def circle(h: np.ndarray) -> tuple[float, float, float, float]:
        angles = np.arctan2(h[:2, 1], h[:2, 0])
        gamma = float(np.angle(np.exp(1j * (angles[1] - angles[0]))))   # hole 1 to hole 2, in (-pi, pi]
        centre = float(angles[0] + gamma / 2)
        return float(np.hypot(*h[0, :2])), float(h[0, 2]), centre, gamma / np.deg2rad(120.0)

    (r_p, z_p, c_p, f_p), (r_b, z_b, c_b, f_b) = circle(platform), circle(base)
    i = np.arange(m)
    sign = np.where(i % 2 == 0, -1.0, 1.0)
    a_p: np.ndarray
    a_b: np.ndarray
    if m % 2 == 0:
        centre = 2 * np.pi / m * 2 * (i // 2)
        a_p = c_p + centre + sign * f_p * np.pi * 2 / m
        a_b = c_b + centre + sign * f_b * np.pi * 2 / m
    else:
        a_p = c_p + 2 * np.pi / m * i
        a_b = c_b + 2 * np.pi / m * i + sign * (f_b - f_p) * 2 * np.pi / m

    def ring(r: float, z: float, a: np.ndarray) -> np.ndarray:
        return np.column_stack([r * np.cos(a), r * np.sin(a), np.full(m, z)])

    return ring(r_p, z_p, a_p), ring(r_b, z_b, a_b)


def draw_rig(rng: np.random.Generator, ranges: RigRanges = RigRanges()) -> Rig:
    """One rig of ``ranges.n_cables`` cables drawn from ``ranges`` (not yet validated)."""
    m = ranges.n_cables
    platform = hexagon_holes(_u(rng, ranges.platform_d12_m), _u(rng, ranges.platform_d23_m),
                             _u(rng, ranges.platform_height_m))
    base = hexagon_holes(_u(rng, ranges.base_d12_m), _u(rng, ranges.base_d23_m), -_u(rng, ranges.base_depth_m),
                         theta0_deg=_u(rng, ranges.base_turn_deg))
    if m != 6:
        platform, base = pattern_holes(m, platform, base)
    if ranges.hole_scatter_m > 0.0:   # drawn only then: the unscattered rigs keep their random stream
        platform = platform + _in_ball(rng, m, ranges.hole_scatter_m)
        base = base + _in_ball(rng, m, ranges.hole_scatter_m)
    k = _u(rng, ranges.stiffness_N_per_m) * rng.uniform(1 - ranges.stiffness_spread, 1 + ranges.stiffness_spread, m)
    com = np.r_[rng.uniform(-ranges.com_xy_m, ranges.com_xy_m, 2), _u(rng, ranges.com_z_m)]
    return Rig(platform_holes_A_m=platform, base_holes_B_m=base, cable_stiffness_N_per_m=k,
               t_min_N=_u(rng, ranges.t_min_N), t_max_N=_u(rng, ranges.t_max_N),
               platform_mass_kg=_u(rng, ranges.mass_kg), com_A_m=com)


def _in_ball(rng: np.random.Generator, n: int, radius_m: float) -> np.ndarray:
    """``n`` vectors uniform in the ball of ``radius_m``."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v * radius_m * rng.uniform(size=(n, 1)) ** (1.0 / 3.0)


def draw_noise(rng: np.random.Generator, ranges: RigRanges = RigRanges()) -> InstrumentNoise:
    """The paper's instrument noise with the F/T and tracker sigmas scaled independently."""
    paper = InstrumentNoise.paper()
    f_tau, f_angle = _u(rng, ranges.noise_factor), _u(rng, ranges.noise_factor)
    tx, ty, tz = (f_tau * s for s in paper.tau_sigma_Nm)
    return InstrumentNoise((tx, ty, tz), f_angle * paper.angle_sigma_rad)


def holds_experiment(rig: Rig, rng: np.random.Generator, n_cycles: int = 4) -> bool:
    """Whether the nominal rig can run ``n_cycles`` of the diagnosis experiment (see module doc)."""
    try:
        design_cycles(rig, n_cycles, rng, max_tries=20)
    except CsjmError:
        return False
    return True


def random_rig(rng: np.random.Generator, ranges: RigRanges = RigRanges(),
               max_tries: int = 30) -> tuple[Rig, InstrumentNoise]:
    """A validated random rig and its instrument noise.

    Parameters
    ----------
    rng : numpy.random.Generator
    ranges : RigRanges, optional
        Where each quantity is drawn from.
    max_tries : int, optional
        Rigs drawn before giving up.

    Returns
    -------
    (Rig, InstrumentNoise)

    Raises
    ------
    CsjmError
        No rig drawn in ``max_tries`` holds its experiment.
    """
    for _ in range(max_tries):
        rig = draw_rig(rng, ranges)
        if holds_experiment(rig, rng):
            return rig, draw_noise(rng, ranges)
    raise CsjmError(f"no random rig in {max_tries} draws holds the experiment; widen RigRanges")
