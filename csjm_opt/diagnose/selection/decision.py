"""The decision: which effect (or pair, or none, or unexplained) the log supports.

Models: the *null* ``nominal_refit`` (nominal + common rest-length offset), each single effect on
top of it, and pairs; each is scored on held-out cycles (:mod:`.scoring`) and priced by its
evidence (:mod:`.evidence`). The rule (detection, plausibility, closing the gap, parsimony, pairs,
masked pairs, the warnings) is stated in the guide, ``docs/guide/diagnosis.md``, section "The
decision rule"; its constants are in :mod:`..decision_rule`. :func:`diagnose` builds the verdict
(:class:`~csjm_opt.diagnose.selection.verdict.Verdict`) in small steps: the singles fitted and tested, the
first effect, the pairs, the verdict, then the warnings about what the log does not rule out.
"""

from __future__ import annotations

from typing import Callable, Mapping, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from ...errors import SolverError
from ...measurement.instruments import InstrumentNoise
from ...measurement.logfile import MeasurementLog
from ...measurement.rig_fit import check_log_rig
from ...model.rig import Rig
from ..data.extra import append_log
from ..data.localisation import localise
from ..data.noise import systematic
from ..data.residuals import (
    ResidualTable,
    compute_residuals,
    gross_rows,
    ill_conditioned_rows,
    left_out_residuals,
    row_pose_noise_rad,
    whitened_norm2,
)
from ..data.tails import chi2_sf, norm_sf
from ..data.trend import time_trend
from ..decision_rule import (  # noqa: F401 (ALPHA and the thresholds are re-exported)
    ALPHA,
    CLOSE_FRACTION,
    EVIDENCE_MIN,
    HELDOUT_ALPHA,
    IMPROVE_MULT,
    LEAD_NATS,
    LOOK_ALIKE_SHARE,
    MATERIAL_SHARE,
    PAIR_SEEDS,
    SHORT_LOG_SHARE,
    _Context,
    combine_scales,
)
from ..effects import EFFECTS, make_effect, n_cables_of
from ..effects.base import PLAUSIBLE_Z
from ..effects.cable_creep import CableCreep
from ..effects.drum_slip import DrumSlip
from ..fitting.augmented import N_NUISANCE
from ..fitting.gauss_newton import FitResult
from ..fitting.model_fits import (  # noqa: F401 (VARIANTS re-exported)
    FIT_ERRORS,
    SCREEN_NATS,
    VARIANTS,
    fit_cost,
    fit_single,
    score_effect,
    screened_pair,
    variant_fit,
)
from ..fitting.pool import map_ordered, resolve_workers
from .pairs import all_separabilities, secondary_alternatives
from .result import Diagnosis
from .rivals import (
    alternatives_warnings,
    inseparable_alternatives,
    rival_warning,
    scored_models,
    unsettled_rivals,
)
from .scoring import CandidateScore, heldout_key, paired_heldout_test
from .verdict import Secondary, Verdict


def diagnose(rig: Rig, log: MeasurementLog, test: MeasurementLog | None = None,
             effects: Sequence[str] | None = None, noise: InstrumentNoise | None = None,
             progress: Callable | None = None, secondary: bool = True,
             ranges: Mapping[str, tuple[float, float]] | None = None,
             extra: MeasurementLog | None = None, workers: int | None = None,
             check_rig: bool = True) -> Diagnosis:
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
        this process may use, :func:`csjm_opt._workers.default_workers`; 1: serial). The result does
        not depend on it.
    check_rig : bool, optional
        Refuse a log (``log``, ``test``, ``extra``) that ``rig`` cannot have produced
        (:func:`csjm_opt.measurement.rig_fit.check_log_rig`).

    Returns
    -------
    Diagnosis

    Raises
    ------
    InvalidInput
        Fewer than two cycles and no test log, an unknown effect name, a malformed log, or an
        ``extra`` log that does not belong to this rig, or ``workers`` below 1; a
        :class:`~csjm_opt.errors.LogRigMismatch` when a log's first rows are out of equilibrium with
        the rig's cables (``check_rig``).
    SolverError
        The nominal model cannot be evaluated on the log (singular tangents: slack cables).

    Notes
    -----
    The fits are many small dense problems: BLAS runs single-threaded inside (threads
    only contend for the cores there); the independent fits (candidates, pairs) run on ``workers``
    processes (:mod:`csjm_opt.diagnose.fitting.pool`), each exactly as the serial loop would.
    """
    workers = resolve_workers(workers)
    if check_rig:
        for what, one in (("log", log), ("test log", test), ("extra log", extra)):
            if one is not None:
                check_log_rig(rig, one, what=one.source or what)
    with threadpool_limits(1), np.errstate(all="ignore"):   # trial steps may overflow; fits guard themselves
        if extra is not None:
            log = append_log(rig, log, extra)
        try:
            return _diagnose(rig, log, test, effects, noise, progress, secondary, ranges, workers)
        except np.linalg.LinAlgError as exc:      # e.g. rows where every cable is slack at the measured pose
            raise SolverError(f"the nominal model cannot be evaluated on this log ({exc}); check that the log "
                              "belongs to this rig (cables taut at the measured poses)", "numpy") from exc


def _diagnose(rig, log, test, effects, noise, progress, secondary, ranges, workers,
              gross: Mapping[str, list[dict]] | None = None) -> Diagnosis:
    """One diagnosis; again without the gross outliers (:func:`_gross_rows`) when the first pass finds some."""
    names = list(EFFECTS) if effects is None else list(effects)
    for n in names:
        make_effect(n, rig)                        # unknown names fail here, before any fitting
    logs = {"log": log, "test log": test}
    (train, test_table), left_out, kept = zip(*[_well_conditioned(rig, one, noise, what, (gross or {}).get(what, []))
                                                for what, one in logs.items()])
    ctx = _Context(rig, train, test_table)
    planned_pairs = _n_pair_fits(min(PAIR_SEEDS, len(names)), len(names)) if secondary else 0
    desc = "diagnose: fitting models" + (" again without the gross outliers" if gross else "")
    bar = progress(total=1 + len(names) + planned_pairs, desc=desc) if progress else None
    tick = bar.update if bar else (lambda n=1: None)
    baseline = ctx.score([])
    tick(1)
    singles, failed, options, point_fits = _fit_singles(ctx, rig, names, ranges, workers, tick)
    found, ratio_max = _gross_rows(ctx, baseline, singles, dict(zip(logs, kept)), logs)
    if gross is None and any(found.values()):
        if bar:
            bar.close()
        return _diagnose(rig, log, test, effects, noise, progress, secondary, ranges, workers, found)
    floor0 = _noise_floor(ctx, baseline, singles)
    tests = _test_singles(ctx, baseline, singles, floor0)
    n_cycles = len(np.unique(ctx.held.cycle))
    detected = [n for n in singles if tests[n]["significant"]]
    first = _first_effect(singles, tests, detected, n_cycles)
    gap_sig = ctx.signature(baseline)
    gap_there = bool(gap_sig["significant"]) and systematic(baseline.heldout_rms_rad, floor0) >= IMPROVE_MULT * floor0
    masked = first is None and gap_there and len(singles) > 1     # two effects may hide each other: rule 6
    key = heldout_key(singles.values())
    by_error = sorted(singles, key=lambda n: key(singles[n]))
    seeds = ([] if first is None and not masked else
             ([first] if first is not None else []) + [n for n in by_error if n != first])[:PAIR_SEEDS]
    pairs, pair_scores = _pairs(ctx, rig, names, singles, seeds, secondary, ranges, tick, planned_pairs,
                                baseline if masked else None, first, options, point_fits, workers, n_cycles)
    if bar:
        bar.close()
    verdict = _verdict(ctx, baseline, singles, tests, first, pairs, pair_scores, gap_there, n_cycles)
    remaining = ctx.signature(verdict.final)
    _rival_warnings(ctx, verdict, singles, tests, detected, pairs, pair_scores, n_cycles, remaining)
    _time_trend_warning(ctx, verdict)
    _trend_probe_warning(ctx, rig, verdict, baseline, floor0, workers)
    d = Diagnosis(train=ctx.train, test=ctx.test, baseline=baseline, candidates=singles,
                  noise_floor_rad=ctx.scale(verdict.final) * ctx.instrument,
                  noise_estimates=_noise_estimates(ctx, verdict.final, baseline, singles), tests=tests,
                  verdict=verdict, confounded_with=_confounded(singles, detected, pairs, verdict.selected),
                  localisation=localise(ctx.held, ctx.held.zeta_rad, verdict.final.heldout_zeta_rad,
                                        ctx.scale(verdict.final) * ctx.instrument),
                  remaining=remaining, failed=failed, pairs=pairs, steps=_steps(baseline, singles, verdict, first),
                  gap_signature=gap_sig, rule=_rule(len(singles)), pair_scores=pair_scores,
                  left_out_rows=[r for rows in left_out for r in rows], outlier_ratio_max=ratio_max)
    for s in d.steps:
        sc = verdict.final if "+" in s["model"] else singles.get(s["model"], baseline)
        s["fraction_explained"] = d.fraction(sc)
    return d


def _well_conditioned(rig: Rig, log: MeasurementLog | None, noise, what: str,
                      gross: Sequence[dict] = ()) -> tuple[ResidualTable | None, list, np.ndarray | None]:
    """``(table, rows left out, log index of each table row)``: ``log`` without ``gross`` and its ill-conditioned rows.

    ``gross`` are the rows :func:`_gross_rows` found (listed first among the rows left out, one dict each). Rows
    where the rig file's model is nearly singular at the measured pose
    (:func:`~csjm_opt.diagnose.data.residuals.ill_conditioned_rows`) are left out of the diagnosis: the table is
    made again from the other rows (the friction path runs through the rows kept).
    """
    if log is None:
        return None, [], None
    kept = np.setdiff1d(np.arange(len(log)), [r["row"] for r in gross])
    part = log.subset(kept) if len(kept) < len(log) else log
    table = compute_residuals(rig, part, noise)
    bad = ill_conditioned_rows(table)
    rows = [{k: v for k, v in r.items() if k != "row"} for r in gross]
    if not bad.size:
        return table, rows, kept
    sd = row_pose_noise_rad(table)
    rows += [{"log": what, "sample": int(part.sample[i]), "cycle": int(part.cycle[i]), "reason": "ill_conditioned",
              "pose_noise_rad": float(sd[i]), "median_pose_noise_rad": float(np.median(sd))} for i in bad]
    kept = np.delete(kept, bad)
    return compute_residuals(rig, log.subset(kept), noise), rows, kept


def _gross_rows(ctx: _Context, baseline: CandidateScore, singles: Mapping[str, CandidateScore],
                kept: Mapping[str, np.ndarray | None],
                logs: Mapping[str, MeasurementLog | None]) -> tuple[dict[str, list], dict[str, float]]:
    """``(gross outliers of each log, each log's largest outlier ratio)``, by ``"log"`` and ``"test log"``.

    Each gross row is a dict (``row``: its index in the log). A tracker glitch or a force spike in one row is
    explained by no model and inflates the noise floor every test is measured against
    (:func:`~csjm_opt.diagnose.data.residuals.gross_rows`: judged on the training rows' fitted residuals and the test
    rows' predicted ones, of the point model that fits the training rows best; a training row's residual as if it
    had been left out of the fit, :func:`~csjm_opt.diagnose.data.residuals.left_out_residuals`: 36 hole offsets bend
    toward a spike in their training rows). Such rows are left out and the diagnosis made again, and listed
    (``left_out_rows``).
    """
    points = [baseline, *(sc for sc in singles.values() if not sc.set_valued)]
    # the point model that fits the training rows best (smallest median whitened residual) judges every row: the
    # nearest model row by row would let a model that fits the log badly vouch for a spike by chance
    best = min(points, key=lambda sc: float(np.median(whitened_norm2(ctx.train, sc.train_zeta_rad))))
    found: dict[str, list] = {}
    ratio_max: dict[str, float] = {}
    for what, table, attr in (("log", ctx.train, "train_zeta_rad"), ("test log", ctx.test, "heldout_zeta_rad")):
        log, idx = logs[what], kept[what]
        if table is None or log is None or idx is None:
            continue
        zeta = (left_out_residuals(table, best.train_zeta_rad, best.fit.jac_x, best.fit.free, best.fit.n_obs)
                if what == "log" else best.heldout_zeta_rad)
        bad, ratio = gross_rows(table, zeta, getattr(baseline, attr))
        found[what] = [{"log": what, "sample": int(log.sample[idx[i]]), "cycle": int(log.cycle[idx[i]]),
                        "reason": "gross_residual", "outlier_ratio": float(ratio[i]), "row": int(idx[i])} for i in bad]
        ratio_max[what] = float(np.max(ratio)) if ratio.size else 0.0
    return found, ratio_max


def _fit_singles(ctx: _Context, rig: Rig, names, ranges, workers: int,
                 tick) -> tuple[dict, dict, dict, dict[str, tuple[dict, FitResult]]]:
    """Every single candidate fitted and scored: ``(scores, failures, variant options, point fits)`` by name.

    The point fits ``(options, fit)`` are the scores' own, and a settled single's loading-path variant's (what
    the pair screen predicts from, :func:`~csjm_opt.diagnose.fitting.model_fits.screened_pair`).
    """
    singles: dict[str, CandidateScore] = {}
    failed: dict[str, str] = {}
    options: dict[str, dict] = {}
    point: dict[str, tuple[dict, FitResult]] = {}
    done = map_ordered(fit_single, (ctx, rig, ranges), names, workers, tick, fit_cost)
    for name, (opt, sc, error, path) in zip(names, done):
        if sc is None:                                          # reported, not fatal
            failed[name] = str(error)
        else:
            options[name], singles[name] = opt, sc
            point[name] = (opt, sc.fit) if path is None else path
    return singles, failed, options, point


def _noise_floor(ctx: _Context, baseline: CandidateScore, singles: Mapping[str, CandidateScore]) -> float:
    """The noise floor (rad): the smallest of the estimates (a misfit, e.g. friction hysteresis, only inflates one).

    Sets the context's noise scale, the one every model's evidence is taken at.
    """
    # (not a set-valued model's: its scale is the largest the held-out rows allow, for its own score only)
    floor0 = min([ctx.noise_floor(baseline)] + [ctx.scale(sc) * baseline.instrument_floor_rad
                                                for sc in singles.values() if sc.heldout_density is None])
    ctx.sigma = floor0 / baseline.instrument_floor_rad
    return floor0


def _test_singles(ctx: _Context, baseline: CandidateScore, singles: Mapping[str, CandidateScore],
                  floor0: float) -> dict[str, dict]:
    """Each single against the null model (rules 1, 2 and 4 of the guide): its test entry by name."""
    m = max(len(singles), 1)
    tests = {n: ctx.compare(baseline, sc, ALPHA / m, floor0) for n, sc in singles.items()}
    for n, sc in singles.items():
        tests[n]["log_evidence"] = ctx.evidence(sc)
        tests[n]["closes_gap"] = ctx.closes(sc)
        tests[n]["residual_signature_p"] = ctx.signature(sc)["p_value"]
    return tests


def flexible(sc: CandidateScore, n_cycles: int) -> bool:
    """Whether a model has more effective parameters than ``SHORT_LOG_SHARE`` of the log's cycle-level offsets.

    Such a model (36 hole offsets) can follow almost any smooth pose error of a short log.

    Parameters
    ----------
    sc : CandidateScore
    n_cycles : int
        Held-out cycles of the log.

    Returns
    -------
    bool
    """
    return bool(sc.fit.p_eff > SHORT_LOG_SHARE * 3 * n_cycles)


def parsimonious(scores: Mapping[str, CandidateScore], evidence: Mapping[str, float], n_cycles: int) -> str:
    """The model to name among ``scores`` (each plausible and closing the gap): parsimony that holds.

    The highest evidence wins, unless it is *flexible* (:func:`flexible`) and a model that is not
    explains the log as well: the flexible one does not beat it on held-out cycles (one-sided paired
    test at ``HELDOUT_ALPHA``), nor, for a set-valued model (settled friction), by a decisive Bayes
    factor (``EVIDENCE_MIN`` nats). A 36-number hole-offset fit then never beats a few-number effect or
    pair that explains the log as well; among those, the highest evidence.

    Parameters
    ----------
    scores : mapping
        Model name -> score (non-empty).
    evidence : mapping
        Model name -> log evidence.
    n_cycles : int

    Returns
    -------
    str
    """
    best = max(scores, key=lambda n: evidence[n])
    if not flexible(scores[best], n_cycles):
        return best
    # a set-valued model (settled friction) is a stick set that can hold almost any pose: its held-out rows
    # alone cannot rule it out, so it explains the log as well only if it is not decisively less probable
    # either (the flexible model's evidence has paid its Occam factor)
    simple = [n for n, sc in scores.items() if not flexible(sc, n_cycles)
              and paired_heldout_test(sc, scores[best]) >= HELDOUT_ALPHA
              and (getattr(sc, "heldout_density", None) is None or evidence[n] >= evidence[best] - EVIDENCE_MIN)]
    return max(simple, key=lambda n: evidence[n]) if simple else best


def _first_effect(singles, tests, detected: list[str], n_cycles: int) -> str | None:
    """The first effect (rule 3): among the detected plausible singles that close the gap, the parsimonious one."""
    plausible = [n for n in detected if tests[n]["plausible"]]
    closers = [n for n in plausible if tests[n]["closes_gap"]]
    if not plausible:
        key = heldout_key(singles[n] for n in detected)
        return min(detected, key=lambda n: key(singles[n])) if detected else None
    pool = closers or plausible
    return parsimonious({n: singles[n] for n in pool}, {n: tests[n]["log_evidence"] for n in pool}, n_cycles)


def _noise_estimates(ctx: _Context, final: CandidateScore, baseline: CandidateScore, singles) -> dict:
    """The noise floor's parts (``noise_floor_estimates`` of the JSON)."""
    scale = ctx.scale(final)
    return {"within_cycle_rad": ctx.local, "within_cycle_dof": ctx.local_dof,
            "selected_fit_rad": float(np.sqrt(final.noise_ratio2)) * ctx.instrument,
            "instrument_model_rad": ctx.instrument, "noise_scale": scale,
            "per_model_rad": {n: scale * c.instrument_floor_rad for n, c in
                              [("nominal_refit", baseline), *singles.items()]}}


def _confounded(singles, detected: list[str], pairs: list[dict], selected: str) -> list[str]:
    """Detected singles the log cannot tell from the selected one: not separable, not worse on held-out cycles."""
    out = []
    if selected in singles:
        for n in detected:
            sep = next((p for p in pairs if set(p["effects"]) == {n, selected}), None)
            if n != selected and paired_heldout_test(singles[n], singles[selected]) >= HELDOUT_ALPHA \
                    and (sep is None or not sep["separable"]):
                out.append(n)
    return out


def _steps(baseline, singles, verdict: Verdict, first: str | None) -> list[dict]:
    """The greedy path: null model, the lead single, the pair (``fraction_explained`` added by the caller)."""
    steps = [{"model": "nominal_refit", "heldout_rms_rad": baseline.heldout_rms_rad}]
    lead = verdict.selected if verdict.selected in singles else first
    if lead is not None:
        steps.append({"model": lead, "heldout_rms_rad": singles[lead].heldout_rms_rad})
    if verdict.secondary.effect != "none":
        steps.append({"model": f"{lead}+{verdict.secondary.effect}", "heldout_rms_rad": verdict.final.heldout_rms_rad})
    return steps


def _rule(m: int) -> dict:
    """The decision rule's constants and tests (``significance`` of the JSON)."""
    return {"alpha": ALPHA, "per_candidate_alpha": ALPHA / max(m, 1), "improve_mult": IMPROVE_MULT,
            "close_fraction": CLOSE_FRACTION,
            "test": "one-sided paired t-test of per-cycle held-out MSE against nominal_refit (Bonferroni over "
                    "candidates) and systematic improvement sqrt(MSE_null - MSE) >= improve_mult noise floors"}


def _rival_warnings(ctx: _Context, verdict: Verdict, singles, tests, detected, pairs, pair_scores,
                    n_cycles: int, remaining: dict) -> None:
    """The warnings of a named verdict: every model the log does not rule out, named (guide, rule 5)."""
    final, selected = verdict.final, verdict.selected
    named = set(final.name.split("+"))
    ev_final = ctx.evidence(final)
    # rivals: other plausible explanations of the gap (a pair that only adds to the named model is none)
    rivals = {n: ctx.evidence(sc) for n, sc in singles.items() if sc is not final and tests[n]["plausible"]
              and tests[n]["closes_gap"] and n not in named}
    rivals.update({"+".join(k): ctx.evidence(sc) for k, sc in pair_scores.items() if sc is not final
                   and not named <= set(k)
                   and next((p["plausible"] and p["closes_gap"] for p in pairs if tuple(p["effects"]) == k), False)})
    verdict.evidence_margin = float(ev_final - max(rivals.values(), default=-np.inf))
    if not verdict.named:
        return
    # a plausible model that closes the gap and is more probable under the priors, not confirmed on held-out
    # cycles: the verdict is the held-out test's pick, not the only reading of the log
    verdict.more_probable_rivals = sorted((n for n, e in rivals.items() if e > ev_final), key=lambda n: -rivals[n])
    if verdict.more_probable_rivals:
        best = verdict.more_probable_rivals[0]
        verdict.warn(f"{best} also closes the gap and has higher evidence ({rivals[best] - ev_final:.1f} nats) "
                     f"than {final.name}, but did not beat it on held-out cycles: the log does not decide between them")
    if flexible(final, n_cycles):
        _look_alike_warning(ctx, verdict, singles, tests, pairs, pair_scores, n_cycles)
        _stand_in_warning(ctx, verdict, singles, pairs, pair_scores)
    if remaining["significant"] and remaining["systematic_rad"] >= MATERIAL_SHARE * ctx.floor(final):
        verdict.warn(f"the residual left by {final.name} still holds structure within cycles (signature test p = "
                     f"{remaining['p_value']:.1e}): the named effect may be a stand-in for one outside the vocabulary; "
                     "see localisation for where the residual lies")
    # rivals the log cannot tell from the selected: detected, not separable, and not ruled out (rivals.py)
    found = _look_alikes(ctx, verdict, singles, tests, detected, pairs, n_cycles)
    verdict.alternatives = [a["model"] for a in found]
    for text in alternatives_warnings(selected, found):
        verdict.warn(text)
    second = verdict.secondary.effect
    verdict.secondary_alternatives = secondary_alternatives(ctx, pairs, pair_scores, final, selected, second)
    if verdict.secondary_alternatives:
        verdict.warn(f"the second effect {second} is not separable on this log from "
                     f"{', '.join(verdict.secondary_alternatives)}: {selected} with either closes the gap "
                     f"(evidence within {LEAD_NATS:g} nats, Fisher block correlation above the separability limit)")
    # every other model the log does not rule out is named (rivals.py); those warned about above are not repeated
    verdict.unsettled_rivals = unsettled_rivals(
        scored_models(ctx.evidence, singles, tests, pairs, pair_scores, noise_scale=ctx.sigma), final.name,
        [*verdict.more_probable_rivals, *verdict.alternatives, *verdict.look_alikes,
         *(f"{selected}+{c}" for c in verdict.secondary_alternatives)])
    for r in verdict.unsettled_rivals:
        verdict.warn(rival_warning(final.name, r))


def _look_alikes(ctx: _Context, verdict: Verdict, singles, tests, detected, pairs, n_cycles: int) -> list[dict]:
    """The detected singles the log cannot tell from the selected one (:func:`.rivals.inseparable_alternatives`)."""
    selected = verdict.selected
    if selected not in singles:
        return []
    s2 = float(ctx.sigma) ** 2

    def entry(n: str) -> dict:
        sep = next((p for p in pairs if set(p["effects"]) == {n, selected}), None)
        return {"detected": n in detected, "plausible": bool(tests[n]["plausible"]),
                "closes_gap": bool(tests[n]["closes_gap"]), "separable": sep is None or bool(sep["separable"]),
                "log_evidence": tests[n]["log_evidence"], "chi2": singles[n].fit.rss / s2,
                "cycle_mse": singles[n].cycle_mse(), "cycle_nll": singles[n].cycle_nll(),
                "set_scale": singles[n].set_scale, "flexible": flexible(singles[n], n_cycles)}

    models = {n: entry(n) for n in [selected, *(n for n in detected if n != selected)]}
    return inseparable_alternatives(models, selected, single_verdict=verdict.final is singles[selected])


def _look_alike_warning(ctx: _Context, verdict: Verdict, singles, tests, pairs, pair_scores, n_cycles: int) -> None:
    """A flexible verdict names the few-number models it does not rule out (and warns only then).

    A few-number model (single or pair, not :func:`flexible`) that is plausible, closes the gap or comes
    within ``LOOK_ALIKE_SHARE`` of it, and that the flexible verdict does not beat on held-out cycles
    (paired test at ``HELDOUT_ALPHA``) explains the log as well with far fewer numbers; a set-valued one
    (settled friction) only if it is not decisively less probable either (as in :func:`parsimonious`).
    """
    final = verdict.final
    models: dict[str, tuple[CandidateScore, bool]] = {
        n: (sc, bool(tests[n]["plausible"])) for n, sc in singles.items()}
    for p in pairs:
        k = tuple(p["effects"])
        if p.get("fitted") and k in pair_scores:
            models["+".join(k)] = (pair_scores[k], bool(p.get("plausible")))
    look = []
    ev_final = ctx.evidence(final)
    for name, (sc, ok) in models.items():
        if sc is final or not ok or flexible(sc, n_cycles) or ctx.fraction(sc) < LOOK_ALIKE_SHARE * CLOSE_FRACTION:
            continue
        if sc.heldout_density is not None and ctx.evidence(sc) < ev_final - EVIDENCE_MIN:
            continue                # a stick set decisively less probable: held-out rows alone do not make it a rival
        p = paired_heldout_test(sc, final)
        if p >= HELDOUT_ALPHA:
            look.append((name, p))
    if not look:
        return
    look.sort(key=lambda t: -ctx.evidence(models[t[0]][0]))
    verdict.look_alikes = [n for n, _ in look]
    names = ", ".join(f"{n} (held-out p = {p:.2f})" for n, p in look[:3])
    verdict.warn(f"{final.name} has {final.fit.p_eff:.0f} effective parameters against {3 * n_cycles} cycle-level "
                 f"pose offsets in this log ({n_cycles} cycles), and {names} explain the log about as well with a "
                 f"few numbers ({final.name} does not beat them on held-out cycles): the log does not single out "
                 f"{final.name}; --suggest designs rows that separate them")


def stand_ins(ctx: _Context, final: CandidateScore, selected: str, pairs, pair_scores) -> list[tuple[str, float]]:
    """Effects a flexible single verdict may be standing in for: ``(effect, z)``, the largest z first.

    ``X`` qualifies when the pair ``selected + X`` is fitted, plausible and closes the gap; the log cannot
    tell ``X`` from ``selected`` (not separable: the flexible effect can mimic it); the pair is not
    decisively less probable (evidence within ``EVIDENCE_MIN`` nats) and the verdict does not beat it on
    held-out cycles; and, in the pair, ``X``'s parameters are away from their nominal values by more than
    ``PLAUSIBLE_Z`` standard errors as a block (Wald test at that level with the pair's own covariance, the
    flexible effect's prior included; ``z = sqrt(Wald statistic)``): the
    log then carries ``X`` as well as the flexible effect's version of it. On a log of the flexible effect
    alone ``X`` fits to within its errors of nominal, and nothing is named.
    """
    ev = ctx.evidence(final)
    out = []
    for p in pairs:
        k = tuple(p["effects"])
        if (not p.get("fitted") or selected not in k or k not in pair_scores or p.get("separable", True)
                or not (p.get("plausible") and p.get("closes_gap"))):
            continue
        sc = pair_scores[k]
        if ctx.evidence(sc) < ev - EVIDENCE_MIN or paired_heldout_test(sc, final) < HELDOUT_ALPHA:
            continue
        other = k[1] if k[0] == selected else k[0]
        j = k.index(other)
        model = sc.fit.model
        start = N_NUISANCE + sum(e.n_params for e in model.effects[:j])
        idx = np.arange(start, start + model.effects[j].n_params)
        delta = sc.fit.theta[idx] - model.effects[j].x0()
        C = sc.fit.cov[np.ix_(idx, idx)]
        if not np.all(np.isfinite(C)) or not np.any(C):
            continue
        rank = int(np.linalg.matrix_rank(C, hermitian=True))
        wald = float(delta @ np.linalg.pinv(C, hermitian=True) @ delta) if rank else 0.0
        # the block's Wald statistic against its chi^2 at the PLAUSIBLE_Z two-sided level (95 % for z = 2)
        if rank and chi2_sf(wald, rank) < 2.0 * norm_sf(PLAUSIBLE_Z):
            out.append((other, float(np.sqrt(wald))))
    return sorted(out, key=lambda t: -t[1])


def _stand_in_warning(ctx: _Context, verdict: Verdict, singles, pairs, pair_scores) -> None:
    """A flexible single verdict names the effects it may be standing in for (:func:`stand_ins`)."""
    if verdict.selected not in singles or verdict.secondary.effect != "none":
        return
    named = set(verdict.look_alikes) | set(verdict.alternatives)
    found = [(x, z) for x, z in stand_ins(ctx, verdict.final, verdict.selected, pairs, pair_scores) if x not in named]
    if not found:
        return
    verdict.stand_ins = [x for x, _ in found]
    sel = verdict.selected
    listed = ", ".join(f"{x} (its parameters away from nominal in {sel}+{x}: Wald z = {z:.1f})" for x, z in found[:3])
    verdict.warn(f"{sel} can stand in for {listed} on this log (not separable from {sel}; the pair is as probable "
                 f"and {sel} alone does not beat it on held-out cycles): these may be present too; --suggest "
                 "designs rows that separate them")


def _time_trend_warning(ctx: _Context, verdict: Verdict) -> None:
    """Warn when the final model's training residual trends with the log's time order (creep, a drifting bias)."""
    final = verdict.final
    trend = time_trend(final.train_zeta_rad, ctx.train.cycle, ctx.floor(final), ALPHA, MATERIAL_SHARE)
    verdict.time_trend = trend
    if trend["trends"] and verdict.selected != "none":
        verdict.warn(f"the residual of {final.name} trends with time (sample order): its cycle means move by "
                     f"{1e3 * max(abs(c) for c in trend['change_rad']):.2f} mrad over {trend['cycles']} cycles "
                     f"(p = {trend['p_value']:.1e}); a time-dependent fault (cable creep, a drifting sensor bias) "
                     "is outside the vocabulary")


def _trend_probe_warning(ctx: _Context, rig: Rig, verdict: Verdict, baseline: CandidateScore, floor0: float,
                         workers: int = 1) -> None:
    """Warn when a fault that builds up over each cycle, outside the vocabulary, explains the log as well.

    Two probes: linear cable creep (:class:`~csjm_opt.diagnose.effects.cable_creep.CableCreep`, a share of
    every tension, row after row) and drum slip (:class:`~csjm_opt.diagnose.effects.drum_slip.DrumSlip`, the
    excess over a threshold). Each is fitted like a single and judged as a rival that replaces the verdict
    (:mod:`.rivals`): detected against the null model, plausible, closing the gap, and either more probable
    than the verdict or within ``EVIDENCE_MIN`` nats of it while the verdict does not beat it on held-out
    cycles. Each that qualifies is recorded (``verdict.creep``, ``verdict.drum_slip``); the more probable one
    is named in the warning that the residual trends with time (sample order within each cycle) in a way the
    verdict only stands in for. With ``none`` nothing is named, and nothing is said.
    """
    if verdict.selected == "none":
        return
    found = []
    probes = (CableCreep(n_cables_of(rig)), DrumSlip(n_cables_of(rig), rig.t_max_N))
    for probe, sc in zip(probes, map_ordered(score_effect, (ctx,), probes, workers)):
        if sc is None:
            continue
        t = ctx.compare(baseline, sc, ALPHA, floor0)
        if not (t["significant"] and t["plausible"] and ctx.closes(sc)):
            continue
        nats = ctx.evidence(sc) - ctx.evidence(verdict.final)
        p = paired_heldout_test(sc, verdict.final)           # one-sided: the verdict's held-out errors are lower
        if verdict.selected != "unexplained" and not (nats > 0.0 or (nats > -EVIDENCE_MIN and p >= HELDOUT_ALPHA)):
            continue
        record = {"heldout_rms_rad": sc.heldout_rms_rad, "nats": nats, "heldout_p": p}
        params = probe.describe(sc.fit.theta[N_NUISANCE:])
        if isinstance(probe, CableCreep):
            verdict.creep = record = {**record, "percent_per_row": params["creep_percent_per_row"]}
            what = f"linear cable creep (tension lost {record['percent_per_row']:.2g} % per row)"
        else:
            verdict.drum_slip = record = {**record, **params}
            what = (f"cables slipping on their drums above {record['slip_threshold_N']:.0f} N "
                    f"({record['slip_percent_of_excess']:.2g} % of the excess a row)")
        found.append((nats, what, sc, p))
    if not found:
        return
    nats, what, sc, p = max(found, key=lambda f: f[0])
    name = verdict.model_name
    who = (f"{name} may be standing in for" if verdict.selected != "unexplained" else "the unexplained gap may be")
    verdict.warn(f"the log trends with time (sample order within each cycle): {what}, outside the vocabulary, "
                 f"explains it with held-out RMS {1e3 * sc.heldout_rms_rad:.2f} mrad and {nats:+.1f} nats of "
                 f"evidence against {name} (held-out p = {p:.2f}): {who} a fault that builds up over each cycle "
                 "(creep, a slipping drive); rows repeated at one constant load separate them (creep keeps moving "
                 "the pose, friction holds it), and so do cycles that return to a light load (slip keeps the "
                 "lengthened cable, friction gives the pose back)")


def _pairs(ctx: _Context, rig: Rig, names, singles, seeds, secondary, ranges, tick, planned: int,
           masked_base: CandidateScore | None, first: str | None, options: dict,
           point_fits: dict[str, tuple[dict, FitResult]], workers: int = 1,
           n_cycles: int | None = None) -> tuple[list, dict]:
    """Every pair's separability; each seed + each other effect fitted and tested (rule 3 / rule 6).

    ``point_fits``: each single's point fit and its options (:func:`_fit_singles`), what the pair screen predicts
    from.

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
    # a settled lead's noise scale (set-valued models are compared at one scale: its pairs are scored at it)
    lead = singles.get(first) if first is not None else None
    stick = {first: lead.heldout_density[2]} if lead is not None and lead.heldout_density is not None else {}
    # beside a settled lead, every other settled single (joint friction beside cable friction) pairs as a stick set
    # too, at the lead's noise scale: the rig that came to rest by its own dynamics left that friction in its band
    # as well, and its pairs are then compared with the lead's on one footing (as a loading path beside the lead's
    # stick pairs, joint friction + link compliance explained 58 % of the gap its stick single explained 84 % of)
    stick.update({n: stick[first] for n, sc in singles.items() if stick and sc.heldout_density is not None})
    # a pair whose evidence, predicted from its singles' fits, lies far below every model a verdict can be
    # measured against is not fitted (:data:`~..fitting.model_fits.SCREEN_NATS`; the Bonferroni level above still
    # counts it): the best single, the first effect (a verdict picked on held-out cycles can be far less probable
    # than the best single, and its rivals are read against it), and the null model when no single leads
    screen = None
    if singles:
        anchors = [max(ctx.evidence(sc) for sc in singles.values())]
        anchors += [ctx.evidence(sc) for sc in (lead, masked_base) if sc is not None]
        screen = ({n: f for n, (_, f) in point_fits.items()}, min(anchors) - SCREEN_NATS,
                  {n: o for n, (o, _) in point_fits.items()})
    done = map_ordered(screened_pair, (ctx, rig, ranges, options, stick, screen), todo, workers, tick, fit_cost)
    for (a, b), (sc, error, predicted) in zip(todo, done):
        entry = next(p for p in pairs if set(p["effects"]) == {a, b})
        entry["predicted_log_evidence"] = predicted
        if sc is None:
            if error is not None:
                entry["error"] = str(error)
            continue
        scores[(a, b)] = sc
        # a few-number pair is tested against its own singles, not against a flexible first effect (36 hole
        # offsets) that can stand in for it; the flexible one must then not beat it on held-out cycles. Likewise
        # a pair without a set-valued first effect (settled friction): a stick set holds almost any held-out pose
        # of a log without friction (on a step-loaded log of cable hardening + tracker registration, settled
        # friction's held-out error was the true pair's, 674 nats less probable), so the pair must then also be
        # decisively more probable than it
        flex = (first is not None and n_cycles is not None and flexible(singles[first], n_cycles)
                and not flexible(sc, n_cycles) and first not in (a, b))
        set_first = first in stick and first not in (a, b)
        left = flex or set_first
        rivals = [singles[a], singles[b]] + ([singles[first]] if first is not None and not left else [])
        base = masked_base or min(rivals, key=heldout_key(rivals))
        t = ctx.compare(base, sc, level, ctx.noise_floor(base))
        ev = ctx.evidence(sc)
        gain = ev - max(ctx.evidence(c) for c in ([masked_base] if masked_base is not None else rivals))
        left_out = (ev - ctx.evidence(singles[first]), paired_heldout_test(sc, singles[first])) if left else None
        t["significant"], by_evidence = pair_confirmed(bool(t["significant"]), gain, t["p_value"],
                                                       t["improvement_rad"], left_out, set_valued=set_first)
        entry.update({"fitted": True, "effects": [a, b], "heldout_rms_rad": sc.heldout_rms_rad,
                      "fraction_explained": ctx.fraction(sc), "bic": sc.fit.bic, "closes_gap": ctx.closes(sc),
                      "log_evidence": ev, "evidence_gain": gain, "supported_by_evidence": by_evidence,
                      "tested_against": base.name, "p_value_vs_first": t["p_value"],
                      "significant_heldout": t["significant"],
                      **{k: t[k] for k in ("improvement_rad", "plausible", "implausible_params")},
                      "significant": bool(t["significant"] or by_evidence)})
    return pairs, scores


def pair_confirmed(heldout: bool, gain: float, p_value: float, improvement_rad: float,
                   flexible_first: tuple[float, float] | None = None, set_valued: bool = False) -> tuple[bool, bool]:
    """Whether a fitted pair is detected: ``(by the held-out route, by the evidence route)``.

    The held-out route is ``heldout`` (the pair beat its baseline at the pairs' level by at least a
    floor, :meth:`~csjm_opt.diagnose.decision_rule._Context.compare`). The evidence route (rule 3b) asks
    a decisive Bayes factor over every rival (``gain >= EVIDENCE_MIN``) confirmed on held-out cycles
    (``p_value < HELDOUT_ALPHA`` and a positive improvement). When a flexible first effect was left out
    of a few-number pair's rivals (parsimony), ``flexible_first = (pair's evidence minus the flexible
    one's, one-sided p that the flexible one's held-out errors are lower)``: the flexible one must not beat
    the pair on held-out cycles (else neither route holds), and, for the evidence route, must not be
    decisively more probable than the pair (``EVIDENCE_MIN``), or the route's decisive Bayes factor over
    the pair's rivals would not hold. (On the 8-cable rig, drive offsets + joint friction replaced hole
    offsets at 3x the floor 6.8 nats more probable: the joint friction stood in for the hole offsets'
    directions outside the drive offsets' span.) A set-valued first effect left out (``set_valued``: settled
    friction, a stick set that holds almost any held-out pose) is treated as a flexible one, and the pair must
    moreover be decisively more probable than it (``nats >= EVIDENCE_MIN``) by either route.

    Parameters
    ----------
    heldout : bool
    gain : float
        The pair's log evidence minus the largest of its rivals' (nats).
    p_value : float
        One-sided p that the pair's held-out errors are lower than its baseline's.
    improvement_rad : float
    flexible_first : tuple of float, optional
    set_valued : bool, optional
        The left-out first effect is set-valued.

    Returns
    -------
    (bool, bool)
    """
    by_evidence = bool(gain >= EVIDENCE_MIN and p_value < HELDOUT_ALPHA and improvement_rad > 0)
    if flexible_first is not None:
        nats, p_flexible_better = flexible_first
        if p_flexible_better < HELDOUT_ALPHA:                 # the flexible first does better on held-out cycles
            return False, False
        if set_valued and nats < EVIDENCE_MIN:                # held-out rows cannot rule a stick set out
            return False, False
        by_evidence = by_evidence and nats >= -EVIDENCE_MIN
    return bool(heldout), by_evidence


def _variant(ctx: _Context, rig: Rig, name: str, ranges, partners: Sequence = ()) -> dict:
    """The variant of ``name`` with the highest evidence, ``partners`` after it (:func:`.model_fits.variant_fit`)."""
    return variant_fit(ctx, rig, name, ranges, after=partners)[0]


def _n_pair_fits(n_seeds: int, n: int) -> int:
    """Pairs fitted from ``n_seeds`` seeds among ``n`` effects (each seed with every other, once)."""
    return n_seeds * (n - 1) - n_seeds * (n_seeds - 1) // 2


def _second(ctx: _Context, singles, first: str, best: dict, sc: CandidateScore) -> Secondary:
    """The ``secondary`` of a pair verdict."""
    return Secondary(best["effects"][1], sc.heldout_rms_rad,
                     {k: v for k, v in sc.fit.params().items() if k not in singles[first].fit.params()},
                     ctx.fraction(sc), best["p_value_vs_first"],
                     **{k: best[k] for k in ("improvement_rad", "separable", "max_correlation", "plausible",
                                             "implausible_params")})


def _verdict(ctx: _Context, baseline, singles, tests, first, pairs, pair_scores, gap_there,
             n_cycles: int) -> Verdict:
    """The verdict by rules 5 and 6 of the guide (warnings about rivals are added afterwards)."""
    ok = [p for p in pairs if p.get("fitted") and p["significant"] and p["plausible"] and p["closes_gap"]]
    if ok:                                         # a pair (rule 5), or a masked pair (rule 6)
        by_name = {"+".join(p["effects"]): p for p in ok}
        name = parsimonious({n: pair_scores[tuple(p["effects"])] for n, p in by_name.items()},
                            {n: p["log_evidence"] for n, p in by_name.items()}, n_cycles)
        best = by_name[name]
        a, b = best["effects"]
        sc = pair_scores[(a, b)]
        reason = (f"{a} and {b} together close the gap on held-out cycles" if first is not None else
                  f"neither alone, but {a} and {b} together close the gap on held-out cycles (each hides the other)")
        v = Verdict(a, reason, sc, _second(ctx, singles, a, best, sc))
        if not best["separable"]:
            v.warn(f"{a} and {b} are not separable on this log "
                   f"(Fisher block correlation {best['max_correlation']:.3f})")
        return v
    if first is None:
        if gap_there:
            return Verdict("unexplained", "the nominal model's held-out residual holds significant structure but no "
                           "candidate improves on it significantly; see localisation for where it lies", baseline)
        return Verdict("none", "no candidate improves significantly on held-out cycles", baseline)
    t1 = tests[first]
    warnings = []
    if not t1["plausible"]:
        warnings.append(f"{first} needs implausible parameters: {', '.join(t1['implausible_params'])}")
    if t1["plausible"] and t1["closes_gap"]:
        return Verdict(first, f"{first} closes the gap on held-out cycles", singles[first], warnings=warnings)
    tried = [p for p in pairs if p.get("fitted") and p["significant"] and p["plausible"]]
    if tried:
        near = max(tried, key=lambda p: p["fraction_explained"])
        warnings.append(f"best pair {'+'.join(near['effects'])} leaves "
                        f"{1 - near['fraction_explained']:.0%} of the systematic gap")
    warnings.append(f"best single {first} leaves {1 - ctx.fraction(singles[first]):.0%} of the systematic gap")
    return Verdict("unexplained", "no plausible single effect or pair brings the held-out gap near the noise floor; "
                   "see localisation for where the residual lies", baseline, warnings=warnings)
