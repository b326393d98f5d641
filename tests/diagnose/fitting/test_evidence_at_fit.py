"""The Laplace evidence centred at the fitted parameters (``log_evidence(..., at_fit=True)``), against the dense
Gaussian marginal likelihood of the linearised model and an independent least-squares solver for its mode."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import lsq_linear

from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.evidence import log_evidence, prior_of
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.testbed import simulate_experiment


def _moved(fit, dx):
    """The same linearised problem expanded at ``x0 + dx`` (scaled parameters): residual moved along J."""
    n = fit.n_obs
    res = fit.res_x.copy()
    res[:n] = fit.res_x[:n] + fit.jac_x[:n] @ dx
    return dataclasses.replace(fit, theta=fit.theta + dx * fit.model.scales, res_x=res)


def test_evidence_at_the_fit_pays_the_quadratic_distance_from_the_mode(rig):
    """For a linear-Gaussian model the default evidence does not depend on where the problem is expanded (it
    equals the dense marginal likelihood), while the one at the fit is it minus ``d^T H d / 2``, ``d`` the
    distance of the expansion point from the posterior mode (found by scipy's lsq_linear on the stacked
    data and prior rows) and ``H`` the posterior precision: zero at the mode, never positive."""
    log = simulate_experiment(rig, 3, np.random.default_rng(31), effect="sensor_bias", severity=2.0, steps=2)
    t = compute_residuals(rig, log)
    fit = fit_model(AugmentedModel(rig, [make_effect("sensor_bias", rig)]), t)
    s = 1.3
    n = fit.n_obs
    J, r0 = fit.jac_x[:n], fit.res_x[:n]
    scales = fit.model.scales
    x0 = fit.theta / scales
    m, sd = prior_of(fit)
    m, sd = m / scales, sd / scales
    rm = r0 + J @ (m - x0)
    C = s ** 2 * np.eye(n) + J @ np.diag(sd ** 2) @ J.T
    exact = -0.5 * rm @ np.linalg.solve(C, rm) - 0.5 * np.linalg.slogdet(2 * np.pi * C)[1]
    const = 0.5 * n * np.log(2 * np.pi * s ** 2)
    # the posterior mode of the linear problem: min |r0 + J dx|^2 / s^2 + |(x0 + dx - m) / sd|^2
    A = np.vstack([J / s, np.diag(1.0 / sd)])
    b = -np.r_[r0 / s, (x0 - m) / sd]
    mode_dx = lsq_linear(A, b, tol=1e-14, lsmr_tol="auto").x
    H = J.T @ J / s ** 2 + np.diag(1.0 / sd ** 2)
    rng = np.random.default_rng(2)
    for step in (np.zeros_like(x0), 0.5 * rng.normal(size=len(x0)), -mode_dx + 2.0 * rng.normal(size=len(x0))):
        f = _moved(fit, mode_dx + step)
        lin = log_evidence(f, s) - const
        here = log_evidence(f, s, at_fit=True) - const
        assert abs(lin - exact) < 1e-6 * max(1.0, abs(exact))
        expected = exact - 0.5 * step @ H @ step
        assert abs(here - expected) < 1e-6 * max(1.0, abs(expected)), (here, expected)
        assert here <= lin + 1e-9
