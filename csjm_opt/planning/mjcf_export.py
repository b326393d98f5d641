"""The MuJoCo model of a rig with rest lengths planned for a pose and a load.

:func:`csjm_opt.model.mjcf.rig_to_mjcf` writes the engine model for any rest
lengths; :func:`export_mjcf` first plans the tensions that hold the pose (this
layer's planner) and converts them to rest lengths.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_rotation, as_vector3
from ..model.mjcf import rig_to_mjcf
from ..model.rig import Rig
from ..model.statics import rest_lengths_for
from .planner import plan_tensions


def export_mjcf(rig: Rig, R: np.ndarray | None = None, tau_ext_A_Nm: np.ndarray | None = None,
                actuation: str = "spring", **options) -> str:
    """MJCF of ``rig`` with rest lengths (or tensions) planned for pose ``R`` and load ``tau_ext_A_Nm``.

    Plans the tensions with :func:`csjm_opt.plan_tensions` (mid-range
    reference), converts them to rest lengths ``l = c(R) - T/k`` and calls
    :func:`rig_to_mjcf`.

    Parameters
    ----------
    rig : Rig
    R : (3, 3) array, optional
        Pose (identity by default).
    tau_ext_A_Nm : (3,) array, optional
        External moment fixed in {A} (N m), weight excluded.
    actuation : {"spring", "winch", "tension"}
    **options
        Passed to :func:`rig_to_mjcf` (``timestep_s``, ``integrator``, ``joint_damping_Nms_per_rad``, ...).

    Returns
    -------
    str
        The MJCF document; at its keyframe MuJoCo is in equilibrium at ``R``.

    Raises
    ------
    InfeasibleLoad
        No tensions within the bounds hold the load at ``R``.
    NotARotation, InvalidInput
        Bad ``R`` or ``tau_ext_A_Nm``.
    """
    R = np.eye(3) if R is None else as_rotation(R, "R")
    tau = np.zeros(3) if tau_ext_A_Nm is None else as_vector3(tau_ext_A_Nm, "tau_ext")
    plan = plan_tensions(rig, R, tau)
    l = rest_lengths_for(rig, R, plan.tensions_N)
    return rig_to_mjcf(rig, l, R, tau, plan.tensions_N, actuation, **options)
