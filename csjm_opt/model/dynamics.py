"""Dynamic properties of a rig: platform inertia and damping (optional ``[dynamics]`` rig section).

The statics need only geometry, cable stiffness, mass and centre of mass; a
dynamic simulation (:mod:`csjm_opt.control.plants.mujoco`, the MJCF export
:mod:`csjm_opt.model.mjcf`) also needs::

    [dynamics]
    inertia = [Ixx, Iyy, Izz]        # kg m^2 about the COM, axes of {A} (or a 3x3 matrix)
    joint_damping = 0.02             # N m s/rad, viscous friction of the spherical joint
    cable_damping = 0.0              # N s/m, viscous damping along each cable (one value or six)

Every key is optional. Defaults (:data:`DEFAULT_JOINT_DAMPING_NMS_PER_RAD`,
:data:`DEFAULT_CABLE_DAMPING_NS_PER_M`, and for the inertia
:func:`estimate_inertia`):

* **inertia**: the platform's mass spread as a uniform thin disc of the
  platform holes' circle radius ``r``, axis along z of {A}, about the COM:
  ``diag(m r^2/4, m r^2/4, m r^2/2)``. For the paper rig (m = 0.4913 kg,
  r = 0.0580 m) that is ``diag(4.12e-4, 4.12e-4, 8.25e-4)`` kg m^2; with the
  COM 0.081 m from O the inertia about O is about 3.6e-3 kg m^2 for tilt,
  so the first mode is near 10-15 Hz (K of 15-30 N m/rad). It is an estimate
  (the paper gives no inertia); measure it for a real rig.
* **joint damping** 0.02 N m s/rad: about 3 % of critical damping for the
  tilt mode of the paper rig (critical ``2 sqrt(K I_O)`` ~ 0.5-0.65 N m s/rad),
  a lightly damped ball joint.
* **cable damping** 0 N s/m (acts along the cable whether taut or slack in
  MuJoCo, so it is off unless asked for).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..errors import RigFileError

DEFAULT_JOINT_DAMPING_NMS_PER_RAD = 0.02
DEFAULT_CABLE_DAMPING_NS_PER_M = 0.0
_KEYS = ("inertia", "joint_damping", "cable_damping")


def _frozen(value: Any) -> np.ndarray:
    arr = np.array(value, dtype=np.float64)
    arr.setflags(write=False)
    return arr


@dataclasses.dataclass(frozen=True, eq=False)
class Dynamics:
    """Inertia about the COM in {A} (kg m^2, 3x3), joint damping (N m s/rad), cable damping (N s/m).

    Cable damping is one number for every cable (a 0-d array) or one per cable ((m,));
    :meth:`cable_damping_per_cable` gives the (m,) values for an m-cable rig.
    """

    inertia_com_A_kgm2: np.ndarray
    joint_damping_Nms_per_rad: float = DEFAULT_JOINT_DAMPING_NMS_PER_RAD
    cable_damping_Ns_per_m: np.ndarray = dataclasses.field(
        default_factory=lambda: _frozen(np.float64(DEFAULT_CABLE_DAMPING_NS_PER_M)))

    def __post_init__(self) -> None:
        object.__setattr__(self, "inertia_com_A_kgm2", _frozen(_inertia(self.inertia_com_A_kgm2, None)))
        object.__setattr__(self, "cable_damping_Ns_per_m", _frozen(_cable_damping(self.cable_damping_Ns_per_m,
                                                                                   None)))
        d = float(self.joint_damping_Nms_per_rad)
        if not (np.isfinite(d) and d >= 0):
            raise RigFileError(f"joint damping must be finite and >= 0, got {d}", None, "dynamics.joint_damping")
        object.__setattr__(self, "joint_damping_Nms_per_rad", d)

    def cable_damping_per_cable(self, n_cables: int) -> np.ndarray:
        """Cable damping (N s/m) of each of ``n_cables`` cables, shape (n_cables,).

        Raises
        ------
        RigFileError
            If per-cable values were given for a different number of cables.
        """
        c = self.cable_damping_Ns_per_m
        if c.ndim == 1 and c.shape[0] != n_cables:
            raise RigFileError(f"expected a number or {n_cables} numbers (one per cable), got {c.shape[0]}",
                               None, "dynamics.cable_damping")
        return np.broadcast_to(c, (n_cables,)).copy()

    def inertia_about_O_A_kgm2(self, mass_kg: float, com_A_m: np.ndarray) -> np.ndarray:
        """Inertia about the joint centre O in {A}: ``I_com + m (|r|^2 I - r r^T)`` (parallel axes)."""
        r = np.asarray(com_A_m, float)
        return self.inertia_com_A_kgm2 + mass_kg * (r @ r * np.eye(3) - np.outer(r, r))

    def as_dict(self) -> dict[str, Any]:
        """The ``[dynamics]`` table (plain numbers; principal values when the inertia is diagonal)."""
        inertia = self.inertia_com_A_kgm2
        diag = np.allclose(inertia, np.diag(np.diag(inertia)), rtol=0, atol=0)
        c = self.cable_damping_Ns_per_m
        return {"inertia": (np.diag(inertia) if diag else inertia).tolist(),
                "joint_damping": self.joint_damping_Nms_per_rad,
                "cable_damping": float(c.ravel()[0]) if np.all(c == c.ravel()[0]) else c.tolist()}

    @classmethod
    def from_dict(cls, table: Any, rig_defaults: "Dynamics", path: str | None = None) -> "Dynamics":
        """Parse a ``[dynamics]`` table; missing keys take ``rig_defaults``; errors name the key."""
        if not isinstance(table, dict):
            raise RigFileError(f"expected a table, got {type(table).__name__}", path, "dynamics")
        for key in table:
            if key not in _KEYS:
                raise RigFileError(f"unknown key (expected one of {sorted(_KEYS)})", path, f"dynamics.{key}")
        inertia = _inertia(table["inertia"], path) if "inertia" in table else rig_defaults.inertia_com_A_kgm2
        cable = (_cable_damping(table["cable_damping"], path) if "cable_damping" in table
                 else rig_defaults.cable_damping_Ns_per_m)
        joint = table.get("joint_damping", rig_defaults.joint_damping_Nms_per_rad)
        if isinstance(joint, bool) or not isinstance(joint, (int, float)) or not (np.isfinite(joint) and joint >= 0):
            raise RigFileError(f"expected a finite number >= 0, got {joint!r:.60}", path, "dynamics.joint_damping")
        return cls(inertia, float(joint), cable)


def estimate_inertia(mass_kg: float, platform_holes_A_m: np.ndarray) -> np.ndarray:
    """Uniform thin disc of the holes' mean radius about z of {A}: ``diag(m r^2/4, m r^2/4, m r^2/2)``."""
    r = float(np.mean(np.linalg.norm(np.asarray(platform_holes_A_m, float)[:, :2], axis=1)))
    return np.diag([mass_kg * r * r / 4, mass_kg * r * r / 4, mass_kg * r * r / 2])


def default_dynamics(mass_kg: float, platform_holes_A_m: np.ndarray) -> Dynamics:
    """The documented defaults for a rig without a ``[dynamics]`` section."""
    return Dynamics(estimate_inertia(mass_kg, platform_holes_A_m))


def rig_dynamics(rig: Any) -> Dynamics:
    """``rig.dynamics`` when the rig file gave one, else :func:`default_dynamics`."""
    dyn = getattr(rig, "dynamics", None)
    return dyn if dyn is not None else default_dynamics(rig.platform_mass_kg, rig.platform_holes_A_m)


def _numbers(value: Any) -> bool:
    if isinstance(value, list):
        return all(_numbers(v) for v in value)
    return not isinstance(value, bool) and isinstance(value, (int, float, np.floating, np.integer))


def _inertia(value: Any, path: str | None) -> np.ndarray:
    key = "dynamics.inertia"
    if not (_numbers(value) or isinstance(value, np.ndarray)):
        raise RigFileError(f"expected numbers, got {value!r:.60}", path, key)
    try:
        arr = np.array(value, dtype=float)
    except ValueError:
        raise RigFileError("expected 3 principal values or a 3x3 matrix, got ragged rows", path, key) from None
    if arr.shape == (3,):
        arr = np.diag(arr)
    if arr.shape != (3, 3):
        raise RigFileError(f"expected 3 principal values or a 3x3 matrix, got shape {arr.shape}", path, key)
    if not np.all(np.isfinite(arr)):
        raise RigFileError("expected finite numbers (no nan or inf)", path, key)
    if not np.allclose(arr, arr.T, rtol=1e-12, atol=1e-15):
        raise RigFileError("inertia matrix must be symmetric", path, key)
    lam = np.linalg.eigvalsh(arr)
    if lam[0] <= 0 or lam[0] + lam[1] < lam[2] * (1 - 1e-9):
        raise RigFileError(f"inertia must be positive definite and satisfy the triangle inequality, "
                           f"principal values {lam.tolist()}", path, key)
    return arr


def _cable_damping(value: Any, path: str | None) -> np.ndarray:
    key = "dynamics.cable_damping"
    if not (_numbers(value) or isinstance(value, np.ndarray)):
        raise RigFileError(f"expected a number or one number per cable, got {value!r:.60}", path, key)
    arr = np.array(value, dtype=float)
    if arr.ndim > 1 or arr.size == 0:
        raise RigFileError(f"expected a number or one number per cable, got shape {arr.shape}", path, key)
    if not np.all(np.isfinite(arr)) or np.any(arr < 0):
        raise RigFileError(f"expected finite numbers >= 0, got {arr.tolist()}", path, key)
    return arr
