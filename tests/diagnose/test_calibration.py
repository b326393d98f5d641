"""Calibration of the diagnosis's pieces against simulation and against each other.

* the prediction covariance of a refitted model, against Monte Carlo of a linear problem;
* the residual-signature test with fold-correlated prediction error: at its level (GLS), where
  the plain test over-rejects;
* plausibility: a weakly determined parameter past its bound within its uncertainty is not
  implausible; the testbed's largest plausible severities stay inside the diagnosis's priors
  (two independent definitions) and are not vacuous.
"""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.diagnose.data.localisation import remaining_signature
from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.gauss_newton import FitResult
from csjm_opt.diagnose.selection.scoring import folds_by_cycle
from csjm_opt.errors import RigFileError
from csjm_opt.testbed import TestbedPlant, inject, random_rig, simulate_experiment
from csjm_opt.testbed.injection import PLAUSIBLE_SEVERITY


def _linear_fit(J: np.ndarray) -> FitResult:
    n3, p = J.shape
    return FitResult(None, np.zeros(p), np.eye(p), 0.0, n3, float(p), p, 1.0, np.zeros((n3 // 3, 3)),  # type: ignore[arg-type]
                     jac_x=J, res_x=np.zeros(n3), free=np.ones(p, bool))


def test_prediction_covariance_matches_monte_carlo():
    """Held-out error of a least-squares refit of y = J b + e on other rows: covariance I + P."""
    rng = np.random.default_rng(0)
    n, p = 30, 5
    J = rng.normal(size=(3 * n, p))
    fit = _linear_fit(J)
    keep, held = np.arange(0, 24), np.arange(24, 30)
    P = fit.prediction_cov(keep, fit.held_rows_jacobian(held))
    rk = (3 * keep[:, None] + np.arange(3)).ravel()
    rh = (3 * held[:, None] + np.arange(3)).ravel()
    b = rng.normal(size=p)
    errs = []
    for _ in range(4000):
        y = J @ b + rng.normal(size=3 * n)
        bh = np.linalg.lstsq(J[rk], y[rk], rcond=None)[0]
        errs.append(y[rh] - J[rh] @ bh)
    emp = np.cov(np.array(errs).T)
    want = np.eye(len(rh)) + P
    assert np.linalg.norm(emp - want) / np.linalg.norm(want) < 0.08
    assert np.trace(P) > 0.05 * len(rh)              # the estimation error is not negligible here


@pytest.fixture(scope="module")
def table(rig):
    log = simulate_experiment(rig, 8, np.random.default_rng(5), steps=3)
    return compute_residuals(rig, log)


def test_signature_test_with_prediction_error_holds_its_level(table):
    """Held-out residuals = noise + a fold-wide offset (a refit's error): GLS keeps alpha, OLS does not."""
    t = table
    L = np.linalg.inv(t.whiten)
    folds = folds_by_cycle(t.cycle, k=4)
    rng = np.random.default_rng(1)
    blocks = []
    for f in folds:
        J = np.tile(np.eye(3), (len(f), 1)) @ rng.normal(size=(3, 3))     # an offset common to the fold
        blocks.append((f, J @ J.T))
    chol = [np.linalg.cholesky(np.eye(3 * len(f)) + P) for f, P in blocks]   # draws e = L z, z ~ N(0, I)
    p_gls, p_ols = [], []
    for _ in range(300):
        e = np.empty((len(t), 3))
        for (f, _P), L_f in zip(blocks, chol):
            e[f] = (L_f @ rng.normal(size=3 * len(f))).reshape(-1, 3)
        zeta = np.einsum("nij,nj->ni", L, e)
        p_gls.append(remaining_signature(t, zeta, 1.0, 0.1, blocks)["p_value"])
        p_ols.append(remaining_signature(t, zeta, 1.0, 0.1)["p_value"])
    assert 0.04 <= np.mean(np.array(p_gls) < 0.1) <= 0.18       # binomial(300, 0.1): 0.1 +- 3 sd
    assert np.mean(np.array(p_ols) < 0.1) > 0.3                 # ignoring the refit's error over-rejects


def test_plausibility_allows_for_uncertainty():
    e = make_effect("sensor_bias")
    p = np.array([0.6, 0.0, 0.0])
    assert e.implausible(p) == ["bias_x_Nm"]
    assert e.implausible(p, sd=np.array([0.06, 0.01, 0.01])) == []     # 0.1 past the bound, 1.7 sd
    assert e.implausible(p, sd=np.array([0.04, 0.01, 0.01])) == ["bias_x_Nm"]   # 2.5 sd


def _true_params(effect: str, rig, plant: TestbedPlant) -> np.ndarray:
    """The diagnosis's parameter vector of ``effect`` for an injected plant (independent of the fit)."""
    if effect == "hole_offsets":
        return np.r_[(plant.rig.platform_holes_A_m - rig.platform_holes_A_m).ravel(),
                     (plant.rig.base_holes_B_m - rig.base_holes_B_m).ravel()]
    rho = plant.friction_platform_fraction           # stick factor rho / (1 - rho), first state 0 (settled)
    if effect == "friction":
        return np.r_[plant.friction_mu_beta, rho / (1 - rho), 0.0]
    if effect == "coulomb_friction":
        return np.r_[plant.friction_coulomb_N, rho / (1 - rho), 0.0]
    if effect == "cable_hardening":
        return np.array([plant.hardening_per_m])
    if effect == "link_compliance":
        iu = np.triu_indices(3)
        return plant.link_compliance_rad_per_Nm[iu]
    if effect == "sensor_bias":
        return plant.sensor_bias_A_Nm
    if effect == "mass_com":
        true_mr = plant.rig.platform_mass_kg * np.asarray(plant.rig.com_A_m)
        return true_mr - rig.platform_mass_kg * np.asarray(rig.com_A_m)
    if effect == "tracker_registration":
        return so3.log(plant.tracker_rotation_B)
    if effect == "stiffness_scale":
        return np.log(plant.rig.cable_stiffness_N_per_m[:1] / rig.cable_stiffness_N_per_m[:1])
    if effect == "drive_offsets":
        return np.asarray(plant.drive_offsets_m)
    if effect == "sensor_gain":                      # the per-axis variant: each axis's log gain
        return np.log(plant.sensor_gain_A)
    if effect == "joint_friction":
        return np.array([plant.joint_friction_Nm])
    raise AssertionError(effect)


@pytest.mark.parametrize("effect", sorted(PLAUSIBLE_SEVERITY))
def test_plausible_severity_stays_inside_the_priors(effect):
    """At the testbed's cap an injected effect is plausible to the diagnosis (>= 95 % of random draws,
    random rigs); at twice the cap a good share is not (the cap is not vacuous)."""
    rng = np.random.default_rng([ord(ch) for ch in effect])      # str hash() is salted per process
    rigs = [random_rig(np.random.default_rng([77, i]))[0] for i in range(3)]
    cap = PLAUSIBLE_SEVERITY[effect]
    inside, outside = [], []
    for k in range(120):
        rig = rigs[k % 3]
        e = (make_effect("friction", rig, law="coulomb") if effect == "coulomb_friction" else
             make_effect("sensor_gain", rig, axes="per_axis") if effect == "sensor_gain" else make_effect(effect, rig))
        for s, out in ((cap, inside), (2 * cap, outside)):
            try:
                plant = inject(TestbedPlant.nominal(rig), effect, s, rng)
            except RigFileError:          # holes moved onto each other: not a rig at all
                out.append(False)
                continue
            out.append(not e.implausible(_true_params(effect, rig, plant)))
    assert np.mean(inside) >= 0.95
    assert np.mean(outside) <= 0.7
