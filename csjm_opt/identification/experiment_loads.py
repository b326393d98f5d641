"""What an identification experiment may use: weights, attachment points, directions, limits.

A load set is read from TOML (every key optional; defaults from the rig)::

    weights_N = [3.0, 6.0, 9.0, 12.0, 15.0]       # dead weights available
    points_A_m = [[0.05, 0.0, 0.08], [-0.05, 0.0, 0.08], [0.0, 0.05, 0.08], [0.0, -0.05, 0.08]]
    directions = 48                               # unit directions in {B} over the sphere (pulleys)
    pretensions_N = [8.0, 14.0, 25.0, 45.0, 80.0]  # reference tensions the planner may choose
    max_rotation_rad = 0.15                       # tracker range: largest turn from the reference

Default attachment points: four points at 50 mm from the axis, at the height of the
platform's holes (the paper's four attachment points).
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np

from .._fileio import read_text
from ..errors import InvalidInput
from ..model.rig import Rig

_KEYS = ("weights_N", "points_A_m", "directions", "pretensions_N", "max_rotation_rad")


@dataclasses.dataclass(frozen=True, eq=False)
class ExperimentLoads:
    """Loads and limits of an identification experiment (SI units)."""

    weights_N: np.ndarray         # (w,)
    points_A_m: np.ndarray        # (p, 3)
    directions_B: np.ndarray      # (d, 3) unit vectors, closed under negation
    pretensions_N: np.ndarray     # (t,)
    max_rotation_rad: float = 0.15

    @classmethod
    def default(cls, rig: Rig) -> "ExperimentLoads":
        """The default set for ``rig`` (module docstring).

        Parameters
        ----------
        rig : Rig

        Returns
        -------
        ExperimentLoads
        """
        h = float(np.mean(np.asarray(rig.platform_holes_A_m)[:, 2]))
        r = 0.05
        points = np.array([[r, 0, h], [-r, 0, h], [0, r, h], [0, -r, h]])
        return cls(np.array([3.0, 6.0, 9.0, 12.0, 15.0]), points, sphere_directions(48),
                   default_pretensions(rig))

    @classmethod
    def from_toml(cls, path: str | Path, rig: Rig) -> "ExperimentLoads":
        """Read a load set; missing keys take the defaults of :meth:`default`.

        Parameters
        ----------
        path : str or Path
        rig : Rig

        Returns
        -------
        ExperimentLoads

        Raises
        ------
        InvalidInput
            Unknown key or a bad value (named with the file and key).
        """
        text = read_text(Path(path), lambda msg: InvalidInput(msg, str(path)), "load set")
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise InvalidInput(f"{path}: not TOML: {exc}", "loads") from None
        unknown = sorted(set(data) - set(_KEYS))
        if unknown:
            raise InvalidInput(f"{path}: unknown key {unknown[0]!r} (known: {', '.join(_KEYS)})", unknown[0])
        d = cls.default(rig)

        def arr(key, default, shape_tail, positive=True):
            if key not in data:
                return default
            try:
                a = np.asarray(data[key], float)
            except (TypeError, ValueError):
                raise InvalidInput(f"{path}: {key}: expected numbers", key) from None
            if a.ndim != 1 + len(shape_tail) or a.shape[1:] != shape_tail or len(a) == 0 \
                    or not np.all(np.isfinite(a)) or (positive and np.any(a <= 0)):
                raise InvalidInput(f"{path}: {key}: expected a non-empty list of "
                                   f"{'positive numbers' if not shape_tail else '[x, y, z] points'}", key)
            return a

        n_dir = data.get("directions", len(d.directions_B))
        if not isinstance(n_dir, int) or isinstance(n_dir, bool) or not 6 <= n_dir <= 2000:
            raise InvalidInput(f"{path}: directions: expected an integer in [6, 2000], got {n_dir!r}", "directions")
        rot = data.get("max_rotation_rad", d.max_rotation_rad)
        if not isinstance(rot, (int, float)) or isinstance(rot, bool) or not 0 < rot <= 1.0:
            raise InvalidInput(f"{path}: max_rotation_rad: expected a number in (0, 1], got {rot!r}",
                               "max_rotation_rad")
        return cls(arr("weights_N", d.weights_N, ()), arr("points_A_m", d.points_A_m, (3,), positive=False),
                   sphere_directions(n_dir), arr("pretensions_N", d.pretensions_N, ()), float(rot))


def default_pretensions(rig: Rig) -> np.ndarray:
    """Reference tensions to choose from: eight levels from just above ``t_min`` to ``0.95 t_max``.

    A higher pretension softens the tilt stiffness (the tension term of K) and lets larger
    weights hang without slackening a cable, so the top levels are often the best.

    Parameters
    ----------
    rig : Rig

    Returns
    -------
    ndarray
    """
    lo, hi = rig.t_min_N, 0.95 * rig.t_max_N
    return np.unique(np.clip(np.geomspace(max(lo + 2.0, 1.0), max(hi, lo + 3.0), 8), lo, rig.t_max_N))


def sphere_directions(n: int) -> np.ndarray:
    """``2 * ceil(n/2)`` nearly uniform unit vectors closed under negation (Fibonacci half-sphere).

    Parameters
    ----------
    n : int

    Returns
    -------
    ndarray (m, 3)
    """
    h = (n + 1) // 2
    i = np.arange(h) + 0.5
    z = i / h                                  # upper half sphere, then its negation
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z * z)
    up = np.column_stack([r * np.cos(phi), r * np.sin(phi), z])
    return np.vstack([up, -up])
