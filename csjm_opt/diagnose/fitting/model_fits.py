"""The fits of one diagnosis: a single candidate or a pair, its variant chosen, then scored.

An effect with variants (friction's law and memory, :data:`VARIANTS`) is fitted in every variant
on the model it belongs to; the variant with the highest evidence is kept, and its fit is the
first fit of the score (:func:`csjm_opt.diagnose.selection.scoring.score` with ``fit=``): fitting it again
would give the same numbers. Each function is one task of :func:`csjm_opt.diagnose.fitting.pool.map_ordered`
(module level, results that pickle).
"""

from __future__ import annotations

import dataclasses
from typing import Mapping, Sequence

import numpy as np
from scipy.special import logsumexp

from ...errors import CsjmError
from ...model.rig import Rig
from ..decision_rule import _Context
from ..effects import make_effect
from ..selection.scoring import CandidateScore, heldout_key, score
from .augmented import N_NUISANCE, AugmentedModel
from .evidence import log_evidence, predicted_evidence
from .friction_stick import settled_score
from .gauss_newton import FitResult, fit_model

#: Variants of an effect the data choose between: the highest Laplace evidence of the training fit wins, at one
#: noise scale for all (the best fit, unless it needs implausible parameters; a variant with more parameters,
#: the sensor gain per axis against the common one, pays their Occam factor).
VARIANTS: dict[str, list[dict]] = {"friction": [{"law": law, "memory": mem} for law in ("capstan", "coulomb")
                                                for mem in ("carried", "reset")],
                                   "sensor_gain": [{"axes": "common"}, {"axes": "per_axis"}]}
#: Failures of one model's fit that a diagnosis reports instead of stopping.
FIT_ERRORS = (np.linalg.LinAlgError, CsjmError, FloatingPointError)


def variant_fit(ctx: _Context, rig: Rig, name: str, ranges, before: Sequence = (),
                after: Sequence = ()) -> tuple[dict, FitResult | None, float]:
    """The variant of ``name`` with the highest evidence on the training rows, its fit, and its log weight.

    The noise scale is the best variant's (whitened RMS): the variants then differ by their fit and by
    what their priors say of the fitted parameters (a fit that needs a parameter far outside its range
    pays). ``before`` and ``after`` are the other effects of the model the variant is for (a pair's
    other effect), in the model's order: the variant is a discrete parameter of that model and is
    chosen with them fitted alongside.

    The variant being a parameter, each of the ``K`` equally likely a priori, the model's evidence is the mean of
    its variants' ``(Z_1 + ... + Z_K) / K``, not the best one's: the log weight
    ``log((Z_1 + ... + Z_K) / K) - log Z_best`` (between ``-log K`` and 0) is what the evidence of the chosen
    variant's fit must add (:attr:`~csjm_opt.diagnose.selection.scoring.CandidateScore.variant_log_weight`). Taken at
    the best one's noise scale. Without it a model with four variants was credited the best of four looks at
    the data: up to ``log 4`` nats over a model without variants that fits as well.

    Parameters
    ----------
    ctx : _Context
        The diagnosis's rows and folds.
    rig : Rig
        The nominal rig.
    name : str
        The effect whose variant is chosen.
    ranges : mapping or None
        Prior-range overrides.
    before, after : sequence of Effect, optional
        Effects before and after ``name`` in the model.

    Returns
    -------
    (dict, FitResult or None)
        The variant's options (``{}`` for an effect without variants) and the plain training fit of
        the model ``[*before, name(variant), *after]`` (None where there is no choice or every fit failed).
    """
    options = VARIANTS.get(name, [])
    if len(options) < 2:
        return (options[0] if options else {}), None, 0.0
    fits: list[FitResult | None] = []
    for opt in options:
        try:
            fits.append(fit_model(AugmentedModel(rig, [*before, make_effect(name, rig, ranges, **opt), *after]),
                                  ctx.train))
        except FIT_ERRORS:
            fits.append(None)
    ok = [f for f in fits if f is not None]
    if not ok:
        return options[0], None, 0.0
    scale = float(np.sqrt(max(min(f.rss for f in ok) / max(ok[0].n_obs, 1), 1e-12)))
    ev = np.array([-np.inf if f is None else log_evidence(f, scale) for f in fits])
    ev = np.where(np.isfinite(ev), ev, -np.inf)          # a failed fit or a nan evidence: no weight
    best = int(np.argmax(ev))
    weight = float(logsumexp(ev - ev[best]) - np.log(len(options))) if np.isfinite(ev[best]) else 0.0
    return options[best], fits[best], weight


#: The variants that need no loading path (:mod:`csjm_opt.diagnose.fitting.friction_stick`): the rest pose is any
#: static equilibrium with the friction forces (cable) or moment (joint) within their bounds.
SETTLED_VARIANTS: dict[str, dict] = {"friction": {"law": "coulomb", "memory": "settled"},
                                     "joint_friction": {"memory": "settled"}}
SETTLED = SETTLED_VARIANTS["friction"]
#: Noise scales tried for the stick model, as shares of the within-cycle estimate (which friction inflates).
SETTLED_SCALES = (0.25, 0.35, 0.5, 0.7, 1.0)


def fit_cost(names: str | Sequence[str]) -> float:
    """Expected cost of fitting the model of effect(s) ``names``, on a relative scale (to order the fits).

    One fit per variant, and an effect with a loading path (an effect with a settled variant) four times a
    point effect's: its state is carried along every row (on ``mujoco_a/paper_mass_com`` friction pairs took
    0.5-3 s, joint friction pairs 0.1-0.9 s, most other pairs under 0.1 s).
    """
    names = [names] if isinstance(names, str) else list(names)
    return float(sum(len(VARIANTS.get(n, [{}])) * (4 if n in SETTLED_VARIANTS else 1) for n in names))


def is_settled(name: str, options: Mapping) -> bool:
    """Whether ``options`` are the settled variant of effect ``name``."""
    return name in SETTLED_VARIANTS and dict(options) == SETTLED_VARIANTS[name]


#: The loading-path variant with a settled variant's parameters (the same law and units): the point model a stick
#: set came to rest along.
PATH_TWINS: dict[str, dict] = {"friction": {"law": "coulomb", "memory": "carried"},
                               "joint_friction": {"memory": "step"}}


def path_twin(effect, theta: np.ndarray, rig: Rig) -> tuple:
    """``(effect, theta)``, or for a settled (set-valued) effect its loading-path twin and the fit's parameters.

    A stick set has no point Jacobian (the pose is any point of the set: its parameters' columns are zero), so
    what needs one, the separability of two effects, takes the path model the set came to rest along: the
    same bounds (law, units, ranges), the twin's further parameters (the path's state) at their starting
    values. ``theta`` is a single's full parameter vector (nuisance first).
    """
    if not getattr(effect, "settled", False):
        return effect, theta
    twin = make_effect(effect.name, rig, effect.range_overrides, **PATH_TWINS[effect.name])
    extra = twin.x0()[effect.n_params:]
    return twin, np.concatenate([np.asarray(theta, float), extra])


def settled_scales(ctx: _Context) -> list[float] | None:
    """The noise scales a stick model is scored at (None without a within-cycle noise estimate)."""
    scale = ctx.local_scale[0]
    if not np.isfinite(scale) or scale <= 0:
        return None
    return [scale * f for f in SETTLED_SCALES]


def _settled(ctx: _Context, rig: Rig, ranges: Mapping | None, effects: Sequence,
             scales: Sequence[float] | None = None) -> CandidateScore | None:
    """A model with a settled effect (a stick condition per row) scored on the diagnosis's rows.

    ``scales``: the noise scales to choose from (default :func:`settled_scales`).
    """
    scales = settled_scales(ctx) if scales is None else list(scales)
    if scales is None:
        return None
    return settled_score(AugmentedModel(rig, list(effects)), ctx.train, ctx.test, ctx.folds, scales)


def _prefer_settled(ctx: _Context, settled: CandidateScore, path: CandidateScore) -> bool:
    """Whether the stick condition explains the log better than the path model.

    A model that closes the held-out gap (its held-out errors at its own floor) beats one that does not
    (selection rule 3): a path model is the more informative where the rig followed it (a slow ramp: it
    predicts a point, the stick condition only a set), and leaves a gap where the rig came to rest by its
    own dynamics. Between two models that both close or both fail, the lower held-out log score wins (each
    at its own noise scale: a stick set's squared errors at a small scale of its own flatter it).
    """
    a, b = ctx.closes(settled), ctx.closes(path)
    if a != b:
        return a and not b
    key = heldout_key([path, settled])
    return key(settled) < key(path)


def score_with(ctx: _Context, model: AugmentedModel, fit: FitResult | None = None,
               variant_log_weight: float = 0.0) -> CandidateScore:
    """``model`` scored on the diagnosis's rows and folds (``fit``: its plain training fit, if known).

    ``variant_log_weight``: what its variants' mixture adds to the evidence (:func:`variant_fit`).
    """
    sc = score(model, ctx.train, ctx.test, ctx.folds, fit, local=ctx.local_scale)
    return dataclasses.replace(sc, variant_log_weight=float(variant_log_weight)) if variant_log_weight else sc


def score_effect(ctx: _Context, effect) -> CandidateScore | None:
    """``effect`` alone scored on the diagnosis's rows (an instance, outside the vocabulary too); None if its fit fails.

    A task of :func:`~csjm_opt.diagnose.fitting.pool.map_ordered`: the trend probes run side by side.
    """
    try:
        return ctx.score([effect])
    except FIT_ERRORS:
        return None


def fit_single(ctx: _Context, rig: Rig, ranges: Mapping | None,
               name: str) -> tuple[dict, CandidateScore | None, str | None, tuple[dict, FitResult] | None]:
    """One candidate: ``(variant options, score, None, path)``, or ``({}, None, message, None)`` when its fit fails.

    ``path``: where the settled variant (a stick set) is preferred, the loading-path variant it was preferred
    over, ``(options, fit)`` (what a pair's point model starts from: the pair screen predicts from it), else None.

    Parameters
    ----------
    ctx : _Context
    rig : Rig
    ranges : mapping or None
    name : str

    Returns
    -------
    tuple
    """
    try:
        opt, fit, weight = variant_fit(ctx, rig, name, ranges)
        sc = score_with(ctx, AugmentedModel(rig, [make_effect(name, rig, ranges, **opt)]), fit, weight)
        if name in SETTLED_VARIANTS:      # the stick condition beside the path: the better held-out score
            settled = _settled(ctx, rig, ranges, [make_effect(name, rig, ranges, **SETTLED_VARIANTS[name])])
            if settled is not None and _prefer_settled(ctx, settled, sc):
                return SETTLED_VARIANTS[name], settled, None, (opt, sc.fit)
        return opt, sc, None, None
    except FIT_ERRORS as exc:
        return {}, None, f"fit failed: {exc}", None


def fit_pair(ctx: _Context, rig: Rig, ranges: Mapping | None, options: Mapping[str, dict],
             stick_scales: Mapping[str, float] | None,
             pair: tuple[str, str]) -> tuple[CandidateScore | None, str | None]:
    """Pair ``(a, b)`` scored, a variant chosen on the pair model: ``(score, None)`` or ``(None, message)``.

    ``options`` are the singles' variants (kept for an effect without variants in this pair). A pair with the
    lead single settled (the stick condition; ``stick_scales`` holds it) is scored at the noise scale that
    single's held-out rows chose: a set-valued model's held-out error is taken at its noise scale, and the
    pair is compared with its single at the same one; a partner with a settled variant joins as it. Without
    a settled lead, a settled single joins as its path variant (:func:`point_pair`).

    Parameters
    ----------
    ctx : _Context
    rig : Rig
    ranges : mapping or None
    options : mapping
    pair : (str, str)

    Returns
    -------
    tuple
    """
    a, b = pair
    try:
        known = [stick_scales[e] for e in (a, b) if stick_scales and e in stick_scales]
        if known:
            # the lead single is settled: the pair is the stick condition with the partner's parameters as point
            # parameters, at the lead's noise scale. A rig that came to rest by its own dynamics holds every
            # friction of it in its band at once: a partner with a settled variant (joint friction beside cable
            # friction) joins as it, never as a loading path inside a stick set (on a log of cable friction
            # alone, joint friction along its path then bought 15 nats as a second hysteresis)
            effects = [make_effect(e, rig, ranges, **SETTLED_VARIANTS.get(e, options.get(e, {}))) for e in (a, b)]
            sc = _settled(ctx, rig, ranges, effects, [max(known)])
            if sc is not None:
                return sc, None
        return score_with(ctx, *point_pair(ctx, rig, ranges, options, pair)), None
    except FIT_ERRORS as exc:
        return None, f"fit failed: {exc}"


def point_options(options: Mapping[str, dict]) -> dict[str, dict]:
    """``options`` with each settled variant replaced by the effect's path variant (a pair's point model)."""
    return {e: ({} if is_settled(e, o) else o) for e, o in options.items()}


def point_pair(ctx: _Context, rig: Rig, ranges: Mapping | None, options: Mapping[str, dict],
               pair: tuple[str, str]) -> tuple[AugmentedModel, FitResult | None, float]:
    """The point model of pair ``(a, b)`` (variants chosen on it), its plain training fit where known, its log weight.

    The log weight sums each chosen variant's (:func:`variant_fit`).

    A settled effect joins as its path variant: a stick set scored at a noise scale of its own would absorb
    the other effect's misfit at a price no point model pays. An effect's variant (friction's law and
    memory) is chosen on the pair's model: a single fit that had to absorb the partner effect may prefer
    another law than the pair does.
    """
    a, b = pair
    options = point_options(options)
    fit: FitResult | None = None
    weight = 0.0
    opt_a = options.get(a, {})
    if a in VARIANTS:
        opt_a, fit, w = variant_fit(ctx, rig, a, ranges, after=[make_effect(b, rig, ranges, **options.get(b, {}))])
        weight += w
    opt_b = options.get(b, {})
    if b in VARIANTS:
        opt_b, fit, w = variant_fit(ctx, rig, b, ranges, before=[make_effect(a, rig, ranges, **opt_a)])
        weight += w
    model = AugmentedModel(rig, [make_effect(a, rig, ranges, **opt_a), make_effect(b, rig, ranges, **opt_b)])
    return model, fit, weight


#: A pair whose evidence, predicted one Gauss-Newton step from its singles' fits
#: (:func:`predicted_pair_evidence`), is this many nats below both the best single's and the first effect's
#: is not fitted: no rule reads a model that far below the verdict (a pair is named, or a rival, within
#: ``LEAD_NATS``), and the margin stands for what the step misses. Measured on the 47 validation logs
#: (``studies/pair_screen``): every verdict, second effect and warning as with every pair fitted, and the
#: dropped pair nearest the verdict 54.6 nats below it.
SCREEN_NATS = 60.0


#: A loose prediction (:func:`predicted_pair_evidence`: an effect whose step from nominal values falls well short
#: of a fit, :attr:`~csjm_opt.diagnose.effects.base.Effect.step_from_nominal`) screens its pair only this many nats
#: below :data:`SCREEN_NATS`'s floor as well. Over the 47 validation logs with every pair fitted
#: (``studies/pair_screen``) a loose pair's fit reached at most 72 % of the gap between the step and the screen's
#: anchor; at 80 %, a pair 300 nats below it (60 + 240) would still lie 60 below after its fit.
LOOSE_SCREEN_NATS = 240.0
#: An own-fit prediction (:func:`pair_step`: a cable-friction pair, from the friction single's fit with the partner
#: stepped from nominal) screens its pair only this many nats below :data:`SCREEN_NATS`'s floor as well: the pair's
#: fit chooses its friction law and path afresh, and reaches far beyond the step. Over the 47 validation logs with
#: every pair fitted (``studies/pair_screen``), of the friction pairs fitted within 60 nats of the verdict or above
#: it, the step lay at most 535 nats below the screen's anchor (sensor gain + friction on ``oracle_hard/oov_creep``,
#: fitted 354 nats above the verdict): the margin, 2,060 below the anchor in all, is almost four times that. What it
#: drops lies thousands of nats below the verdict (friction with a compliance, guide or gain on a log of neither).
OWN_FIT_SCREEN_NATS = 2000.0
#: The screen's extra margin below its floor by :func:`pair_step` kind.
STEP_MARGIN_NATS = {"tight": 0.0, "loose": LOOSE_SCREEN_NATS, "own_fit": OWN_FIT_SCREEN_NATS}
#: :attr:`~csjm_opt.diagnose.effects.base.Effect.step_from_nominal` in order: a model's step is its worst effect's.
STEPS = ("tight", "loose", "none")


def model_step(effects: Sequence) -> str:
    """How well a model of ``effects`` (instances) is predicted from nominal values: its worst effect's step kind."""
    return max((e.step_from_nominal for e in effects), key=STEPS.index)


def pair_step(effects: Sequence) -> str:
    """How a pair of ``effects`` (instances) is predicted by :func:`predicted_pair_evidence`.

    ``"tight"`` or ``"loose"`` (:func:`model_step`) from either single's fit; ``"own_fit"`` where one effect's
    step from nominal sees almost nothing (cable friction, ``step_from_nominal = "none"``): only from that
    effect's own fit, on the path its fit followed, the partner stepped from nominal (screened with
    :data:`OWN_FIT_SCREEN_NATS`); ``"none"`` (no prediction) where both are such effects.
    """
    kinds = [e.step_from_nominal for e in effects]
    if "none" not in kinds:
        return model_step(effects)
    return "none" if all(k == "none" for k in kinds) else "own_fit"


def predicted_pair_evidence(ctx: _Context, rig: Rig, ranges: Mapping | None, options: Mapping[str, dict],
                            fits: Mapping[str, FitResult], pair: tuple[str, str]) -> tuple[float, str]:
    """The pair's log evidence predicted from each single's fit, the larger (nan: none), and its :func:`pair_step`.

    From the fit of one effect of the pair, the other at its nominal value, the pair model is linearised
    and its evidence taken (:func:`.evidence.predicted_evidence`, a score test): where a second effect
    would explain part of what the first leaves, the step finds it; where two effects hide each other
    (neither single detected), the step from either finds the pair's joint direction. No prediction from a
    settled single (a stick model's fit is not a point of the pair's path model). An effect whose step from
    nominal sees almost nothing (cable friction: from zero forces a pair's fit reached 2.3 times the gap the
    step left) is predicted only from its own fit, on the path that fit followed (``FitResult.rows``: where its
    state was scored), the partner stepped from nominal (:func:`pair_step`, ``"own_fit"``). *Loose* where an
    effect's fit reaches well beyond its step (link compliance, joint friction: :attr:`~csjm_opt.diagnose.
    effects.base.Effect.step_from_nominal`); each kind has its margin (:data:`STEP_MARGIN_NATS`). Each effect
    keeps its single's variant (the pair's fit chooses afresh: the margin covers the difference).
    """
    point = point_options(options)
    effects = [make_effect(e, rig, ranges, **point.get(e, {})) for e in pair]
    step = pair_step(effects)
    best = float("nan")
    if step == "none":
        return best, step
    model = AugmentedModel(rig, effects)
    own = step == "own_fit"
    for i, name in enumerate(pair):
        if own and effects[i].step_from_nominal != "none":
            continue                  # from the partner's fit, friction's bands at zero: the step sees nothing
        fit = fits.get(name)
        if fit is None or fit.evidence_fn is not None or is_settled(name, options.get(name, {})):
            continue
        parts = [effects[j].x0() for j in range(2)]
        if len(fit.theta) != N_NUISANCE + len(parts[i]):
            continue
        parts[i] = fit.theta[N_NUISANCE:]
        theta = np.concatenate([fit.theta[:N_NUISANCE], *parts])
        table = dataclasses.replace(ctx.train, rows=fit.rows) if own and fit.rows is not None else ctx.train
        try:
            ev = predicted_evidence(model, table, theta, ctx.sigma)
        except FIT_ERRORS:
            continue
        if np.isfinite(ev):
            best = ev if not np.isfinite(best) else max(best, ev)
    return best, step


def screened_pair(ctx: _Context, rig: Rig, ranges: Mapping | None, options: Mapping[str, dict],
                  stick_scales: Mapping[str, float] | None,
                  screen: tuple[Mapping[str, FitResult], float, Mapping[str, dict]] | None,
                  pair: tuple[str, str]) -> tuple[CandidateScore | None, str | None, float]:
    """:func:`fit_pair`, unless its predicted evidence is below ``screen``'s floor: ``(score, message, predicted)``.

    ``screen``: the singles' point fits, the evidence below which a pair is not scored, and the fits' variant
    options (a settled single's: its loading-path variant's, :func:`fit_single`) (None: every pair is scored). A
    pair with a settled lead (``stick_scales``) is always scored, and so is a pair without a prediction
    (:func:`predicted_pair_evidence`); a loose or own-fit prediction must lie :data:`STEP_MARGIN_NATS` further
    below the floor. ``predicted`` is nan where no prediction was made; a pair not scored returns
    ``(None, None, predicted)``.
    """
    predicted = float("nan")
    if screen is None or (stick_scales and any(e in stick_scales for e in pair)):
        return (*fit_pair(ctx, rig, ranges, options, stick_scales, pair), predicted)
    fits, floor, fit_options = screen
    step = "none"
    try:
        predicted, step = predicted_pair_evidence(ctx, rig, ranges, fit_options, fits, pair)
    except FIT_ERRORS:
        predicted = float("nan")
    if predicted < floor - STEP_MARGIN_NATS.get(step, np.inf):     # (nan: never below)
        return None, None, predicted
    return (*fit_pair(ctx, rig, ranges, options, stick_scales, pair), predicted)
