"""Plants and dynamic controllers in the loop (MuJoCo plant checked against the engine itself)."""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.control import simulate
from csjm_opt.control.controllers import (
    InverseDynamicsController,
    SO3FeedbackController,
    StiffnessShapingController,
    TensionPlanningController,
)
from csjm_opt.control.controllers.base import Observation
from csjm_opt.control.controllers.reference import reference_rates
from csjm_opt.control.load_profiles import Constant, Step
from csjm_opt.control.plants import MujocoPlant, QuasiStaticPlant

R_HOLD = so3.exp([0.08, -0.05, 0.1])
TAU = np.array([0.2, -0.15, 0.1])


def tilt_and_torsion(t):
    """10 deg, 0.5 Hz tilt about x with 15 deg torsion about z (a reference with inertial load)."""
    s = np.sin(np.pi * t)
    return so3.exp([np.radians(10) * s, 0.0, np.radians(15) * s])


def test_reference_rates_match_closed_form():
    """omega and omega_dot of R(t) = exp(theta(t) a) for a fixed axis: theta' a and theta'' a."""
    a = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    ref = lambda t: so3.exp(0.3 * np.sin(2.0 * t) * a)  # noqa: E731
    _, w, dw = reference_rates(ref, 0.4)
    assert np.allclose(w, 0.6 * np.cos(0.8) * a, atol=1e-6)
    assert np.allclose(dw, -1.2 * np.sin(0.8) * a, atol=1e-5)


@pytest.mark.parametrize("make_plant", [lambda rig: QuasiStaticPlant(rig),
                                        lambda rig: MujocoPlant(rig, joint_damping_Nms_per_rad=0.3)])
def test_both_plants_settle_at_the_held_pose(rig, make_plant):
    """A held pose under a constant load: both plants end at R_ref (MuJoCo after its transient)."""
    ctrl = TensionPlanningController(rig, R_HOLD, solver="active_set")
    log = simulate(rig, ctrl, Constant(TAU), 1.5, plant=make_plant(rig))
    assert log.pose_error_rad[-1] <= 1e-9
    assert np.allclose(log.tensions_N[-1], co.plan_tensions(rig, R_HOLD, TAU).tensions_N, atol=1e-6)


def test_winch_rate_limit(rig):
    plant = MujocoPlant(rig, rest_length_rate_m_per_s=0.1)
    plant.reset(np.eye(3))
    ctrl = TensionPlanningController(rig, np.eye(3), solver="active_set")
    cmd = ctrl(Observation(0.0, np.eye(3), np.zeros(3)))
    plant.step(cmd, Constant([0, 0, 0]), 0.0, 1e-3)
    assert np.allclose(plant.rest_lengths_m, cmd.rest_lengths_m)          # first command taken at once
    far = type(cmd)(cmd.tensions_N, cmd.rest_lengths_m - 0.05, cmd.R_cmd)
    plant.step(far, Constant([0, 0, 0]), 1e-3, 2e-3)
    assert np.allclose(plant.rest_lengths_m - cmd.rest_lengths_m, -1e-4)   # 0.1 m/s for 1 ms


def test_inverse_dynamics_feedforward_tracks_in_mujoco(rig):
    """Tilt and torsion in MuJoCo: planning for the pose alone lags; with the inverse-dynamics
    moment the error is <= 0.1 mrad RMS (before an unknown moment step); PID feedback then
    makes the step's error decay."""
    w0 = reference_rates(tilt_and_torsion, 0.0)[1]
    load = Step(1.0, [0.3, -0.2, 0.1])
    n_before = 1000
    runs = {}
    for name, ctrl in [("pose only", InverseDynamicsController(rig, tilt_and_torsion, feedforward=False,
                                                                use_measured_load=False)),
                       ("feedforward", InverseDynamicsController(rig, tilt_and_torsion, use_measured_load=False)),
                       ("pid", SO3FeedbackController(rig, tilt_and_torsion, use_measured_load=False))]:
        runs[name] = simulate(rig, ctrl, load, 2.0, plant=MujocoPlant(rig), omega_init_A_rad_s=w0).pose_error_rad
    rms = {k: float(np.sqrt(np.mean(e[:n_before] ** 2))) for k, e in runs.items()}
    assert rms["feedforward"] <= 1e-4
    assert rms["pose only"] > 10 * rms["feedforward"]
    e = runs["pid"]
    peak = e[n_before:].max()
    assert peak > 1e-3                                     # the unknown step does disturb
    assert e[-50:].max() < 0.05 * peak                     # and the feedback removes it
    assert runs["feedforward"][-50:].mean() > 0.3 * runs["feedforward"][n_before:].max()  # no feedback: stays


@pytest.mark.parametrize("load_fixed_in", ["A", "B"])
def test_stiffness_switch_measured_in_mujoco(rig, load_fixed_in):
    """Shaping switches from a soft to a stiff K mid-run; K measured in MuJoCo by perturbation
    (weight Hessian and 1/2 hat(tau_ext) removed) matches the commanded K in both phases."""
    R = R_HOLD
    # on this rig K falls as the tensions rise (the length Hessians G_i are negative here)
    K_soft = co.stiffness(rig, R, co.plan_tensions(rig, R, TAU, t_ref_N=np.full(6, 140.0)).tensions_N)
    K_stiff = co.stiffness(rig, R, co.plan_tensions(rig, R, TAU, t_ref_N=np.full(6, 15.0)).tensions_N)
    ctrl = StiffnessShapingController(rig, R, lambda t: K_soft if t < 0.6 else K_stiff)
    plant = MujocoPlant(rig, joint_damping_Nms_per_rad=0.3, load_fixed_in=load_fixed_in)
    load = (lambda t: TAU) if load_fixed_in == "A" else (lambda t: R @ TAU)   # same moment at R
    state = plant.reset(R, load=load)
    dt = 1e-3
    for k, t_check, K_target in [(0, 0.6, K_soft), (600, 1.2, K_stiff)]:
        while k * dt < t_check - 1e-12:
            cmd = ctrl(Observation(k * dt, state.R, plant.measured_load_A(state.R, state.tau_ext_A_Nm)))
            state = plant.step(cmd, load, k * dt, (k + 1) * dt)
            k += 1
        K_engine, K_raw = plant.perturbation_stiffness()
        scale = np.abs(cmd.K_planned).max()
        assert np.abs(K_engine - cmd.K_planned).max() <= 1e-5 * scale
        assert np.abs(K_engine - K_target).max() <= 1e-3 * scale          # the targets are reachable
        assert np.abs(K_raw - cmd.K_planned).max() > 1e-3 * scale         # the correction matters
    assert np.trace(K_stiff) > 1.5 * np.trace(K_soft)


def test_plant_input_errors(rig):
    with pytest.raises(co.InvalidInput):
        MujocoPlant(rig, actuation="magic")
    with pytest.raises(co.InvalidInput):
        MujocoPlant(rig, load_fixed_in="C")
    with pytest.raises(co.InvalidInput):
        simulate(rig, TensionPlanningController(rig, np.eye(3)), Constant([0, 0, 0]), 0.01,
                 plant=MujocoPlant(rig), point_forces=[(np.array([0, 0, -1.0]), np.array([0, 0, 0.1]))])


def test_tension_actuation_needs_and_takes_feedback(rig):
    """Cables as force sources (no k J^T J): a PID with kp above the negative geometric stiffness
    holds the pose and rejects an unknown step; the tensions stay within the rig's bounds."""
    ctrl = SO3FeedbackController(rig, R_HOLD, kp=40.0, kd=0.5, ki=200.0, use_measured_load=False)
    log = simulate(rig, ctrl, Step(0.5, [0.3, -0.2, 0.1]), 2.0, plant=MujocoPlant(rig, actuation="tension"))
    e = log.pose_error_rad
    assert e[:500].max() < 1e-9                              # at rest, planned tensions hold the pose
    assert e[500:].max() > 1e-3 and e[-100:].max() < 0.01 * e[500:].max()
    assert rig.t_min_N <= log.tensions_N[1:].min() and log.tensions_N[1:].max() <= rig.t_max_N
