"""Closed-loop simulation (csjm_opt/closed_loop.py, controllers/, load_profiles.py)."""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import so3
from csjm_opt._plotting import save
from csjm_opt.control.closed_loop import plot_closed_loop, plot_closed_loop_stiffness, simulate
from csjm_opt.control.controllers import (
    Command,
    Controller,
    Observation,
    StiffnessShapingController,
    TensionPlanningController,
)
from csjm_opt.control.load_profiles import Constant, Ramp, Sinusoid, Step
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.shaping.shaper import shape_stiffness

R_REF = so3.exp(np.array([0.08, 0.05, -0.03]))
TAU_STEP = np.array([0.3, -0.4, 0.1])


def reachable_K(rig, model, tau, move):
    """K of feasible tensions (plan moved in the null space of J^T): reachable by construction."""
    plan = co.plan_tensions(rig, R_REF, tau, model=model)
    N = np.linalg.svd(model.jacobian(R_REF).T)[2][3:].T
    T = plan.tensions_N + N @ np.asarray(move, float)
    assert np.all(T > rig.t_min_N) and np.all(T < rig.t_max_N)
    return model.stiffness(R_REF, T)


def test_load_profiles_closed_forms():
    step = Step(0.1, [1.0, 0, 0], before_A_Nm=[0, 1.0, 0])
    assert np.allclose(step(0.05), [0, 1, 0]) and np.allclose(step(0.1), [1, 0, 0])
    ramp = Ramp(1.0, 3.0, [0, 0, 2.0])
    assert np.allclose(ramp(0.0), 0) and np.allclose(ramp(2.0), [0, 0, 1.0]) and np.allclose(ramp(9), [0, 0, 2])
    sine = Sinusoid([0.5, 0, 0], 2.0, t0_s=0.25)
    assert np.allclose(sine(0.2), 0) and np.isclose(sine(0.25 + 0.125)[0], 0.5)
    total = step + ramp + sine + Constant([0, 0, -1.0])
    t = 2.0
    assert np.allclose(total(t), step(t) + ramp(t) + sine(t) + np.array([0, 0, -1.0]))
    with pytest.raises(co.InvalidInput):
        Ramp(1.0, 1.0, [0, 0, 1])


def test_step_load_converges_and_tracks_reachable_target(rig, model):
    K_target = reachable_K(rig, model, TAU_STEP, [20.0, -10.0, 15.0])
    ctrl = StiffnessShapingController(rig, R_REF, K_target)
    log = simulate(rig, ctrl, Step(0.02, TAU_STEP), duration_s=0.06, dt_s=1e-3)
    err = log.pose_error_rad
    k_step = int(round(0.02 / 1e-3))
    assert np.all(err[:k_step] < 1e-9)                        # held before the step
    assert err[k_step] > 1e-3                                  # the step moves the pose once (one-step delay)
    assert np.all(err[k_step + 1:] < 1e-9)                     # then the pose is held again
    # first-order size of the deflection: K_t^-1 dtau with the plant's tangent stiffness
    assert err[k_step] < 2.0 * np.linalg.norm(TAU_STEP) / np.linalg.eigvalsh(log.K[k_step - 1])[0]
    # achieved stiffness (plant, at its actual pose) equals the reachable target after the step
    assert np.abs(log.K[-1] - K_target).max() <= 1e-6
    assert np.all(log.stiffness_error[k_step + 1:] <= 1e-6)
    assert np.all(np.linalg.norm(model.jacobian(R_REF).T @ log.tensions_N[-1:].T, axis=0) > 0)


def test_switching_targets_tracked(rig, model):
    K_soft = reachable_K(rig, model, TAU_STEP, [-30.0, 20.0, -25.0])
    K_stiff = reachable_K(rig, model, TAU_STEP, [30.0, -20.0, 25.0])
    assert np.linalg.norm(K_soft - K_stiff) > 1.0
    target = lambda t: K_soft if (t // 0.01) % 2 == 0 else K_stiff            # noqa: E731
    ctrl = StiffnessShapingController(rig, R_REF, target)
    log = simulate(rig, ctrl, Constant(TAU_STEP), duration_s=0.04, dt_s=1e-3)
    assert np.all(log.pose_error_rad[1:] < 1e-9)
    assert np.all(log.stiffness_error[1:] <= 1e-6)
    assert np.allclose(log.K[5], K_soft, atol=1e-6) and np.allclose(log.K[15], K_stiff, atol=1e-6)


def test_unreachable_target_gives_best_and_holds_pose(rig, model):
    ctrl = StiffnessShapingController(rig, R_REF, 60.0 * np.eye(3))
    log = simulate(rig, ctrl, Constant(TAU_STEP), duration_s=0.005, dt_s=1e-3)
    ref = shape_stiffness(rig, R_REF, TAU_STEP, 60.0 * np.eye(3), model=model)
    assert np.all(log.pose_error_rad[1:] < 1e-9)
    assert np.allclose(log.K[-1], ref.K, atol=1e-6) and log.stiffness_error[-1] > 1.0


def test_tension_planning_controller(rig, model):
    ctrl = TensionPlanningController(rig, R_REF)
    log = simulate(rig, ctrl, Step(0.003, TAU_STEP), duration_s=0.008, dt_s=1e-3)
    assert np.all(log.pose_error_rad[5:] < 1e-9)
    plan = co.plan_tensions(rig, R_REF, TAU_STEP, model=model)
    assert np.allclose(log.tensions_N[-1], plan.tensions_N, atol=1e-6)
    assert np.all(np.isnan(log.K_target))


def test_integral_action_removes_model_mismatch(rig):
    plant = rig.replace(cable_stiffness_N_per_m=rig.cable_stiffness_N_per_m * np.array([1.1, 0.9, 1.05, 1, 0.95, 1.1]),
                        platform_mass_kg=0.6)
    open_loop = simulate(rig, TensionPlanningController(rig, R_REF), Constant(TAU_STEP), 0.05, plant_rig=plant)
    closed = simulate(rig, TensionPlanningController(rig, R_REF, integral_gain=0.5), Constant(TAU_STEP), 0.05,
                      plant_rig=plant)
    assert open_loop.pose_error_rad[-1] > 1e-4
    assert closed.pose_error_rad[-1] < 1e-3 * open_loop.pose_error_rad[-1]


def test_noise_and_dead_weight(rig):
    """Noisy instruments and a dead weight on the platform (measured by the F/T sensor)."""
    ctrl = TensionPlanningController(rig, R_REF, integral_gain=0.2)
    weight = (np.array([0.0, 0.0, -3.0]), np.array([0.02, 0.0, 0.05]))
    log = simulate(rig, ctrl, Sinusoid([0.2, 0, 0], 5.0), 0.1, noise=InstrumentNoise.paper(),
                   rng=np.random.default_rng(0), point_forces=[weight])
    sigma = InstrumentNoise.paper()
    # error bounded by a few noise levels and the sinusoid's one-step lag
    assert np.max(log.pose_error_rad) < 10 * (sigma.angle_sigma_rad + np.max(sigma.tau_sigma_Nm) / 10) + 0.01
    noiseless = simulate(rig, TensionPlanningController(rig, R_REF), Constant(np.zeros(3)), 0.005,
                         point_forces=[weight])
    assert np.all(noiseless.pose_error_rad[1:] < 1e-9)       # the dead weight's moment is fed forward


class FixedRestLengths(Controller):
    """A user controller: constant rest lengths (open loop)."""

    def __init__(self, rig, l):
        self.rig, self.l = rig, l

    def __call__(self, observation: Observation) -> Command:
        return Command(np.full(6, np.nan), self.l, np.eye(3))


def test_custom_controller_and_figures(rig, model, tmp_path):
    plan = co.plan_tensions(rig, np.eye(3), np.zeros(3), model=model)
    l = model.rest_lengths(np.eye(3), plan.tensions_N)
    log = simulate(rig, FixedRestLengths(rig, l), Ramp(0.0, 0.01, [0.2, 0, 0]), 0.01)
    assert log.R.shape == (11, 3, 3) and log.tensions_N.shape == (11, 6)
    assert log.pose_error_rad[-1] > 1e-3                     # open loop yields under the ramp
    axes = plot_closed_loop(log, rig.t_min_N, rig.t_max_N)
    np.testing.assert_allclose(axes[2].get_lines()[0].get_ydata(), log.tensions_N[:, 0])
    paths = [save(axes[0].figure, tmp_path / "closed_loop.png"),
             save(plot_closed_loop_stiffness(log)[0].figure, tmp_path / "closed_loop_K.png")]
    assert all(p.exists() and p.stat().st_size > 5000 for p in paths)
    summary = log.summary()
    assert summary["steps"] == 10 and summary["median_step_time_s"] > 0


def test_slack_command_raises_with_time(rig, model):
    plan = co.plan_tensions(rig, np.eye(3), np.zeros(3), model=model)
    l = model.rest_lengths(np.eye(3), plan.tensions_N) + 0.2
    with pytest.raises(co.NoEquilibrium, match="at t = 0.0000 s"):
        simulate(rig, FixedRestLengths(rig, l), Constant(np.zeros(3)), 0.002)
    with pytest.raises(co.InvalidInput):
        simulate(rig, FixedRestLengths(rig, l), Constant(np.zeros(3)), 0.0)


def test_moving_reference_tracked_with_one_step_lag(rig):
    """A slowly rotating reference: the plant reaches the pose commanded one step earlier."""
    w = np.array([0.0, 0.0, 0.5])                                              # rad/s about z
    ref = lambda t: R_REF @ so3.exp(w * t)                                     # noqa: E731
    log = simulate(rig, TensionPlanningController(rig, ref), Constant(TAU_STEP), 0.02, dt_s=1e-3)
    lag = np.linalg.norm(w) * 1e-3
    assert np.allclose(log.pose_error_rad[2:], lag, rtol=1e-6)
    for k in range(1, len(log.t_s)):
        assert so3.angle_between(log.R[k], ref(log.t_s[k - 1])) < 1e-9
