"""Laplace evidence of a fitted model under its prior ranges (issue 20)."""

from __future__ import annotations

import numpy as np

from csjm_opt.diagnose.augmented import AugmentedModel
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.evidence import log_evidence, prior_of
from csjm_opt.diagnose.fit import fit_model
from csjm_opt.diagnose.residuals import compute_residuals
from csjm_opt.testbed import simulate_experiment


def test_evidence_is_the_gaussian_marginal_likelihood_of_the_linearised_model(rig):
    """Against the dense formula log N(r(m); 0, s^2 I + J S^2 J^T) (no Woodbury, no MAP step)."""
    log = simulate_experiment(rig, 3, np.random.default_rng(31), effect="sensor_bias", severity=2.0, steps=2)
    t = compute_residuals(rig, log)
    fit = fit_model(AugmentedModel(rig, [make_effect("sensor_bias", rig)]), t)
    s = 1.3
    n = fit.n_obs
    J, r0 = fit.jac_x[:n], fit.res_x[:n]
    scales = fit.model.scales
    m, sd = prior_of(fit)
    rm = r0 + J @ (m / scales - fit.theta / scales)
    C = s ** 2 * np.eye(n) + J @ np.diag((sd / scales) ** 2) @ J.T
    exact = -0.5 * rm @ np.linalg.solve(C, rm) - 0.5 * np.linalg.slogdet(2 * np.pi * C)[1]
    mine = log_evidence(fit, s) - 0.5 * n * np.log(2 * np.pi * s ** 2)
    assert abs(mine - exact) < 1e-6 * max(1.0, abs(exact))


def test_prior_is_the_range_as_two_sd(rig):
    fit = fit_model(AugmentedModel(rig, [make_effect("sensor_bias", rig)]),
                    compute_residuals(rig, simulate_experiment(rig, 2, np.random.default_rng(32), steps=2)))
    m, sd = prior_of(fit)
    lo, hi = make_effect("sensor_bias", rig).ranges()["bias_x_Nm"]
    assert m[1] == 0.0 and sd[1] == (hi - lo) / 4


def test_occam_factor_prefers_the_simple_model_on_an_effect_free_log(rig):
    """Hole offsets (36 numbers) fit noise a little better, but their evidence is lower than the null's."""
    t = compute_residuals(rig, simulate_experiment(rig, 4, np.random.default_rng(33), steps=2))
    null = fit_model(AugmentedModel(rig), t)
    holes = fit_model(AugmentedModel(rig, [make_effect("hole_offsets", rig)]), t)
    s = float(np.sqrt(null.rss / (null.n_obs - 1)))
    assert holes.rss < null.rss
    assert log_evidence(holes, s) < log_evidence(null, s)
