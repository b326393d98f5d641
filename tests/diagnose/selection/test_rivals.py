"""Rivals the log does not rule out (csjm_opt.diagnose.selection.rivals): the stated rule, and its held-out part
against the closed-form power of a paired t-test (noncentral t), an independent construction."""

from __future__ import annotations

import numpy as np
from scipy import stats

from csjm_opt.diagnose.decision_rule import EVIDENCE_MIN, HELDOUT_ALPHA
from csjm_opt.diagnose.selection.rivals import rival_warning, unsettled_rivals

N_CYCLES = 12


def _model(ev, cycle_mse, plausible=True, closes=True):
    return {"log_evidence": ev, "cycle_mse": list(cycle_mse), "plausible": plausible, "closes_gap": closes}


def test_the_stated_rule_on_constructed_models():
    """Nested: listed iff more probable; replacing: listed iff within EVIDENCE_MIN and not beaten on held-out
    cycles; a rival short of the closure threshold only when the verdict does not beat it on held-out cycles;
    parts of the verdict, implausible and already-warned models never."""
    rng = np.random.default_rng(3)
    same = np.exp(rng.normal(0.0, 0.1, N_CYCLES))             # held-out errors like the verdict's
    worse = 3.0 * np.ones(N_CYCLES)                           # the verdict beats it on every cycle
    one = np.ones(N_CYCLES)
    models = {
        "A+B": _model(0.0, one),                               # the verdict
        "A": _model(-1.0, same), "B": _model(-50.0, same),     # parts of the verdict: never rivals
        "C": _model(-EVIDENCE_MIN / 2, same),                  # replaces it, close, same errors: listed
        "D": _model(-EVIDENCE_MIN / 2, worse),                 # close in evidence, beaten held-out: not
        "E": _model(-2 * EVIDENCE_MIN, same),                  # decisively less probable: not
        "C+D": _model(+3.0, worse),                            # more probable: listed even though beaten held-out
        "A+F": _model(-1.0, same, plausible=False),            # implausible: not
        "A+G": _model(-1.0, same),                             # already warned about (skip): not
        "H": _model(+20.0, same, closes=False),                # short of the threshold, tied held-out: listed
        "I": _model(+20.0, worse, closes=False),               # short of the threshold, beaten held-out: not
    }
    got = unsettled_rivals(models, "A+B", skip=["G+A"])
    assert [r["model"] for r in got] == ["H", "C+D", "C"]
    assert [r["closes_gap"] for r in got] == [False, True, True]
    assert "within the noise" in rival_warning("A+B", got[0])
    assert all(r["adds"] == [] for r in got)
    # a single verdict: a pair that adds to it is listed only when the evidence prefers it
    single = {"A": _model(0.0, one), "A+B": _model(2.0, same), "A+C": _model(-0.5, same), "B": _model(-20.0, same)}
    got = unsettled_rivals(single, "A")
    assert [(r["model"], r["adds"]) for r in got] == [("A+B", ["B"])]
    assert "B may be present too" in rival_warning("A", got[0])
    assert unsettled_rivals({"A": _model(0.0, one)}, "A") == []


def test_an_addition_needs_the_prior_odds_of_one_among_m():
    """An effect added to the verdict is listed when its evidence beats the verdict's by ln m, m the number of
    additions fitted (prior odds 1/m each): with eleven, 2.3 nats is not enough (ln 11 = 2.398) and 2.5 is; with
    one addition, any lead is. Replacements keep their own rule (more probable, or close and tied)."""
    rng = np.random.default_rng(2)
    same = np.exp(rng.normal(0.0, 0.1, N_CYCLES))
    worse = 3.0 * np.ones(N_CYCLES)

    def eleven(lead):
        models = {"A": _model(0.0, np.ones(N_CYCLES))}
        models.update({f"A+X{i}": _model(-3.0, worse) for i in range(10)})
        models["A+B"] = _model(lead, same)
        return models

    assert np.log(11) > 2.3
    assert unsettled_rivals(eleven(2.3), "A") == []
    assert [r["model"] for r in unsettled_rivals(eleven(2.5), "A")] == ["A+B"]
    one = {"A": _model(0.0, np.ones(N_CYCLES)), "A+B": _model(0.1, same)}
    assert [r["model"] for r in unsettled_rivals(one, "A")] == ["A+B"]
    # a replacement more probable by any margin is listed whatever the number of additions
    models = {**eleven(2.3), "C": _model(0.1, worse)}
    assert [r["model"] for r in unsettled_rivals(models, "A")] == ["C"]


def test_heldout_part_matches_the_noncentral_t_power():
    """Rival errors with per-cycle log ratios N(delta, s^2) to the verdict's: the rule lists the rival (within
    EVIDENCE_MIN) exactly when the one-sided paired t-test fails at HELDOUT_ALPHA, i.e. with probability
    1 - power, the power from the noncentral t distribution (scipy.stats.nct)."""
    rng = np.random.default_rng(11)
    n, s, draws = N_CYCLES, 0.3, 600
    t_crit = stats.t.ppf(1 - HELDOUT_ALPHA, n - 1)
    for delta in (0.0, 0.1, 0.25):
        listed = 0
        for _ in range(draws):
            d = rng.normal(delta, s, n)
            models = {"A": _model(0.0, np.ones(n)), "C": _model(-1.0, np.exp(d))}
            listed += bool(unsettled_rivals(models, "A"))
        power = 1 - stats.nct.cdf(t_crit, n - 1, delta * np.sqrt(n) / s)
        expected = 1 - power
        sd = np.sqrt(expected * (1 - expected) / draws)
        assert abs(listed / draws - expected) < 4 * sd + 1e-3, (delta, listed / draws, expected)


def test_scored_models_reads_acceptability_and_errors_from_the_diagnosis_pieces():
    """Singles take plausibility and closure from their tests, pairs from their entries; unfitted pairs are
    left out; the evidence comes from the given function."""
    from csjm_opt.diagnose.selection.rivals import scored_models

    class Score:
        def __init__(self, ev, mse):
            self.ev, self.mse = ev, mse

        def cycle_mse(self):
            return dict(enumerate(self.mse))

    singles = {"A": Score(-1.0, [1.0, 2.0, 1.5]), "B": Score(-2.0, [20.0, 30.0, 31.0])}
    tests = {"A": {"plausible": True, "closes_gap": True}, "B": {"plausible": True, "closes_gap": False}}
    pairs = [{"effects": ["A", "B"], "fitted": True, "plausible": True, "closes_gap": True},
             {"effects": ["A", "C"], "fitted": False, "plausible": True, "closes_gap": True}]
    got = scored_models(lambda sc: sc.ev, singles, tests, pairs, {("A", "B"): Score(3.0, [0.5, 0.5, 0.6])})
    assert set(got) == {"A", "B", "A+B"}
    assert [got[k]["closes_gap"] for k in ("A", "B", "A+B")] == [True, False, True]
    assert got["A+B"]["log_evidence"] == 3.0 and got["A"]["cycle_mse"] == {0: 1.0, 1: 2.0, 2: 1.5}
    # the verdict A: A+B adds B with 4 more nats -> listed as "B may be present too"
    assert [r["adds"] for r in unsettled_rivals(got, "A")] == [["B"]]


def test_heldout_better_rivals_hold_the_bonferroni_level():
    """K rivals as good as the verdict (per-cycle log ratios N(0, s^2), independent), decisively less probable:
    only the held-out-better clause can list them, at HELDOUT_ALPHA / K each, so some rival is listed with
    probability 1 - (1 - HELDOUT_ALPHA / K)^K (uniform p-values of an exact t-test); a rival whose errors are
    a quarter of the verdict's on every cycle is always listed."""
    rng = np.random.default_rng(5)
    k, draws = 4, 500
    listed = 0
    for _ in range(draws):
        models = {"A": _model(0.0, np.ones(N_CYCLES))}
        models.update({f"R{i}": _model(-3 * EVIDENCE_MIN, np.exp(rng.normal(0.0, 0.3, N_CYCLES))) for i in range(k)})
        listed += bool(unsettled_rivals(models, "A"))
    expected = 1 - (1 - HELDOUT_ALPHA / k) ** k
    assert abs(listed / draws - expected) < 4 * np.sqrt(expected * (1 - expected) / draws), (listed / draws, expected)
    better = {"A": _model(0.0, np.ones(N_CYCLES)),
              "B": _model(-3 * EVIDENCE_MIN, 0.25 * np.exp(rng.normal(0.0, 0.1, N_CYCLES)))}
    got = unsettled_rivals(better, "A")
    assert [r["model"] for r in got] == ["B"] and got[0]["heldout_better"]
    assert "yardsticks disagree" in rival_warning("A", got[0])


def test_evidence_leads_are_taken_at_the_fitted_parameters():
    """A rival whose lead exists only at its linearised mode (the fit reached a worse misfit) is not listed; one
    whose fit realises the lead is, with both leads reported; entries without the fitted evidence fall back."""
    one = np.ones(N_CYCLES)
    rng = np.random.default_rng(7)
    same = np.exp(rng.normal(0.0, 0.1, N_CYCLES))

    def m(lin, fitted, mse):
        return {**_model(lin, mse), "log_evidence_at_fit": fitted}

    models = {"A": m(0.0, -0.5, one),
              "A+B": m(10.0, -5.0, same),        # linearised +10 nats, as fitted -4.5: not more probable
              "A+C": m(-1.0, 2.0, same)}         # linearised -1, as fitted +2.5: more probable
    got = unsettled_rivals(models, "A")
    assert [r["model"] for r in got] == ["A+C"]
    assert abs(got[0]["nats"] - 2.5) < 1e-12 and abs(got[0]["nats_linearised"] + 1.0) < 1e-12
    assert "2.5 nats more evidence" in rival_warning("A", got[0])
    # without the fitted evidence the linearised one decides (records made before it was kept)
    plain = {k: {kk: vv for kk, vv in v.items() if kk != "log_evidence_at_fit"} for k, v in models.items()}
    assert [r["model"] for r in unsettled_rivals(plain, "A")] == ["A+B"]


def test_scored_models_gives_the_evidence_at_the_fit_from_the_context_noise_scale(rig):
    """``log_evidence_at_fit`` is the evidence module's, at the ``sigma`` of the context whose ``evidence`` is
    passed (or the explicit noise scale), and never above the linearised evidence."""
    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.evidence import log_evidence
    from csjm_opt.diagnose.fitting.gauss_newton import fit_model
    from csjm_opt.diagnose.selection.rivals import scored_models
    from csjm_opt.testbed import simulate_experiment

    t = compute_residuals(rig, simulate_experiment(rig, 2, np.random.default_rng(4), effect="sensor_bias",
                                                   severity=2.0, steps=2))
    fit = fit_model(AugmentedModel(rig, [make_effect("sensor_bias", rig)]), t)

    class Score:
        def __init__(self, f):
            self.fit = f

        def cycle_mse(self):
            return {0: 1.0, 1: 1.0}

    class Ctx:
        sigma = 1.7

        def evidence(self, sc):
            return log_evidence(sc.fit, self.sigma)

    tests = {"sensor_bias": {"plausible": True, "closes_gap": True}}
    got = scored_models(Ctx().evidence, {"sensor_bias": Score(fit)}, tests, [], {})["sensor_bias"]
    assert got["log_evidence_at_fit"] == log_evidence(fit, 1.7, at_fit=True)
    assert got["log_evidence_at_fit"] <= got["log_evidence"] + 1e-9
    explicit = scored_models(lambda sc: 0.0, {"sensor_bias": Score(fit)}, tests, [], {}, noise_scale=0.9)
    assert explicit["sensor_bias"]["log_evidence_at_fit"] == log_evidence(fit, 0.9, at_fit=True)
    assert scored_models(lambda sc: 0.0, {"sensor_bias": Score(fit)}, tests, [], {})["sensor_bias"][
        "log_evidence_at_fit"] is None


def test_held_out_ties_to_round_off_are_not_improvements():
    """A rival whose added effect fitted to zero predicts every cycle to round-off of the verdict, or a few 1e-4
    of each cycle's MSE better (a stick pair's relinearised nuisance): no evidence either way (p = 1), where a
    shared 1e-15 'improvement' once gave p = 0 and a shared 2e-4 one p = 0.000. A real improvement shared by
    every cycle stays significant, and noisy differences get scipy's t-test (ties within a thousandth at 0)."""
    from csjm_opt.diagnose.selection.rivals import _Cycles
    from csjm_opt.diagnose.selection.scoring import TIE_LOG_RATIO, paired_heldout_test

    rng = np.random.default_rng(3)
    mse = rng.uniform(1e-6, 4e-6, 12)
    for shared in (1e-14, rng.uniform(2e-5, 5e-4, 12)):
        same = _Cycles(mse * (1.0 - shared))
        assert paired_heldout_test(_Cycles(mse), same) == 1.0
        assert unsettled_rivals({"a": {"log_evidence": 0.0, "plausible": True, "closes_gap": True,
                                       "cycle_mse": list(mse)},
                                 "a+b": {"log_evidence": -3.0, "plausible": True, "closes_gap": True,
                                         "cycle_mse": list(mse * (1.0 - shared))}}, "a") == []
    assert paired_heldout_test(_Cycles(mse), _Cycles(0.9 * mse)) == 0.0
    other = mse * np.exp(rng.normal(0.05, 0.1, 12))
    d = np.log(other / mse)
    d[np.abs(d) < TIE_LOG_RATIO] = 0.0
    assert np.isclose(paired_heldout_test(_Cycles(other), _Cycles(mse)),
                      stats.ttest_1samp(d, 0.0, alternative="greater").pvalue)


def test_a_set_valued_rival_is_not_confirmed_by_held_out_errors_alone():
    """Lower held-out errors on every cycle (p ~ 0) list a point rival however improbable, but not a stick set
    (settled friction) decisively less probable than the verdict; within EVIDENCE_MIN nats it is listed."""
    one = np.ones(N_CYCLES)
    lower = 0.5 * one * np.exp(np.random.default_rng(4).normal(0.0, 0.05, N_CYCLES))
    point = {"V": _model(0.0, one), "R": _model(-500.0, lower)}
    assert [r["model"] for r in unsettled_rivals(point, "V")] == ["R"]
    stick = {"V": _model(0.0, one), "R": {**_model(-500.0, lower), "set_valued": True}}
    assert unsettled_rivals(stick, "V") == []
    close = {"V": _model(0.0, one), "R": {**_model(-EVIDENCE_MIN / 2, lower), "set_valued": True}}
    assert [r["model"] for r in unsettled_rivals(close, "V")] == ["R"]


def test_an_effect_added_to_a_stick_model_is_listed_on_held_out_errors_only():
    """V + X with the same held-out errors: listed at any positive margin over a point verdict (one addition),
    never over a set-valued one (settled friction, whose Laplace evidence favours the larger model by several
    nats), however large the margin; with lower held-out errors on every cycle it is listed over either."""
    rng = np.random.default_rng(6)
    one = np.ones(N_CYCLES)
    same = np.exp(rng.normal(0.0, 0.1, N_CYCLES))
    lower = 0.5 * same
    for margin in (0.5 * EVIDENCE_MIN, 1.5 * EVIDENCE_MIN, 5 * EVIDENCE_MIN):
        point = {"V": _model(0.0, one), "V+X": _model(margin, same)}
        assert [r["model"] for r in unsettled_rivals(point, "V")] == ["V+X"]
        stick = {"V": {**_model(0.0, one), "set_valued": True}, "V+X": {**_model(margin, same), "set_valued": True}}
        assert unsettled_rivals(stick, "V") == []
        better = {**stick, "V+X": {**_model(margin, lower), "set_valued": True}}
        assert [r["model"] for r in unsettled_rivals(better, "V")] == ["V+X"]
    # a replacing rival is judged as before: within EVIDENCE_MIN and tied on held-out cycles, it is listed
    stick = {"V": {**_model(0.0, one), "set_valued": True}, "Y": _model(-0.5 * EVIDENCE_MIN, same)}
    assert [r["model"] for r in unsettled_rivals(stick, "V")] == ["Y"]


def test_inseparable_look_alikes_are_listed_when_they_fit_as_well():
    """A detected effect the log cannot separate from the verdict is listed when it is a leading hypothesis (evidence
    within LEAD_NATS), or, for a single verdict, when it closes the gap, is not beaten on held-out cycles and its misfit
    is not decisively worse (chi^2 excess below 2 EVIDENCE_MIN) however many nats its priors cost it; never when it is
    separable, undetected, decisively worse fitting, beaten on held-out cycles or flexible (then only as a leading
    hypothesis)."""
    from csjm_opt.diagnose.decision_rule import LEAD_NATS
    from csjm_opt.diagnose.selection.rivals import alternatives_warnings, inseparable_alternatives

    rng = np.random.default_rng(13)
    same = np.exp(rng.normal(0.0, 0.1, N_CYCLES))
    worse = 3.0 * np.ones(N_CYCLES)

    def m(ev, chi2, mse, separable=False, detected=True, closes=True):
        return {"detected": detected, "plausible": True, "closes_gap": closes, "separable": separable,
                "log_evidence": ev, "chi2": chi2, "cycle_mse": list(mse)}

    far = -2 * LEAD_NATS                                   # decisively less probable by the priors
    models = {"V": m(0.0, 300.0, np.ones(N_CYCLES)),
              "X": m(far, 290.0, same),                    # fits as well, held-out tied: listed ("fit")
              "Y": m(far, 290.0, same, separable=True),    # separable: not
              "Z": m(far, 300.0 + 2 * EVIDENCE_MIN + 1.0, same),   # fits decisively worse: not
              "W": m(far, 290.0, worse),                   # beaten on held-out cycles: not
              "U": m(-LEAD_NATS / 2, 330.0, worse),        # a leading hypothesis: listed ("evidence")
              "S": m(far, 290.0, same, detected=False),    # not detected: not
              "T": m(far, 290.0, same, closes=False),      # does not close the gap: not
              "F": {**m(far, 290.0, same), "flexible": True}}   # flexible (36 hole offsets): parsimony rules it out
    got = inseparable_alternatives(models, "V")
    assert [(a["model"], a["route"]) for a in got] == [("X", "fit"), ("U", "evidence")]
    assert got[0]["chi2_excess"] == -10.0 and got[0]["nats"] == far
    # a pair verdict: only the evidence route (the fit route compares a single with the verdict's model)
    assert [a["model"] for a in inseparable_alternatives(models, "V", single_verdict=False)] == ["U"]
    texts = alternatives_warnings("V", got)
    assert len(texts) == 2 and "from U " in texts[0] and "from X " in texts[1] and "--suggest" in texts[1]
    assert alternatives_warnings("V", []) == []
