"""Stiffness shaping: hold the pose with tensions that bring K closest to a (time-varying) target."""

from __future__ import annotations

from typing import Callable, Union

import numpy as np

from ..._validate import as_array
from ...model.dynamics import Dynamics
from ...model.rig import Rig
from ...shaping.shaper import REGULARIZATION, Shaper, StiffnessObjective, make_objective
from ._rigid_body import RigidBody
from .base import Observation, PoseHoldingController, PoseReference
from .reference import MemoReference

#: A stiffness target: a fixed (3, 3) matrix (N m/rad) or a function of time returning one.
StiffnessReference = Union[np.ndarray, Callable[[float], np.ndarray]]


class StiffnessShapingController(PoseHoldingController):
    """Shapes K toward ``K_target`` (see :func:`csjm_opt.shape_stiffness`) at every step.

    Uses the loop form :class:`csjm_opt.shaping.shaper.Shaper`: the stiffness basis is
    reused while the commanded pose is unchanged and the exact active-set QP
    is warm-started from the previous step, so a step costs tens of
    microseconds. ``objective``/``weights``/``directions`` as in
    :func:`csjm_opt.shaping.shaper.make_objective`.

    With ``feedforward=True`` the load held also carries the inverse-dynamics
    moment of the reference (as in
    :class:`~csjm_opt.control.controllers.InverseDynamicsController`, inertia
    from ``dynamics`` or the rig), and ``lookahead_s`` plans for the
    reference that far ahead (one control period suits a plant with
    inertia; 0 keeps the quasi-static behaviour). ``use_measured_load=False``
    ignores the measured external moment.
    """

    def __init__(self, rig: Rig, R_ref: PoseReference, K_target: StiffnessReference,
                 weights: np.ndarray | None = None, objective: str = "frobenius",
                 directions: np.ndarray | None = None, integral_gain: float = 0.0,
                 regularization: float = REGULARIZATION, feedforward: bool = False,
                 lookahead_s: float = 0.0, use_measured_load: bool = True, dynamics: Dynamics | None = None):
        super().__init__(rig, MemoReference(R_ref) if callable(R_ref) else R_ref, integral_gain)
        self.feedforward, self.lookahead_s, self.use_measured_load = feedforward, float(lookahead_s), use_measured_load
        self.body = RigidBody(rig, dynamics)
        self._K_target = K_target if callable(K_target) else as_array(K_target, (3, 3), "K_target")
        self._objective_args = (weights, objective, directions)
        self._shaper = Shaper(rig, regularization)
        self._cache: tuple[np.ndarray, StiffnessObjective] | None = None
        self._last_T: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the integral correction, the shaper's warm start and the last tensions."""
        super().reset()
        self._shaper = Shaper(self.rig, self._shaper.regularization)
        self._last_T = None

    def target(self, time_s: float) -> np.ndarray:
        """The target stiffness at ``time_s`` (N m/rad; the fixed target, or the callable evaluated).

        Parameters
        ----------
        time_s : float
            Time (s).

        Returns
        -------
        (3, 3) array
            Target K (N m/rad).
        """
        return self._K_target(time_s) if callable(self._K_target) else self._K_target

    def _objective(self, K_target: np.ndarray) -> StiffnessObjective:
        if self._cache is None or not np.array_equal(self._cache[0], K_target):
            self._cache = (np.array(K_target, float), make_objective(K_target, *self._objective_args))
        return self._cache[1]

    def commanded_pose(self, observation: Observation) -> np.ndarray:
        """The pose to plan for, taken ``lookahead_s`` ahead of the observation time when set.

        Parameters
        ----------
        observation : Observation
            The measurement of this step.

        Returns
        -------
        (3, 3) array
            Commanded pose of {A} in {B}.
        """
        if not self.lookahead_s:
            return super().commanded_pose(observation)
        return super().commanded_pose(Observation(observation.time_s + self.lookahead_s, observation.R,
                                                  observation.tau_ext_A_Nm, observation.omega_A_rad_s))

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
            ``(tensions_N, K_target, K_planned)``: (m,) tensions (N), then the target K and the
            K the tensions give (N m/rad).

        Raises
        ------
        InfeasibleLoad
            No tensions within the bounds hold the load at ``R_cmd``.
        """
        K_target = self.target(observation.time_s)
        tau = np.array(observation.tau_ext_A_Nm, float) if self.use_measured_load else np.zeros(3)
        if self.feedforward:
            tau -= self.body.reference_moment(self._R_ref, observation.time_s + self.lookahead_s)
        T, basis, _ = self._shaper.solve(R_cmd, tau, self._objective(K_target))
        self._last_T = T
        return T, np.asarray(K_target, float), basis.K(T)
