"""Reproducible uniform samples of SO(3) within a tilt and torsion range.

Orientations use the tilt-and-torsion angles of Bonev et al. (ASME J. Mech.
Des. 2002)::

    R(phi, theta, sigma) = Rz(phi) Ry(theta) Rz(-phi) Rz(sigma)

``theta`` (tilt) is the angle between the platform axis z_A and the base axis
z_B, ``phi`` (azimuth) the direction of the tilt, ``sigma`` (torsion) the
rotation about the platform's own axis. The Haar (uniform) measure of SO(3) in
these coordinates is ``sin(theta) dphi dtheta dsigma`` (the map from ZYZ
Euler angles has unit Jacobian), so drawing ``cos(theta)`` uniform on
``[cos(max_tilt), 1]``, ``phi`` uniform on ``[0, 2 pi)`` and ``sigma``
uniform on ``[-max_torsion, max_torsion]`` gives the uniform distribution
restricted to ``{tilt <= max_tilt, |torsion| <= max_torsion}``.

The unit cube is filled by a scrambled Halton sequence (``scipy.stats.qmc``)
with a fixed seed: reproducible, low-discrepancy, and nested (the first n of
2n points are the n points), which makes density studies cheap and fair.
``method = "random"`` uses a seeded PCG64 generator instead.
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
from scipy.stats import qmc

from ..errors import DesignError

METHODS = ("halton", "random")


@dataclasses.dataclass(frozen=True)
class OrientationSampling:
    """How to sample orientations: count, tilt/torsion limits (deg), seed, method."""

    n: int = 1000
    max_tilt_deg: float = 30.0
    max_torsion_deg: float = 30.0
    seed: int = 0
    method: str = "halton"

    def __post_init__(self) -> None:
        if isinstance(self.n, bool) or not isinstance(self.n, (int, np.integer)) or self.n < 1:
            raise DesignError(f"expected a positive integer, got {self.n!r}", "orientations")
        if not 0 < self.max_tilt_deg <= 180:
            raise DesignError(f"expected 0 < max_tilt_deg <= 180, got {self.max_tilt_deg}", "max_tilt_deg")
        if not 0 <= self.max_torsion_deg <= 180:
            raise DesignError(f"expected 0 <= max_torsion_deg <= 180, got {self.max_torsion_deg}",
                              "max_torsion_deg")
        if self.method not in METHODS:
            raise DesignError(f"expected one of {METHODS}, got {self.method!r}", "method")

    def angles(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sampled angles.

        Returns
        -------
        tilt, azimuth, torsion : ndarray, shape (n,)
            Angles (rad).
        """
        return _angles(self)

    def rotations(self) -> np.ndarray:
        """The sampled orientations (read-only, cached per process).

        Returns
        -------
        ndarray, shape (n, 3, 3)
            Orientations of {A} in {B}.
        """
        return _rotations(self)


def unit_cube(n: int, seed: int, method: str = "halton") -> np.ndarray:
    """(n, 3) points in [0, 1)^3: scrambled Halton (nested in n) or PCG64 uniform."""
    if method == "halton":
        return qmc.Halton(d=3, scramble=True, seed=np.random.default_rng(seed)).random(n)
    return np.random.default_rng(seed).random((n, 3))


def tilt_torsion_rotations(tilt: np.ndarray, azimuth: np.ndarray, torsion: np.ndarray) -> np.ndarray:
    """Rotations ``Rz(phi) Ry(theta) Rz(-phi) Rz(sigma)`` from tilt, azimuth and torsion angles.

    Parameters
    ----------
    tilt : array_like, shape (n,)
        Tilt ``theta`` of the platform axis from the base axis (rad).
    azimuth : array_like, shape (n,)
        Azimuth ``phi`` of the tilt (rad).
    torsion : array_like, shape (n,)
        Torsion ``sigma`` about the platform axis (rad).

    Returns
    -------
    ndarray, shape (n, 3, 3)
        Orientations of {A} in {B}.
    """
    tilt, azimuth, torsion = (np.asarray(a, float) for a in (tilt, azimuth, torsion))
    return _rz(azimuth) @ _ry(tilt) @ _rz(torsion - azimuth)


def tilt_torsion_angles(R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`tilt_torsion_rotations`.

    Parameters
    ----------
    R : array_like, shape (n, 3, 3)
        Orientations of {A} in {B}.

    Returns
    -------
    tilt : ndarray, shape (n,)
        In ``[0, pi]`` (rad).
    azimuth : ndarray, shape (n,)
        In ``(-pi, pi]`` (rad).
    torsion : ndarray, shape (n,)
        In ``(-pi, pi]`` (rad).
    """
    R = np.asarray(R, float)
    z = R[..., :, 2]                                  # platform axis in {B}
    tilt = np.arccos(np.clip(z[..., 2], -1.0, 1.0))
    azimuth = np.arctan2(z[..., 1], z[..., 0])
    # Rz(phi) Ry(theta) Rz(sigma - phi): ZYZ Euler angles (phi, theta, psi)
    psi = np.arctan2(R[..., 2, 1], -R[..., 2, 0])
    torsion = np.angle(np.exp(1j * (psi + azimuth)))
    upright = np.sin(tilt) < 1e-9          # tilt 0: only azimuth + psi is defined
    azimuth = np.where(upright, 0.0, azimuth)
    torsion = np.where(upright, np.arctan2(R[..., 1, 0], R[..., 0, 0]), torsion)
    return tilt, azimuth, torsion


@functools.lru_cache(maxsize=8)
def _angles(s: OrientationSampling) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    u = unit_cube(s.n, s.seed, s.method)
    cos_max = np.cos(np.deg2rad(s.max_tilt_deg))
    tilt = np.arccos(1.0 - u[:, 0] * (1.0 - cos_max))       # area-uniform on the cap
    azimuth = 2 * np.pi * u[:, 1]
    torsion = np.deg2rad(s.max_torsion_deg) * (2 * u[:, 2] - 1)
    for a in (tilt, azimuth, torsion):
        a.setflags(write=False)
    return tilt, azimuth, torsion


@functools.lru_cache(maxsize=8)
def _rotations(s: OrientationSampling) -> np.ndarray:
    R = tilt_torsion_rotations(*_angles(s))
    R.setflags(write=False)
    return R


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    out[..., 0, 0], out[..., 0, 1], out[..., 1, 0], out[..., 1, 1] = c, -s, s, c
    out[..., 2, 2] = 1.0
    return out


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    out = np.zeros(a.shape + (3, 3))
    out[..., 0, 0], out[..., 0, 2], out[..., 2, 0], out[..., 2, 2] = c, s, -s, c
    out[..., 1, 1] = 1.0
    return out
