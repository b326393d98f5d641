"""Controller interface: observation in, command out.

Conventions (docs/conventions.md): ``R`` is the orientation of {A} in {B}; moments are
in {A} about O; ``tau_ext`` excludes the platform's own weight; SI units.
"""

from __future__ import annotations

import abc
import dataclasses
from typing import Callable, Union

import numpy as np

from ... import so3
from ..._validate import as_rotation
from ...model.numeric import model_for
from ...model.rig import Rig

#: A pose reference: a fixed rotation or a function of time returning one.
PoseReference = Union[np.ndarray, Callable[[float], np.ndarray]]


@dataclasses.dataclass(frozen=True, eq=False)
class Observation:
    """What the controller reads at one step (possibly noisy)."""

    time_s: float
    R: np.ndarray                # (3, 3) measured orientation of {A} in {B}
    tau_ext_A_Nm: np.ndarray     # (3,) measured external moment in {A} (weight excluded)
    omega_A_rad_s: np.ndarray | None = None   # (3,) angular velocity in {A}, when measured


@dataclasses.dataclass(frozen=True, eq=False)
class Command:
    """What the controller sends to the drives.

    ``rest_lengths_m`` is what the drives execute; ``tensions_N`` are the
    tensions the controller expects at ``R_cmd``; ``K_target``/``K_planned``
    (N m/rad) are the requested and the predicted stiffness, ``None`` when the
    controller does not shape stiffness.
    """

    tensions_N: np.ndarray       # (m,)
    rest_lengths_m: np.ndarray   # (m,)
    R_cmd: np.ndarray            # (3, 3) pose the command is planned for
    K_target: np.ndarray | None = None
    K_planned: np.ndarray | None = None

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (N)."""
        return self.tensions_N


class Controller(abc.ABC):
    """Base class: ``reset()`` before a run, then ``command = controller(observation)`` per step."""

    rig: Rig

    def reset(self) -> None:
        """Forget internal state (integrators, warm starts)."""

    @abc.abstractmethod
    def __call__(self, observation: Observation) -> Command:
        """The command for this step."""

    def reference(self, time_s: float) -> np.ndarray:
        """The pose the controller tries to hold at ``time_s`` (for logging); identity by default."""
        return np.eye(3)


class PoseHoldingController(Controller):
    """Holds a pose reference: integral pose correction and rest-length conversion.

    With ``integral_gain`` g > 0 the commanded pose is corrected by the
    accumulated body-frame pose error, ``R_cmd = R_ref exp(hat(z))``,
    ``z <- z + g log(R_meas^T R_ref)``, which removes steady-state error when
    the plant differs from the model. Subclasses implement :meth:`tensions`.
    """

    def __init__(self, rig: Rig, R_ref: PoseReference, integral_gain: float = 0.0):
        self.rig = rig
        self._R_ref = R_ref if callable(R_ref) else as_rotation(R_ref, "R_ref")
        self.integral_gain = float(integral_gain)
        self._model = model_for(rig)   # compiled model-layer kernels
        self._z = np.zeros(3)

    def reset(self) -> None:
        """Forget the accumulated integral pose correction."""
        self._z = np.zeros(3)

    def reference(self, time_s: float) -> np.ndarray:
        """The reference pose at ``time_s`` (the fixed pose, or the callable evaluated).

        Parameters
        ----------
        time_s : float
            Time (s).

        Returns
        -------
        (3, 3) array
            Reference orientation of {A} in {B}.
        """
        return self._R_ref(time_s) if callable(self._R_ref) else self._R_ref

    def commanded_pose(self, observation: Observation) -> np.ndarray:
        """The pose to plan for: the reference, corrected by the integral of the pose error.

        Advances the integrator when ``integral_gain`` > 0.

        Parameters
        ----------
        observation : Observation
            The measurement of this step.

        Returns
        -------
        (3, 3) array
            Commanded pose of {A} in {B}.
        """
        R_ref = self.reference(observation.time_s)
        if self.integral_gain:
            self._z = self._z + self.integral_gain * so3.log(observation.R.T @ R_ref)
            return R_ref @ so3.exp(self._z)
        return R_ref

    def rest_lengths(self, R_cmd: np.ndarray, tensions_N: np.ndarray) -> np.ndarray:
        """``l = c(R_cmd) - T / k`` (m), closed form."""
        return self._model.geometry(R_cmd)[0] - tensions_N / self._model.k

    @abc.abstractmethod
    def tensions(self, R_cmd: np.ndarray, observation: Observation) -> tuple[np.ndarray, np.ndarray | None,
                                                                               np.ndarray | None]:
        """``(tensions, K_target, K_planned)`` holding the measured load at ``R_cmd``."""

    def __call__(self, observation: Observation) -> Command:
        """The command for this step: commanded pose, planned tensions and rest lengths.

        Parameters
        ----------
        observation : Observation
            The measurement of this step.

        Returns
        -------
        Command
            Tensions, rest lengths and the pose they are planned for.

        Raises
        ------
        InfeasibleLoad
            No tensions within the bounds hold the load at the commanded pose.
        """
        R_cmd = self.commanded_pose(observation)
        T, K_target, K_planned = self.tensions(R_cmd, observation)
        return Command(T, self.rest_lengths(R_cmd, T), R_cmd, K_target, K_planned)
