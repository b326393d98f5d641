"""A controller that plans with the generated C library: :class:`CTensionPlanningController`.

The drop-in twin of :class:`csjm_opt.control.controllers.TensionPlanningController`: the same
pose holding (reference, integral correction), with tensions and rest lengths from the C
planner (:func:`csjm_opt.codegen.load`), warm-started from the previous step's active set as a
real-time loop would run it.
"""

from __future__ import annotations

import numpy as np

from ..control.controllers.base import Observation, PoseHoldingController, PoseReference
from ..errors import InvalidInput
from ..model.rig import Rig
from .bindings import CPlanner
from .generate import rig_fingerprint

__all__ = ["CTensionPlanningController"]


class CTensionPlanningController(PoseHoldingController):
    """Tensions from the C planner (min ``||T - t_ref||`` holding the measured load).

    Parameters
    ----------
    rig : Rig
        The rig the library was generated from (checked by its fingerprint).
    planner : CPlanner
        The loaded library.
    R_ref : ndarray, shape (3, 3), or callable
        Fixed orientation of {A} in {B}, or a function of time (s) returning one.
    t_ref_N : ndarray, shape (m,), optional
        Reference tensions (N); default mid-range.
    integral_gain : float, optional
        Integral pose correction (as :class:`PoseHoldingController`).
    warm_start : bool, optional
        Warm-start each step from the previous one's active set.

    Raises
    ------
    InvalidInput
        The library was generated from another rig.
    """

    def __init__(self, rig: Rig, planner: CPlanner, R_ref: PoseReference, t_ref_N: np.ndarray | None = None,
                 integral_gain: float = 0.0, warm_start: bool = True):
        super().__init__(rig, R_ref, integral_gain)
        if planner.rig_sha256 != rig_fingerprint(rig):
            raise InvalidInput(f"{planner.path} was generated from another rig (fingerprint "
                               f"{planner.rig_sha256[:12]}, this rig {rig_fingerprint(rig)[:12]})", "planner")
        self.planner = planner
        self.t_ref_N = t_ref_N
        self.warm_start = warm_start
        self._rest_m = np.zeros(rig.n_cables)

    def reset(self) -> None:
        """Forget the integral state and the warm start."""
        super().reset()
        self.planner.reset_warm_start()

    def tensions(self, R_cmd: np.ndarray, observation: Observation):
        """Tensions planned in C at ``R_cmd`` for the measured load (no stiffness target).

        Parameters
        ----------
        R_cmd : ndarray, shape (3, 3)
            Commanded orientation of {A} in {B}.
        observation : Observation
            The step's measurements (its ``tau_ext_A_Nm`` is held).

        Returns
        -------
        tuple
            ``(tensions_N, None, None)``: the (m,) tensions (N), no target K and no planned K.

        Raises
        ------
        InfeasibleLoad
            No tensions within the bounds hold the measured load.
        SolverError
            The C planner reached its iteration cap.
        """
        plan = self.planner.plan_tensions(R_cmd, observation.tau_ext_A_Nm, self.t_ref_N, warm_start=self.warm_start)
        self._rest_m = plan.rest_lengths_m
        return plan.tensions_N, None, None

    def rest_lengths(self, R_cmd: np.ndarray, tensions_N: np.ndarray) -> np.ndarray:
        """The rest lengths the C planner computed with the tensions (``l = c - T / k``).

        Parameters
        ----------
        R_cmd, tensions_N : ndarray
            The pose and tensions of this step's plan (unused: the plan's rest lengths are kept).

        Returns
        -------
        ndarray, shape (m,)
            Rest lengths (m).
        """
        return self._rest_m.copy()
