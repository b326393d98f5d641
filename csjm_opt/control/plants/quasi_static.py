"""Quasi-static plant: after every command the platform sits at its static equilibrium."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ...errors import InvalidInput
from ...model.cable_terms import point_force_terms
from ...model.rig import Rig
from ...model.statics import EquilibriumSolver, PointForce
from .base import LoadFunction, Plant, PlantState


class QuasiStaticPlant(Plant):
    """Forward statics (:class:`~csjm_opt.model.statics.EquilibriumSolver`) warm-started from the last pose.

    Dynamics are not modelled: the platform settles within each control
    period at the equilibrium for the commanded rest lengths under the load
    at the period's end. ``point_forces`` are dead weights fixed in {B}
    (``(force_B_N, point_A_m)``); a force/torque sensor under the platform
    sees their moments. Loads are moments fixed in {A} only.
    """

    def __init__(self, rig: Rig, point_forces: Sequence[PointForce] = ()):
        self.rig = rig
        self.load_fixed_in = "A"
        forces = list(point_forces)
        self._solver = EquilibriumSolver(rig, point_forces=forces)
        self._F = np.array([f for f, _ in forces], float).reshape(-1, 3)
        self._P = np.array([p for _, p in forces], float).reshape(-1, 3)
        self._R = np.eye(3)

    def reset(self, R0: np.ndarray, omega0_A_rad_s: np.ndarray | None = None,
              load: LoadFunction | None = None) -> PlantState:
        """Start at pose ``R0`` (see :meth:`Plant.reset`); tensions and K unknown (NaN) until the first step.

        Parameters
        ----------
        R0 : (3, 3) array
            Initial orientation of {A} in {B}.
        omega0_A_rad_s : (3,) array, optional
            Initial angular velocity (rad/s, in {A}); must be zero or ``None``.
        load : callable, optional
            Load function ``t -> moment`` (N m, fixed in the frame ``load_fixed_in``), read at t = 0.

        Returns
        -------
        PlantState
            The state at the start.

        Raises
        ------
        InvalidInput
            A non-zero ``omega0_A_rad_s``.
        """
        if omega0_A_rad_s is not None and np.any(omega0_A_rad_s):
            raise InvalidInput("a quasi-static plant has no velocity; omega0 must be zero", "omega0_A_rad_s")
        self._R = np.array(R0, float)
        tau = np.zeros(3) if load is None else self.external_moment_A(load, 0.0, self._R)
        nan = np.full(self.rig.n_cables, np.nan)
        return PlantState(self._R, np.zeros(3), nan, np.full((3, 3), np.nan), tau)

    def step(self, command, load: LoadFunction, t0_s: float, t1_s: float) -> PlantState:
        """The equilibrium for the commanded rest lengths under the load at ``t1_s`` (see :meth:`Plant.step`).

        Parameters
        ----------
        command : Command
            The controller's command: its ``rest_lengths_m`` are used.
        load : callable
            Load function ``t -> moment`` (N m, fixed in the frame ``load_fixed_in``).
        t0_s, t1_s : float
            Start and end of the control period (s).

        Returns
        -------
        PlantState
            The state at ``t1_s``.

        Raises
        ------
        NoEquilibrium
            No stable equilibrium with all cables taut near the current pose.
        """
        tau = self.external_moment_A(load, t1_s, self._R)
        eq = self._solver.solve(command.rest_lengths_m, tau, self._R)
        self._R = eq.R
        return PlantState(eq.R, np.zeros(3), eq.tensions_N, eq.K, tau)

    def measured_load_A(self, R: np.ndarray, tau_ext_A_Nm: np.ndarray) -> np.ndarray:
        """What a force/torque sensor under the platform reads: the load plus the point forces' moments.

        Parameters
        ----------
        R : (3, 3) array
            Orientation of {A} in {B}.
        tau_ext_A_Nm : (3,) array
            External moment (N m, in {A}).

        Returns
        -------
        (3,) array
            Sensor moment (N m, in {A}), weight excluded.
        """
        if len(self._F):
            return tau_ext_A_Nm + point_force_terms(R, self._F, self._P)[0]
        return np.asarray(tau_ext_A_Nm, float)
