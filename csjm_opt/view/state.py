"""The numbers a view shows at one pose: planned tensions, K and its eigen-decomposition, or why not.

Everything here is computed by the toolkit (:func:`csjm_opt.planning.planner.plan_tensions`,
:func:`csjm_opt.model.stiffness.stiffness`); the page only displays it. A pose and load the rig
cannot hold is not an error: :func:`rig_state` returns the tensions within the bounds that come
nearest to holding it (bounded least squares on ``J^T T + tau_load``), the cables those tensions
leave at a bound, and the moment left over.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_rotation, as_vector3
from ..errors import InfeasibleLoad
from ..model.joint_stiffness import stiffness
from ..model.numeric import model_for
from ..model.rig import Rig
from ..planning.planner import plan_tensions

__all__ = ["RigState", "rig_state"]


@dataclasses.dataclass(frozen=True, eq=False)
class RigState:
    """One rig at one pose under one load, with the toolkit's numbers.

    Attributes
    ----------
    rig : Rig
    R : (3, 3) orientation of {A} in {B}.
    tau_ext_A_Nm : (3,) external moment in {A} (N m), weight excluded.
    tensions_N : (m,) planned tensions; when the load cannot be held, the tensions within
        ``[t_min, t_max]`` nearest to holding it.
    feasible : whether the planner holds the load.
    K : (3, 3) stiffness (N m/rad) at the planned tensions, or ``None`` when not feasible.
    eigenvalues_Nm_per_rad, eigenvectors_A : K's eigenvalues (ascending) and eigenvectors
        (columns, in {A}), or ``None``.
    residual_Nm : ``||J^T T + tau_load||`` of the tensions shown (0 to round-off when feasible).
    at_bounds : cable index (0-based) -> ``"t_min"`` or ``"t_max"`` for cables at a bound.
    label : a short name of the pose (shown on the page).
    """

    rig: Rig
    R: np.ndarray
    tau_ext_A_Nm: np.ndarray
    tensions_N: np.ndarray
    feasible: bool
    K: np.ndarray | None
    eigenvalues_Nm_per_rad: np.ndarray | None
    eigenvectors_A: np.ndarray | None
    residual_Nm: float
    at_bounds: dict[int, str]
    label: str = ""

    @property
    def n_cables(self) -> int:
        """Number of cables m (rows of the rig's hole arrays)."""
        return int(len(self.rig.platform_holes_A_m))

    @property
    def message(self) -> str:
        """One sentence: held (with the bounds in use) or which cables cannot hold the load."""
        hit = ", ".join(f"{i + 1} ({b})" for i, b in sorted(self.at_bounds.items()))
        if self.feasible:
            return "Held within the tension bounds" + (f"; cables at a bound: {hit}." if hit else ".")
        return (f"NOT held: no tensions within [{self.rig.t_min_N:g}, {self.rig.t_max_N:g}] N hold this load at "
                f"this pose. Nearest tensions leave {self.residual_Nm:.3g} N m unbalanced, with cables "
                f"{hit or 'none'} at their bounds: these cannot pull harder (t_max) or less (t_min).")


def _at_bounds(T: np.ndarray, lo: float, hi: float) -> dict[int, str]:
    tol = 1e-6 * max(1.0, hi)
    out: dict[int, str] = {}
    for i, t in enumerate(T):
        if abs(t - lo) <= tol:
            out[i] = "t_min"
        elif abs(t - hi) <= tol:
            out[i] = "t_max"
    return out


def rig_state(rig: Rig, R: ArrayLike, tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0), label: str = "") -> RigState:
    """The planned tensions and K of ``rig`` at ``R`` under ``tau_ext``, or the nearest tensions if not held.

    Parameters
    ----------
    rig : Rig
        The rig (any number of cables).
    R : (3, 3) array
        Orientation of {A} in {B}.
    tau_ext_A_Nm : (3,) array
        External moment about O in {A} (N m), platform weight excluded.
    label : str
        Name of the pose shown on the page.

    Returns
    -------
    RigState
        Tensions (planned, or nearest within bounds), K and its eigen-decomposition when held.

    Raises
    ------
    InvalidInput, NotARotation
        Bad shapes, non-finite numbers, not a rotation.
    """
    R = as_rotation(R)
    tau = as_vector3(tau_ext_A_Nm, "tau_ext")
    lo, hi = rig.t_min_N, rig.t_max_N
    try:
        plan = plan_tensions(rig, R, tau)
    except InfeasibleLoad:
        from scipy.optimize import lsq_linear  # only for a load the rig cannot hold

        _, J, tau_w = model_for(rig).pose_terms(R)
        b = -(tau + tau_w)
        T = np.clip(lsq_linear(J.T, b, bounds=(lo, hi), method="bvls", tol=1e-14).x, lo, hi)
        return RigState(rig, R, tau, T, False, None, None, None, float(np.linalg.norm(J.T @ T - b)),
                        _at_bounds(T, lo, hi), label)
    T = np.asarray(plan.tensions_N, float)
    K = stiffness(rig, R, T)
    w, V = np.linalg.eigh(0.5 * (K + K.T))
    return RigState(rig, R, tau, T, True, K, w, V, plan.equilibrium_residual_Nm, _at_bounds(T, lo, hi), label)
