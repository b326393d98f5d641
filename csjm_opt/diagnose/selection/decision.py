"""The decision: which effect (or pair, or none, or unexplained) the log supports.

Models: the *null* ``nominal_refit`` (nominal + common rest-length offset),
each single effect on top of it, and pairs (each of ``PAIR_SEEDS`` seed
singles + each other effect). Every model is scored on held-out cycles (:mod:`.scoring`). The
noise floor combines a model-free within-cycle estimate (:mod:`.noise`) with
the model's own whitened training residual (:func:`combine_scales`).

Rule (constants below; ``m`` candidates tried):

1. *Detected*: a single effect whose per-cycle held-out MSE is lower than the
   null's in a one-sided paired t-test over cycles at ``ALPHA / m``
   (Bonferroni: family-wise false-alarm rate at most ``ALPHA`` on an
   effect-free log), **and** whose systematic improvement
   ``sqrt(MSE_null - MSE_effect)`` (held-out) is at least ``IMPROVE_MULT``
   noise floors. Only held-out errors decide, so a non-smooth model
   (friction) cannot win on training noise the way a linearised F-test lets
   it; the F-test is still reported.
2. *Plausible*: its fitted parameters lie inside the effect's prior ranges
   (:meth:`~csjm_opt.diagnose.effects.base.Effect.default_ranges`,
   overridable per rig through ``ranges``).
3. The first effect is the detected, plausible one with the lowest BIC among
   those that close the gap (rule 4), else among all detected plausible ones
   (the detected one with the lowest held-out error if none is plausible): a
   model that explains the gap beats a simpler one that does not.
   *Pairs*: the seeds are the first effect and the singles with the lowest
   held-out errors (``PAIR_SEEDS`` in all, the whole vocabulary: every pair is
   fitted, so no wrong first pick hides the right pair); each seed is paired with every other effect (a
   variant effect's law chosen again on the pair model), and a pair is
   detected by the same test against the best of its two singles and the
   first effect, at ``ALPHA`` over the number of pairs fitted (two wrong
   effects that together mimic the right one do not beat it).
4. A model *closes the gap* when it explains at least ``CLOSE_FRACTION`` of
   the systematic held-out gap, measured against its held-out floor (noise
   plus its refits' estimation error). Nothing else counts: a named verdict
   always closes at least that share.
5. Verdict: the detected, plausible pair that closes the gap with the lowest
   BIC (``selected`` = its seed, ``secondary`` = the other); else the first
   effect when it is plausible and closes; ``unexplained`` when something was detected, or
   the null's residual holds significant structure of at least
   ``IMPROVE_MULT`` floors, but no plausible single or pair closes the gap;
   ``none`` otherwise. Pairs whose parameter blocks are not separable on this
   log (:mod:`.pairs`) are reported as such. A named verdict whose remaining
   residual still fails the signature test carries a warning that it may
   stand in for an effect outside the vocabulary; so does one whose model has
   more effective parameters than ``SHORT_LOG_SHARE`` of the log's cycle-level
   pose offsets (3 per cycle: such a model can follow any smooth pose error).
6. *Masked pairs*: when no single effect is detected but the null's residual
   holds significant structure of at least ``IMPROVE_MULT`` floors, two
   effects may hide each other: the seeds are the singles with the lowest
   held-out errors, and a pair is named when it beats the null model at
   ``ALPHA`` over the number of possible pairs (Bonferroni), is plausible and
   closes the gap.
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from ...errors import SolverError
from ...measurement.instruments import InstrumentNoise
from ...measurement.logfile import MeasurementLog
from ...model.rig import Rig
from ..data.extra import append_log
from ..data.localisation import localise
from ..data.noise import systematic
from ..data.residuals import compute_residuals
from ..decision_rule import (  # noqa: F401 (ALPHA and the thresholds are re-exported)
    ALPHA,
    CLOSE_FRACTION,
    EVIDENCE_MIN,
    HELDOUT_ALPHA,
    IMPROVE_MULT,
    LEAD_NATS,
    MATERIAL_SHARE,
    PAIR_SEEDS,
    SHORT_LOG_SHARE,
    _Context,
    combine_scales,
)
from ..effects import EFFECTS, make_effect
from ..fitting.model_fits import VARIANTS, fit_pair, fit_single, variant_fit  # noqa: F401 (VARIANTS re-exported)
from ..fitting.pool import map_ordered, resolve_workers
from .pairs import all_separabilities, secondary_alternatives
from .result import Diagnosis
from .rivals import rival_warning, scored_models, unsettled_rivals
from .scoring import CandidateScore, paired_heldout_test


def diagnose(rig: Rig, log: MeasurementLog, test: MeasurementLog | None = None,
             effects: Sequence[str] | None = None, noise: InstrumentNoise | None = None,
             progress: Callable | None = None, secondary: bool = True,
             ranges: Mapping[str, tuple[float, float]] | None = None,
             extra: MeasurementLog | None = None, workers: int | None = None) -> Diagnosis:
    """Residuals, noise floor, every candidate and pair scored, the verdict, localisation.

    Parameters
    ----------
    rig : Rig
        The nominal rig (the rig file).
    log : MeasurementLog
        Training log (held-out rows by grouped cross-validation unless ``test``).
    test : MeasurementLog, optional
        Held-out log.
    effects : sequence of str, optional
        Candidates (default: the whole vocabulary, :data:`EFFECTS`).
    noise : InstrumentNoise, optional
        Instrument model (shape of the noise; its scale is estimated from the data).
    progress : callable, optional
        ``tqdm``-like factory for a progress bar.
    secondary : bool, optional
        Search pairs (a second effect) too.
    ranges : mapping, optional
        Prior-range overrides for plausibility: parameter name or fnmatch pattern -> ``(lo, hi)``.
    extra : MeasurementLog, optional
        Further rows (e.g. a suggested experiment, run after ``log``): appended to the training
        log as later cycles, after checking that they come from this rig.
    workers : int, optional
        Worker processes for the candidates' and pairs' fits (default: ``CSJM_WORKERS``, else the cores
        this process may use, :func:`csjm_opt.diagnose.fitting.pool.default_workers`; 1: serial). The result does
        not depend on it.

    Returns
    -------
    Diagnosis

    Raises
    ------
    InvalidInput
        Fewer than two cycles and no test log, an unknown effect name, a malformed log, or an
        ``extra`` log that does not belong to this rig, or ``workers`` below 1.
    SolverError
        The nominal model cannot be evaluated on the log (singular tangents: slack cables).

    Notes
    -----
    The fits are many small dense problems: BLAS runs single-threaded inside (threads
    only contend for the cores there); the independent fits (candidates, pairs) run on ``workers``
    processes (:mod:`csjm_opt.diagnose.fitting.pool`), each exactly as the serial loop would.
    """
    workers = resolve_workers(workers)
    with threadpool_limits(1), np.errstate(all="ignore"):   # trial steps may overflow; fits guard themselves
        if extra is not None:
            log = append_log(rig, log, extra)
        try:
            return _diagnose(rig, log, test, effects, noise, progress, secondary, ranges, workers)
        except np.linalg.LinAlgError as exc:      # e.g. rows where every cable is slack at the measured pose
            raise SolverError(f"the nominal model cannot be evaluated on this log ({exc}); check that the log "
                              "belongs to this rig (cables taut at the measured poses)", "numpy") from exc


def _diagnose(rig, log, test, effects, noise, progress, secondary, ranges, workers) -> Diagnosis:
    names = list(EFFECTS) if effects is None else list(effects)
    for n in names:
        make_effect(n, rig)                        # unknown names fail here, before any fitting
    ctx = _Context(rig, compute_residuals(rig, log, noise),
                   compute_residuals(rig, test, noise) if test is not None else None)
    planned_pairs = _n_pair_fits(min(PAIR_SEEDS, len(names)), len(names)) if secondary else 0
    total = 1 + len(names) + planned_pairs
    bar = progress(total=total, desc="diagnose: fitting models") if progress else None
    tick = bar.update if bar else (lambda n=1: None)
    baseline = ctx.score([])
    tick(1)
    singles: dict[str, CandidateScore] = {}
    failed: dict[str, str] = {}
    options: dict[str, dict] = {}
    for name, (opt, sc, error) in zip(names, map_ordered(fit_single, (ctx, rig, ranges), names, workers, tick)):
        if sc is None:                                          # reported, not fatal
            failed[name] = str(error)
        else:
            options[name], singles[name] = opt, sc
    m = max(len(singles), 1)
    # the noise: the smallest of the estimates (a misfit, e.g. friction hysteresis, only inflates one)
    # (not a set-valued model's: its scale is the largest the held-out rows allow, for its own score only)
    floor0 = min([ctx.noise_floor(baseline)] + [ctx.scale(sc) * baseline.instrument_floor_rad
                                                for sc in singles.values() if sc.heldout_density is None])
    tests = {n: ctx.compare(baseline, sc, ALPHA / m, floor0) for n, sc in singles.items()}
    ctx.sigma = floor0 / baseline.instrument_floor_rad       # one noise scale for every model's evidence
    for n, sc in singles.items():
        tests[n]["log_evidence"] = ctx.evidence(sc)
    detected = [n for n in singles if tests[n]["significant"]]
    for n, sc in singles.items():
        tests[n]["closes_gap"] = ctx.closes(sc)
        tests[n]["residual_signature_p"] = ctx.signature(sc)["p_value"]
    plausible = [n for n in detected if tests[n]["plausible"]]
    closers = [n for n in plausible if tests[n]["closes_gap"]]
    first = (max(closers or plausible, key=lambda n: tests[n]["log_evidence"]) if plausible
             else min(detected, key=lambda n: singles[n].heldout_mse) if detected else None)

    gap_sig = ctx.signature(baseline)
    gap_there = bool(gap_sig["significant"]) and systematic(baseline.heldout_rms_rad, floor0) >= IMPROVE_MULT * floor0
    masked = first is None and gap_there and len(singles) > 1     # two effects may hide each other: rule 6
    by_error = sorted(singles, key=lambda n: singles[n].heldout_mse)
    seeds = ([] if first is None and not masked else
             ([first] if first is not None else []) + [n for n in by_error if n != first])[:PAIR_SEEDS]
    pairs, pair_scores = _pairs(ctx, rig, names, singles, seeds, secondary, ranges, tick, planned_pairs,
                                baseline if masked else None, first, options, workers)
    if bar:
        bar.close()
    selected, second, final, verdict = _verdict(ctx, baseline, singles, tests, first, pairs, pair_scores, gap_there)
    remaining = ctx.signature(final)
    n_cycles = len(np.unique(ctx.held.cycle))
    ev_final = ctx.evidence(final)
    # rivals: other plausible explanations of the gap (a pair that only adds to the named model is none)
    named = set(final.name.split("+"))
    rivals = {n: ctx.evidence(sc) for n, sc in singles.items() if sc is not final and tests[n]["plausible"]
              and tests[n]["closes_gap"] and n not in named}
    rivals.update({"+".join(k): ctx.evidence(sc) for k, sc in pair_scores.items() if sc is not final
                   and not named <= set(k)
                   and next((p["plausible"] and p["closes_gap"] for p in pairs if tuple(p["effects"]) == k), False)})
    verdict["evidence_margin"] = float(ev_final - max(rivals.values(), default=-np.inf))
    # a plausible model that closes the gap and is more probable under the priors, not confirmed on held-out
    # cycles: the verdict is the held-out test's pick, not the only reading of the log
    verdict["more_probable_rivals"] = sorted((n for n, e in rivals.items() if e > ev_final),
                                             key=lambda n: -rivals[n])
    if selected not in ("none", "unexplained") and verdict["more_probable_rivals"]:
        best_rival = verdict["more_probable_rivals"][0]
        verdict["warnings"].append(
            f"{best_rival} also closes the gap and has higher evidence ({rivals[best_rival] - ev_final:.1f} nats) "
            f"than {final.name}, but did not beat it on held-out cycles: the log does not decide between them")
    # not waived when the verdict is decisive: a lead over the rivals inside the vocabulary says
    # nothing about an effect outside it, which a model this flexible can mimic
    if selected not in ("none", "unexplained") and final.fit.p_eff > SHORT_LOG_SHARE * 3 * n_cycles:
        verdict["warnings"].append(
            f"{final.name} has {final.fit.p_eff:.0f} effective parameters against {3 * n_cycles} cycle-level "
            f"pose offsets in this log ({n_cycles} cycles): flexible enough to stand in for an effect outside the "
            "vocabulary; confirm with a longer log (more cycles at other poses)")
    if selected not in ("none", "unexplained") and remaining["significant"] \
            and remaining["systematic_rad"] >= MATERIAL_SHARE * ctx.floor(final):
        verdict["warnings"].append(
            f"the residual left by {final.name} still holds structure within cycles (signature test p = "
            f"{remaining['p_value']:.1e}): the named effect may be a stand-in for one outside the vocabulary; "
            "see localisation for where the residual lies")
    scale = ctx.scale(final)
    floor = scale * ctx.instrument
    estimates = {"within_cycle_rad": ctx.local, "within_cycle_dof": ctx.local_dof,
                 "selected_fit_rad": float(np.sqrt(final.noise_ratio2)) * ctx.instrument,
                 "instrument_model_rad": ctx.instrument, "noise_scale": scale,
                 "per_model_rad": {n: scale * c.instrument_floor_rad for n, c in
                                   [("nominal_refit", baseline), *singles.items()]}}
    confounded = []
    if selected in singles:
        for n in detected:
            sep = next((p for p in pairs if set(p["effects"]) == {n, selected}), None)
            if n != selected and paired_heldout_test(singles[n], singles[selected]) >= HELDOUT_ALPHA \
                    and (sep is None or not sep["separable"]):
                confounded.append(n)
    # rivals the log cannot tell from the selected: detected, not separable, and not decisively worse
    alternatives = [n for n in detected if n != selected and selected in singles
                    and any(set(p["effects"]) == {n, selected} and not p["separable"] for p in pairs)
                    and tests[n]["log_evidence"] >= tests[selected]["log_evidence"] - LEAD_NATS]
    verdict["alternatives"] = alternatives
    if alternatives:
        verdict["warnings"].append(f"{selected} is not separable on this log from {', '.join(alternatives)} "
                                   "(detected too; Fisher block correlation above the separability limit)")
    verdict["secondary_alternatives"] = secondary_alternatives(ctx, pairs, pair_scores, final, selected,
                                                                second.get("effect", "none"))
    if verdict["secondary_alternatives"]:
        verdict["warnings"].append(
            f"the second effect {second['effect']} is not separable on this log from "
            f"{', '.join(verdict['secondary_alternatives'])}: {selected} with either closes the gap "
            f"(evidence within {LEAD_NATS:g} nats, Fisher block correlation above the separability limit)")
    # every other model the log does not rule out is named (rivals.py); those warned about above are not repeated
    verdict["unsettled_rivals"] = [] if selected in ("none", "unexplained") else unsettled_rivals(
        scored_models(ctx.evidence, singles, tests, pairs, pair_scores, noise_scale=ctx.sigma), final.name,
        [*verdict["more_probable_rivals"], *alternatives,
         *(f"{selected}+{c}" for c in verdict["secondary_alternatives"])])
    verdict["warnings"] += [rival_warning(final.name, r) for r in verdict["unsettled_rivals"]]
    steps = [{"model": "nominal_refit", "heldout_rms_rad": baseline.heldout_rms_rad}]
    lead = selected if selected in singles else first
    if lead is not None:
        steps.append({"model": lead, "heldout_rms_rad": singles[lead].heldout_rms_rad})
    if second.get("effect", "none") != "none":
        steps.append({"model": f"{lead}+{second['effect']}", "heldout_rms_rad": final.heldout_rms_rad})
    rule = {"alpha": ALPHA, "per_candidate_alpha": ALPHA / m, "improve_mult": IMPROVE_MULT,
            "close_fraction": CLOSE_FRACTION,
            "test": "one-sided paired t-test of per-cycle held-out MSE against nominal_refit (Bonferroni over "
                    "candidates) and systematic improvement sqrt(MSE_null - MSE) >= improve_mult noise floors"}
    d = Diagnosis(ctx.train, ctx.test, baseline, singles, floor, estimates, tests, selected, confounded,
                  localise(ctx.held, ctx.held.zeta_rad, final.heldout_zeta_rad, floor),
                  remaining, second, failed, pairs, steps, verdict, gap_sig, final, rule, pair_scores)
    for s in d.steps:
        sc = final if "+" in s["model"] else singles.get(s["model"], baseline)
        s["fraction_explained"] = d.fraction(sc)
    return d


def _pairs(ctx: _Context, rig: Rig, names, singles, seeds, secondary, ranges, tick, planned: int,
           masked_base: CandidateScore | None, first: str | None, options: dict,
           workers: int = 1) -> tuple[list, dict]:
    """Every pair's separability; each seed + each other effect fitted and tested (rule 3 / rule 6).

    A pair is tested against the best of its two singles and the first effect (``masked_base``,
    the null model, when no single was detected), at ``ALPHA`` over the number of pairs fitted
    (Bonferroni): two wrong effects that together mimic the right one do not beat it. The progress
    bar advances by ``planned`` in all (fits that are not needed count as done).
    """
    pairs: list[dict] = []
    scores: dict[tuple[str, str], CandidateScore] = {}
    if not secondary:
        return pairs, scores
    seps = all_separabilities(rig, ctx.train, singles, names) if len(singles) > 1 else {}
    for (a, b), sep in seps.items():
        pairs.append({"effects": [a, b], **sep, "fitted": False})
    todo: list[tuple[str, str]] = []
    for a in seeds:
        todo += [(a, b) for b in singles if b != a and (a, b) not in todo and (b, a) not in todo]
    tick(max(planned - len(todo), 0))
    m = len(singles)
    level = ALPHA / max(m * (m - 1) // 2 if masked_base is not None else len(todo), 1)
    # the pairs are independent fits: on ``workers`` processes, results in the order of ``todo``
    for (a, b), (sc, error) in zip(todo, map_ordered(fit_pair, (ctx, rig, ranges, options), todo, workers, tick)):
        entry = next(p for p in pairs if set(p["effects"]) == {a, b})
        if sc is None:
            entry["error"] = str(error)
            continue
        scores[(a, b)] = sc
        rivals = [singles[a], singles[b]] + ([singles[first]] if first is not None else [])
        base = masked_base or min(rivals, key=lambda c: c.heldout_mse)
        t = ctx.compare(base, sc, level, ctx.noise_floor(base))
        ev = ctx.evidence(sc)
        gain = ev - max(ctx.evidence(c) for c in ([masked_base] if masked_base is not None else rivals))
        # the evidence route (rule 3b): decisive Bayes factor over every rival, confirmed on held-out cycles
        by_evidence = bool(gain >= EVIDENCE_MIN and t["p_value"] < HELDOUT_ALPHA and t["improvement_rad"] > 0)
        entry.update({"fitted": True, "effects": [a, b], "heldout_rms_rad": sc.heldout_rms_rad,
                      "fraction_explained": ctx.fraction(sc), "bic": sc.fit.bic, "closes_gap": ctx.closes(sc),
                      "log_evidence": ev, "evidence_gain": gain, "supported_by_evidence": by_evidence,
                      "tested_against": base.name, "p_value_vs_first": t["p_value"],
                      "significant_heldout": t["significant"],
                      **{k: t[k] for k in ("improvement_rad", "plausible", "implausible_params")},
                      "significant": bool(t["significant"] or by_evidence)})
    return pairs, scores


def _variant(ctx: _Context, rig: Rig, name: str, ranges, partners: Sequence = ()) -> dict:
    """The variant of ``name`` with the highest evidence, ``partners`` after it (:func:`.model_fits.variant_fit`)."""
    return variant_fit(ctx, rig, name, ranges, after=partners)[0]


def _n_pair_fits(n_seeds: int, n: int) -> int:
    """Pairs fitted from ``n_seeds`` seeds among ``n`` effects (each seed with every other, once)."""
    return n_seeds * (n - 1) - n_seeds * (n_seeds - 1) // 2


def _second(ctx: _Context, singles, first: str, best: dict, sc: CandidateScore) -> dict:
    """The ``secondary`` entry of a pair verdict."""
    return {"effect": best["effects"][1], "heldout_rms_rad": sc.heldout_rms_rad,
            "params": {k: v for k, v in sc.fit.params().items() if k not in singles[first].fit.params()},
            "fraction_explained": ctx.fraction(sc), "p_value": best["p_value_vs_first"],
            **{k: best[k] for k in ("improvement_rad", "separable", "max_correlation", "plausible",
                                    "implausible_params")}}


def _verdict(ctx: _Context, baseline, singles, tests, first, pairs, pair_scores, gap_there):
    """``(selected, secondary, final score, verdict dict)`` by rules 5 and 6 of the module doc."""
    warnings: list[str] = []
    none2 = {"effect": "none"}
    ok = [p for p in pairs if p.get("fitted") and p["significant"] and p["plausible"] and p["closes_gap"]]
    best = max(ok, key=lambda p: p["log_evidence"]) if ok else None
    if best is not None:                           # a pair (rule 5), or a masked pair (rule 6)
        a, b = best["effects"]
        sc = pair_scores[(a, b)]
        if not best["separable"]:
            warnings.append(f"{a} and {b} are not separable on this log "
                            f"(Fisher block correlation {best['max_correlation']:.3f})")
        reason = (f"{a} and {b} together close the gap on held-out cycles" if first is not None else
                  f"neither alone, but {a} and {b} together close the gap on held-out cycles (each hides the other)")
        return a, _second(ctx, singles, a, best, sc), sc, {"selected": a, "warnings": warnings, "reason": reason}
    if first is None:
        if gap_there:
            return "unexplained", none2, baseline, {
                "selected": "unexplained", "warnings": warnings,
                "reason": "the nominal model's held-out residual holds significant structure but no candidate "
                          "improves on it significantly; see localisation for where it lies"}
        return "none", none2, baseline, {"selected": "none", "warnings": warnings,
                                         "reason": "no candidate improves significantly on held-out cycles"}
    t1 = tests[first]
    if not t1["plausible"]:
        warnings.append(f"{first} needs implausible parameters: {', '.join(t1['implausible_params'])}")
    if t1["plausible"] and t1["closes_gap"]:
        return first, none2, singles[first], {"selected": first, "warnings": warnings,
                                              "reason": f"{first} closes the gap on held-out cycles"}
    tried = [p for p in pairs if p.get("fitted") and p["significant"] and p["plausible"]]
    if tried:
        near = max(tried, key=lambda p: p["fraction_explained"])
        warnings.append(f"best pair {'+'.join(near['effects'])} leaves "
                        f"{1 - near['fraction_explained']:.0%} of the systematic gap")
    warnings.append(f"best single {first} leaves {1 - ctx.fraction(singles[first]):.0%} of the systematic gap")
    return "unexplained", none2, baseline, {
        "selected": "unexplained", "warnings": warnings,
        "reason": "no plausible single effect or pair brings the held-out gap near the noise floor; "
                  "see localisation for where the residual lies"}
