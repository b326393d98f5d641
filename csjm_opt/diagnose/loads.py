"""The load set of a lab: the dead weights it can hang on the platform (for suggested experiments).

A small TOML file, one table per load::

    # loads.toml: masses (kg) hung at points of the platform (m, in {A})
    [[load]]
    name = "200 g at +x"
    mass_kg = 0.2
    point_A_m = [0.05, 0.0, 0.0]

The external moment of a load depends on the pose: ``tau_ext = point x (R^T m g_B)`` (in
{A}, the weight fixed in {B}). Without a file, :func:`default_load_set` gives masses of
0.1, 0.2 and 0.5 kg at four points (+-x, +-y) in the platform's hole plane, at 0.8 of the
holes' radius: what any lab with a set of calibration weights has.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np

from ..errors import InvalidInput
from ..model.rig import Rig

#: Default masses (kg) and the share of the platform-hole radius at which they hang.
DEFAULT_MASSES_KG = (0.1, 0.2, 0.5)
DEFAULT_RADIUS_SHARE = 0.8


@dataclasses.dataclass(frozen=True)
class Load:
    """A dead weight: ``mass_kg`` hung at ``point_A_m`` (m, in {A})."""

    name: str
    mass_kg: float
    point_A_m: tuple[float, float, float]

    def moment_A_Nm(self, R: np.ndarray, gravity_B: np.ndarray) -> np.ndarray:
        """External moment (N m, in {A}) at poses ``R`` ((3, 3) or (n, 3, 3)).

        Parameters
        ----------
        R : numpy.ndarray
            Pose(s) of {A} in {B}.
        gravity_B : numpy.ndarray
            Gravity in {B} (m/s^2).

        Returns
        -------
        numpy.ndarray
        """
        g_A = np.einsum("...ji,j->...i", np.asarray(R, float), np.asarray(gravity_B, float))
        return np.cross(np.asarray(self.point_A_m, float), self.mass_kg * g_A)


def default_load_set(rig: Rig) -> list[Load]:
    """Masses ``DEFAULT_MASSES_KG`` at +-x, +-y, radius ``DEFAULT_RADIUS_SHARE`` x the platform holes'.

    Parameters
    ----------
    rig : Rig

    Returns
    -------
    list of Load
    """
    A = np.asarray(rig.platform_holes_A_m, float)
    r = DEFAULT_RADIUS_SHARE * float(np.mean(np.linalg.norm(A[:, :2], axis=1)))
    z = float(A[:, 2].mean())
    points = {"+x": (r, 0.0, z), "-x": (-r, 0.0, z), "+y": (0.0, r, z), "-y": (0.0, -r, z)}
    return [Load(f"{1e3 * m:.0f} g at {k}", m, p) for m in DEFAULT_MASSES_KG for k, p in points.items()]


def load_load_set(path: str | Path) -> list[Load]:
    """Read a load-set TOML file (format in the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path

    Returns
    -------
    list of Load

    Raises
    ------
    InvalidInput
        Unreadable file, bad TOML, or a load whose keys are missing or wrong (named by index and key).
    """
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidInput(f"{path}: cannot read the load set ({exc})", "loads") from exc
    except tomllib.TOMLDecodeError as exc:
        raise InvalidInput(f"{path}: not valid TOML ({exc})", "loads") from exc
    items = data.get("load")
    if not isinstance(items, list) or not items:
        raise InvalidInput(f"{path}: expected at least one [[load]] table", "load")
    out = []
    for i, item in enumerate(items):
        where = f"{path}: [[load]] #{i + 1}"
        if not isinstance(item, dict):
            raise InvalidInput(f"{where}: expected a table", "load")
        unknown = set(item) - {"name", "mass_kg", "point_A_m"}
        if unknown:
            raise InvalidInput(f"{where}: unknown key(s) {', '.join(sorted(unknown))}", sorted(unknown)[0])
        mass = item.get("mass_kg")
        if not isinstance(mass, (int, float)) or isinstance(mass, bool) or not (0 < mass < np.inf):
            raise InvalidInput(f"{where} key 'mass_kg': expected a positive number (kg), got {mass!r}", "mass_kg")
        point = item.get("point_A_m")
        if not (isinstance(point, list) and len(point) == 3 and all(isinstance(v, (int, float)) for v in point)
                and np.all(np.isfinite(point))):
            raise InvalidInput(f"{where} key 'point_A_m': expected 3 finite numbers (m, in {{A}}), got {point!r}",
                               "point_A_m")
        x, y, z = (float(v) for v in point)
        out.append(Load(str(item.get("name", f"load {i + 1}")), float(mass), (x, y, z)))
    return out
