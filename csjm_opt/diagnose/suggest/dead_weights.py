"""The load set of a lab: the dead weights it can hang on the platform (for suggested experiments).

A small TOML file, one table per load::

    # loads.toml: masses (kg) hung at points of the platform (m, in {A})
    [[load]]
    name = "200 g at +x"
    mass_kg = 0.2
    point_A_m = [0.05, 0.0, 0.0]

The external moment of a load depends on the pose: ``tau_ext = point x (R^T m g_B)`` (in
{A}, the weight fixed in {B}). Without a file, :func:`default_dead_weights` gives masses of
0.1, 0.2 and 0.5 kg at four points (+-x, +-y) in the platform's hole plane, at 0.8 of the
holes' radius: what any lab with a set of calibration weights has; ``--suggest`` asks for
masses that reach the largest moment the log already applied (the lab has shown it can).
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np

from ...errors import InvalidInput
from ...model.rig import Rig

#: Default masses (kg) and the share of the platform-hole radius at which they hang.
DEFAULT_MASSES_KG = (0.1, 0.2, 0.5)
DEFAULT_RADIUS_SHARE = 0.8
#: With a moment to reach: masses at these shares of the one that reaches it.
REACH_SHARES = (1 / 3, 2 / 3, 1.0)


@dataclasses.dataclass(frozen=True)
class DeadWeight:
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


def default_dead_weights(rig: Rig, reach_Nm: float | None = None) -> list[DeadWeight]:
    """Masses hung at +-x, +-y, radius ``DEFAULT_RADIUS_SHARE`` x the platform holes'.

    Without ``reach_Nm`` the masses are ``DEFAULT_MASSES_KG``. With it (the largest external moment
    the lab already applied, e.g. in the log being diagnosed) the masses are ``REACH_SHARES`` of the
    mass that exerts ``reach_Nm`` at that radius with the lever horizontal: a lab that applied a moment
    can apply it again, and load-dependent effects (compliance, hardening, friction) show in
    proportion to the load, so rows with a tenth of the log's moments tell them apart poorly.

    Parameters
    ----------
    rig : Rig
    reach_Nm : float, optional
        Largest external moment to reach (N m).

    Returns
    -------
    list of DeadWeight
    """
    A = np.asarray(rig.platform_holes_A_m, float)
    r = DEFAULT_RADIUS_SHARE * float(np.mean(np.linalg.norm(A[:, :2], axis=1)))
    z = float(A[:, 2].mean())
    points = {"+x": (r, 0.0, z), "-x": (-r, 0.0, z), "+y": (0.0, r, z), "-y": (0.0, -r, z)}
    masses: tuple[float, ...] = DEFAULT_MASSES_KG
    if reach_Nm is not None and np.isfinite(reach_Nm) and reach_Nm > 0:
        top = float(reach_Nm) / (r * float(np.linalg.norm(rig.gravity_B_m_per_s2)))
        masses = tuple(max(top * s, DEFAULT_MASSES_KG[0]) for s in REACH_SHARES)
    return [DeadWeight(f"{1e3 * m:.0f} g at {k}", m, p) for m in masses for k, p in points.items()]


def read_dead_weights(path: str | Path) -> list[DeadWeight]:
    """Read a load-set TOML file (format in the module docstring).

    Parameters
    ----------
    path : str or pathlib.Path

    Returns
    -------
    list of DeadWeight

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
        out.append(DeadWeight(str(item.get("name", f"load {i + 1}")), float(mass), (x, y, z)))
    return out
