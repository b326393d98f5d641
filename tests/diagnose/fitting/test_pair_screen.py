"""The pair screen: a pair's evidence predicted one Gauss-Newton step from a single's fit (a score test).

Checked against an independent optimiser (``scipy.optimize.least_squares`` through ``fit_model`` on the pair
model) and, in a diagnosis, against the same diagnosis with every pair fitted. Margins over many logs the
project did not make are measured by ``studies/pair_screen``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from csjm_opt.diagnose import diagnose
from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.evidence import log_evidence, predicted_evidence
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.diagnose.selection import decision
from csjm_opt.testbed import simulate_experiment


@pytest.mark.parametrize("injected, seed, partner", [("sensor_bias", "mass_com", "sensor_bias"),
                                                      ("sensor_bias", "stiffness_scale", "sensor_bias"),
                                                      ("mass_com", "stiffness_scale", "sensor_bias")])
def test_the_prediction_from_a_single_reaches_the_fitted_pairs_evidence(rig, injected, seed, partner):
    """The effect the single lacks is found by one step: within 3 nats of the pair fitted from scratch.

    The gains are large (the seed alone lies 20-600 nats below), so the prediction is no restatement of the
    seed's own evidence.
    """
    log = simulate_experiment(rig, 4, np.random.default_rng(7), effect=injected, severity=2.0, steps=3)
    t = compute_residuals(rig, log)
    single = fit_model(AugmentedModel(rig, [make_effect(seed, rig)]), t)
    model = AugmentedModel(rig, [make_effect(seed, rig), make_effect(partner, rig)])
    theta = np.concatenate([single.theta, make_effect(partner, rig).x0()])
    predicted = predicted_evidence(model, t, theta, 1.0)
    fitted = log_evidence(fit_model(model, t), 1.0)
    assert fitted - log_evidence(single, 1.0) > 5.0
    assert predicted == pytest.approx(fitted, abs=3.0)


def test_at_a_fit_the_prediction_is_the_fits_own_linearised_evidence(rig):
    log = simulate_experiment(rig, 3, np.random.default_rng(8), effect="mass_com", severity=2.0, steps=2)
    t = compute_residuals(rig, log)
    fit = fit_model(AugmentedModel(rig, [make_effect("mass_com", rig)]), t)
    linearised = dataclasses.replace(fit, residuals=None)    # a prediction's step is not checked against the model
    assert predicted_evidence(fit.model, t, fit.theta, 1.3) == pytest.approx(
        log_evidence(linearised, 1.3, trust=False), abs=1e-6)


def test_screened_diagnosis_names_what_the_unscreened_one_names(rig, monkeypatch):
    """Pairs dropped by the screen lie far below the best single in the diagnosis that fits them all."""
    few = ["sensor_bias", "mass_com", "stiffness_scale", "tracker_registration", "hole_offsets"]
    log = simulate_experiment(rig, 4, np.random.default_rng(9), effect="hole_offsets", severity=2.0, steps=3)
    screened = diagnose(rig, log, effects=few, workers=1).as_json()
    monkeypatch.setattr(decision, "SCREEN_NATS", float("inf"))
    full = diagnose(rig, log, effects=few, workers=1).as_json()
    dropped = [p for p in screened["pairs"] if np.isfinite(p.get("predicted_log_evidence", np.nan))
               and not p["fitted"]]
    assert dropped, "the screen dropped no pair on this log: the test checks nothing"
    best = max(c["log_evidence"] for c in full["candidates"])
    for p in dropped:
        twin = next(q for q in full["pairs"] if set(q["effects"]) == set(p["effects"]))
        assert twin["log_evidence"] < best - decision.LEAD_NATS
    assert (screened["selected"], screened["verdict"]["warnings"]) == (full["selected"], full["verdict"]["warnings"])


def test_each_effects_step_from_nominal_is_one_the_screen_reads():
    from csjm_opt.diagnose.effects import EFFECTS
    from csjm_opt.diagnose.fitting.model_fits import STEPS

    steps = {name: cls.step_from_nominal for name, cls in EFFECTS.items()}
    assert set(steps.values()) <= set(STEPS)
    assert steps["friction"] == "none" and steps["link_compliance"] == steps["joint_friction"] == "loose"


@pytest.mark.parametrize("injected, seed", [("link_compliance", "sensor_bias"), ("joint_friction", "mass_com")])
def test_a_loose_step_from_nominal_reaches_most_of_the_fitted_gain(rig, injected, seed):
    """A loose effect (its tangent or its path moves) from nominal: the step, against the pair fitted from scratch.

    The screen drops a loose pair only when its step lies ``SCREEN_NATS + LOOSE_SCREEN_NATS`` below the anchor,
    which is safe while a fit reaches no more than 80 % of the gap beyond its step; here the effect is present
    and large (the seed alone lies hundreds of nats below), and the step must reach at least 20 % of the
    fitted gain without overshooting the fit.
    """
    log = simulate_experiment(rig, 4, np.random.default_rng(11), effect=injected, severity=3.0, steps=3)
    t = compute_residuals(rig, log)
    single = fit_model(AugmentedModel(rig, [make_effect(seed, rig)]), t)
    model = AugmentedModel(rig, [make_effect(seed, rig), make_effect(injected, rig)])
    assert make_effect(injected, rig).step_from_nominal == "loose"
    theta = np.concatenate([single.theta, make_effect(injected, rig).x0()])
    predicted = predicted_evidence(model, t, theta, 1.0)
    fitted = log_evidence(fit_model(model, t), 1.0)
    gain = fitted - log_evidence(single, 1.0)
    assert gain > 100.0, "the effect adds little on this log: the test checks nothing"
    assert predicted <= fitted + 3.0
    assert fitted - predicted <= 0.8 * gain


def test_a_friction_pair_is_predicted_from_the_friction_fit_and_screened_only_far_below(rig, monkeypatch):
    """Cable friction's pairs: predicted from the friction single's own fit (the partner stepped from nominal).

    On a log of hole offsets, friction with a stiffness scale or a sensor gain explains nothing the log shows; the
    screened diagnosis drops such pairs and names what the diagnosis fitting every pair names, and each dropped
    pair lies far below the best single there.
    """
    from csjm_opt.diagnose.fitting import model_fits
    from csjm_opt.diagnose.fitting.model_fits import pair_step

    assert pair_step([make_effect("friction", rig), make_effect("mass_com", rig)]) == "own_fit"
    assert pair_step([make_effect("friction", rig), make_effect("link_compliance", rig)]) == "own_fit"
    assert pair_step([make_effect("mass_com", rig), make_effect("link_compliance", rig)]) == "loose"
    few = ["friction", "hole_offsets", "stiffness_scale", "sensor_gain"]
    log = simulate_experiment(rig, 8, np.random.default_rng(12), effect="hole_offsets", severity=3.0, steps=3)
    screened = diagnose(rig, log, effects=few, workers=1).as_json()
    monkeypatch.setattr(decision, "SCREEN_NATS", float("inf"))
    full = diagnose(rig, log, effects=few, workers=1).as_json()
    dropped = [p for p in screened["pairs"] if "friction" in p["effects"] and not p["fitted"]
               and np.isfinite(p.get("predicted_log_evidence", np.nan))]
    assert dropped, "the screen dropped no friction pair on this log: the test checks nothing"
    best = max(c["log_evidence"] for c in full["candidates"])
    for p in dropped:
        twin = next(q for q in full["pairs"] if set(q["effects"]) == set(p["effects"]))
        assert twin["log_evidence"] < best - decision.LEAD_NATS
        # the margin covers the fit's reach beyond its step
        assert twin["log_evidence"] <= p["predicted_log_evidence"] + model_fits.OWN_FIT_SCREEN_NATS
    assert (screened["selected"], screened["verdict"]["warnings"]) == (full["selected"], full["verdict"]["warnings"])
