"""Parsimony that holds (a flexible model never beats a few-number one that explains the log as well),
and the time-trend check for faults outside the vocabulary that drift."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from csjm_opt.diagnose.data.trend import time_trend
from csjm_opt.diagnose.selection.decision import flexible, parsimonious


class _Score(SimpleNamespace):
    def cycle_mse(self):
        return dict(enumerate(self.mse))


def _score(p_eff, mse):
    return _Score(fit=SimpleNamespace(p_eff=p_eff), mse=list(mse))


def test_flexible_is_measured_against_the_cycles():
    assert flexible(_score(23, [1.0]), 8)          # 23 > 0.5 * 24
    assert not flexible(_score(23, [1.0]), 20)
    assert not flexible(_score(4, [1.0]), 8)


def test_a_flexible_model_never_beats_a_few_number_one_that_explains_the_log_as_well():
    rng = np.random.default_rng(0)
    base = rng.uniform(1.0, 2.0, 8)
    holes = _score(23, base * rng.uniform(0.97, 1.03, 8))
    drive = _score(5, base * rng.uniform(0.97, 1.03, 8))
    scores = {"hole_offsets": holes, "drive_offsets": drive}
    # hole offsets ahead on evidence, no better on held-out cycles: the few numbers are named
    assert parsimonious(scores, {"hole_offsets": -270.0, "drive_offsets": -280.0}, 8) == "drive_offsets"
    # hole offsets clearly better on every held-out cycle: they are named
    better = _score(23, base * 0.6)
    assert parsimonious({"hole_offsets": better, "drive_offsets": drive},
                        {"hole_offsets": -270.0, "drive_offsets": -280.0}, 8) == "hole_offsets"
    # a set-valued few-number model (settled friction: a stick set holds almost any pose, so held-out rows
    # cannot rule it out) decisively less probable than the flexible one (Bayes factor e^-1000) is no rival
    stick = _score(7, base * rng.uniform(0.97, 1.03, 8))
    stick.heldout_density = ("q", "var", 1.0)
    assert parsimonious({"hole_offsets": holes, "friction": stick},
                        {"hole_offsets": -270.0, "friction": -1270.0}, 8) == "hole_offsets"
    # ... but within a few nats (not decisive) it is named
    assert parsimonious({"hole_offsets": holes, "friction": stick},
                        {"hole_offsets": -270.0, "friction": -273.0}, 8) == "friction"
    # two few-number models: the evidence decides
    assert parsimonious({"a": drive, "b": _score(3, base)}, {"a": -1.0, "b": -2.0}, 8) == "a"


def _cycles(C, rows=11):
    return np.repeat(np.arange(C), rows)


def test_time_trend_finds_a_drift_and_not_a_pose_dependent_misfit():
    rng = np.random.default_rng(1)
    C = 12
    cyc = _cycles(C)
    noise = rng.normal(0, 3e-4, (len(cyc), 3))
    misfit = rng.normal(0, 1e-3, (C, 3))[cyc]          # a per-cycle misfit in no time order
    flat = time_trend(noise + misfit, cyc, floor_rad=5e-4)
    assert not flat["trends"] and flat["p_value"] > 0.01
    drift = np.outer(np.arange(len(cyc)) / len(cyc), [4e-3, 0.0, -1e-3])   # 4 mrad over the log on x
    found = time_trend(noise + misfit + drift, cyc, floor_rad=5e-4)
    assert found["trends"] and found["p_value"] < 1e-3
    # the fitted change over the log, first cycle to last: the drift's, within the misfit's scatter
    expected = 4e-3 * (C - 1) / C
    assert abs(found["change_rad"][0] - expected) < 1.5e-3


def test_time_trend_needs_material_size_and_cycles():
    cyc = _cycles(12)
    tiny = np.outer(np.arange(len(cyc)), [1e-7, 0, 0])       # a perfect line of 13 urad
    assert not time_trend(tiny, cyc, floor_rad=5e-4)["trends"]
    assert time_trend(np.zeros((33, 3)), _cycles(3), 5e-4)["cycles"] == 3
    assert not time_trend(np.zeros((33, 3)), _cycles(3), 5e-4)["trends"]


def test_drive_offsets_are_named_not_hole_offsets():
    """The issue's failure shape: drive zero offsets (0.6 mm homing errors) came out ``hole_offsets``."""
    import dataclasses

    import csjm_opt as co
    from csjm_opt.diagnose import diagnose
    from csjm_opt.testbed import TestbedPlant
    from csjm_opt.testbed.simulate import simulate_experiment

    rig = co.paper_rig()
    rng = np.random.default_rng(11)
    plant = dataclasses.replace(TestbedPlant.nominal(rig), drive_offsets_m=rng.choice([-1.0, 1.0], 6) * 6e-4)
    train = simulate_experiment(rig, 10, rng, plant)
    test = simulate_experiment(rig, 6, rng, plant, first_cycle=20)
    d = diagnose(rig, train, test, effects=["hole_offsets", "drive_offsets", "sensor_bias"], secondary=False,
                 workers=1)
    assert d.selected == "drive_offsets"
    assert not any("hole_offsets has" in w for w in d.verdict.warnings)
    j = d.as_json()
    assert j["verdict"]["selected"] == "drive_offsets" and j["secondary"] == {"effect": "none"}


def _pair_score(rig, delta_mr_kgm, sd_kgm, mse):
    """A fitted pair hole_offsets + mass_com: the mass block off nominal by ``delta``, standard errors ``sd``."""
    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel

    model = AugmentedModel(rig, [make_effect("hole_offsets", rig), make_effect("mass_com", rig)])
    theta = model.x0()
    theta[-3:] += delta_mr_kgm
    cov = np.diag(np.full(model.n_params, 1e-8))
    cov[-3:, -3:] = np.diag(np.asarray(sd_kgm, float) ** 2)
    return _Score(name="hole_offsets+mass_com", fit=SimpleNamespace(model=model, theta=theta, cov=cov),
                  mse=list(mse))


class _Ctx:
    def __init__(self, ev):
        self.ev = ev

    def evidence(self, sc):
        return self.ev[sc.name]


def test_a_flexible_verdict_names_what_it_may_stand_in_for_by_the_partners_wald_test(rig):
    from csjm_opt.diagnose.selection.decision import stand_ins

    rng = np.random.default_rng(2)
    base = rng.uniform(1.0, 2.0, 8)
    holes = _Score(name="hole_offsets", fit=SimpleNamespace(p_eff=23), mse=list(base))
    pair_entry = [{"effects": ["hole_offsets", "mass_com"], "fitted": True, "separable": False,
                   "plausible": True, "closes_gap": True}]
    ctx = _Ctx({"hole_offsets": -250.0, "hole_offsets+mass_com": -250.5})
    sd = np.array([2e-3, 2e-3, 4e-3])
    # the block three standard errors off nominal along x (Wald z = 3, chi^2_3 p = 0.03 < 0.046): named
    far = _pair_score(rig, np.array([6e-3, 0.0, 0.0]), sd, base * rng.uniform(0.97, 1.03, 8))
    got = stand_ins(ctx, holes, "hole_offsets", pair_entry, {("hole_offsets", "mass_com"): far})
    assert [x for x, _ in got] == ["mass_com"] and abs(got[0][1] - 3.0) < 1e-9
    # within its errors of nominal (a log of hole offsets alone): nothing is named
    near = _pair_score(rig, np.array([2e-3, -1e-3, 2e-3]), sd, far.mse)
    assert stand_ins(ctx, holes, "hole_offsets", pair_entry, {("hole_offsets", "mass_com"): near}) == []
    # separable (the log tells them apart), or decisively less probable: nothing is named
    sep = [{**pair_entry[0], "separable": True}]
    assert stand_ins(ctx, holes, "hole_offsets", sep, {("hole_offsets", "mass_com"): far}) == []
    assert stand_ins(_Ctx({"hole_offsets": -250.0, "hole_offsets+mass_com": -260.0}), holes, "hole_offsets",
                     pair_entry, {("hole_offsets", "mass_com"): far}) == []


def test_a_pair_is_confirmed_by_evidence_only_when_no_left_out_flexible_first_is_decisively_more_probable():
    """The evidence route (decisive Bayes factor, confirmed on held-out cycles); a flexible first effect left out of
    the pair's rivals blocks both routes when it beats the pair on held-out cycles, and the evidence route when it is
    more probable than the pair by more than EVIDENCE_MIN."""
    from csjm_opt.diagnose.decision_rule import EVIDENCE_MIN, HELDOUT_ALPHA
    from csjm_opt.diagnose.selection.decision import pair_confirmed

    good = dict(gain=EVIDENCE_MIN + 2.7, p_value=0.04, improvement_rad=5e-4)
    assert pair_confirmed(False, **good) == (False, True)
    assert pair_confirmed(False, EVIDENCE_MIN - 0.1, 0.04, 5e-4) == (False, False)      # not decisive
    assert pair_confirmed(False, EVIDENCE_MIN + 1, HELDOUT_ALPHA, 5e-4) == (False, False)  # not confirmed held out
    assert pair_confirmed(True, **good, flexible_first=(-(EVIDENCE_MIN + 1.8), 0.11)) == (True, False)
    assert pair_confirmed(False, **good, flexible_first=(-(EVIDENCE_MIN - 0.5), 0.11)) == (False, True)
    assert pair_confirmed(True, **good, flexible_first=(+3.0, HELDOUT_ALPHA / 2)) == (False, False)


def test_a_pair_without_a_set_valued_first_must_be_decisively_more_probable_than_it():
    """Settled friction (a stick set) left out of a pair's rivals: its held-out errors cannot rule it out, so the pair
    is detected by neither route unless EVIDENCE_MIN nats more probable than it (and not beaten on held-out cycles);
    a flexible (point) first effect left out keeps the weaker bar."""
    from csjm_opt.diagnose.decision_rule import EVIDENCE_MIN, HELDOUT_ALPHA
    from csjm_opt.diagnose.selection.decision import pair_confirmed

    good = dict(gain=EVIDENCE_MIN + 2.7, p_value=0.04, improvement_rad=5e-4)
    assert pair_confirmed(True, **good, flexible_first=(EVIDENCE_MIN - 0.1, 0.54), set_valued=True) == (False, False)
    assert pair_confirmed(True, **good, flexible_first=(EVIDENCE_MIN + 0.1, 0.54), set_valued=True) == (True, True)
    assert pair_confirmed(True, **good, flexible_first=(674.0, HELDOUT_ALPHA / 2), set_valued=True) == (False, False)
    assert pair_confirmed(True, **good, flexible_first=(EVIDENCE_MIN - 0.1, 0.54)) == (True, True)
