"""Plant interface: reset to a pose, then advance one control period under a command and a load."""

from __future__ import annotations

import abc
import dataclasses
from typing import Callable

import numpy as np

from ...model.rig import Rig

#: A load as a function of time (s) -> moment (3,), N m; in {A} or {B} per ``Plant.load_fixed_in``.
LoadFunction = Callable[[float], np.ndarray]


@dataclasses.dataclass(frozen=True, eq=False)
class PlantState:
    """The true state of the plant at one instant."""

    R: np.ndarray                  # (3, 3) orientation of {A} in {B}
    omega_A_rad_s: np.ndarray      # (3,) angular velocity in {A} (zero for a quasi-static plant)
    tensions_N: np.ndarray         # (m,)
    K: np.ndarray                  # (3, 3) cable stiffness at this state (load convention, docs/conventions.md)
    tau_ext_A_Nm: np.ndarray       # (3,) external moment acting now, in {A}


class Plant(abc.ABC):
    """Base class of the simulated rigs.

    ``load_fixed_in`` is ``"A"`` when the load function gives a moment fixed
    in the platform (the package's ``tau_ext``) and ``"B"`` when it gives a
    moment fixed in the world.
    """

    rig: Rig
    load_fixed_in: str = "A"

    @abc.abstractmethod
    def reset(self, R0: np.ndarray, omega0_A_rad_s: np.ndarray | None = None,
              load: LoadFunction | None = None) -> PlantState:
        """Start at pose ``R0`` (and angular velocity, when the plant has inertia)."""

    @abc.abstractmethod
    def step(self, command, load: LoadFunction, t0_s: float, t1_s: float) -> PlantState:
        """Apply ``command`` (a :class:`~csjm_opt.control.controllers.base.Command`) from ``t0_s`` to ``t1_s``."""

    def measured_load_A(self, R: np.ndarray, tau_ext_A_Nm: np.ndarray) -> np.ndarray:
        """What a force/torque sensor under the platform reads (weight excluded), in {A}."""
        return np.asarray(tau_ext_A_Nm, float)

    def external_moment_A(self, load: LoadFunction, t_s: float, R: np.ndarray) -> np.ndarray:
        """The load at ``t_s`` expressed in {A}."""
        tau = np.asarray(load(t_s), float)
        return tau if self.load_fixed_in == "A" else R.T @ tau
