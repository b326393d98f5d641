"""The MuJoCo plant: agreement with the toolkit's statics, each effect's physics, certified friction settling."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.errors import NoEquilibrium
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed import TestbedPlant, as_mujoco, certify_static, make_plant
from csjm_opt.testbed.mujoco.engine import Engine
from tests.testbed.mujoco.conftest import rows_args


def test_nominal_mujoco_plant_agrees_with_the_toolkit_statics(rig, cycle):
    args = rows_args(cycle)
    rows = as_mujoco(TestbedPlant.nominal(rig)).respond_rows(*args)
    for i, row in enumerate(rows):
        eq = solve_equilibrium(rig, cycle.rest_lengths_m, cycle.tau_ext_A_Nm[i], R_init=cycle.R_ref)
        assert so3.angle_between(row.R_tool, eq.R) < 1e-9
        np.testing.assert_allclose(row.tensions_N, eq.tensions_N, atol=1e-6)
        assert row.certificate is None                      # frictionless: polished, not certified


@pytest.mark.parametrize("what", ["stiffness", "mass"])
def test_small_changes_move_the_pose_by_the_tangent_stiffness(rig, cycle, what):
    """Stiffness x (1 + eps): delta = K_t^-1 eps tau_cable; mass x (1 + eps): delta = K_t^-1 eps tau_weight."""
    i, eps = 2, (2e-3 if what == "stiffness" else 2e-2)
    eq = solve_equilibrium(rig, cycle.rest_lengths_m, cycle.tau_ext_A_Nm[i], R_init=cycle.R_ref)
    if what == "stiffness":
        true = rig.replace(cable_stiffness_N_per_m=(1 + eps) * np.asarray(rig.cable_stiffness_N_per_m))
        push = eps * eq.tau_cable_A_Nm
    else:
        true = rig.replace(platform_mass_kg=(1 + eps) * rig.platform_mass_kg)
        push = eps * eq.tau_points_A_Nm                     # the weight's moment (no other point forces)
    row = as_mujoco(TestbedPlant(true)).respond_rows(cycle.rest_lengths_m[None], cycle.tau_ext_A_Nm[i:i + 1],
                                              np.zeros(1, int), eq.R[None])[0]
    moved = so3.log(eq.R.T @ row.R_tool)
    predicted = np.linalg.solve(eq.K_tangent, push)
    assert np.linalg.norm(predicted) > 1e-5
    np.testing.assert_allclose(moved, predicted, rtol=0, atol=3 * eps * np.linalg.norm(predicted))   # O(eps^2)


def test_hole_offsets_hardening_and_link_match_the_quasi_static_plant(rig, cycle):
    """Two independent implementations (MuJoCo's tendons and the toolkit's kinematics) of the same physics."""
    args = rows_args(cycle)
    for effect, severity in (("hole_offsets", 1.0), ("cable_hardening", 3.0), ("link_compliance", 2.0)):
        plant = make_plant(rig, effect, severity, np.random.default_rng(3))
        R_q = plant.respond(*args)
        rows = as_mujoco(plant).respond_rows(*args)
        nominal = TestbedPlant.nominal(rig).respond(*args)
        for i, row in enumerate(rows):
            assert so3.angle_between(row.R_tool, nominal[i]) > 1e-4, effect      # the effect shows
            assert so3.angle_between(row.R_tool, R_q[i]) < 1e-9, effect


def test_hardening_with_a_link_matches_the_quasi_static_plant(rig, cycle):
    """Hardening on a plant with a link (six dofs: the tendons span only the platform's three)."""
    args = rows_args(cycle)
    plant = make_plant(rig, ["cable_hardening", "link_compliance"], 2.0, np.random.default_rng(3))
    R_q = plant.respond(*args)
    rows = as_mujoco(plant).respond_rows(*args)
    for i, row in enumerate(rows):
        assert row.settled
        assert so3.angle_between(row.R_tool, R_q[i]) < 1e-9


def test_tendon_jacobian_is_the_derivative_of_the_tendon_lengths(rig):
    """The dense tendon Jacobian (MuJoCo 4 stores it sparse) against central differences of the lengths."""
    import mujoco

    from csjm_opt.testbed.mujoco.statics import tendon_jacobian

    plant = dataclasses.replace(TestbedPlant.nominal(rig), link_compliance_rad_per_Nm=np.diag([0.006, 0.004, 0.008]))
    engine = Engine(as_mujoco(plant), np.full(6, 0.1))
    m, d = engine.m, engine.d
    rng = np.random.default_rng(8)
    q0 = np.zeros(m.nq)
    q0[:4], q0[4:8] = _quat(0.2 * rng.normal(size=3)), _quat(0.05 * rng.normal(size=3))
    d.qpos[:] = q0
    mujoco.mj_forward(m, d)
    J = tendon_jacobian(m, d)
    assert J.shape == (m.ntendon, m.nv)
    h = 1e-6
    fd = np.zeros_like(J)
    for k in range(m.nv):
        for sgn in (1.0, -1.0):
            q = q0.copy()
            mujoco.mj_integratePos(m, q, sgn * h * np.eye(m.nv)[k], 1.0)
            d.qpos[:] = q
            mujoco.mj_forward(m, d)
            fd[:, k] += sgn * np.asarray(d.ten_length) / (2 * h)
    np.testing.assert_allclose(J, fd, atol=1e-8)
    assert np.abs(J[:, 3:]).max() == 0.0 and np.abs(J[:, :3]).min() > 0.0    # the link moves no tendon


def _quat(v):
    from csjm_opt.model.mjcf import quat_wxyz

    return quat_wxyz(so3.exp(v))


def test_link_turns_the_tool_by_the_compliance_times_the_tool_moment(rig, cycle):
    C = np.diag([0.006, 0.004, 0.008])
    plant = dataclasses.replace(TestbedPlant.nominal(rig), link_compliance_rad_per_Nm=C)
    rows = as_mujoco(plant).respond_rows(*rows_args(cycle))
    g = np.asarray(rig.gravity_B_m_per_s2)
    for i, row in enumerate(rows):
        tau_m = cycle.tau_ext_A_Nm[i] + np.cross(rig.platform_mass_kg * np.asarray(rig.com_A_m), row.R_tool.T @ g)
        np.testing.assert_allclose(so3.log(row.R_platform.T @ row.R_tool), C @ tau_m, atol=1e-10)


def test_dead_weight_equals_a_point_force_in_the_toolkit_statics(rig, cycle):
    mass, point = 0.3, np.array([0.03, -0.02, 0.01])
    g = np.asarray(rig.gravity_B_m_per_s2)
    eq = solve_equilibrium(rig, cycle.rest_lengths_m, cycle.tau_ext_A_Nm[1], point_forces=[(mass * g, point)],
                           R_init=cycle.R_ref)
    args = (cycle.rest_lengths_m[None], cycle.tau_ext_A_Nm[1:2], np.zeros(1, int), cycle.R_ref[None],
            (mass * point)[None])
    assert so3.angle_between(TestbedPlant.nominal(rig).respond(*args)[0], eq.R) < 1e-9
    assert so3.angle_between(as_mujoco(TestbedPlant.nominal(rig)).respond(*args)[0], eq.R) < 1e-9


def test_certify_static_against_the_closed_form():
    """One coordinate, two friction elements pushing along it: the smallest share is |q| / (b1 + b2)."""
    cert = certify_static(np.array([0.3]), np.array([[1.0, 2.0]]), np.array([0.1, 0.2]))
    assert cert.certified and cert.utilisation == pytest.approx(0.3 / (0.1 + 2 * 0.2), rel=1e-6)
    too_much = certify_static(np.array([0.6]), np.array([[1.0, 2.0]]), np.array([0.1, 0.2]))
    assert not too_much.certified and too_much.utilisation == pytest.approx(0.6 / 0.5, rel=1e-6)
    # a frictionless coordinate must balance on its own
    assert not certify_static(np.array([0.0, 1e-3]), np.array([[1.0], [0.0]]), np.array([1.0])).certified


def test_friction_settle_is_certified_and_holds_when_simulated_longer(rig, cycle):
    """The LP certifies the settled pose; it holds for 2 s more; without noslip the soft friction creeps
    (towards the frictionless pose) until it no longer holds anything."""
    moved, settled = {}, {}
    for noslip in (1000, 0):
        plant = make_plant(rig, "coulomb_friction", 3.0, np.random.default_rng(4))
        engine = Engine(as_mujoco(plant, noslip_iterations=noslip), cycle.rest_lengths_m)
        engine.relaxed_start(cycle.R_ref, cycle.rest_lengths_m, cycle.tau_ext_A_Nm[0], np.zeros(3))
        engine.settle(0)
        engine.ramp(cycle.rest_lengths_m, cycle.tau_ext_A_Nm[2], np.zeros(3))
        try:
            row = engine.settle(1)
        except NoEquilibrium:            # (without noslip the wait may end uncertified)
            row = None
        R_settled = settled[noslip] = _rot(engine.d.qpos[:4])
        engine.run(int(2.0 / engine.m.opt.timestep))             # two more seconds at the same inputs
        moved[noslip] = so3.angle_between(R_settled, _rot(engine.d.qpos[:4]))
        if noslip:
            assert row is not None and row.certificate is not None and row.certificate.certified
            assert row.certificate.utilisation > 0.5             # friction carries a real share of the load
    assert moved[1000] < 1e-6                                     # 0.1 % of the tracker's noise
    assert so3.angle_between(settled[0], settled[1000]) > 3e-3


def test_coulomb_rows_come_to_rest_with_the_default_noslip(rig, cycle):
    """Rigid Coulomb stick: every row of a carried two-cycle run comes to rest (a stuck cable does not creep).

    With too few noslip iterations the redundant tendon frictions (six on three dofs) are not solved and
    the plant kept creeping at up to 2e-4 rad/s after 6 s of settling; rows then failed to certify.
    """
    plant = make_plant(rig, "coulomb_friction", 3.0, np.random.default_rng(4))
    rows = as_mujoco(plant).respond_rows(*rows_args(cycle, repeat=2))
    for row in rows:
        assert row.certificate is not None and row.certificate.certified
        assert row.speed_rad_per_s < 1e-5


def _rot(quat):
    from csjm_opt.testbed.mujoco.engine import _rotation

    return _rotation(quat)


@pytest.mark.parametrize("effect", ["coulomb_friction", "joint_friction"])
def test_mujoco_hysteresis_and_memory_across_cycles(rig, cycle, effect):
    """Loading then unloading does not return to the start with friction, and the next cycle starts there."""
    args = rows_args(cycle, repeat=2)
    m = len(cycle.alphas)
    R = as_mujoco(make_plant(rig, effect, 3.0, np.random.default_rng(5))).respond(*args)
    assert so3.angle_between(R[0], R[m - 1]) > 1e-3
    # nothing changed: nothing moves (but MuJoCo's residual creep, ~1e-6 rad over the 20 s ramp to a new cycle)
    assert so3.angle_between(R[m], R[m - 1]) < 5e-6
    R0 = as_mujoco(TestbedPlant.nominal(rig)).respond(*args)
    assert so3.angle_between(R0[0], R0[m - 1]) < 1e-10
    if effect == "joint_friction":       # relaxed cycles: the second repeats the first
        relaxed = dataclasses.replace(make_plant(rig, effect, 3.0, np.random.default_rng(5)), persistent=False)
        R_r = as_mujoco(relaxed).respond(*args)
        for i in range(m):
            assert so3.angle_between(R_r[m + i], R_r[i]) < 1e-7


def test_mujoco_friction_agrees_with_the_quasi_static_play_operator(rig, cycle):
    """MuJoCo's tendon friction is the quasi-static Coulomb law with a rigid platform-side segment (rho -> 0)."""
    args = rows_args(cycle)
    plant = make_plant(rig, "coulomb_friction", 3.0, np.random.default_rng(6))
    R_m = as_mujoco(plant).respond(*args)
    R_q = dataclasses.replace(plant, friction_platform_fraction=0.01).respond(*args)
    R_n = TestbedPlant.nominal(rig).respond(*args)
    for i in range(1, len(R_m)):
        size = so3.angle_between(R_n[i], R_q[i])
        assert size > 3e-3
        assert so3.angle_between(R_m[i], R_q[i]) < 0.1 * size


def test_joint_friction_agrees_between_the_plants(rig, cycle):
    """Ball-joint friction: MuJoCo's per-axis frictionloss and the quasi-static per-axis play operator."""
    args = rows_args(cycle)
    plant = make_plant(rig, "joint_friction", 3.0, np.random.default_rng(7))
    R_m = as_mujoco(plant).respond(*args)
    R_q = plant.respond(*args)
    R_n = TestbedPlant.nominal(rig).respond(*args)
    for i in range(1, len(R_m)):
        size = so3.angle_between(R_n[i], R_q[i])
        assert size > 1e-3
        assert so3.angle_between(R_m[i], R_q[i]) < 0.1 * size


def test_remaining_travel_is_the_distance_left_to_the_equilibrium(rig, cycle):
    """Overdamped approach: ``|K^-1 c v|`` is the distance still to go (toolkit statics), up to the inertia term."""
    import mujoco

    from csjm_opt.model.mjcf import quat_wxyz

    eq = solve_equilibrium(rig, cycle.rest_lengths_m, cycle.tau_ext_A_Nm[2], R_init=cycle.R_ref)
    engine = Engine(as_mujoco(TestbedPlant.nominal(rig)), cycle.rest_lengths_m)
    engine.set_inputs(cycle.rest_lengths_m, cycle.tau_ext_A_Nm[2], np.zeros(3))
    engine.d.qpos[:4] = quat_wxyz(eq.R @ so3.exp(np.array([0.02, -0.01, 0.015])))
    mujoco.mj_forward(engine.m, engine.d)
    engine.run(100)                                      # past the fast transient
    for _ in range(4):
        engine.run(50)
        left = so3.angle_between(_rot(engine.d.qpos[:4]), eq.R)
        assert left > 1e-5
        assert engine.remaining_travel() == pytest.approx(left, rel=0.1)


def test_frictionless_rows_settle_when_the_move_outlasts_one_wait(rig, cycle):
    """A wait far shorter than the move (as a long move on a soft rig): further waits, then Newton's method,
    reach the toolkit's stable equilibrium."""
    args = rows_args(cycle)
    rows = as_mujoco(TestbedPlant.nominal(rig), max_settle_s=0.05, ramp_s=0.01).respond_rows(*args)
    for i, row in enumerate(rows):
        eq = solve_equilibrium(rig, cycle.rest_lengths_m, cycle.tau_ext_A_Nm[i], R_init=cycle.R_ref)
        assert so3.angle_between(row.R_tool, eq.R) < 1e-9
