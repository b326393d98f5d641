"""What a perturbation experiment in a physics engine measures, and how to get K from it.

Perturb the platform at a static equilibrium, ``R exp(hat(zeta))``, and read
the net moment ``Q`` on it (in {A}; in MuJoCo ``qfrc_smooth`` of the ball
joint). The measured tangent stiffness ``-dQ/dzeta`` is **not** the cable
stiffness ``K`` of the load convention (docs/conventions.md) but::

    -dQ/dzeta = K + H_weight + s/2 hat(tau_ext)

* ``H_weight = (f_A . r) I - 1/2 (f_A r^T + r f_A^T)``, ``f_A = R^T m g``,
  ``r`` the COM in {A}: the Hessian of the weight's potential (symmetric);
* ``s = +1`` when the external moment is fixed in {A} (turns with the
  platform, like this package's ``tau_ext``), ``s = -1`` when it is fixed in
  the world {B} (a constant torque in the engine's world frame, e.g. MuJoCo's
  ``xfrc_applied``).

Both signs were checked against MuJoCo to 1e-10 (``tests/testbed/mujoco/test_reference.py``).
Dead weights fixed in {B} at other points add their own ``H`` like the weight.
"""

from __future__ import annotations

import numpy as np

from .. import so3
from .cable_terms import point_force_terms
from .rig import Rig

LOAD_FRAMES = ("A", "B")


def weight_hessian(rig: Rig, R: np.ndarray) -> np.ndarray:
    """``H_weight`` (3, 3), N m/rad, at ``R``."""
    return point_force_terms(np.asarray(R, float), rig.weight_B_N.reshape(1, 3), rig.com_A_m.reshape(1, 3))[1]


def engine_stiffness(rig: Rig, R: np.ndarray, K: np.ndarray, tau_ext_A_Nm: np.ndarray,
                     load_fixed_in: str = "A") -> np.ndarray:
    """``-dQ/dzeta`` a perturbation in an engine measures, from the cable stiffness ``K``.

    Parameters
    ----------
    rig : Rig
    R : (3, 3) array
        Equilibrium pose.
    K : (3, 3) array
        Cable stiffness (load convention, docs/conventions.md), e.g. :attr:`Equilibrium.K`.
    tau_ext_A_Nm : (3,) array
        External moment at the equilibrium, in {A}.
    load_fixed_in : {"A", "B"}
        Whether the external moment turns with the platform ("A") or is fixed in the world ("B").

    Returns
    -------
    (3, 3) array
    """
    s = _sign(load_fixed_in)
    return np.asarray(K, float) + weight_hessian(rig, R) + 0.5 * s * so3.hat(np.asarray(tau_ext_A_Nm, float))


def stiffness_from_engine(rig: Rig, R: np.ndarray, K_measured: np.ndarray, tau_ext_A_Nm: np.ndarray,
                          load_fixed_in: str = "A") -> np.ndarray:
    """The cable stiffness ``K`` from a measured ``-dQ/dzeta`` (inverse of :func:`engine_stiffness`)."""
    return np.asarray(K_measured, float) - (engine_stiffness(rig, R, np.zeros((3, 3)), tau_ext_A_Nm,
                                                             load_fixed_in))


def _sign(load_fixed_in: str) -> float:
    if load_fixed_in not in LOAD_FRAMES:
        from ..errors import InvalidInput

        raise InvalidInput(f"load_fixed_in must be 'A' (platform) or 'B' (world), got {load_fixed_in!r}",
                           "load_fixed_in")
    return 1.0 if load_fixed_in == "A" else -1.0
