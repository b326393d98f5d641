"""MuJoCo plant: the rig with inertia and damping, simulated by the MuJoCo engine.

The model is :func:`csjm_opt.model.mjcf.rig_to_mjcf` (ball joint at O,
pull-only tendon springs, mass and inertia of the rig's ``[dynamics]``).
One control period ``[t0, t1]`` (1 ms at 1 kHz) runs ``(t1 - t0) / timestep``
engine steps (default 0.5 ms, RK4). Actuation:

* ``"rest_length"`` (winch, default): the commanded rest lengths are reached
  by a linear ramp over the period (a winch moving at constant speed, value
  at each engine step's midpoint), the speed limited to
  ``rest_length_rate_m_per_s``; the springs are MuJoCo's dead-band tendon
  springs (``model.tendon_lengthspring[:, 1]``). The first command is taken
  at once (the drives start there);
* ``"tension"``: the commanded tensions act as forces along the cables,
  clipped to ``[t_min, t_max]`` (MuJoCo's ``ctrlrange``).

Loads: ``load_fixed_in="A"`` applies the load function's moment fixed in the
platform (``qfrc_applied`` of the ball joint, whose axes are {A});
``"B"`` applies it fixed in the world (``xfrc_applied``). The load is
evaluated at every engine step's midpoint.

Not to be confused with :class:`csjm_opt.testbed.mujoco.plant.MujocoTestbedPlant`, which *settles*
each row of a diagnosis log statically with effects injected (friction, hardening, a compliant
link); both build their engine model with
:func:`csjm_opt.model.mjcf.rig_to_mjcf`.
"""

from __future__ import annotations

import mujoco
import numpy as np

from ...errors import InvalidInput
from ...model.cable_terms import CableTerms
from ...model.mjcf import quat_wxyz, rig_to_mjcf
from ...model.perturbation import LOAD_FRAMES, stiffness_from_engine
from ...model.rig import Rig
from .. import loop_kernels as loop_kernels
from .base import LoadFunction, Plant, PlantState

#: Default winch speed limit (m/s) of the rest-length actuation.
REST_LENGTH_RATE_M_PER_S = 0.2
ACTUATIONS = ("rest_length", "tension")


class MujocoPlant(Plant):
    """The rig in MuJoCo, stepped by :meth:`step` one control period at a time (see module doc).

    Parameters
    ----------
    rig : Rig
        Rig (with its ``[dynamics]``, or the defaults of :mod:`csjm_opt.model.dynamics`).
    timestep_s : float
        Engine step (s); must divide the control period.
    integrator : str
        MuJoCo integrator (``"RK4"``, ``"implicitfast"``, ``"Euler"``).
    actuation : {"rest_length", "tension"}
    load_fixed_in : {"A", "B"}
    rest_length_rate_m_per_s : float
        Winch speed limit for ``"rest_length"`` actuation.
    joint_damping_Nms_per_rad : float, optional
        Overrides the rig's joint damping.
    """

    def __init__(self, rig: Rig, timestep_s: float = 5e-4, integrator: str = "RK4",
                 actuation: str = "rest_length", load_fixed_in: str = "A",
                 rest_length_rate_m_per_s: float = REST_LENGTH_RATE_M_PER_S,
                 joint_damping_Nms_per_rad: float | None = None):
        if actuation not in ACTUATIONS:
            raise InvalidInput(f"actuation must be one of {ACTUATIONS}, got {actuation!r}", "actuation")
        if load_fixed_in not in LOAD_FRAMES:
            raise InvalidInput(f"load_fixed_in must be 'A' or 'B', got {load_fixed_in!r}", "load_fixed_in")
        if not rest_length_rate_m_per_s > 0:
            raise InvalidInput(f"rest-length rate limit must be > 0, got {rest_length_rate_m_per_s}",
                               "rest_length_rate_m_per_s")
        self.rig, self.actuation, self.load_fixed_in = rig, actuation, load_fixed_in
        self.rate_m_per_s = float(rest_length_rate_m_per_s)
        xml = rig_to_mjcf(rig, actuation="spring" if actuation == "rest_length" else "tension",
                          timestep_s=timestep_s, integrator=integrator,
                          joint_damping_Nms_per_rad=joint_damping_Nms_per_rad)
        self.model = mujoco.MjModel.from_xml_string(xml)
        self.data = mujoco.MjData(self.model)
        self._terms = CableTerms.from_rig(rig)
        self._k = np.asarray(rig.cable_stiffness_N_per_m, float)
        self._l: np.ndarray | None = None
        self._tau_A = np.zeros(3)
        self._body = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "platform")

    # ------------------------------------------------------------ state
    @property
    def R(self) -> np.ndarray:
        """Current orientation of {A} in {B} (from the ball joint's quaternion)."""
        R = np.empty(9)
        mujoco.mju_quat2Mat(R, self.data.qpos)
        return R.reshape(3, 3)

    @property
    def rest_lengths_m(self) -> np.ndarray | None:
        """Rest lengths the winches hold now (``None`` before the first command)."""
        return None if self._l is None else self._l.copy()

    def _state(self) -> PlantState:
        R = self.R
        if self.actuation == "rest_length" and self._l is not None:
            T, K = loop_kernels.rest_state(self._terms.A, self._terms.B, self._terms.k, R, self._l)
        else:
            m = self.rig.n_cables
            T = np.clip(self.data.ctrl[:m], self.rig.t_min_N, self.rig.t_max_N) if self.actuation == "tension" \
                else np.zeros(m)
            _, _, G = self._terms.stiffness_basis(R)
            K = np.einsum("i,ijk->jk", T, G)
        return PlantState(R, self.data.qvel.copy(), T, K, self._tau_A.copy())

    def reset(self, R0: np.ndarray, omega0_A_rad_s: np.ndarray | None = None,
              load: LoadFunction | None = None) -> PlantState:
        """Reset the engine to pose ``R0`` (see :meth:`Plant.reset`); no rest lengths until the first step.

        Parameters
        ----------
        R0 : (3, 3) array
            Initial orientation of {A} in {B}.
        omega0_A_rad_s : (3,) array, optional
            Initial angular velocity (rad/s, in {A}); default zero.
        load : callable, optional
            Load function ``t -> moment`` (N m, fixed in the frame ``load_fixed_in``), read at t = 0.

        Returns
        -------
        PlantState
            The state at the start.
        """
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = quat_wxyz(np.asarray(R0, float))
        self.data.qvel[:] = 0.0 if omega0_A_rad_s is None else np.asarray(omega0_A_rad_s, float)
        self._l = None
        self._tau_A = np.zeros(3) if load is None else self.external_moment_A(load, 0.0, np.asarray(R0, float))
        mujoco.mj_forward(self.model, self.data)
        return self._state()

    # ------------------------------------------------------------ stepping
    def _apply_load(self, load: LoadFunction, t_s: float) -> None:
        tau = np.asarray(load(t_s), float)
        if self.load_fixed_in == "A":
            self.data.qfrc_applied[:] = tau
            self._tau_A = tau
        else:
            self.data.xfrc_applied[self._body, 3:] = tau
            self._tau_A = self.R.T @ tau

    def step(self, command, load: LoadFunction, t0_s: float, t1_s: float) -> PlantState:
        """Run the engine from ``t0_s`` to ``t1_s`` under ``command`` (see :meth:`Plant.step`).

        Rest-length actuation ramps the tendon rest lengths toward the command, at most
        ``rate_m_per_s``; tension actuation applies the clipped tensions as motor controls.

        Parameters
        ----------
        command : Command
            The controller's command: ``rest_lengths_m`` or ``tensions_N`` by ``actuation``.
        load : callable
            Load function ``t -> moment`` (N m, fixed in the frame ``load_fixed_in``).
        t0_s, t1_s : float
            Start and end of the control period (s).

        Returns
        -------
        PlantState
            The state at ``t1_s``.
        """
        dt = self.model.opt.timestep
        n = max(1, int(round((t1_s - t0_s) / dt)))
        if self.actuation == "rest_length":
            target = np.asarray(command.rest_lengths_m, float)
            start = target if self._l is None else self._l
            end = start + np.clip(target - start, -self.rate_m_per_s * (t1_s - t0_s),
                                  self.rate_m_per_s * (t1_s - t0_s))
        else:
            self.data.ctrl[:6] = np.clip(command.tensions_N, self.rig.t_min_N, self.rig.t_max_N)
        lengthspring = self.model.tendon_lengthspring
        for j in range(n):
            s = (j + 0.5) / n
            if self.actuation == "rest_length":
                lengthspring[:, 1] = start + s * (end - start)
            self._apply_load(load, t0_s + s * (t1_s - t0_s))
            mujoco.mj_step(self.model, self.data)
        if self.actuation == "rest_length":
            self._l = end.copy()
            lengthspring[:, 1] = end
        self._apply_load(load, t1_s)
        return self._state()

    # ------------------------------------------------------------ measurement
    def perturbation_stiffness(self, h_rad: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
        """Cable stiffness measured in the engine by small rotations of the current state.

        Central differences of MuJoCo's net moment ``qfrc_smooth`` under
        ``R exp(hat(zeta))``, ``|zeta| = h_rad``, at zero velocity; the load
        held fixed in its frame. Returns ``(K, K_measured)``: ``K_measured =
        -dQ/dzeta`` and ``K`` after removing the weight Hessian and
        ``+-1/2 hat(tau_ext)`` (:mod:`csjm_opt.model.perturbation`). Meaningful
        at (or near) a static equilibrium.
        """
        m, d = self.model, mujoco.MjData(self.model)
        mujoco.mj_copyData(d, m, self.data)
        q0 = self.data.qpos.copy()

        def Q(z: np.ndarray) -> np.ndarray:
            d.qpos[:] = q0
            mujoco.mj_integratePos(m, d.qpos, z, 1.0)
            d.qvel[:] = 0.0
            mujoco.mj_forward(m, d)
            return d.qfrc_smooth.copy()

        K_meas = -np.column_stack([(Q(h_rad * e) - Q(-h_rad * e)) / (2 * h_rad) for e in np.eye(3)])
        return stiffness_from_engine(self.rig, self.R, K_meas, self._tau_A, self.load_fixed_in), K_meas
