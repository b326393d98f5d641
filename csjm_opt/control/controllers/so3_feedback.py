"""Orientation feedback on SO(3): PID on the rotation error, on top of the inverse-dynamics plan."""

from __future__ import annotations

import numpy as np

from ...model.dynamics import Dynamics
from ...model.rig import Rig
from ..loop_kernels import log_so3
from .base import Observation, PoseReference
from .inverse_dynamics import InverseDynamicsController
from .reference import reference_rates


class SO3FeedbackController(InverseDynamicsController):
    """Inverse-dynamics feedforward plus a feedback moment from the measured pose error.

    With the body-frame error ``e = log(R^T R_ref)`` (``= -log(R_ref^T R)``,
    rad, in {A}) and the rate error ``omega_ref - omega``::

        tau_fb = Kp e + Kd (omega_ref - omega) + Ki integral(e dt)

    (N m) is added to the moment the cables must supply, i.e. the tensions are
    planned for the external moment ``tau_planned - tau_fb``. The cables'
    own stiffness ``K`` acts in parallel. ``omega`` is the measured angular
    velocity when the observation has one, else a finite difference of the
    measured poses. The integral (``ki > 0``) removes the steady error of an
    unknown constant moment. Gains are scalars or (3, 3) matrices.
    """

    def __init__(self, rig: Rig, R_ref: PoseReference, kp: float | np.ndarray = 20.0,
                 kd: float | np.ndarray = 0.3, ki: float | np.ndarray = 200.0,
                 dynamics: Dynamics | None = None, lookahead_s: float = 1e-3, use_measured_load: bool = True,
                 feedforward: bool = True, t_ref_N: np.ndarray | None = None, integral_limit_Nm: float = 5.0):
        super().__init__(rig, R_ref, dynamics, lookahead_s, use_measured_load, feedforward, t_ref_N)
        self.kp, self.kd, self.ki = (np.asarray(g, float) * (np.eye(3) if np.ndim(g) == 0 else 1.0)
                                     for g in (kp, kd, ki))
        self.integral_limit_Nm = float(integral_limit_Nm)
        self.reset()

    def reset(self) -> None:
        """Forget the integral correction, the QP's warm start, the feedback integral and the last pose."""
        super().reset()
        self._integral = np.zeros(3)
        self._last: tuple[float, np.ndarray] | None = None

    def feedback_moment(self, observation: Observation) -> np.ndarray:
        """``tau_fb`` (N m, {A}) for this observation; advances the integrator."""
        t, R = observation.time_s, observation.R
        R_ref, w_ref, _ = reference_rates(self._R_ref, t)
        e = log_so3(np.ascontiguousarray(R.T @ R_ref))
        if observation.omega_A_rad_s is not None:
            w = np.asarray(observation.omega_A_rad_s, float)
        elif self._last is not None and t > self._last[0]:
            w = log_so3(np.ascontiguousarray(self._last[1].T @ R)) / (t - self._last[0])
        else:
            w = w_ref
        if self._last is not None and t > self._last[0]:
            self._integral = self._integral + (t - self._last[0]) * e
            m = self.ki @ self._integral
            n = np.linalg.norm(m)
            if n > self.integral_limit_Nm:               # anti-windup: clamp the integral moment
                self._integral *= self.integral_limit_Nm / n
        self._last = (t, np.array(R, float))
        return self.kp @ e + self.kd @ (w_ref - w) + self.ki @ self._integral

    def planned_load(self, observation: Observation) -> np.ndarray:
        """External moment the tensions are planned for, minus the feedback moment (N m, {A}).

        Advances the feedback integrator (see :meth:`feedback_moment`).

        Parameters
        ----------
        observation : Observation
            The measurement of this step.

        Returns
        -------
        (3,) array
            ``tau_planned - tau_fb`` (N m, in {A}).
        """
        return super().planned_load(observation) - self.feedback_moment(observation)
