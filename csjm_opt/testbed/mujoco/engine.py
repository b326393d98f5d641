"""One MuJoCo run of a :class:`~csjm_opt.testbed.mujoco.plant.MujocoTestbedPlant` (its state carries across rows)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from ...errors import NoEquilibrium
from ...model.dynamics import rig_dynamics
from ...model.mjcf import quat_wxyz
from ..static_certificate import certify_static
from .model import has_link, plant_mjcf
from .statics import NetForceStatics, tendon_jacobian

if TYPE_CHECKING:
    from .plant import MujocoRow, MujocoTestbedPlant

#: Inputs are changed in this many chunks over a ramp.
RAMP_CHUNKS = 30
#: Highest natural frequency (rad/s) of the tool on its link (its inertia is raised to keep it there).
LINK_OMEGA_RAD_PER_S = 300.0
#: Steps between checks of the joint speed while settling.
CHECK_STEPS = 25
#: Joint speed (rad/s) at which a frictionless plant hands over to Newton's method.
FRICTIONLESS_SPEED_TOL = 1e-4
#: Relative excess over a friction bound still counted as within it (a slipping element sits on its bound).
BOUND_SLACK = 1e-4
#: Below this joint speed (rad/s) a frictional row's remaining quasi-static travel is checked.
TRAVEL_CHECK_SPEED = 1e-4
#: A frictionless row hands over to Newton's method once the quasi-static travel left is below this (rad).
NEWTON_HANDOVER_RAD = 0.02
#: Below this joint speed (rad/s) a frictionless row's travel left is checked for the hand-over.
HANDOVER_CHECK_SPEED = 0.1
#: Waits of ``max_settle_s`` a frictionless row may take before it is refused (it needs no history: only CPU).
FRICTIONLESS_WAITS = 4
#: Below this tendon speed (m/s) a cable's friction holds up to the static bound (static over sliding ratio).
STICK_SPEED_M_PER_S = 1e-4
#: Below this joint speed (rad/s, per axis) the ball joint's friction holds up to its static bound.
STICK_SPEED_RAD_PER_S = 1e-3


def _rotation(q: np.ndarray) -> np.ndarray:
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(q, float))
    return R.reshape(3, 3)


class Engine(NetForceStatics):
    """MuJoCo model and data of a plant, with the run-time forces (hardening, link spring, load)."""

    def __init__(self, mp: MujocoTestbedPlant, l0: np.ndarray) -> None:
        from .plant import critical_damping

        self.mp, self.p = mp, mp.plant
        rig = self.p.rig
        self.link = has_link(self.p)
        I = rig_dynamics(rig).inertia_com_A_kgm2
        lam_I = np.linalg.eigvalsh(I)
        damping = critical_damping(self.p)
        timestep = 1e-3
        if self.link:
            self.K_link = np.linalg.inv(np.asarray(self.p.link_compliance_rad_per_Nm, float))
            k_max = float(np.linalg.eigvalsh(0.5 * (self.K_link + self.K_link.T)).max())
            timestep = min(timestep, 0.3 / np.sqrt(k_max / max(lam_I[0], k_max / LINK_OMEGA_RAD_PER_S ** 2)))
        self.m = mujoco.MjModel.from_xml_string(plant_mjcf(self.p, l0, damping, timestep,
                                                           noslip_iterations=mp.noslip_iterations))
        if self.link:       # inertia does not change statics: the tool's is raised so the link is not stiff
            I_tool = np.maximum(self.m.body_inertia[-1], k_max / LINK_OMEGA_RAD_PER_S ** 2)
            self.m.body_inertia[-1] = I_tool
            self.m.dof_damping[3:6] = 2.0 * np.sqrt(k_max * I_tool.max())
        # tight solver and noslip tolerances: at the defaults (1e-8, 1e-6) a stuck tendon still creeps (~2e-6 rad/s)
        self.m.opt.tolerance = 1e-12
        self.m.opt.iterations = 200
        self.m.opt.noslip_tolerance = mp.noslip_tolerance
        self.d = mujoco.MjData(self.m)
        self.nv = self.m.nv
        self.tool = slice(3, 6) if self.link else slice(0, 3)
        self.k = np.asarray(rig.cable_stiffness_N_per_m, float)
        self.h = float(self.p.hardening_per_m)
        self.mu = np.asarray(self.p.friction_mu_beta, float)
        self.capstan = bool(np.any(self.mu > 0))
        self.F0 = np.array(self.m.tendon_frictionloss, float)
        self.M0 = np.array(self.m.dof_frictionloss, float)
        self.frictional = bool(self.capstan or np.any(self.F0 > 0) or np.any(self.M0 > 0))
        self.ratio = float(getattr(mp, "static_friction_ratio", 1.0))
        self.stick_slip = self.frictional and self.ratio != 1.0
        self.busy_always = self.link or self.h != 0 or self.stick_slip    # forces to update every step
        self.busy = self.busy_always
        self.g_B = np.asarray(rig.gravity_B_m_per_s2, float)
        self.l = np.asarray(l0, float).copy()
        self.tau = np.zeros(3)
        self.mr = np.zeros(3)
        self.has_weights = False
        self._v3 = np.zeros(3)
        self.tool_body = self.m.nbody - 1          # 'tool' with a link, else 'platform'
        self.t = 0.0
        self._scratch = mujoco.MjData(self.m)     # finite differences without touching the run's state

    # ------------------------------------------------------------ forces
    def set_inputs(self, l: np.ndarray, tau: np.ndarray, mr: np.ndarray) -> None:
        """Rest lengths (the tendon springs' dead band), the load on the tool, its dead weights' ``m p``."""
        self.l = np.asarray(l, float).copy()
        self.tau = np.asarray(tau, float).copy()
        self.mr = np.asarray(mr, float).copy()
        self.has_weights = bool(np.any(self.mr != 0))
        self.busy = self.busy_always or self.has_weights
        self.m.tendon_lengthspring[:, 1] = self.l

    def applied(self) -> tuple[np.ndarray, np.ndarray]:
        """Run-time generalised forces at the data's current kinematics, and the cable tensions."""
        d = self.d
        e = np.maximum(d.ten_length - self.l, 0.0)
        qfrc = np.zeros(self.nv)
        tau = self.tau
        if self.has_weights:                 # dead weights: (m p) x (R_tool^T g)
            q_tool = d.xquat[self.tool_body]
            g_tool = np.zeros(3)
            mujoco.mju_rotVecQuat(g_tool, self.g_B, np.array([q_tool[0], -q_tool[1], -q_tool[2], -q_tool[3]]))
            tau = tau + np.cross(self.mr, g_tool)
        qfrc[self.tool] = tau                # the load on the tool, in its frame
        if self.h:
            extra = self.k * self.h * e * e
            qfrc -= tendon_jacobian(self.m, d).T @ extra
            e_T = self.k * e + extra
        else:
            e_T = self.k * e
        if self.link:                         # the load is external: it also acts on the platform's dofs
            q_link = d.qpos[4:8]
            mujoco.mju_rotVecQuat(self._v3, tau, q_link)
            qfrc[0:3] += self._v3
            mujoco.mju_quat2Vel(self._v3, q_link, 1.0)             # the link's rotation vector
            qfrc[3:6] -= self.K_link @ self._v3                      # its spring (internal)
        return qfrc, e_T

    def net(self, qpos: np.ndarray) -> np.ndarray:
        """Frictionless generalised net force at rest at ``qpos`` (MuJoCo's ``qfrc_smooth`` plus run-time forces)."""
        m, d = self.m, self.d
        d.qpos[:] = qpos
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0
        mujoco.mj_forward(m, d)
        qfrc, _ = self.applied()
        return np.asarray(d.qfrc_smooth) + qfrc

    # ------------------------------------------------------------ motion
    def run(self, steps: int) -> None:
        """``steps`` engine steps with the current inputs.

        Forces that follow the state within a step (hardening, the link's
        spring, dead weights) are set every step; a capstan law's friction
        bounds follow the tensions once per call (every 10-25 steps).
        """
        m, d = self.m, self.d
        if self.capstan and self.frictional:
            e = np.maximum(np.asarray(d.ten_length) - self.l, 0.0)
            m.tendon_frictionloss[:] = self.F0 + self.mu * (self.k * e * (1.0 + self.h * e))
        if self.stick_slip:
            self._slide_bounds = np.array(m.tendon_frictionloss, float) if self.capstan else self.F0
        if not self.busy:
            d.qfrc_applied[:] = 0.0
            d.qfrc_applied[self.tool] = self.tau
            mujoco.mj_step(m, d, nstep=int(steps))
        else:
            for _ in range(int(steps)):
                mujoco.mj_step1(m, d)
                d.qfrc_applied[:] = self.applied()[0]
                if self.stick_slip:
                    self._stick_or_slide()
                mujoco.mj_step2(m, d)
        self.t += steps * m.opt.timestep

    def _stick_or_slide(self) -> None:
        """Friction bounds of this step: static (ratio x sliding) where an element is still, sliding where it moves."""
        m, d = self.m, self.d
        still = np.abs(np.asarray(d.ten_velocity)) < STICK_SPEED_M_PER_S
        m.tendon_frictionloss[:] = self._slide_bounds * np.where(still, self.ratio, 1.0)
        if np.any(self.M0 > 0):
            w = np.abs(np.asarray(d.qvel[:3]))
            m.dof_frictionloss[:3] = self.M0[:3] * np.where(w < STICK_SPEED_RAD_PER_S, self.ratio, 1.0)

    def static_bounds(self, T: np.ndarray) -> np.ndarray:
        """Largest friction forces that can hold a row at rest: cables' (m,) then the joint's axes (3,)."""
        return self.p.friction_bounds(T) * self.ratio

    def ramp(self, l: np.ndarray, tau: np.ndarray, mr: np.ndarray, seconds: float | None = None) -> None:
        """Move the inputs to ``(l, tau, mr)`` over ``seconds`` (default the plant's ``ramp_s``)."""
        l0, tau0, mr0 = self.l.copy(), self.tau.copy(), self.mr.copy()
        seconds = self.mp.ramp_s if seconds is None else seconds
        steps = max(1, int(round(seconds / self.m.opt.timestep / RAMP_CHUNKS)))
        for q in range(1, RAMP_CHUNKS + 1):
            f = q / RAMP_CHUNKS
            self.set_inputs(l0 + (l - l0) * f, tau0 + (tau - tau0) * f, mr0 + (mr - mr0) * f)
            self.run(steps)
        self.set_inputs(l, tau, mr)

    def relaxed_start(self, R: np.ndarray, l: np.ndarray, tau: np.ndarray, mr: np.ndarray) -> None:
        """Start at ``R`` and settle without friction (nothing stuck), then switch friction on."""
        d = self.d
        d.qpos[:] = 0.0
        d.qpos[:4] = quat_wxyz(R)
        if self.link:
            d.qpos[4] = 1.0
        d.qvel[:] = 0.0
        self.set_inputs(l, tau, mr)
        F, M, fr, ss = self.F0.copy(), self.M0.copy(), self.frictional, self.stick_slip
        self.m.tendon_frictionloss[:] = 0.0
        self.m.dof_frictionloss[:] = 0.0
        self.frictional = self.stick_slip = False
        try:
            self._wait()
            self.polish(np.arange(self.nv))
        finally:
            self.m.tendon_frictionloss[:] = F
            self.m.dof_frictionloss[:] = M
            self.frictional, self.stick_slip = fr, ss
        mujoco.mj_forward(self.m, self.d)

    def _wait(self) -> bool:
        """Run until at rest, at most ``max_settle_s``; whether it got there.

        At rest: the joint speed is below ``speed_tol_rad_per_s``, or, with friction, the
        quasi-static travel left (:meth:`remaining_travel`) is below ``rest_travel_tol_rad``.
        Without friction the engine only has to bring the pose into the basin of its
        equilibrium, Newton's method finishes: the speed below ``FRICTIONLESS_SPEED_TOL`` or the
        travel left below ``NEWTON_HANDOVER_RAD`` (a soft direction of the rig, heavily
        overdamped by a damping set for the stiff ones, would otherwise creep for many seconds).
        """
        m, d = self.m, self.d
        q_start = d.qpos[:4].copy()
        if self.frictional:
            tol, travel_tol, check_below = self.mp.speed_tol_rad_per_s, self.mp.rest_travel_tol_rad, TRAVEL_CHECK_SPEED
        else:
            tol, travel_tol, check_below = FRICTIONLESS_SPEED_TOL, NEWTON_HANDOVER_RAD, HANDOVER_CHECK_SPEED
        for _ in range(max(1, int(round(self.mp.max_settle_s / (m.opt.timestep * CHECK_STEPS))))):
            self.run(CHECK_STEPS)
            speed = float(np.linalg.norm(d.qvel))
            if speed < tol or (travel_tol > 0 and speed < check_below and self.remaining_travel() < travel_tol):
                return True
            if not np.all(np.isfinite(d.qpos)) or abs(float(np.dot(q_start, d.qpos[:4]))) < np.cos(np.pi / 4):
                raise NoEquilibrium("the MuJoCo plant fell over (more than 90 deg from the row's start)",
                                    "fell", np.nan)
        return False

    def settle(self, row: int) -> MujocoRow:
        """Run until at rest; polish (no friction) or certify (friction); the row's record.

        With friction the certificate includes the joints' damping force at the speed left when
        the wait ends: a row on the verge of slipping may still creep (about 1e-5 rad/s), held by
        friction at its bounds plus that damping force. The speed is recorded, and a row whose wait
        reached ``max_settle_s`` before the speed fell below ``speed_tol_rad_per_s`` is flagged
        (``settled=False``; still certified, or refused). A frictionless row is polished to an
        exact equilibrium by Newton's method (``settled=True``) or refused.
        """
        from .plant import MujocoRow

        t0 = self.t
        at_rest = self._wait()
        speed = float(np.linalg.norm(self.d.qvel))
        cert = None
        if not self.frictional:
            for _ in range(FRICTIONLESS_WAITS):
                q_wait, v_wait = self.d.qpos.copy(), self.d.qvel.copy()
                left = self.polish(np.arange(self.nv))
                if left <= 1e-8 and self._stable():
                    break
                # not yet in the basin (a long move, e.g. to a new cycle on a soft rig): wait on from there
                self.d.qpos[:], self.d.qvel[:] = q_wait, v_wait
                mujoco.mj_forward(self.m, self.d)
                at_rest = self._wait()
            else:
                left = self.polish(np.arange(self.nv))
            if left > 1e-8:
                raise NoEquilibrium(f"MuJoCo plant: row {row} did not settle (net force {left:.2e} N m left)",
                                    "diverged", left)
            if not self._stable():
                raise NoEquilibrium(f"MuJoCo plant: row {row} settled at an unstable equilibrium", "unstable",
                                    0.0)
        else:
            # a row may still slide slowly when the wait ends (a cable on the verge of slipping creeps
            # under the joint's damping); the damping force at that speed is a real force of the plant
            v = np.array(self.d.qvel, float)
            if self.link:
                self.polish(np.arange(3, 6))
                v[3:6] = 0.0                      # the link's dofs are polished to rest
            q = self.d.qpos.copy()
            net = self.net(q) - np.asarray(self.m.dof_damping, float) * v
            _, T = self.applied()
            A = np.column_stack([tendon_jacobian(self.m, self.d).T, np.eye(self.nv)[:, :3]])
            cert = certify_static(net, A, self.static_bounds(T) * (1.0 + BOUND_SLACK))
            self.d.qpos[:] = q
            if not cert.certified:
                raise NoEquilibrium(f"MuJoCo plant: row {row} is not held by friction within its bounds "
                                    f"(utilisation {cert.utilisation:.6g})", "not certified", cert.residual_Nm)
        mujoco.mj_forward(self.m, self.d)
        _, T = self.applied()
        R_p = _rotation(self.d.qpos[:4])
        R_tool = R_p @ _rotation(self.d.qpos[4:8]) if self.link else R_p
        return MujocoRow(R_tool, R_p, T, cert, self.t - t0, speed, at_rest or not self.frictional)
