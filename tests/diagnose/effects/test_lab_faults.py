"""The faults labs meet, in the vocabulary: drive offsets, sensor gain, joint friction.

Each effect is checked against something it did not produce: an independent moment balance
written out cable by cable, the package's equilibrium solver, rotations measured by brute force,
the paper rig's stiffness, and the testbed (a separate simulator) for recovery.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import DriveOffsets, JointFriction, SensorGain, make_effect
from csjm_opt.diagnose.effects.joint_friction import SLIP_TRAVEL_RAD, rotation_steps
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.testbed import TestbedPlant
from csjm_opt.testbed.simulate import simulate_experiment


def _rows(l, tau, cycle=None):
    n = len(l)
    cycle = np.zeros(n, int) if cycle is None else cycle
    return Rows(np.asarray(l, float), np.asarray(tau, float), cycle, np.zeros((n, l.shape[1])))


def _balance_by_hand(rig, R, rest, tau_ext):
    """Cable moments summed cable by cable: ``sum a_i x (R^T u_i) T_i`` plus load and weight (N m, in {A})."""
    A, B = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    k = np.asarray(rig.cable_stiffness_N_per_m)
    out = []
    for Ri, li, ti in zip(R, rest, tau_ext):
        m = np.zeros(3)
        for a, b, ki, l0 in zip(A, B, k, li):
            v = b - Ri @ a
            c = np.linalg.norm(v)
            m += np.cross(a, Ri.T @ (v / c)) * ki * max(c - l0, 0.0)
        g_A = Ri.T @ np.asarray(rig.gravity_B_m_per_s2)
        out.append(m + ti + np.cross(rig.platform_mass_kg * np.asarray(rig.com_A_m), g_A))
    return np.array(out)


@pytest.fixture(scope="module")
def poses(rig):
    rng = np.random.default_rng(3)
    R = np.stack([co.so3.exp(rng.normal(0, 0.15, 3)) for _ in range(5)])
    tau = rng.normal(0, 0.5, (5, 3))
    l = np.stack([co.plan_tensions(rig, Ri, ti).rest_lengths_m for Ri, ti in zip(R, tau)])
    return R, tau, l


def test_drive_offsets_balance_matches_a_hand_written_one(rig, poses):
    R, tau, l = poses
    d = np.array([3e-4, -2e-4, 1e-4, 0.0, -4e-4, 2.5e-4])
    model = AugmentedModel(rig, [DriveOffsets(n_cables=6)])
    theta = np.r_[1e-4, d]
    g = model.balance(R, _rows(l, tau), theta)
    np.testing.assert_allclose(g, _balance_by_hand(rig, R, l + 1e-4 + d, tau), atol=1e-9)


def test_drive_offsets_are_sized_by_the_rig(rig):
    e = DriveOffsets(n_cables=4)
    assert e.param_names == ("drive_offset1_m", "drive_offset2_m", "drive_offset3_m", "drive_offset4_m")
    assert make_effect("drive_offsets", rig).n_params == len(rig.cable_stiffness_N_per_m)


def test_sensor_gain_predicts_the_equilibrium_of_the_true_moment(rig, poses):
    R, tau, l = poses
    gains = np.array([0.8, 1.1, 0.9])
    model = AugmentedModel(rig, [SensorGain("per_axis")])
    sol = model.predict_poses(_rows(l, tau * gains), np.r_[0.0, np.log(gains)], R)
    for Ri, li, ti, Rp in zip(R, l, tau, sol.R):
        eq = co.solve_equilibrium(rig, li, ti, R_init=Ri)     # the package's solver, given the true moment
        assert np.linalg.norm(co.so3.log(eq.R.T @ Rp)) < 1e-8


def test_sensor_gain_common_is_one_gain_on_every_axis():
    e = SensorGain("common")
    np.testing.assert_allclose(e.gains(np.array([np.log(0.8)])), [0.8, 0.8, 0.8])
    assert SensorGain("per_axis").n_params == 3
    with pytest.raises(ValueError):
        SensorGain("diagonal")


def test_rotation_steps_recover_a_rotation(rig):
    rng = np.random.default_rng(0)
    R = np.stack([co.so3.exp(rng.normal(0, 0.2, 3)) for _ in range(4)])
    dz = rng.normal(0, 1e-5, (4, 3))
    A, B = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    c0 = np.array([[np.linalg.norm(b - Ri @ a) for a, b in zip(A, B)] for Ri in R])
    c1 = np.array([[np.linalg.norm(b - Ri @ co.so3.exp(d) @ a) for a, b in zip(A, B)] for Ri, d in zip(R, dz)])
    from csjm_opt.model import kinematics as kin

    _, J = kin.cable_terms(R, A, B)
    np.testing.assert_allclose(rotation_steps(J, c1 - c0), dz, rtol=1e-3, atol=1e-10)


def test_joint_friction_opposes_the_motion_by_its_bound(rig, poses):
    """A row reached by a large rotation feels ``-M sign(dzeta)``; the frictionless balance is unchanged else."""
    R, tau, l = poses
    A, B = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    from csjm_opt.model import kinematics as kin

    c_now, _ = kin.cable_terms(R, A, B)
    step = np.array([0.02, -0.015, 0.01])         # the platform came from R exp(-step): it moved by +step
    c_before, _ = kin.cable_terms(R @ co.so3.exp(-step), A, B)
    rows = dataclasses.replace(_rows(l, tau), log_steps_m=c_now - c_before)
    M = 0.07
    g_fric = AugmentedModel(rig, [JointFriction()]).balance(R, rows, np.r_[0.0, M])
    g_nom = AugmentedModel(rig, []).balance(R, rows, np.r_[0.0])
    expected = -M * np.tanh(step / SLIP_TRAVEL_RAD)       # about (-M, +M, 0)
    np.testing.assert_allclose(g_fric - g_nom, np.broadcast_to(expected, g_nom.shape), atol=2e-3 * M)


def test_joint_friction_lags_the_load_by_the_compliance_times_the_bound(rig):
    """Loading in +x from rest: the pose lags the frictionless one by ``K^-1 M s`` (K from co.stiffness)."""
    R0 = np.eye(3)
    l = co.plan_tensions(rig, R0, np.zeros(3)).rest_lengths_m
    tau = np.array([[0.0, 0.0, 0.0], [0.6, 0.0, 0.0]])
    rows = _rows(np.repeat(l[None], 2, 0), tau)
    M = 0.03
    free = co.solve_equilibrium(rig, l, tau[1], R_init=R0)
    model = AugmentedModel(rig, [JointFriction()])
    from csjm_opt.model import kinematics as kin

    c0, _ = kin.cable_terms(R0[None], rig.platform_holes_A_m, rig.base_holes_B_m)   # the row before, at rest
    rows_seq = dataclasses.replace(rows.take(np.array([1])), state_prev=np.zeros((1, 6)), lengths_prev_m=c0)
    sol = kin.solve_poses(lambda R: model.balance(R, rows_seq, np.r_[0.0, M]), free.R[None])
    dz_free = co.so3.log(free.R)
    dz_fric = co.so3.log(sol.R[0])
    s = np.tanh(dz_fric / SLIP_TRAVEL_RAD)        # the direction the model slid in
    K = co.stiffness(rig, free.R, free.tensions)
    np.testing.assert_allclose(dz_free - dz_fric, np.linalg.solve(K, M * s), rtol=0.1, atol=2e-5)


def test_testbed_plant_realises_drive_offsets_and_gains(rig):
    d = np.array([4e-4, -3e-4, 0.0, 1e-4, -2e-4, 0.0])
    shifted = TestbedPlant.nominal(rig)
    offset = dataclasses.replace(TestbedPlant.nominal(rig), drive_offsets_m=d)
    l = co.plan_tensions(rig, np.eye(3), np.zeros(3)).rest_lengths_m[None]
    tau = np.array([[0.3, -0.2, 0.1]])
    R1 = offset.respond(l, tau, np.zeros(1, int), np.eye(3)[None])
    R2 = shifted.respond(l + d, tau, np.zeros(1, int), np.eye(3)[None])
    np.testing.assert_allclose(R1, R2, atol=1e-12)
    gained = dataclasses.replace(TestbedPlant.nominal(rig), sensor_gain_A=np.array([0.8, 1.0, 1.2]))
    np.testing.assert_allclose(gained.measured_moment(tau), tau * [0.8, 1.0, 1.2])


@pytest.mark.parametrize("seed", [1])
def test_drive_offsets_recovered_from_a_testbed_log(rig, seed):
    rng = np.random.default_rng(seed)
    d = np.array([6e-4, -4e-4, 2e-4, -5e-4, 3e-4, -2e-4])
    plant = dataclasses.replace(TestbedPlant.nominal(rig), drive_offsets_m=d)
    log = simulate_experiment(rig, 10, rng, plant)
    fit = fit_model(AugmentedModel(rig, [make_effect("drive_offsets", rig)]), compute_residuals(rig, log))
    got = fit.theta[1:] + fit.theta[0]            # the common part sits in the nuisance
    rel = got - got.mean()
    np.testing.assert_allclose(rel, d - d.mean(), atol=1.5e-4)


def test_sensor_gain_variant_chosen_by_the_data(rig):
    from csjm_opt.diagnose.decision_rule import _Context
    from csjm_opt.diagnose.fitting.model_fits import variant_fit

    rng = np.random.default_rng(5)
    per_axis = dataclasses.replace(TestbedPlant.nominal(rig), sensor_gain_A=np.array([0.75, 1.0, 1.25]))
    log = simulate_experiment(rig, 8, rng, per_axis)
    ctx = _Context(rig, compute_residuals(rig, log), None)
    opt, fit, _ = variant_fit(ctx, rig, "sensor_gain", None)
    assert opt == {"axes": "per_axis"}
    np.testing.assert_allclose(np.exp(fit.theta[1:]), [0.75, 1.0, 1.25], atol=0.05)
    common = dataclasses.replace(TestbedPlant.nominal(rig), sensor_gain_A=np.full(3, 0.85))
    log = simulate_experiment(rig, 8, rng, common)
    ctx = _Context(rig, compute_residuals(rig, log), None)
    opt, fit, _ = variant_fit(ctx, rig, "sensor_gain", None)
    assert opt == {"axes": "common"}
    assert abs(np.exp(fit.theta[1]) - 0.85) < 0.03


def test_a_models_evidence_is_the_mean_over_its_variants(rig):
    # the variant is a parameter with K equally likely values: the evidence of the model is the mean of its
    # variants' evidences, each variant fitted here on its own (not through variant_fit)
    from scipy.special import logsumexp

    from csjm_opt.diagnose.decision_rule import _Context
    from csjm_opt.diagnose.fitting.evidence import log_evidence
    from csjm_opt.diagnose.fitting.model_fits import VARIANTS, variant_fit

    rng = np.random.default_rng(6)
    log = simulate_experiment(rig, 8, rng, dataclasses.replace(TestbedPlant.nominal(rig),
                                                               sensor_gain_A=np.full(3, 0.9)))
    table = compute_residuals(rig, log)
    ctx = _Context(rig, table, None)
    fits = [fit_model(AugmentedModel(rig, [make_effect("sensor_gain", rig, **o)]), table)
            for o in VARIANTS["sensor_gain"]]
    scale = np.sqrt(min(f.rss for f in fits) / fits[0].n_obs)
    ev = np.array([log_evidence(f, scale) for f in fits])
    opt, fit, weight = variant_fit(ctx, rig, "sensor_gain", None)
    assert -np.log(2) <= weight <= 0.0
    assert np.isclose(log_evidence(fit, scale) + weight, logsumexp(ev) - np.log(2), atol=1e-6)
    assert opt == VARIANTS["sensor_gain"][int(np.argmax(ev))]
