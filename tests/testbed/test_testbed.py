"""Synthetic experiment generator: designs, plant physics, noisy logs in the documented log format."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.model import kinematics as kin
from csjm_opt.model.numeric import Model
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed import TestbedPlant, design_cycles, make_plant, simulate_experiment, up_down


def test_kinematics_match_the_casadi_model(rig, model):
    R = so3.random_rotations(5, np.random.default_rng(0), 0.4)
    lengths, J = kin.cable_terms(R, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    np.testing.assert_allclose(lengths, model.cable_lengths(R), atol=1e-14)
    np.testing.assert_allclose(J, model.jacobian(R), atol=1e-14)
    m_r_A = rig.platform_mass_kg * np.asarray(rig.com_A_m)
    np.testing.assert_allclose(kin.weight_moment(R, m_r_A, np.asarray(rig.gravity_B_m_per_s2)),
                               model.weight_moment(R), atol=1e-14)


def test_up_down_cycle_order():
    np.testing.assert_allclose(up_down(2), [0, 0.5, 1, 0.5, 0])


def test_nominal_plant_agrees_with_core_forward_statics(rig):
    c = design_cycles(rig, 1, np.random.default_rng(1))[0]
    n = len(c.alphas)
    R = TestbedPlant.nominal(rig).respond(np.repeat(c.rest_lengths_m[None], n, 0), c.tau_ext_A_Nm, np.zeros(n, int),
                                   np.repeat(c.R_ref[None], n, 0))
    m = Model(rig)
    for i in (0, n // 2, n - 1):
        eq = solve_equilibrium(rig, c.rest_lengths_m, c.tau_ext_A_Nm[i], R_init=c.R_ref, model=m)
        assert so3.angle_between(eq.R, R[i]) < 1e-9
    assert so3.angle_between(R[0], c.R_ref) < 1e-8      # planned pre-load holds the reference pose


def test_simulated_log_is_a_valid_spec_log(rig, tmp_path):
    log = simulate_experiment(rig, 3, np.random.default_rng(2), steps=3)
    assert len(log) == 3 * 7 and log.cycle_ids == [0, 1, 2]
    path = log.to_csv(tmp_path / "log.csv")
    back = MeasurementLog.from_csv(path)
    np.testing.assert_allclose(back.rotvec_rad, log.rotvec_rad)
    np.testing.assert_array_equal(back.cycle, log.cycle)
    for c in log.cycle_ids:   # rest lengths fixed within a cycle
        assert np.ptp(log.rest_lengths_m[log.cycle_rows(c)], axis=0).max() == 0


def test_noise_has_the_instrument_scale(rig):
    noise = InstrumentNoise.paper()
    rng = np.random.default_rng(3)
    plant = TestbedPlant.nominal(rig)
    clean = simulate_experiment(rig, 6, np.random.default_rng(3), effect=plant, noise=InstrumentNoise.none())
    noisy = simulate_experiment(rig, 6, rng, effect=plant, noise=noise)
    dtau = noisy.tau_ext_A_Nm - clean.tau_ext_A_Nm
    np.testing.assert_allclose(dtau.std(axis=0), noise.tau_sigma_Nm, rtol=0.35)


def test_friction_plant_is_path_dependent(rig):
    rng = np.random.default_rng(4)
    c = design_cycles(rig, 1, rng)[0]
    n = len(c.alphas)
    args = (np.repeat(c.rest_lengths_m[None], n, 0), c.tau_ext_A_Nm, np.zeros(n, int), np.repeat(c.R_ref[None], n, 0))
    R_nom = TestbedPlant.nominal(rig).respond(*args)
    R_fr = make_plant(rig, "friction", 1.0, rng).respond(*args)
    up, down = 1, n - 2                      # same load on the way up and down
    assert c.alphas[up] == c.alphas[down]
    assert so3.angle_between(R_nom[up], R_nom[down]) < 1e-9
    assert so3.angle_between(R_fr[up], R_fr[down]) > 1e-3


def test_sensor_bias_and_link_compliance_laws(rig):
    rng = np.random.default_rng(5)
    b = make_plant(rig, "sensor_bias", 1.0, rng)
    np.testing.assert_allclose(b.measured_moment(np.zeros(3)), b.sensor_bias_A_Nm)
    assert np.linalg.norm(b.sensor_bias_A_Nm) == pytest.approx(0.12)
    C = make_plant(rig, "link_compliance", 1.0, rng).link_compliance_rad_per_Nm
    np.testing.assert_allclose(C, C.T, atol=1e-15)
    assert np.all(np.linalg.eigvalsh(C) > 0)
    # with C, the measured body turns by exp(C tau_m) relative to the cable platform
    c = design_cycles(rig, 1, rng)[0]
    plant = dataclasses.replace(TestbedPlant.nominal(rig), link_compliance_rad_per_Nm=C)
    R_m = plant.respond(c.rest_lengths_m[None], c.tau_ext_A_Nm[:1], np.zeros(1, int), c.R_ref[None])[0]
    tau_m = c.tau_ext_A_Nm[0] + Model(rig).weight_moment(R_m)
    R_cable = R_m @ so3.exp(C @ tau_m).T
    eq = solve_equilibrium(rig, c.rest_lengths_m, so3.exp(C @ tau_m) @ tau_m, R_init=R_cable,
                           include_weight=False)
    assert so3.angle_between(eq.R, R_cable) < 1e-8


def test_random_rigs_hold_their_experiment_and_stay_in_range():
    from csjm_opt.testbed import RigRanges, random_rig

    ranges = RigRanges()
    k_all = []
    for seed in range(3):
        rig, noise = random_rig(np.random.default_rng(seed))
        k = np.asarray(rig.cable_stiffness_N_per_m)
        k_all.append(k.mean())
        lo, hi = ranges.stiffness_N_per_m
        assert np.all(k >= lo * 0.9) and np.all(k <= hi * 1.1)
        assert ranges.mass_kg[0] <= rig.platform_mass_kg <= ranges.mass_kg[1]
        assert ranges.t_min_N[0] <= rig.t_min_N <= ranges.t_min_N[1]
        paper = InstrumentNoise.paper()
        f = np.asarray(noise.tau_sigma_Nm) / np.asarray(paper.tau_sigma_Nm)
        assert np.allclose(f, f[0]) and ranges.noise_factor[0] <= f[0] <= ranges.noise_factor[1]
        log = simulate_experiment(rig, 2, np.random.default_rng(seed), steps=2)   # the drawn rig runs the experiment
        assert len(log) == 10
    assert np.ptp(k_all) > 100                                                    # rigs differ


def test_tracker_registration_and_drift_laws(rig):
    import dataclasses

    Q = so3.exp([0.01, -0.02, 0.005])
    plant = dataclasses.replace(TestbedPlant.nominal(rig), tracker_rotation_B=Q,
                                sensor_drift_A_Nm_per_row=np.array([1e-3, 0.0, 0.0]))
    R = so3.random_rotations(4, np.random.default_rng(6), 0.3)
    np.testing.assert_allclose(plant.measured_pose(R), Q @ R)
    tau = np.zeros((5, 3))
    np.testing.assert_allclose(plant.measured_moment(tau)[:, 0], 1e-3 * np.arange(5))


def test_eyelet_moves_the_base_hole_towards_the_cable(rig):
    import dataclasses

    plant = dataclasses.replace(TestbedPlant.nominal(rig), guide_radius_m=2e-3)
    R = so3.random_rotations(3, np.random.default_rng(7), 0.3)
    B_eff = plant._base_holes(R)
    shift = B_eff - np.asarray(rig.base_holes_B_m)
    np.testing.assert_allclose(np.linalg.norm(shift, axis=-1), 2e-3)          # on the rim
    np.testing.assert_allclose(shift[..., 2], 0.0)                             # in the base plane
    a_B = np.einsum("nij,kj->nki", R, np.asarray(rig.platform_holes_A_m))
    assert np.all(np.sum(shift * (a_B - np.asarray(rig.base_holes_B_m)), axis=-1) > 0)   # towards the cable


def test_outside_effects_make_a_gap_and_unknown_names_are_input_errors(rig):
    from csjm_opt.errors import InvalidInput
    from csjm_opt.testbed import OUTSIDE_NAMES

    for name in OUTSIDE_NAMES:
        clean = simulate_experiment(rig, 2, np.random.default_rng(8), effect=name, severity=2.0,
                                    noise=InstrumentNoise.none(), steps=2)
        nominal = simulate_experiment(rig, 2, np.random.default_rng(8), noise=InstrumentNoise.none(), steps=2)
        assert np.abs(clean.rotvec_rad - nominal.rotvec_rad).max() + \
            np.abs(clean.tau_ext_A_Nm - nominal.tau_ext_A_Nm).max() > 1e-4, name
    with pytest.raises(InvalidInput):
        make_plant(rig, "gremlins", 1.0, np.random.default_rng(0))
    with pytest.raises(InvalidInput):
        simulate_experiment(rig, 0, np.random.default_rng(0))
