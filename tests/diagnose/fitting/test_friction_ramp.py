"""Dry friction along the ramp between rows: the play operator remembers where a cable's motion reversed."""

from __future__ import annotations

import numpy as np

from csjm_opt.diagnose.data.residuals import compute_residuals, pose_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.effects.friction import CORNER, band_position
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows, with_entry
from csjm_opt.diagnose.fitting.friction_path import end_state, on_predicted_path
from csjm_opt.diagnose.fitting.friction_ramp import predict_ramp, ramp_shape_of
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed import simulate_experiment
from csjm_opt.testbed.plant import TestbedPlant


def _rows(dc, shape=None):
    n = len(dc)
    return Rows(np.zeros((n, 6)), np.zeros((n, 3)), np.zeros(n, int), dc, log_steps_m=dc,
                rest_steps_m=np.zeros((n, 6)), ramp_shape_m=shape)


def test_a_reversal_inside_the_ramp_sets_the_state():
    """Brute force: a cable drawn out by 10 stick travels then back by 3 ends stuck at the lower edge
    (clip(clip(0 + 10) - 3) = -1), while one step of the net +7 leaves it at the upper edge."""
    travel = 1e-5
    path = np.zeros((2, 9, 6))
    path[1, :, 0] = travel * np.r_[0, 2.5, 5, 7.5, 10, 9, 8, 7, 7]      # out, then back in
    path[1, :, 1] = travel * np.linspace(0, 0.5, 9)                     # monotone: no memory of the path
    dc = path[:, -1] - path[:, 0]
    tr = np.full((2, 6), travel)
    one = band_position(_rows(dc), tr, 0.0)
    ramp = band_position(_rows(dc, ramp_shape_of(path)), tr, 0.0)
    assert one[1, 0] > 0.95 and ramp[1, 0] < -0.95
    expect = 0.0                                                        # exact play along the points
    for q in range(1, 9):
        expect = np.clip(expect + (path[1, q, 1] - path[1, q - 1, 1]) / travel, -1, 1)
    assert abs(ramp[1, 1] - expect) < 2 * CORNER and abs(one[1, 1] - expect) < 2 * CORNER


def test_predicted_ramp_follows_the_testbed_plant(rig):
    """Injected ground truth: the testbed's Coulomb plant (stuck segment lengths, its own stepping) against
    the model with the parameters that law implies (band (1 - rho) F, stick factor rho / (1 - rho)):
    predicted along the ramps, the poses agree to a fraction of the one-step model's error."""
    F = np.array([3.0, 4.5, 6.0, 3.6, 5.4, 2.4])
    plant = TestbedPlant(rig, friction_coulomb_N=F)
    log = simulate_experiment(rig, 2, np.random.default_rng(5), effect=plant, noise=InstrumentNoise.none(), steps=4)
    t = compute_residuals(rig, log)
    model = AugmentedModel(rig, [make_effect("friction", rig, None, law="coulomb", memory="carried")])
    rho = plant.friction_platform_fraction
    theta = np.r_[0.0, (1 - rho) * F, rho / (1 - rho), 0.0]
    rows = with_entry(model, t.rows, t.R_meas, theta)
    one = np.linalg.norm(pose_residuals(model.predict_poses(rows, theta, t.R_meas).R, t.R_meas), axis=1)
    sol, shape = predict_ramp(model, rows, theta, t.R_meas)
    ramp = np.linalg.norm(pose_residuals(sol.R, t.R_meas), axis=1)
    assert np.all(sol.converged(1e-6))
    assert np.sqrt(np.mean(ramp ** 2)) < 0.25 * np.sqrt(np.mean(one ** 2))
    assert ramp.max() < 2e-4
    # the shape carries the predicted path: a row-by-row prediction along it (as held-out cycles are
    # predicted) agrees with the sub-stepped one far better than the one-step model does
    path = on_predicted_path(model, t, theta)
    again = model.predict_poses(with_entry(model, path.rows, t.R_meas, theta), theta, t.R_meas)
    assert np.linalg.norm(pose_residuals(again.R, sol.R), axis=1).max() < 0.25 * one.max()


def test_end_state_is_the_fitted_paths(rig):
    """The state a next experiment starts from is read on the rows the fit used (its path and ramps):
    on the predicted path it differs from the measured-step state, and equals a plain play operator
    (brute force, in Python) driven by the path's own steps."""
    F = np.full(6, 4.0)
    log = simulate_experiment(rig, 3, np.random.default_rng(8), effect=TestbedPlant(rig, friction_coulomb_N=F),
                              noise=InstrumentNoise.paper(), steps=3)
    t = compute_residuals(rig, log)
    model = AugmentedModel(rig, [make_effect("friction", rig, None, law="coulomb", memory="carried")])
    fit = fit_model(model, on_predicted_path(model, t, fit_model(model, t).theta))
    s_end, _ = end_state(model, fit.rows, t.R_meas, fit.theta)
    band, f, s0 = fit.theta[1:7], fit.theta[7], fit.theta[8]
    travel = np.maximum(f * band / np.asarray(rig.cable_stiffness_N_per_m), 5e-6)
    dc, dl = fit.rows.steps_since_previous
    steps = dc[:, None, :] / fit.rows.ramp_shape_m.shape[1] + fit.rows.ramp_shape_m
    s = np.full(6, s0)
    for i in range(1, len(dc)):
        for q in range(steps.shape[1]):
            s = np.clip(s + (steps[i, q] + f * dl[i] / steps.shape[1]) / travel, -1, 1)
    assert np.abs(s_end - s).max() < 2 * CORNER
