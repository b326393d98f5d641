"""The rig: hole geometry, cable stiffness, tension bounds and platform mass.

A :class:`Rig` is immutable; arrays are read-only copies. It reads and writes
the TOML format of docs/conventions.md::

    [geometry]
    platform_holes = [[x, y, z], ...]   # m rows (4 <= m <= 12), A_i in {A}, m
    base_holes     = [[x, y, z], ...]   # m rows, B_i in {B}, m
    # or, instead of the two arrays, a [geometry.pattern] table
    # (csjm_opt.model.hole_pattern: count, radii, angles, heights, twist, ...)
    [cables]
    stiffness = [k1, ..., km]           # N/m, each cable with its drive
    t_min = 5.0                         # N
    t_max = 150.0                       # N
    [platform]
    mass = 0.4913                       # kg
    com = [0.0, 0.0, 0.081]             # m, in {A}
    gravity = [0.0, 0.0, -9.81]         # m/s^2, in {B}
    [dynamics]                          # optional, see csjm_opt.model.dynamics
    inertia = [Ixx, Iyy, Izz]           # kg m^2 about the COM in {A} (or 3x3)
    joint_damping = 0.02                # N m s/rad
    cable_damping = 0.0                 # N s/m
    [link]                              # optional, see csjm_opt.model.link
    rod_radius = 0.004                  # m, rod from (0, 0, -rod_length) in {B} to O
    rod_length = 0.08                   # m
    ball_radius = 0.005                 # m, the joint's ball at O
    [workspace]                         # optional, the rig's stated range
    tilt_deg = 20.0                     # deg, largest tilt the rig must hold its weight at

A rig read from a file or dict is refused when it cannot work
(:mod:`csjm_opt.model.tension_closure`): no tensions in ``[t_min, t_max]`` hold
the platform's weight at some pose of its stated range (the zero pose, plus
tilts up to ``workspace.tilt_deg`` when given).
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from .._fileio import atomic_write_text, read_text
from ..errors import InvalidInput, RigFileError
from . import hexagon
from ._rig_schema import _check
from ._rig_toml import _format_toml
from .dynamics import Dynamics
from .hole_pattern import expand_pattern
from .link import DEFAULT_LINK, Link

#: Shared cable-plus-drive stiffness of the built-in paper rig (N/m). The paper
#: gives none. K is affine in k for fixed tensions, so k was chosen by least
#: squares: the model's K at the corrected R0 under Table 3's pre-load (as the
#: total load), tensions planned from mid-range, fitted to the symmetric part of
#: Table 3's K_D gives k = 4638 N/m, rounded to 4600. Eigenvalues of K are then
#: about 17, 27, 29 N m/rad against K_D's 6.8, 28.9, 30.6. See docs/guide/modelling.md
#: and ``tests/model/test_rig.py``.
PAPER_CABLE_STIFFNESS_N_PER_M = 4600.0
PAPER_T_MIN_N = 5.0
PAPER_T_MAX_N = 150.0
PAPER_MASS_KG = 0.4913          # G = 4.82 N (Section IV-A) at g = 9.81
PAPER_COM_A_M = (0.0, 0.0, 0.081)
STANDARD_GRAVITY_B = (0.0, 0.0, -9.81)


def _frozen(value: Any) -> np.ndarray:
    arr = np.array(value, dtype=np.float64)
    arr.setflags(write=False)
    return arr


@dataclasses.dataclass(frozen=True, eq=False)
class Rig:
    """A cable-driven spherical joint module (units SI, frames per docs/conventions.md)."""

    platform_holes_A_m: np.ndarray      # (m, 3) A_i in {A}, 4 <= m <= 12
    base_holes_B_m: np.ndarray          # (m, 3) B_i in {B}
    cable_stiffness_N_per_m: np.ndarray  # (m,)
    t_min_N: float
    t_max_N: float
    platform_mass_kg: float = PAPER_MASS_KG
    com_A_m: np.ndarray = dataclasses.field(default_factory=lambda: _frozen(PAPER_COM_A_M))
    gravity_B_m_per_s2: np.ndarray = dataclasses.field(default_factory=lambda: _frozen(STANDARD_GRAVITY_B))
    #: Inertia and damping for dynamic simulation; ``None``: the documented defaults
    #: (:func:`csjm_opt.model.dynamics.rig_dynamics`).
    dynamics: Dynamics | None = None
    #: The central link the cables must clear; ``None``: :data:`csjm_opt.model.link.DEFAULT_LINK`.
    link: Link | None = None
    #: The stated range: largest tilt (deg) at which the rig must hold its weight; ``None``: the zero pose.
    workspace_tilt_deg: float | None = None

    def __post_init__(self) -> None:
        data = self.as_dict()
        data.pop("dynamics", None)
        data.pop("link", None)
        data.pop("workspace", None)
        if self.link is not None and not isinstance(self.link, Link):
            raise RigFileError(f"expected a Link, got {type(self.link).__name__}", None, "link")
        _check(data, path=None)
        if self.dynamics is not None and not isinstance(self.dynamics, Dynamics):
            raise RigFileError(f"expected a Dynamics, got {type(self.dynamics).__name__}", None, "dynamics")
        for field in ("platform_holes_A_m", "base_holes_B_m", "cable_stiffness_N_per_m",
                      "com_A_m", "gravity_B_m_per_s2"):
            object.__setattr__(self, field, _frozen(getattr(self, field)))
        object.__setattr__(self, "t_min_N", float(self.t_min_N))
        object.__setattr__(self, "t_max_N", float(self.t_max_N))
        object.__setattr__(self, "platform_mass_kg", float(self.platform_mass_kg))
        if self.dynamics is not None:
            self.dynamics.cable_damping_per_cable(self.n_cables)   # raises on a per-cable count mismatch
        if self.workspace_tilt_deg is not None:
            object.__setattr__(self, "workspace_tilt_deg", _tilt_deg(self.workspace_tilt_deg, None))

    @property
    def n_cables(self) -> int:
        """m, the number of cables (rows of the hole arrays)."""
        return int(self.platform_holes_A_m.shape[0])

    # ------------------------------------------------------------ derived
    @property
    def weight_B_N(self) -> np.ndarray:
        """Platform weight force in {B} (N)."""
        return self.platform_mass_kg * self.gravity_B_m_per_s2

    @property
    def link_or_default(self) -> Link:
        """The rig's link, or the documented default when the rig gives none."""
        return DEFAULT_LINK if self.link is None else self.link

    @property
    def t_mid_N(self) -> np.ndarray:
        """Mid-range tension, the planner's default reference (N), shape (m,)."""
        return np.full(self.n_cables, 0.5 * (self.t_min_N + self.t_max_N))

    def replace(self, **changes: Any) -> "Rig":
        """A copy with some fields changed (validated again).

        Parameters
        ----------
        **changes
            New values of fields, e.g. ``cable_stiffness_N_per_m=[6000.0] * 6``.

        Returns
        -------
        Rig
            The changed copy; this rig is unchanged.

        Raises
        ------
        InvalidInput
            If a name is not a field of :class:`Rig` or a value is invalid (a change of the
            cable count must change the holes and stiffness together).
        """
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            raise InvalidInput(f"Rig has no field {', '.join(unknown)}; fields: "
                               + ", ".join(f.name for f in dataclasses.fields(self)), unknown[0])
        return dataclasses.replace(self, **changes)

    # ------------------------------------------------------------ conversion
    def as_dict(self) -> dict[str, dict[str, Any]]:
        """The rig as a nested dict in the TOML layout of docs/conventions.md.

        Returns
        -------
        dict
            ``{"geometry": {...}, "cables": {...}, "platform": {...}}`` of plain Python numbers
            (plus ``"dynamics"``, ``"link"`` and ``"workspace"`` when set).
        """
        tolist = lambda a: np.asarray(a, dtype=float).tolist()  # noqa: E731
        data = {
            "geometry": {"platform_holes": tolist(self.platform_holes_A_m),
                         "base_holes": tolist(self.base_holes_B_m)},
            "cables": {"stiffness": tolist(self.cable_stiffness_N_per_m),
                       "t_min": float(self.t_min_N), "t_max": float(self.t_max_N)},
            "platform": {"mass": float(self.platform_mass_kg), "com": tolist(self.com_A_m),
                         "gravity": tolist(self.gravity_B_m_per_s2)},
        }
        if self.dynamics is not None:
            data["dynamics"] = self.dynamics.as_dict()
        if self.link is not None:
            data["link"] = self.link.as_dict()
        if self.workspace_tilt_deg is not None:
            data["workspace"] = {"tilt_deg": float(self.workspace_tilt_deg)}
        return data

    @classmethod
    def from_dict(cls, data: dict[str, Any], path: str | None = None, check_closure: bool = True) -> "Rig":
        """Build a rig from the nested TOML layout.

        Parameters
        ----------
        data : dict
            ``{"geometry": {...}, "cables": {...}, "platform": {...}}`` as in a rig file; the
            geometry may be a ``pattern`` table (:mod:`csjm_opt.model.hole_pattern`).
        path : str, optional
            File the data came from, named in errors.
        check_closure : bool, optional
            Refuse a rig without tension closure over its stated range
            (:func:`csjm_opt.model.tension_closure.check_tension_closure`).

        Returns
        -------
        Rig
            The validated rig.

        Raises
        ------
        RigFileError
            If a key is unknown or missing, a shape is wrong, a number is not finite, ``t_min >=
            t_max``, a stiffness is not positive, holes coincide, there are fewer than 4 (or
            more than 12) cables, or the cables cannot hold the platform's weight with tensions
            in bounds over the stated range (naming the key and file).
        """
        if isinstance(data, dict) and isinstance(data.get("geometry"), dict) and "pattern" in data["geometry"]:
            geometry = dict(data["geometry"])
            for key in ("platform_holes", "base_holes"):
                if key in geometry:
                    raise RigFileError("give hole coordinates or a pattern, not both", path, f"geometry.{key}")
            platform, base = expand_pattern(geometry.pop("pattern"), path)
            geometry.update(platform_holes=platform.tolist(), base_holes=base.tolist())
            data = {**data, "geometry": geometry}
        statics = ({key: value for key, value in data.items() if key not in ("dynamics", "link", "workspace")}
                   if isinstance(data, dict) else data)
        _check(statics, path)
        g, c, p = data["geometry"], data["cables"], data["platform"]
        dynamics = None
        if "dynamics" in data:
            from .dynamics import default_dynamics

            dynamics = Dynamics.from_dict(data["dynamics"], default_dynamics(p["mass"], g["platform_holes"]), path)
        link = Link.from_dict(data["link"], path) if "link" in data else None
        tilt = _workspace_tilt(data.get("workspace"), path)
        if dynamics is not None and np.ndim(dynamics.cable_damping_Ns_per_m) == 1 \
                and len(dynamics.cable_damping_Ns_per_m) != len(g["platform_holes"]):
            raise RigFileError(f"expected a number or {len(g['platform_holes'])} numbers (one per cable), got "
                               f"{len(dynamics.cable_damping_Ns_per_m)}", path, "dynamics.cable_damping")
        rig = cls(platform_holes_A_m=g["platform_holes"], base_holes_B_m=g["base_holes"],
                  cable_stiffness_N_per_m=c["stiffness"], t_min_N=c["t_min"], t_max_N=c["t_max"],
                  platform_mass_kg=p["mass"], com_A_m=p["com"], gravity_B_m_per_s2=p["gravity"],
                  dynamics=dynamics, link=link, workspace_tilt_deg=tilt)
        if check_closure:
            from .tension_closure import check_tension_closure

            check_tension_closure(rig, path)
        return rig

    @classmethod
    def from_toml(cls, path: str | Path) -> "Rig":
        """Read a rig file (format in docs/conventions.md).

        Parameters
        ----------
        path : str or Path
            The TOML file.

        Returns
        -------
        Rig
            The validated rig.

        Raises
        ------
        RigFileError
            If the file cannot be read, is not TOML, or fails the checks of :meth:`from_dict`.
        """
        path = Path(path)
        text = read_text(path, lambda msg: RigFileError(msg, str(path)), "rig file")
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise RigFileError(f"not valid TOML: {exc}", str(path)) from exc
        return cls.from_dict(data, str(path))

    def to_toml(self, path: str | Path | None = None, overwrite: bool = False) -> str:
        """The rig as TOML text; written atomically to ``path`` when given.

        Parameters
        ----------
        path : str or Path, optional
            Output file; an existing file is never replaced unless ``overwrite=True``.
        overwrite : bool, optional
            Replace an existing file.

        Returns
        -------
        str
            The TOML text (one hole per line; :meth:`from_toml` reads it back to the same rig).

        Raises
        ------
        InvalidInput
            If ``path`` exists and ``overwrite`` is false, or it cannot be written.
        """
        text = _format_toml(self.as_dict())
        if path is not None:
            atomic_write_text(path, text, overwrite=overwrite)
        return text


def _tilt_deg(value: Any, path: str | None) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
            or not 0.0 <= float(value) <= 90.0:
        raise RigFileError(f"expected a number of degrees in [0, 90], got {value!r:.60}", path, "workspace.tilt_deg")
    return float(value)


def _workspace_tilt(table: Any, path: str | None) -> float | None:
    if table is None:
        return None
    if not isinstance(table, dict):
        raise RigFileError(f"expected a table, got {type(table).__name__}", path, "workspace")
    for key in table:
        if key != "tilt_deg":
            raise RigFileError("unknown key (expected one of ['tilt_deg'])", path, f"workspace.{key}")
    if "tilt_deg" not in table:
        raise RigFileError("missing key", path, "workspace.tilt_deg")
    return _tilt_deg(table["tilt_deg"], path)


def paper_rig(cable_stiffness_N_per_m: float = PAPER_CABLE_STIFFNESS_N_PER_M) -> Rig:
    """The rig of the paper's Section IV-A (holes paired as the paper labels them).

    Parameters
    ----------
    cable_stiffness_N_per_m : float, optional
        Shared stiffness of each cable with its drive (N/m); the paper gives none, the default
        4600 N/m is fitted to Table 3 (docs/guide/modelling.md).

    Returns
    -------
    Rig
        Semi-regular hexagons of Section IV-A, weight 4.82 N at (0, 0, 0.081) m, tensions in
        [5, 150] N.

    Raises
    ------
    RigFileError
        If ``cable_stiffness_N_per_m`` is not positive and finite.
    """
    platform, base = hexagon.paper_holes()
    return Rig(platform_holes_A_m=platform, base_holes_B_m=base,
               cable_stiffness_N_per_m=np.full(6, float(cable_stiffness_N_per_m)),
               t_min_N=PAPER_T_MIN_N, t_max_N=PAPER_T_MAX_N)


def load_rig(spec: str | Path | None) -> Rig:
    """A rig from a TOML file, or the built-in paper rig.

    Parameters
    ----------
    spec : str or Path or None
        Path of a rig file (format in docs/conventions.md), or ``None`` / ``"paper"`` for
        :func:`paper_rig`.

    Returns
    -------
    Rig
        The validated rig.

    Raises
    ------
    RigFileError
        If the file cannot be read or is malformed (naming the key).
    """
    if spec is None or str(spec) == "paper":
        return paper_rig()
    return Rig.from_toml(spec)
