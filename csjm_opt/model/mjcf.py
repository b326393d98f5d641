"""MuJoCo model (MJCF) of a rig, written from its geometry, stiffness, mass and inertia only.

Frames and conventions of the file:

* the world frame is {B}; its origin is the joint centre O. The base holes
  ``B_i`` are world sites ``B1..Bm`` (m = ``rig.n_cables``);
* body ``platform`` has frame {A}, origin at O, identity pose in the model;
  the ball joint ``ball`` sits at O, so the joint's quaternion ``qpos``
  (MuJoCo order ``w, x, y, z``) is the orientation ``R`` of {A} in {B}, and
  its ``qvel`` is the angular velocity **in {A}** (body frame). Generalised
  forces of the joint (``qfrc_*``) are moments about O in {A}, like
  ``tau_ext`` here. The platform holes ``A_i`` are body sites ``A1..Am``;
* mass at the COM, inertia about the COM in {A} (``[dynamics]`` of the rig
  file or the defaults of :mod:`csjm_opt.model.dynamics`); gravity
  ``rig.gravity_B_m_per_s2``; the ball joint's damping; no contacts;
* cable ``i`` is the spatial tendon ``cable<i>`` from ``A<i>`` to ``B<i>``.
  How it pulls depends on ``actuation``:

  - ``"spring"`` (default): a pull-only linear spring. MuJoCo's two-value
    ``springlength="0 l_i"`` makes a dead band: no force for lengths in
    ``[0, l_i]``, tension ``k_i (c_i - l_i)`` beyond. ``l_i`` is the rest
    length (cable plus drive); a winch changes it at run time through
    ``model.tendon_lengthspring[i, 1]``;
  - ``"winch"``: the same law as an actuator ``winch<i>`` per cable,
    ``ctrl = l_i`` (m), force ``clamp(k_i (l_i - c_i) - b_i dc_i/dt, -t_max, 0)``
    (pull-only, capped at the rig's ``t_max``);
  - ``"tension"``: a motor ``tension<i>`` per cable, ``ctrl = t_i`` (N)
    within ``[t_min, t_max]``; the cable has no spring.

* three motors ``load_x, load_y, load_z`` on the ball joint apply the
  external moment ``tau_ext`` fixed in {A} (``ctrl`` in N m).

The keyframe ``planned`` holds the pose and the controls of the export;
``mj_resetDataKeyframe(model, data, 0)`` then settles at that pose (the
file's rest lengths or tensions are those planned for it by
:func:`csjm_opt.plan_tensions`).
"""

from __future__ import annotations

from typing import Iterable
from xml.sax.saxutils import quoteattr

import numpy as np

from ..errors import InvalidInput
from .cable_terms import cable_lengths
from .dynamics import rig_dynamics
from .rig import Rig

ACTUATIONS = ("spring", "winch", "tension")


def _f(x: float) -> str:
    return repr(float(x))


def _v(values: Iterable[float]) -> str:
    return " ".join(_f(x) for x in values)


def quat_wxyz(R: np.ndarray) -> np.ndarray:
    """Unit quaternion ``(w, x, y, z)`` of a rotation matrix (Shepperd's method, w >= 0)."""
    R = np.asarray(R, float)
    tr = np.trace(R)
    if tr > max(R[0, 0], R[1, 1], R[2, 2]):
        w = 0.5 * np.sqrt(1.0 + tr)
        q = np.array([w, (R[2, 1] - R[1, 2]) / (4 * w), (R[0, 2] - R[2, 0]) / (4 * w), (R[1, 0] - R[0, 1]) / (4 * w)])
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        q = np.empty(4)
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    q = q / np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def rig_to_mjcf(rig: Rig, rest_lengths_m: np.ndarray | None = None, R: np.ndarray | None = None,
                tau_ext_A_Nm: np.ndarray | None = None, tensions_N: np.ndarray | None = None,
                actuation: str = "spring", timestep_s: float = 5e-4, integrator: str = "RK4",
                joint_damping_Nms_per_rad: float | None = None, model_name: str = "csjm") -> str:
    """MJCF text of ``rig`` (see the module doc for frames and names).

    Parameters
    ----------
    rig : Rig
        Geometry, cable stiffness, limits, mass/COM, gravity and (optional) dynamics.
    rest_lengths_m : (m,) array, optional
        Rest lengths written into the springs (``"spring"``) or the winch
        controls of the keyframe (``"winch"``). Default: cable lengths at ``R``
        (every cable just taut, no tension).
    R : (3, 3) array, optional
        Pose of the keyframe ``planned`` (identity by default).
    tau_ext_A_Nm : (3,) array, optional
        External moment fixed in {A}, the keyframe's ``load_*`` controls.
    tensions_N : (m,) array, optional
        Tensions of the keyframe for ``actuation="tension"`` (default ``t_min``).
    actuation : {"spring", "winch", "tension"}
        How the cables pull (module doc).
    timestep_s, integrator : float, str
        Engine step (s) and MuJoCo integrator (``"RK4"``, ``"implicitfast"``, ...).
    joint_damping_Nms_per_rad : float, optional
        Overrides the rig's joint damping (e.g. heavy damping to settle statics).

    Returns
    -------
    str
        The MJCF document.

    Raises
    ------
    InvalidInput
        Unknown ``actuation``, non-positive mass or timestep, wrong shapes.
    """
    if actuation not in ACTUATIONS:
        raise InvalidInput(f"actuation must be one of {ACTUATIONS}, got {actuation!r}", "actuation")
    if not rig.platform_mass_kg > 0:
        raise InvalidInput("a dynamic model needs a positive platform mass", "platform.mass")
    if not timestep_s > 0:
        raise InvalidInput(f"timestep must be > 0, got {timestep_s}", "timestep_s")
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    k, dyn = rig.cable_stiffness_N_per_m, rig_dynamics(rig)
    R = np.eye(3) if R is None else np.asarray(R, float)
    m = A.shape[0]
    c = cable_lengths(R, A, B)
    l = c if rest_lengths_m is None else np.asarray(rest_lengths_m, float).reshape(m)
    tau = np.zeros(3) if tau_ext_A_Nm is None else np.asarray(tau_ext_A_Nm, float).reshape(3)
    T = np.full(m, rig.t_min_N) if tensions_N is None else np.asarray(tensions_N, float).reshape(m)
    b_cable = dyn.cable_damping_per_cable(m)
    damping = dyn.joint_damping_Nms_per_rad if joint_damping_Nms_per_rad is None else joint_damping_Nms_per_rad
    I = dyn.inertia_com_A_kgm2
    l_max = 2.0 * float(np.max(np.linalg.norm(A, axis=1) + np.linalg.norm(B, axis=1)))

    out = [f"<mujoco model={quoteattr(model_name)}>",
           "  <!-- csjm_opt export: world = {B} (origin O), body 'platform' = {A}; ball qpos = R as (w x y z),",
           "       ball qvel/qfrc in {A}; cable i = tendon 'cable<i>' from site A<i> to site B<i>. SI units. -->",
           '  <compiler angle="radian" autolimits="true"/>',
           f'  <option timestep={quoteattr(_f(timestep_s))} integrator={quoteattr(integrator)} '
           f'gravity="{_v(rig.gravity_B_m_per_s2)}"/>',
           '  <default><geom contype="0" conaffinity="0"/></default>',
           "  <custom>",
           f'    <numeric name="t_min_N" data="{_f(rig.t_min_N)}"/>',
           f'    <numeric name="t_max_N" data="{_f(rig.t_max_N)}"/>',
           f'    <numeric name="cable_stiffness_N_per_m" data="{_v(k)}"/>',
           "  </custom>",
           "  <worldbody>"]
    out += [f'    <site name="B{i + 1}" pos="{_v(B[i])}" size="0.003"/>' for i in range(m)]
    out += ['    <body name="platform" pos="0 0 0">',
            f'      <joint name="ball" type="ball" pos="0 0 0" damping="{_f(damping)}"/>',
            f'      <inertial pos="{_v(rig.com_A_m)}" mass="{_f(rig.platform_mass_kg)}" '
            f'fullinertia="{_v([I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])}"/>']
    out += [f'      <site name="A{i + 1}" pos="{_v(A[i])}" size="0.003"/>' for i in range(m)]
    out += ["    </body>", "  </worldbody>", "  <tendon>"]
    for i in range(m):
        spring = (f'stiffness="{_f(k[i])}" springlength="0 {_f(l[i])}"' if actuation == "spring"
                  else 'stiffness="0"')
        out += [f'    <spatial name="cable{i + 1}" {spring} damping="{_f(b_cable[i])}" '
                f'width="0.001">',
                f'      <site site="A{i + 1}"/>', f'      <site site="B{i + 1}"/>', "    </spatial>"]
    out += ["  </tendon>", "  <actuator>"]
    ctrl: list[float] = []
    for i in range(m):
        if actuation == "winch":
            out.append(f'    <general name="winch{i + 1}" tendon="cable{i + 1}" gaintype="fixed" gainprm="{_f(k[i])}" '
                       f'biastype="affine" biasprm="0 {_f(-k[i])} {_f(-b_cable[i])}" '
                       f'ctrlrange="0 {_f(l_max)}" forcerange="{_f(-rig.t_max_N)} 0"/>')
            ctrl.append(l[i])
        elif actuation == "tension":
            out.append(f'    <motor name="tension{i + 1}" tendon="cable{i + 1}" gear="-1" '
                       f'ctrlrange="{_f(rig.t_min_N)} {_f(rig.t_max_N)}"/>')
            ctrl.append(T[i])
    for j, axis in enumerate("xyz"):
        gear = np.eye(3)[j]
        out.append(f'    <motor name="load_{axis}" joint="ball" gear="{_v(gear)}" ctrllimited="false"/>')
        ctrl.append(tau[j])
    out += ["  </actuator>", "  <keyframe>",
            f'    <key name="planned" qpos="{_v(quat_wxyz(R))}" ctrl="{_v(ctrl)}"/>',
            "  </keyframe>", "</mujoco>"]
    return "\n".join(out) + "\n"

