"""The friction state's driving motion from the model's own predicted poses (``friction_path``)."""

from __future__ import annotations

import numpy as np

from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.friction_path import on_predicted_path
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
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


def test_path_steps_are_the_cables_own_lengths_between_the_models_holes(rig):
    """With hole offsets in the model, the friction state is driven by each cable's length between its
    *offset* holes (written out here: |R (a_i + da_i) - (b_i + db_i)|), not between the nominal ones."""
    from csjm_opt.diagnose.fitting.augmented import with_entry
    from csjm_opt.diagnose.fitting.friction_ramp import predict_ramp

    table = compute_residuals(rig, _log(rig, InstrumentNoise.none()))
    model = AugmentedModel(rig, [make_effect("hole_offsets", rig), make_effect("friction", rig, law="coulomb")])
    theta = model.x0()
    offsets = np.random.default_rng(3).normal(0.0, 2e-3, 36)          # 2 mm holes offsets
    theta[1:37] = offsets
    theta[37:43] = 0.5                                                   # 0.5 N of friction on each cable
    path = on_predicted_path(model, table, theta)
    sol, _ = predict_ramp(model, with_entry(model, table.rows, table.R_meas, theta), theta, table.R_meas)
    a = np.asarray(rig.platform_holes_A_m) + offsets[:18].reshape(6, 3)
    b = np.asarray(rig.base_holes_B_m) + offsets[18:].reshape(6, 3)
    lengths = np.linalg.norm(np.einsum("nij,kj->nki", sol.R, a) - b[None], axis=2)
    assert np.all(sol.converged(1e-6))
    np.testing.assert_allclose(path.rows.log_steps_m[1:], np.diff(lengths, axis=0), atol=1e-12)
    nominal = np.linalg.norm(np.einsum("nij,kj->nki", sol.R, np.asarray(rig.platform_holes_A_m))
                             - np.asarray(rig.base_holes_B_m)[None], axis=2)
    assert np.abs(np.diff(nominal, axis=0) - path.rows.log_steps_m[1:]).max() > 5e-6   # the offsets matter
