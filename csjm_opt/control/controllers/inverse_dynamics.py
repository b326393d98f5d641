"""Tension planning with the inverse-dynamics moment of the reference trajectory (feedforward)."""

from __future__ import annotations

import numpy as np

from ...model.dynamics import Dynamics
from ...model.rig import Rig
from ._rigid_body import RigidBody
from ._tensions import TensionQP
from .base import Observation, PoseHoldingController, PoseReference
from .reference import MemoReference


class InverseDynamicsController(PoseHoldingController):
    """Plans tensions for the reference pose under the load plus the inertial moment.

    The platform obeys ``I_O omega_dot + omega x I_O omega + D omega = J^T T +
    tau_weight + tau_ext`` (Euler's equation about O in {A}, ``I_O`` the
    inertia about O, ``D = c_joint I + J^T diag(b) J`` the joint and cable
    damping; a cable lengthens at ``dc_i/dt = -J_i omega``). To follow
    ``R_ref(t)`` the cables must supply the inverse-dynamics moment
    ``tau_id = I_O omega_dot_ref + omega_ref x I_O omega_ref + D omega_ref`` on top
    of holding the load, so the tensions are planned
    (:class:`~csjm_opt.control.controllers._tensions.TensionQP`) for the
    external moment ``tau_ext - tau_id`` at ``R_ref(t + lookahead_s)``; ``lookahead_s`` (one control period by
    default) puts the plan at the end of the period over which the drives
    ramp to it.

    Parameters
    ----------
    rig : Rig
    R_ref : rotation or callable
        Reference pose (fixed or ``t -> R``).
    dynamics : Dynamics, optional
        Inertia used by the model (default :func:`~csjm_opt.model.dynamics.rig_dynamics`).
    lookahead_s : float
        Plan for the reference this far ahead (s).
    use_measured_load : bool
        Hold the measured external moment (an F/T sensor); ``False`` treats it as unknown (zero).
    feedforward : bool
        Add the inverse-dynamics moment (``False``: plain planning for the target pose).
    t_ref_N : array, optional
        Reference tensions of the QP (default mid-range).
    integral_gain : float
        Integral pose correction of :class:`PoseHoldingController`.
    """

    def __init__(self, rig: Rig, R_ref: PoseReference, dynamics: Dynamics | None = None,
                 lookahead_s: float = 1e-3, use_measured_load: bool = True, feedforward: bool = True,
                 t_ref_N: np.ndarray | None = None, integral_gain: float = 0.0):
        super().__init__(rig, MemoReference(R_ref) if callable(R_ref) else R_ref, integral_gain)
        self.body = RigidBody(rig, dynamics)
        self.lookahead_s = float(lookahead_s)
        self.use_measured_load, self.feedforward = use_measured_load, feedforward
        self._qp = TensionQP(rig, t_ref_N)

    def reset(self) -> None:
        """Forget the integral correction and the QP's warm start."""
        super().reset()
        self._qp = TensionQP(self.rig, self._qp.t_ref)

    def inverse_dynamics_moment(self, t_s: float) -> np.ndarray:
        """``tau_id = I_O omega_dot_ref + omega_ref x I_O omega_ref + D omega_ref`` at ``t_s`` (N m, {A})."""
        return self.body.reference_moment(self._R_ref, t_s)

    def commanded_pose(self, observation: Observation) -> np.ndarray:
        """The pose to plan for, taken ``lookahead_s`` ahead of the observation time.

        Parameters
        ----------
        observation : Observation
            The measurement of this step.

        Returns
        -------
        (3, 3) array
            Commanded pose of {A} in {B}.
        """
        shifted = Observation(observation.time_s + self.lookahead_s, observation.R, observation.tau_ext_A_Nm,
                              observation.omega_A_rad_s)
        return super().commanded_pose(shifted)

    def planned_load(self, observation: Observation) -> np.ndarray:
        """External moment the tensions are planned for (N m, {A})."""
        tau = np.array(observation.tau_ext_A_Nm, float) if self.use_measured_load else np.zeros(3)
        if self.feedforward:
            tau -= self.inverse_dynamics_moment(observation.time_s + self.lookahead_s)
        return tau

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
        return self._qp(R_cmd, self.planned_load(observation)), None, None
