"""The friction state's driving motion from the model's own predicted poses (``friction_path``)."""

from __future__ import annotations

import numpy as np

from csjm_opt.diagnose.augmented import AugmentedModel
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fit import fit_model
from csjm_opt.diagnose.friction_path import on_predicted_path
from csjm_opt.diagnose.residuals import compute_residuals
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed import simulate_experiment


def _log(rig, noise):
    return simulate_experiment(rig, 4, np.random.default_rng(41), effect="coulomb_friction", severity=4.0,
                               noise=noise, steps=3)


def test_path_of_an_exact_model_is_the_measured_motion(rig):
    """Injected ground truth: on noise-free nominal data a friction model with zero bands predicts the true
    poses, so the cable motion along its predicted path is the measured (true) motion, across cycles too."""
    table = compute_residuals(rig, simulate_experiment(rig, 3, np.random.default_rng(41),
                                                       noise=InstrumentNoise.none(), steps=3))
    model = AugmentedModel(rig, [make_effect("friction", rig, law="coulomb")])
    theta = model.x0()                                    # no friction: the nominal model, exact here
    path = on_predicted_path(model, table, theta)
    np.testing.assert_allclose(path.rows.log_steps_m, table.rows.log_steps_m, atol=1e-9)
    np.testing.assert_allclose(path.rows.cable_steps_m, table.rows.cable_steps_m, atol=1e-9)
    assert path.R_meas is table.R_meas                    # only the steps change


def test_noisy_coulomb_log_fits_better_along_the_predicted_path(rig):
    """Pose noise flips a play operator driven by measured motion; the same model driven along its own
    predicted path fits the log better (lower training RSS at the same parameters' count)."""
    noisy = compute_residuals(rig, _log(rig, InstrumentNoise.paper()))
    model = AugmentedModel(rig, [make_effect("friction", rig, law="coulomb")])
    fit = fit_model(model, noisy)
    on_path = fit_model(model, on_predicted_path(model, noisy, fit.theta), fit.theta)
    assert on_path.rss < fit.rss


def test_path_independent_models_are_left_alone(rig):
    table = compute_residuals(rig, _log(rig, InstrumentNoise.none()))
    model = AugmentedModel(rig, [make_effect("sensor_bias", rig)])
    assert on_predicted_path(model, table, model.x0()) is table
