"""An epsilon-constraint front in the sweep's own metrics (workspace fraction, minimum stiffness).

``csjm sweep`` draws its Pareto front in (``workspace_fraction``,
``min_stiffness_Nm_per_rad``) on its own sample orientations. :func:`sweep_front`
traces the same front by optimisation, on the smooth twins ``F`` and ``S`` of
those metrics (:mod:`csjm_opt.design.optimisation.surrogates`), with exact
first and second derivatives, by a trust-region method on their quadratic
models (:mod:`csjm_opt.design.optimisation.front_model`):

1. the space-filling starts are evaluated (one evaluation each); from the two
   of largest ``F`` that lie apart, trust-region Newton steps on ``F`` reach
   their local maxima of the workspace (until the model promises less than
   :data:`~csjm_opt.design.optimisation.front_model.F_TOL`), and the larger one, ``F*``, is the first branch's anchor
   (the start of largest ``F`` may sit in the basin of a lower maximum); then
   the front's other end, the stiffest design, by the same steps on ``S``,
   raced like the first end: from the ``race`` designs of largest ``S``
   evaluated so far (starts and ascents) that lie apart, the largest of the
   maxima reached, every distinct one scored (with at most a third of the
   evaluations left): on a design space with mirror-image geometries it may
   lie on another branch, and it sets the spacing of the front's points;
2. predictor-corrector continuation down the front, one evaluation per point:
   from the models at the last front point, the next point is the model's
   solution of ``max S subject to F >= eps`` in the trust region, ``eps``
   chosen so that the point moves :data:`FRONT_STEP` along the front (in
   fractions of ``F*`` and ``S``); a point the twins do not confirm (``F``
   more than :data:`F_SLACK` short of ``eps``, or ``S`` not gained) shrinks
   the trust region and is not scored; the branch ends where the constraint
   is inactive inside the trust region (its stiffest design);
3. every confirmed point is scored by the sweep's evaluator
   (:func:`~csjm_opt.design.design_evaluation.evaluate_design`, one evaluation
   each): those are the reported numbers, and the front is the Pareto front of
   the scored designs.

Evaluations are counted honestly: every evaluation of the twins (over all the
sweep's sample orientations, with gradients and Hessians) counts one, and so
does every call of the sweep's evaluator. ``max_evaluations`` is a hard bound:
no evaluation starts past it.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable

import numpy as np
from scipy.stats import qmc

from ...errors import DesignError
from ..design_evaluation import design_id, evaluate_design
from ..evaluation_settings import EvaluationSettings
from .front_model import (
    ANCHOR_STEPS,
    APART,
    MIN_RADIUS,
    QuadModel,
    ascent,
    model_function,
    next_point,
    on_box,
    race_starts,
    ratio,
    trust_radius,
)
from .settings import OptimiseSettings

#: Length of a front step, in fractions of the largest workspace F* and of S there (Euclidean); longer (up to
#: MAX_FRONT_STEP) when the evaluations left would not reach the end of the front (:func:`_step_length`).
FRONT_STEP, MAX_FRONT_STEP = 0.015, 0.06
#: Radius (scaled variables) within which the model's stiffest design estimates the end of the front.
END_RADIUS = 0.25
#: A front point counts as on the front when its F is at most this far below its epsilon.
F_SLACK = 2e-3
#: Initial trust-region radius of the front (scaled variables, infinity norm; its bounds are in
#: :mod:`csjm_opt.design.optimisation.front_model`).
RADIUS = 0.05
#: A further branch starts only with this many evaluations left (an ascent step, its scoring, a corrector
#: and two front points, at the least).
MIN_BRANCH_EVALUATIONS = 6
#: Starts ascended before the first branch is chosen (the largest of their local maxima is traced first).
RACE = 2


@dataclasses.dataclass
class SweepFrontResult:
    """Designs of the front, each scored by the sweep's evaluator, and the work it took."""

    records: list[dict[str, Any]]        # sweep records (+ "epsilon", "surrogate", "evaluations_used", "elapsed_s")
    evaluations: int
    twin_evaluations: int
    sweep_evaluations: int

    def front(self) -> list[dict[str, Any]]:
        """The Pareto-optimal records (workspace fraction and minimum stiffness, both maximised), widest first.

        Returns
        -------
        list of dict
        """
        pts = [(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0) for r in self.records]
        keep = [i for i, (x, y) in enumerate(pts) if r_ok(self.records[i]) and not any(
            (a >= x and b >= y and (a > x or b > y)) for a, b in pts)]
        return [self.records[i] for i in sorted(keep, key=lambda i: -pts[i][0])]   # largest workspace first

    def as_json(self) -> dict[str, Any]:
        """JSON-able summary.

        Returns
        -------
        dict
        """
        return {"evaluations": self.evaluations, "twin_evaluations": self.twin_evaluations,
                "sweep_evaluations": self.sweep_evaluations, "records": self.records,
                "front": self.front()}


def r_ok(record: dict[str, Any]) -> bool:
    """Whether a sweep record is valid with a non-empty workspace.

    Parameters
    ----------
    record : dict

    Returns
    -------
    bool
    """
    return record.get("status") == "ok" and bool(record.get("workspace_fraction"))


class _Work:
    """The evaluation counter and the two evaluators it counts."""

    def __init__(self, limit: int | None, twins: Callable[[np.ndarray], QuadModel],
                 settings: OptimiseSettings, evaluation: EvaluationSettings):
        self.limit, self.twins_n, self.sweep_n = limit, 0, 0
        self.t0 = time.perf_counter()
        self._twins, self.settings, self.evaluation = twins, settings, evaluation
        self.records: list[dict[str, Any]] = []
        self.models: list[QuadModel] = []          # every evaluation of the twins

    def left(self) -> int:
        return 10 ** 9 if self.limit is None else self.limit - self.twins_n - self.sweep_n

    def twins(self, u: np.ndarray) -> QuadModel:
        assert self.left() >= 1
        self.twins_n += 1
        self.models.append(self._twins(u))
        return self.models[-1]

    def score(self, u: np.ndarray, eps: float | None, model: tuple[float, float]) -> dict[str, Any] | None:
        """Score a design by the sweep's evaluator (None, and no evaluation, for a design already scored)."""
        lo, hi = np.array(self.settings.lower), np.array(self.settings.upper)
        params = dict(zip(self.settings.names, (lo + u * (hi - lo)).tolist()))
        if any(r["params"] == params for r in self.records):
            return None
        assert self.left() >= 1
        self.sweep_n += 1
        rec = evaluate_design(params, self.evaluation)
        digest = self.evaluation.digest()      # the sweep's record keys: a csjm sweep result file line
        rec.update(id=design_id(digest, params), index=len(self.records), settings=digest)
        rec["epsilon"], rec["surrogate"] = eps, {"F": float(model[0]), "S": float(model[1])}
        rec["evaluations_used"] = self.twins_n + self.sweep_n      # work done when this design was scored
        rec["elapsed_s"] = time.perf_counter() - self.t0
        self.records.append(rec)
        return rec


def _step_length(F0: float, S0: float, end: tuple[float, float], left: int, scale: tuple[float, float]) -> float:
    """FRONT_STEP, or longer when the evaluations left do not reach the stiffest design ``end`` at that spacing.

    The points left are 2/3 of the evaluations left (two predicted points per corrector).
    """
    remaining = float(np.hypot((F0 - end[0]) / scale[0], max(end[1] - S0, 0.0) / scale[1]))
    return float(np.clip(remaining / max(2 * left // 3, 1), FRONT_STEP, MAX_FRONT_STEP))


def _branch(work: _Work, m: QuadModel, points: int | None, end: tuple[float, float]) -> QuadModel:
    """Continuation down the front from the largest-workspace design ``m`` to the branch's stiffest design.

    Predictor: from the models at ``m`` the points of the model's front, each FRONT_STEP beyond the last,
    are scored while they lie in the trust region. Corrector: the twins are evaluated at the last of them,
    which becomes the next centre; the model's error there sets the next trust region.
    """
    scale = (max(m.F, 1e-3), max(abs(m.S), 1e-3))
    radius, done, finished = RADIUS, 0, False
    while work.left() >= 1 and not finished and radius >= MIN_RADIUS:
        F0, S0, chain = m.F, m.S, 0
        d = np.zeros_like(m.u)
        step = _step_length(m.F, m.S, end, work.left(), scale)
        while work.left() >= 1 and (points is None or done < points):
            eps, d_next, binds = next_point(m, radius, F0, S0, scale, step)
            F0, S0 = m.predict(d_next)
            if np.max(np.abs(d_next - d)) < 1e-6:   # no further model front within the region
                break
            d = d_next
            work.score(on_box(m.u + d), eps, (F0, S0))
            chain, done = chain + 1, done + 1
            if not binds:
                finished = np.max(np.abs(d)) < 0.9 * radius     # F free inside the region: stiffest design
                break
        if chain == 0 or work.left() < 2 or finished or (points is not None and done >= points):
            break
        trial = work.twins(on_box(m.u + d))        # corrector: the new centre, and the model's error
        rho = ratio(trial.S - m.S, S0 - m.S)
        good = abs(trial.F - F0) <= F_SLACK and rho > 0.25
        radius = trust_radius(radius, rho if good else 0.0, d)
        m = trial
    return m


def _stiffest(work: _Work, anchor: QuadModel, race: int) -> QuadModel:
    """The front's stiffest design: S ascended from the ``race`` stiffest designs evaluated that lie apart.

    As for the first end (:func:`~csjm_opt.design.optimisation.front_model.race_starts`), the design of
    largest S may sit in the basin of a lower local maximum, so the maxima are compared, not their
    starts. The ascents share a third of the evaluations left (the first half of it, a later one stops
    where it comes within APART of a maximum already reached); every distinct maximum is scored.
    """
    held = sorted((x for x in work.models if x.F > 0.0), key=lambda x: -x.S)
    floor = max(work.left() * 2 // 3, 2)
    reached: list[QuadModel] = []
    for k, x in enumerate(h for i, h in enumerate(held) if all(np.max(np.abs(h.u - g.u)) >= APART
                                                              for g in held[:i])):
        if k >= max(race, 1) or (k and work.left() <= floor + 1):
            break
        keep = floor + (work.left() - floor) // 2 if k == 0 and race > 1 else floor
        reached.append(ascent(work, x, "S", ANCHOR_STEPS, keep=keep, known=[r.u for r in reached]))
    distinct: list[QuadModel] = []
    for r in sorted(reached, key=lambda x: -x.S):
        if all(np.max(np.abs(r.u - d.u)) >= APART for d in distinct):
            distinct.append(r)
    for r in distinct:
        if work.left() >= 1 and np.max(np.abs(r.u - anchor.u)) > 1e-9:
            work.score(r.u, None, (r.F, r.S))
    return distinct[0]


def sweep_front(settings: OptimiseSettings, evaluation: EvaluationSettings, points: int | None = None,
                max_evaluations: int | None = None, starts: list[dict[str, float]] | None = None,
                branches: int = 2, race: int = RACE) -> SweepFrontResult:
    """Trace the front in the sweep's metrics (see the module docstring).

    Parameters
    ----------
    settings : OptimiseSettings
        Variables, bounds, base design, ``starts`` and ``seed`` of the space-filling starts.
    evaluation : EvaluationSettings
        The sweep's evaluator settings (``SweepSpec.settings``): its samples define both metrics.
    points : int, optional
        Most front points per branch after its largest-workspace design (default: until the branch's
        stiffest design or the budget).
    max_evaluations : int, optional
        Hard bound on evaluations (the twins' evaluations plus the sweep evaluator's calls).
    starts : list of dict, optional
        Starting designs (default: ``settings.starts`` Halton designs in the variable box).
    branches : int
        Most fronts traced, from the starts of largest ``F`` that lead to different largest-workspace
        designs (mirror-image geometries are separate local optima); a further branch only uses what
        the previous ones left of the budget.

    race : int
        Starts (of largest ``F``, apart from each other) ascended before a branch is chosen: the
        branches are traced from their local maxima, largest first
        (:func:`~csjm_opt.design.optimisation.front_model.race_starts`).

    Returns
    -------
    SweepFrontResult

    Raises
    ------
    DesignError
        If the budget does not allow the starts and one scored design, or no start holds any pose.
    """
    names, lo, hi = settings.names, np.array(settings.lower), np.array(settings.upper)
    if starts is None:
        u_starts = qmc.Halton(d=len(names), scramble=True, seed=np.random.default_rng(settings.seed)).random(
            settings.starts)
    else:
        u_starts = np.clip([(np.array([s[n] for n in names]) - lo) / (hi - lo) for s in starts], 0.0, 1.0)
    if max_evaluations is not None and max_evaluations < len(u_starts) + 1:
        raise DesignError(f"max_evaluations = {max_evaluations} leaves no room for {len(u_starts)} starts and "
                          "one scored design", "max_evaluations")
    work = _Work(max_evaluations, model_function(settings, evaluation), settings, evaluation)
    models = [work.twins(u) for u in u_starts]
    if max(m.F for m in models) <= 0.0:
        raise DesignError("no start holds any of the sweep's sample poses", "starts")
    anchors, rest = race_starts(work, models, race, MIN_BRANCH_EVALUATIONS)
    ends: list[np.ndarray] = []
    for m in anchors + rest:
        if len(ends) >= max(branches, 1) or work.left() < (1 if not ends else MIN_BRANCH_EVALUATIONS):
            break
        if ends and min(np.max(np.abs(m.u - e)) for e in ends) < APART:
            continue                                # starts near a traced branch lead to it again
        m = ascent(work, m, "F", ANCHOR_STEPS, keep=2)      # the largest workspace (done for a race's anchor)
        work.score(m.u, None, (m.F, m.S))
        if not ends:    # the front's other end first: the stiffest design, raced like the first end
            stiff = _stiffest(work, m, race)
            end = (stiff.F, stiff.S)
        ends.append(_branch(work, m, points, end).u)
    return SweepFrontResult(records=work.records, evaluations=work.twins_n + work.sweep_n,
                            twin_evaluations=work.twins_n, sweep_evaluations=work.sweep_n)


def hypervolume(points: np.ndarray) -> float:
    """Area dominated by ``points`` (range, stiffness; both maximised) above the reference point (0, 0).

    Parameters
    ----------
    points : numpy.ndarray
        (n, 2) points of a front.

    Returns
    -------
    float
        The dominated area (0 when no point is positive in both).
    """
    pts = np.asarray([p for p in points if p[0] > 0 and p[1] > 0])
    if not len(pts):
        return 0.0
    pts = pts[np.argsort(-pts[:, 0])]
    area, best_y = 0.0, 0.0
    for x, y in pts:   # widest first: each point adds the strip above everything wider
        if y > best_y:
            area += x * (y - best_y)
            best_y = y
    return float(area)
