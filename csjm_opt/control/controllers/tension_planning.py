"""Plain tension planning: hold the pose, tensions closest to a reference (no stiffness shaping)."""

from __future__ import annotations

import numpy as np

from ...model.numeric import Model
from ...model.rig import Rig
from ...planning.planner import plan_tensions
from .base import Observation, PoseHoldingController, PoseReference


class TensionPlanningController(PoseHoldingController):
    """Tensions from :func:`csjm_opt.plan_tensions` (min ``||T - t_ref||`` holding the measured load)."""

    def __init__(self, rig: Rig, R_ref: PoseReference, t_ref_N: np.ndarray | None = None,
                 integral_gain: float = 0.0, solver: str = "active_set"):
        super().__init__(rig, R_ref, integral_gain)
        self.t_ref_N = t_ref_N
        self.solver = solver
        self._model = Model(rig)

    def tensions(self, R_cmd: np.ndarray, observation: Observation):
        """The tensions holding the measured load at ``R_cmd`` (see :meth:`PoseHoldingController.tensions`).

        Parameters
        ----------
        R_cmd : (3, 3) array
            Commanded pose of {A} in {B}.
        observation : Observation
            The measurement of this step.

        Returns
        -------
        tuple
            ``(tensions_N, K_target, K_planned)``: (m,) tensions (N), then ``None, None``
            (no stiffness shaping).

        Raises
        ------
        InfeasibleLoad
            No tensions within the bounds hold the load at ``R_cmd``.
        """
        plan = plan_tensions(self.rig, R_cmd, observation.tau_ext_A_Nm, self.t_ref_N, self.solver, self._model)
        return plan.tensions_N, None, None
