"""Selection: the right effect is named, `none` on effect-free data, the gap closes on held-out cycles."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.diagnose import VOCABULARY, diagnose
from csjm_opt.diagnose.noise import noise_floor
from csjm_opt.diagnose.residuals import compute_residuals
from csjm_opt.diagnose.selection import ALPHA, folds_by_cycle
from csjm_opt.errors import InvalidInput
from csjm_opt.testbed import simulate_experiment

SPEC_KEYS = {"baseline", "noise_floor_rad", "candidates", "selected", "gap", "localisation"}


def test_folds_are_grouped_by_cycle():
    cycle = np.repeat(np.arange(7), 5)
    folds = folds_by_cycle(cycle)
    assert len(folds) == 5
    assert sorted(np.concatenate(folds).tolist()) == list(range(35))
    for f in folds:    # a held-out set holds whole cycles only
        for c in np.unique(cycle[f]):
            assert set(np.flatnonzero(cycle == c)) <= set(f)
    with pytest.raises(InvalidInput):
        folds_by_cycle(np.zeros(9, int))


def test_noise_floor_matches_the_instrument_noise(rig):
    log = simulate_experiment(rig, 10, np.random.default_rng(20))
    t = compute_residuals(rig, log)
    floor, dof = noise_floor(t)
    # effect-free plant: the nominal residual *is* the noise
    assert dof > 50
    assert floor == pytest.approx(t.rms_rad, rel=0.2)
    assert floor == pytest.approx(t.instrument_floor_rad, rel=0.2)


def test_none_on_effect_free_data(rig):
    d = diagnose(rig, simulate_experiment(rig, 8, np.random.default_rng(21)))
    j = d.as_json()
    assert SPEC_KEYS <= set(j)
    assert j["selected"] == "none"
    assert j["significance"]["alpha"] == ALPHA
    assert {c["effect"] for c in j["candidates"]} == set(VOCABULARY[1:])
    assert j["gap"]["after_rad"] == pytest.approx(j["nominal_refit"]["heldout_rms_rad"])


# one seed per effect, severities varied; the seeds x severities study is studies/diagnose_confusion.py
CASES = [("hole_offsets", 1.5, 31), ("friction", 1.0, 32), ("cable_hardening", 0.5, 33),
         ("link_compliance", 1.5, 34), ("sensor_bias", 1.0, 35), ("mass_com", 2.0, 36)]


@pytest.mark.parametrize("effect,severity,seed", CASES)
def test_injected_effect_is_named_and_gap_closes(rig, effect, severity, seed):
    log = simulate_experiment(rig, 8, np.random.default_rng(seed), effect=effect, severity=severity)
    j = diagnose(rig, log).as_json()
    assert j["selected"] == effect
    gap = j["gap"]
    assert gap["systematic_before_rad"] > j["noise_floor_rad"]      # a real gap was injected
    assert gap["fraction_explained"] >= 0.8                           # >= 80 % of the systematic gap, held out
    sel = next(c for c in j["candidates"] if c["effect"] == effect)
    assert sel["significant"] and sel["p_value"] < ALPHA / 6
    assert sel["heldout_rms_rad"] < j["nominal_refit"]["heldout_rms_rad"]
    assert sel["bic"] == min(c["bic"] for c in j["candidates"] if c["significant"])


def test_two_effects_dominant_selected_second_reported(rig):
    log = simulate_experiment(rig, 10, np.random.default_rng(37), effect=["friction", "sensor_bias"], severity=1.5)
    j = diagnose(rig, log).as_json()
    assert j["selected"] == "friction"          # the larger gap
    assert j["secondary"]["effect"] == "sensor_bias"
    assert j["secondary"]["fraction_explained"] > j["gap"]["fraction_explained"]
