"""Effects library: nesting, physics against the independent plant, identifiability."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.model import kinematics as kin
from csjm_opt.diagnose.augmented import AugmentedModel
from csjm_opt.diagnose.effects import EFFECTS, make_effect
from csjm_opt.diagnose.fit import fit_model
from csjm_opt.diagnose.residuals import compute_residuals, pose_residuals
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed import make_plant, simulate_experiment


@pytest.fixture(scope="module")
def clean_nominal(rig):
    return simulate_experiment(rig, 3, np.random.default_rng(10), noise=InstrumentNoise.none())


def test_vocabulary_is_spec():
    from csjm_opt.diagnose import VOCABULARY

    assert VOCABULARY == ("none", "hole_offsets", "friction", "cable_hardening", "link_compliance",
                          "sensor_bias", "mass_com")


def test_nominal_residuals_vanish_on_noise_free_nominal_data(rig, clean_nominal):
    t = compute_residuals(rig, clean_nominal)
    assert t.converged.all()
    assert np.abs(t.zeta_rad).max() < 1e-9
    assert np.abs(t.moment_residual_Nm).max() < 1e-8


def test_tangent_is_minus_core_tangent_stiffness(rig, clean_nominal):
    t = compute_residuals(rig, clean_nominal)
    i = 4
    eq = solve_equilibrium(rig, clean_nominal.rest_lengths_m[i], clean_nominal.tau_ext_A_Nm[i], R_init=t.R_meas[i])
    np.testing.assert_allclose(-t.G[i], eq.K_tangent, rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize("name", list(EFFECTS))
def test_effects_nest_the_nominal_model(rig, clean_nominal, name):
    t = compute_residuals(rig, clean_nominal)
    m0, m1 = AugmentedModel(rig), AugmentedModel(rig, [make_effect(name, rig)])
    th = m1.x0()
    np.testing.assert_allclose(m1.balance(t.R_meas, t.rows, th), m0.balance(t.R_meas, t.rows, m0.x0()), atol=1e-12)
    assert len(m1.param_names) == m1.n_params == len(m1.scales)


@pytest.mark.parametrize("name,truth", [("sensor_bias", lambda p: p.sensor_bias_A_Nm),
                                        ("cable_hardening", lambda p: [p.hardening_per_m]),
                                        ("link_compliance",
                                         lambda p: p.link_compliance_rad_per_Nm[np.triu_indices(3)])])
def test_fit_recovers_injected_parameters_from_clean_data(rig, name, truth):
    rng = np.random.default_rng(11)
    plant = make_plant(rig, name, 1.5, rng)
    log = simulate_experiment(rig, 5, rng, effect=plant, noise=InstrumentNoise.none())
    f = fit_model(AugmentedModel(rig, [make_effect(name, rig)]), compute_residuals(rig, log))
    np.testing.assert_allclose(f.theta[2:], truth(plant), rtol=0.03, atol=2e-5)
    assert abs(f.theta[0]) < 1e-3 and abs(f.theta[1]) < 1e-6      # no stiffness/pretension error injected


def test_mass_com_identifies_the_first_mass_moment(rig):
    rng = np.random.default_rng(12)
    plant = make_plant(rig, "mass_com", 1.5, rng)
    log = simulate_experiment(rig, 5, rng, effect=plant, noise=InstrumentNoise.none())
    f = fit_model(AugmentedModel(rig, [make_effect("mass_com", rig)]), compute_residuals(rig, log))
    true_dmr = (plant.rig.platform_mass_kg * np.asarray(plant.rig.com_A_m)
                - rig.platform_mass_kg * np.asarray(rig.com_A_m))
    np.testing.assert_allclose(f.theta[2:], true_dmr, atol=2e-5)


def test_friction_model_explains_clean_hysteresis(rig):
    rng = np.random.default_rng(13)
    log = simulate_experiment(rig, 5, rng, effect="friction", severity=1.0, noise=InstrumentNoise.none())
    t = compute_residuals(rig, log)
    m = AugmentedModel(rig, [make_effect("friction", rig)])
    f = fit_model(m, t)
    pred = m.predict_poses(t.rows, f.theta, t.R_meas)
    before = np.sqrt(np.mean(np.sum(t.zeta_rad ** 2, 1)))
    after = np.sqrt(np.mean(np.sum(pose_residuals(pred.R, t.R_meas) ** 2, 1)))
    assert after < 0.15 * before


def test_forward_prediction_matches_linearised_residual_for_small_gaps(rig):
    log = simulate_experiment(rig, 2, np.random.default_rng(14), effect="sensor_bias", severity=0.5)
    t = compute_residuals(rig, log)
    from csjm_opt.diagnose.fit import linearised_zeta

    lin = linearised_zeta(AugmentedModel(rig), t, np.zeros(2))
    np.testing.assert_allclose(lin, t.zeta_rad, atol=2e-4)


def test_identifiability_is_reported(rig):
    log = simulate_experiment(rig, 4, np.random.default_rng(15))
    t = compute_residuals(rig, log)
    good = fit_model(AugmentedModel(rig, [make_effect("sensor_bias", rig)]), t)
    assert good.identifiable and good.rank == 5
    holes = fit_model(AugmentedModel(rig, [make_effect("hole_offsets", rig)]), t)
    assert holes.condition > 100 * good.condition          # 36 offsets are weakly determined
    assert holes.p_eff < holes.model.n_params              # the ridge prior removes effective parameters


def test_batched_solver_matches_core(rig, clean_nominal):
    m = AugmentedModel(rig)
    t = compute_residuals(rig, clean_nominal)
    sol = m.predict_poses(t.rows, m.x0(), np.repeat(np.eye(3)[None], len(t), 0))
    assert sol.converged(1e-9).all()
    assert np.abs(pose_residuals(sol.R, t.R_meas)).max() < 1e-9
    assert kin.PoseSolution is type(sol)
