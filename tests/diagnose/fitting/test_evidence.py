"""Laplace evidence of a fitted model under its prior ranges (issue 20)."""

from __future__ import annotations

import numpy as np

from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.evidence import log_evidence, prior_of, prior_sides
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
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


def test_half_normal_prior_is_integrated_exactly_for_one_bounded_parameter(rig):
    """Against quadrature over the bounded parameter, the other five integrated in closed form.

    Link compliance with two diagonal entries given ranges around 0 (Gaussian priors) keeps one
    half-normal parameter, ``C_11`` (bounded at 0), so the truncation factor is exact there.
    """
    from scipy.special import logsumexp

    log = simulate_experiment(rig, 3, np.random.default_rng(34), effect="link_compliance", severity=1.0, steps=2)
    t = compute_residuals(rig, log)
    eff = make_effect("link_compliance", rig, {"C_22*": (-0.05, 0.05), "C_33*": (-0.05, 0.05)})
    fit = fit_model(AugmentedModel(rig, [eff]), t)
    s = 1.1
    n = fit.n_obs
    J, r0 = fit.jac_x[:n], fit.res_x[:n]
    scales = fit.model.scales
    x0 = fit.theta / scales
    m, sd = prior_of(fit)
    m, sd = m / scales, sd / scales
    i = 1 + list(eff.param_names).index("C_11_rad_per_Nm")
    assert list(np.flatnonzero(prior_sides(fit))) == [i]
    o = [k for k in range(len(x0)) if k != i]
    C = s ** 2 * np.eye(n) + J[:, o] @ np.diag(sd[o] ** 2) @ J[:, o].T
    Ci = np.linalg.inv(C)
    logdetC = np.linalg.slogdet(2 * np.pi * C)[1]
    grid = np.linspace(0.0, 8 * sd[i], 4001)
    vals = []
    for xi in grid:                       # r at the other parameters' prior means, x_i on the grid
        r = r0 + J[:, o] @ (m[o] - x0[o]) + J[:, i] * (xi - x0[i])
        vals.append(-0.5 * r @ Ci @ r - 0.5 * logdetC + np.log(2 / np.sqrt(2 * np.pi * sd[i] ** 2))
                    - 0.5 * (xi / sd[i]) ** 2)
    exact = logsumexp(vals, b=np.r_[0.5, np.ones(len(grid) - 2), 0.5]) + np.log(grid[1] - grid[0])
    mine = log_evidence(fit, s) - 0.5 * n * np.log(2 * np.pi * s ** 2)
    assert abs(mine - exact) < 1e-4 * max(1.0, abs(exact))


def test_half_normal_sides_are_the_bounded_parameters_at_their_nominal_value(rig):
    fit = fit_model(AugmentedModel(rig, [make_effect("link_compliance", rig)]),
                    compute_residuals(rig, simulate_experiment(rig, 2, np.random.default_rng(35), steps=2)))
    eff = fit.model.effects[0]
    side = prior_sides(fit)[1:]
    diag = np.array([n[2] == n[3] for n in eff.param_names])
    assert np.array_equal(side, np.where(diag, 1.0, 0.0))
    m, sd = prior_of(fit)
    lo, hi = eff.ranges()["C_11_rad_per_Nm"]
    assert sd[1 + list(eff.param_names).index("C_11_rad_per_Nm")] == (hi - lo) / 2   # the range is 2 sd


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


def test_a_flat_direction_followed_far_out_pays_its_prior_density(rig):
    """A parameter the log does not see (its Jacobian column zeroed) integrates to 1 under its prior in the
    linear-Gaussian model, wherever the fit left it, as long as that is within the trusted step; a fit left
    10 prior sds out is held there and pays ``10^2 / 2`` nats (the linearisation is local)."""
    import dataclasses

    fit = fit_model(AugmentedModel(rig, [make_effect("sensor_bias", rig)]),
                    compute_residuals(rig, simulate_experiment(rig, 3, np.random.default_rng(36), steps=2)))
    n, k = fit.n_obs, 2                       # k: bias_y (index 0 is the nuisance)
    J = fit.jac_x.copy()
    J[:n, k] = 0.0
    m, sd = prior_of(fit)
    s = 1.2

    def moved(z):
        theta = fit.theta.copy()
        theta[k] = m[k] + z * sd[k]
        # a linear-Gaussian model of its own: the model's cost function (which sees bias_y) is not this fit's
        return dataclasses.replace(fit, theta=theta, jac_x=J, residuals=None)

    base = log_evidence(moved(0.0), s)
    assert abs(log_evidence(moved(1.5), s) - base) < 1e-8 * max(1.0, abs(base))
    assert abs(log_evidence(moved(10.0), s) - (base - 50.0)) < 1e-6 * max(1.0, abs(base))


def test_a_pair_that_fits_no_better_than_its_nested_single_is_not_credited_more():
    """A nested pair's evidence exceeds its single's by at most half their misfit difference (law of nested models).

    Stiffness scale + sensor gain differ from the scale alone only by the weight's share (the gain is a
    scale and a lighter platform, test_look_alikes.py). Adding a parameter can only add to the Occam factor
    (``det(I + S J^T J S)`` grows with a column) and to the prior's cost, so
    ``ev_pair - ev_single <= (quad_single - rss_pair / s^2) / 2``, ``quad_single`` the single's misfit and prior
    cost at its fit, ``rss_pair`` the least misfit the pair reaches. On a random rig's log of a stiffer cable
    batch, the Gauss-Newton Jacobian (which leaves out how the pair changes its own tangent) promised the pair
    32 nats along the direction it barely sees, with a misfit above the single's.
    """
    import dataclasses

    from csjm_opt.testbed import make_plant, random_rig

    rig, noise = random_rig(np.random.default_rng([1234, 2]))
    plant = make_plant(rig, "stiffness_scale", 9.0, np.random.default_rng(5))
    t = compute_residuals(rig, simulate_experiment(rig, 6, np.random.default_rng(7), effect=plant, noise=noise), noise)
    single = fit_model(AugmentedModel(rig, [make_effect("stiffness_scale", rig)]), t)
    pair = fit_model(AugmentedModel(rig, [make_effect("stiffness_scale", rig), make_effect("sensor_gain", rig)]), t)
    s = float(np.sqrt(single.rss / (single.n_obs - 2)))
    m, sd = prior_of(single)
    quad_single = single.rss / s ** 2 + float(np.sum(((single.theta - m) / sd) ** 2))
    step_end = dataclasses.replace(pair, residuals=None)     # the linearisation's promise, unchecked
    rss_pair = min(pair.rss, single.rss)
    assert log_evidence(pair, s) - log_evidence(single, s) <= 0.5 * (quad_single - rss_pair / s ** 2) + 1e-9
    assert log_evidence(step_end, s) > log_evidence(pair, s)  # what the check takes away on this log
