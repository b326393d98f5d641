"""Step loading on the quasi-static plant: each load hung at once, the platform stopping where friction holds it.

Every check is made with the toolkit's own statics, not the plant's (its cable geometry, weight
moment and equilibrium solver, :func:`solve_equilibrium`), or against a closed form: the paper
rig twisted from upright by a pure moment about its axis moves by symmetry along the twist only,
where the first held point is the root of a scalar equation.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq

from csjm_opt import so3
from csjm_opt.errors import InvalidInput
from csjm_opt.model import kinematics as kin
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed import TestbedPlant, as_mujoco, certify_static, design_cycles, make_plant
from csjm_opt.testbed.step_settling import settle_after_step

#: Imbalance (N m) the toolkit's statics allow at a held row.
HOLD_TOL_NM = 1e-6


@pytest.fixture(scope="module")
def log_args(rig):
    """Two load cycles (a new cycle's rest lengths differ: the drives move between them)."""
    cycles = design_cycles(rig, 2, np.random.default_rng(21), steps=3)
    l = np.concatenate([np.repeat(c.rest_lengths_m[None], len(c.alphas), 0) for c in cycles])
    tau = np.concatenate([c.tau_ext_A_Nm for c in cycles])
    cycle = np.concatenate([np.full(len(c.alphas), i) for i, c in enumerate(cycles)])
    R0 = np.concatenate([np.repeat(c.R_ref[None], len(c.alphas), 0) for c in cycles])
    return l, tau, cycle, R0


@pytest.fixture(scope="module")
def coulomb_rows(rig, log_args):
    """Step-loaded poses of one Coulomb-friction plant (3x typical) at static ratios 1 and 1.5."""
    l, tau, cycle, R0 = log_args
    return {ratio: make_plant(rig, "coulomb_friction", 3.0, np.random.default_rng(4), loading="step",
                              static_friction_ratio=ratio).respond(l, tau, cycle, R0) for ratio in (1.0, 1.5)}


def _held(plant: TestbedPlant, R: np.ndarray, rest: np.ndarray, tau: np.ndarray, ratio: float):
    """The toolkit's certificate: cable (Coulomb + capstan) and joint friction within ``ratio`` x sliding bounds."""
    rig = plant.rig
    c, J = kin.cable_terms(R[None], rig.platform_holes_A_m, rig.base_holes_B_m)
    T = np.asarray(rig.cable_stiffness_N_per_m) * np.maximum(c[0] - rest, 0.0)
    tau_w = kin.weight_moment(R[None], rig.platform_mass_kg * np.asarray(rig.com_A_m),
                              np.asarray(rig.gravity_B_m_per_s2))[0]
    net = J[0].T @ T + tau + tau_w
    bounds = np.r_[np.asarray(plant.friction_coulomb_N) + np.asarray(plant.friction_mu_beta) * T,
                   np.full(3, plant.joint_friction_Nm)]
    return certify_static(net, np.column_stack([J[0].T, np.eye(3)]), ratio * bounds, HOLD_TOL_NM)


@pytest.mark.parametrize("effects, ratio", [("coulomb_friction", 1.0), ("coulomb_friction", 1.5),
                                            (("friction", "joint_friction"), 1.3)])
def test_every_step_loaded_row_is_held_by_static_friction(rig, log_args, coulomb_rows, effects, ratio):
    l, tau, cycle, R0 = log_args
    plant = make_plant(rig, effects, 3.0, np.random.default_rng(4), loading="step", static_friction_ratio=ratio)
    R = coulomb_rows[ratio] if effects == "coulomb_friction" else plant.respond(l, tau, cycle, R0)
    beyond_sliding = 0
    for i in range(len(R)):
        cert = _held(plant, R[i], l[i], tau[i], ratio)
        assert cert.certified, f"row {i}: utilisation {cert.utilisation:.6f} of the static bounds"
        beyond_sliding += not _held(plant, R[i], l[i], tau[i], 1.0).certified
    if ratio > 1:
        assert beyond_sliding > 0       # rows stopped where only static friction holds them


def test_without_friction_a_step_ends_at_the_equilibrium(rig, log_args):
    """The overdamped path from one row's equilibrium under the next row's load ends at that row's equilibrium."""
    l, tau, cycle, R0 = log_args
    plant = make_plant(rig, None, 1.0, np.random.default_rng(0), loading="step")
    R_prev = solve_equilibrium(rig, l[0], tau[0], R_init=R0[0]).R
    for i in range(1, len(l)):
        rest = settle_after_step(lambda R, i=i: plant.frictionless_net(R, l[i], tau[i]), R_prev)
        eq = solve_equilibrium(rig, l[i], tau[i], R_init=R0[i])
        assert rest.moved and so3.angle_between(rest.R, eq.R) < 1e-8
        R_prev = rest.R
    R = plant.respond(l, tau, cycle, R0)          # the plant solves for the equilibria directly
    assert max(so3.angle_between(R[i], solve_equilibrium(rig, l[i], tau[i], R_init=R0[i]).R)
               for i in range(len(l))) < 1e-8


def _twist_args(rig, tau_z):
    """Upright with the rig's equal pretension, then a moment ``tau_z`` about the rig's axis hung at once."""
    c0, _ = kin.cable_terms(np.eye(3)[None], rig.platform_holes_A_m, rig.base_holes_B_m)
    rest = c0[0] - 77.5 / np.asarray(rig.cable_stiffness_N_per_m)
    return (np.stack([rest, rest]), np.array([[0.0, 0.0, 0.0], [0.0, 0.0, tau_z]]), np.zeros(2, int),
            np.stack([np.eye(3), np.eye(3)]))


def _twist_net(rig, rest, tau_z, theta):
    """Net moment about the axis at a twist ``theta`` and the cables' moments per unit force about it."""
    R = so3.exp(np.array([0.0, 0.0, theta]))[None]
    c, J = kin.cable_terms(R, rig.platform_holes_A_m, rig.base_holes_B_m)
    T = np.asarray(rig.cable_stiffness_N_per_m) * (c[0] - rest)
    return float(J[0][:, 2] @ T + tau_z), J[0][:, 2]


@pytest.mark.parametrize("ratio", [1.0, 1.5])
def test_a_twist_stops_at_the_near_edge_of_the_static_band(rig, ratio):
    """Closed form: the first held twist solves ``q_z(theta) = ratio F sum_i |J_iz(theta)|``.

    The paper rig is symmetric under a third of a turn about its axis, its centre of mass on the
    axis: a pure twist moment from upright twists it only, every cable sliding with the same
    friction force. Sliding from the start, the platform passes the sliding band's far side
    first, so it stops on the near edge of the static band (ratio 1: of the one band).
    """
    F, tau_z = 1.5, 0.4
    args = _twist_args(rig, tau_z)
    plant = dataclasses.replace(TestbedPlant(rig, friction_coulomb_N=np.full(rig.n_cables, F)),
                                loading="step", static_friction_ratio=ratio)
    R = plant.respond(*args)
    rest = args[0][1]

    def excess(theta):
        q_z, J_z = _twist_net(rig, rest, tau_z, theta)
        return q_z - ratio * F * np.abs(J_z).sum()

    free = brentq(lambda t: _twist_net(rig, rest, tau_z, t)[0], 0.0, 0.1)        # frictionless equilibrium
    theta = brentq(excess, 0.0, free)
    assert so3.angle_between(R[1], so3.exp(np.array([0.0, 0.0, theta]))) < 1e-8
    assert theta < free - 1e-3                                    # well short of where no friction would leave it
    if ratio > 1:       # held only by static friction: a sliding band would not hold it there
        assert excess(theta) == pytest.approx(0.0, abs=1e-9)
        q_z, J_z = _twist_net(rig, rest, tau_z, theta)
        assert q_z > F * np.abs(J_z).sum() + 1e-3


def test_a_held_pose_does_not_move_and_a_one_axis_spring_stops_at_its_static_edge():
    """``settle_after_step`` on a decoupled spring (closed form): from 0 towards ``theta0`` about z, friction ``b``."""
    k = np.array([30.0, 20.0, 10.0])
    theta0, b = np.array([0.0, 0.0, 0.05]), 0.2

    def net(R):
        q = -(so3.log(R) - theta0) * k
        return q, np.broadcast_to(np.array([0.0, 0.0, 1.0])[:, None], (len(R), 3, 1)), np.full((len(R), 1), b)

    for ratio in (1.0, 1.7):
        rest = settle_after_step(net, np.eye(3), ratio)
        assert rest.moved and rest.certificate.certified
        # within the certificate's imbalance (1e-7 N m) over the stiffness
        assert so3.log(rest.R) == pytest.approx([0.0, 0.0, theta0[2] - ratio * b / k[2]], abs=1.5e-8)
        again = settle_after_step(net, rest.R, ratio)
        assert not again.moved and np.array_equal(again.R, rest.R)


def test_ratio_above_one_holds_where_ratio_one_slides(rig, log_args, coulomb_rows):
    """With static friction above sliding, rows stop where the one-band plant cannot."""
    l, tau, cycle, R0 = log_args
    R = coulomb_rows
    plant = make_plant(rig, "coulomb_friction", 3.0, np.random.default_rng(4))
    outside = [not _held(plant, R[1.5][i], l[i], tau[i], 1.0).certified for i in range(1, len(l))]
    assert sum(outside) >= len(outside) // 2
    gaps = [so3.angle_between(a, b) for a, b in zip(R[1.0], R[1.5])]
    assert max(gaps) > 1e-3


def test_step_loading_defaults_and_bad_input(rig, log_args):
    plant = make_plant(rig, "coulomb_friction", 1.0, np.random.default_rng(0))
    assert plant.loading == "ramp" and plant.static_friction_ratio == 1.0
    step = dataclasses.replace(plant, loading="step", static_friction_ratio=1.4)
    engine = as_mujoco(step)                      # the same plant realised in MuJoCo, loaded the same way
    assert engine.loading == "step" and engine.static_friction_ratio == 1.4
    for bad in (0.5, float("nan"), float("inf"), "1.5x", None):
        with pytest.raises(InvalidInput, match="static_friction_ratio"):
            make_plant(rig, "coulomb_friction", 1.0, np.random.default_rng(0), loading="step",
                       static_friction_ratio=bad)
    with pytest.raises(InvalidInput, match="step loading"):
        TestbedPlant(rig, static_friction_ratio=1.2)          # ramped loads follow one band
    with pytest.raises(InvalidInput, match="loading"):
        TestbedPlant(rig, loading="jerk")
