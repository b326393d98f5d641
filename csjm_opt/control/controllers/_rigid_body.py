"""The platform as a rigid body on a ball joint: the inverse-dynamics moment of a reference motion."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ...model.cable_terms import CableTerms
from ...model.dynamics import Dynamics, rig_dynamics
from ...model.rig import Rig
from .reference import reference_rates


class RigidBody:
    """Euler's equation about O in {A}: ``I_O omega_dot + omega x I_O omega + D omega = moments``.

    ``I_O`` is the inertia about O (parallel axes from the COM inertia),
    ``D = c_joint I + J^T diag(b) J`` the joint and cable damping (a cable
    lengthens at ``dc_i/dt = -J_i omega``, so its damper pulls ``-b_i dc_i/dt``).
    """

    def __init__(self, rig: Rig, dynamics: Dynamics | None = None):
        dyn = dynamics or rig_dynamics(rig)
        self.I_O = dyn.inertia_about_O_A_kgm2(rig.platform_mass_kg, rig.com_A_m)
        self.c_joint = dyn.joint_damping_Nms_per_rad
        self.b_cable = dyn.cable_damping_per_cable(rig.n_cables)
        self._terms = CableTerms.from_rig(rig)

    def moment(self, R: np.ndarray, omega: np.ndarray, omega_dot: np.ndarray) -> np.ndarray:
        """``I_O omega_dot + omega x I_O omega + D omega`` (N m, {A}) at pose ``R``."""
        Iw = self.I_O @ omega
        tau = self.I_O @ omega_dot + _cross3(omega, Iw) + self.c_joint * omega
        if np.any(self.b_cable):
            J = self._terms.geometry(R)[2]
            tau = tau + J.T @ (self.b_cable * (J @ omega))
        return tau

    def reference_moment(self, R_ref: Callable[[float], np.ndarray] | np.ndarray, t_s: float) -> np.ndarray:
        """The inverse-dynamics moment of the reference at ``t_s`` (zero for a fixed pose)."""
        if not callable(R_ref):
            return np.zeros(3)
        return self.moment(*reference_rates(R_ref, t_s))


def _cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` for two 3-vectors (np.cross costs ~20x more for one pair)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
