"""MuJoCo as the independent reference for the statics and stiffness (tests and studies).

The engine model comes from :func:`csjm_opt.model.mjcf.rig_to_mjcf`, which uses
only the rig's geometry, stiffness, mass, COM and gravity (no statics). Poses
are read with MuJoCo's own ``mju_quat2Mat``; tensions with MuJoCo's tendon
lengths; forces are MuJoCo's ``qfrc_smooth`` (passive + actuator + applied
minus bias, all in {A} for the ball joint).

How statics are settled: a heavily damped simulation (ball-joint damping
``SETTLE_DAMPING`` N m s/rad, RK4 at 1 ms) from the start pose until the
angular velocity is below 1e-6 rad/s (at most ``SETTLE_S`` s; a platform
more than 90 deg from its start has fallen over), then a few
Newton steps on MuJoCo's own net moment (``qfrc_smooth``) polish the pose to
round-off; it has settled when that polish stays within 1 mrad and finds a
stable equilibrium. The damping is heavy (overdamped: the platform
creeps, like the gradient flow the forward statics follows); with light
damping a platform released far from equilibrium can overshoot into another
stable equilibrium (``studies/statics_vs_mujoco/statics_vs_mujoco.py``, which uses this module
with ``damping`` lowered to show it).
"""

from __future__ import annotations

import mujoco
import numpy as np

from ...model.mjcf import rig_to_mjcf

SETTLE_DAMPING = 1.0
SETTLE_S = 30.0


def build(rig, rest_lengths, R, tau_ext, damping=SETTLE_DAMPING, timestep=1e-3):
    """MuJoCo model and data of ``rig`` at its keyframe (rest lengths, pose ``R``, load ``tau_ext``)."""
    xml = rig_to_mjcf(rig, rest_lengths, R, tau_ext, joint_damping_Nms_per_rad=damping, timestep_s=timestep)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    return m, d


def rotation(qpos: np.ndarray) -> np.ndarray:
    """The platform's rotation matrix from the ball joint's quaternion (MuJoCo's own conversion)."""
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, np.asarray(qpos, float))
    return R.reshape(3, 3)


def tensions(rig, d, rest_lengths) -> np.ndarray:
    """Cable tensions from MuJoCo's tendon lengths (N; slack cables 0)."""
    return np.asarray(rig.cable_stiffness_N_per_m) * np.maximum(d.ten_length - rest_lengths, 0.0)


def _net_moment(m, d, q0, z):
    d.qpos[:] = q0
    mujoco.mj_integratePos(m, d.qpos, z, 1.0)
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    return d.qfrc_smooth.copy()


def polish(m, d, max_iter=20, h=1e-7):
    """Newton on MuJoCo's own net moment from the current pose: ``(moved_rad, stable)``.

    The moment is ``qfrc_smooth`` at rest, its Jacobian central differences under ``mj_integratePos``.
    """
    q_start, moved = d.qpos.copy(), 0.0
    for _ in range(max_iter):
        q0 = d.qpos.copy()
        Q = _net_moment(m, d, q0, np.zeros(3))
        D = np.column_stack([(_net_moment(m, d, q0, h * e) - _net_moment(m, d, q0, -h * e)) / (2 * h)
                             for e in np.eye(3)])
        d.qpos[:] = q0
        if np.abs(Q).max() < 1e-12:
            break
        step = -np.linalg.solve(D, Q)
        mujoco.mj_integratePos(m, d.qpos, step, 1.0)
        moved += float(np.linalg.norm(step))
    mujoco.mj_forward(m, d)
    stable = bool(np.all(np.linalg.eigvals(-D).real > 0))
    return float(np.linalg.norm(rotation(q_start) - rotation(d.qpos))) if moved else 0.0, stable


def settle(rig, rest_lengths, R0, tau_ext, seconds=SETTLE_S, nudge=None, damping=SETTLE_DAMPING):
    """Settle from ``R0`` (optionally nudged by a body-frame rotation vector): (R, tensions, settled).

    Heavily damped simulation until the motion has (nearly) died out (or the
    platform is more than 90 deg from the start: fell over), then
    :func:`polish` to round-off; ``settled`` when the polish moved less than
    1 mrad (the same basin), the result is stable and the net moment vanishes.
    """
    m, d = build(rig, rest_lengths, R0, tau_ext, damping)
    if nudge is not None:
        mujoco.mj_integratePos(m, d.qpos, np.asarray(nudge, float), 1.0)
    R_start = rotation(d.qpos)
    for _ in range(int(round(seconds / m.opt.timestep / 250))):
        for _ in range(250):
            mujoco.mj_step(m, d)
        if np.linalg.norm(d.qvel) < 1e-6:
            break
        if np.trace(R_start.T @ rotation(d.qpos)) < 1.0:           # more than 90 deg away: fell over
            return rotation(d.qpos), tensions(rig, d, rest_lengths), False
    moved, stable = polish(m, d)
    settled = bool(moved < 1e-3 and stable and np.abs(d.qfrc_smooth).max() < 1e-11)
    return rotation(d.qpos), tensions(rig, d, rest_lengths), settled


def measured_stiffness(rig, rest_lengths, R, tau_ext, world_fixed=False, h=1e-6):
    """``-dQ/dzeta`` by central differences of MuJoCo's generalised force at ``R exp(hat(zeta))``.

    ``Q`` is the net moment on the platform in {A}. The external moment is
    applied by the keyframe's load motors (fixed in {A}) or, with
    ``world_fixed``, as ``xfrc_applied`` torque ``R tau_ext`` fixed in {B}.
    """
    m, d = build(rig, rest_lengths, R, tau_ext)
    q0 = d.qpos.copy()
    if world_fixed:
        d.ctrl[:] = 0.0

    def Q(z):
        d.qpos[:] = q0
        mujoco.mj_integratePos(m, d.qpos, z, 1.0)
        d.qvel[:] = 0.0
        if world_fixed:
            d.xfrc_applied[1, 3:] = R @ tau_ext
        mujoco.mj_forward(m, d)
        return d.qfrc_smooth.copy()

    return -np.column_stack([(Q(h * e) - Q(-h * e)) / (2 * h) for e in np.eye(3)]), Q(np.zeros(3))
