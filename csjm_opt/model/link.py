"""The central link of a rig: a rod from the base up to the joint, and the ball (optional ``[link]`` section).

The cables must not touch the parts that carry the spherical joint. They are
described, in the base frame {B}, by::

    [link]
    rod_radius = 0.004       # m, radius of the rod (a capsule: its ends are rounded)
    rod_length = 0.08        # m, the rod runs from (0, 0, -rod_length) in {B} up to the joint centre O
    ball_radius = 0.005      # m, the ball of the spherical joint, centred on O

Every key is optional. The paper gives no dimensions for the link; the
defaults (:data:`DEFAULT_LINK`) are assumed values chosen to fit the paper's
module: the rod reaches down to the base holes' plane (OO_B = 0.08 m), an
8 mm rod, and a 10 mm ball, whose radius equals the 5 mm clearance from O that
a sweep asks of every cable at the home pose (``min_cable_clearance_m``), so
at R = I the old rule and the new one agree. A rig file without ``[link]``
uses them; measure a real rig and write its section.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..errors import RigFileError

_KEYS = ("rod_radius", "rod_length", "ball_radius")
#: Upper bound of every link dimension (m): far larger than any CSJM.
MAX_LINK_SIZE_M = 10.0


@dataclasses.dataclass(frozen=True)
class Link:
    """Rod (capsule) from ``(0, 0, -rod_length_m)`` in {B} to O, and a ball at O; all m."""

    rod_radius_m: float = 0.004
    rod_length_m: float = 0.08
    ball_radius_m: float = 0.005

    def __post_init__(self) -> None:
        for key, value in zip(_KEYS, (self.rod_radius_m, self.rod_length_m, self.ball_radius_m)):
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
                    or not math.isfinite(float(value)) or not 0 <= float(value) <= MAX_LINK_SIZE_M:
                raise RigFileError(f"expected a number in [0, {MAX_LINK_SIZE_M:g}] m, got {value!r:.40}",
                                   None, f"link.{key}")
            object.__setattr__(self, f"{key}_m", float(value))

    @property
    def rod_ends_B_m(self) -> tuple[np.ndarray, np.ndarray]:
        """Bottom and top end of the rod's axis in {B} (m): ``(0, 0, -rod_length)`` and O.

        Returns
        -------
        bottom, top : ndarray, shape (3,)
        """
        return np.array([0.0, 0.0, -self.rod_length_m]), np.zeros(3)

    def as_dict(self) -> dict[str, float]:
        """The ``[link]`` section of a rig file.

        Returns
        -------
        dict of str to float
        """
        return {"rod_radius": self.rod_radius_m, "rod_length": self.rod_length_m,
                "ball_radius": self.ball_radius_m}

    @classmethod
    def from_dict(cls, data: Any, path: str | None = None) -> "Link":
        """Read a ``[link]`` section (missing keys take the defaults).

        Parameters
        ----------
        data : dict
            The section.
        path : str, optional
            File it came from, named in errors.

        Returns
        -------
        Link

        Raises
        ------
        RigFileError
            If the section is not a table, a key is unknown or a value is not a number in range.
        """
        if not isinstance(data, dict):
            raise RigFileError("expected a table", path, "link")
        for key in data:
            if key not in _KEYS:
                raise RigFileError(f"unknown key (expected one of {list(_KEYS)})", path, f"link.{key}")
        try:
            return cls(**{f"{k}_m": data[k] for k in _KEYS if k in data})
        except RigFileError as exc:
            raise RigFileError(str(exc).split("] ", 1)[-1], path, exc.key) from exc


#: The link assumed for the paper's rig and for any rig file without a ``[link]`` section.
DEFAULT_LINK = Link()
