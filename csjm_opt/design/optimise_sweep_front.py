"""An epsilon-constraint front in the sweep's own metrics (workspace fraction, minimum stiffness).

``csjm sweep`` draws its Pareto front in (``workspace_fraction``,
``min_stiffness_Nm_per_rad``) on its own sample orientations. :func:`sweep_front`
traces the same front by optimisation, on the smooth twins ``F`` and ``S`` of
those metrics (:mod:`csjm_opt.design.optimise_sweep_surrogate`), with IPOPT and
exact first and second derivatives:

1. the space-filling starts are scored by ``F`` (one evaluation each); from the
   best, ``max F`` gives the largest workspace ``F*``;
2. continuation down the front: ``max S subject to F >= eps_j``,
   ``eps_j = F* (1 - j STEP)``, each point warm-started from the previous
   solution (primal and dual), until the constraint is no longer active (the
   stiffest design has been reached) or the points run out;
3. every design is scored by the sweep's evaluator
   (:func:`~csjm_opt.design.design_evaluation.evaluate_design`, one evaluation
   each): those are the reported numbers, and the front is the Pareto front of
   the scored designs.

Evaluations are counted honestly: every point at which IPOPT evaluates the NLP
(the surrogate over all the sweep's sample orientations), line-search trials
included, and every call of the sweep's evaluator. ``max_evaluations`` is a
hard bound: IPOPT takes every trial step (``accept_every_trial_step``: no
backtracking, so one new point per iteration, exact Hessian and bounds keep the
steps sensible), each solve's iteration cap is what is left, and no solve or
scoring starts past it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import casadi as ca
import numpy as np
from scipy.stats import qmc

from ..errors import DesignError
from .design_evaluation import evaluate_design
from .evaluation_settings import EvaluationSettings
from .optimise_settings import OptimiseSettings
from .optimise_sweep_surrogate import sweep_surrogate

#: Relative step of the workspace-fraction constraint between front points.
STEP = 0.03
#: Iterations of one front point's solve (warm-started, so a few Newton steps).
POINT_MAX_ITER = 4
#: Iterations of the largest-workspace solve.
ANCHOR_MAX_ITER = 4
#: The constraint counts as inactive (the front has reached its stiffest design) above this slack.
INACTIVE_SLACK = 1e-3


@dataclasses.dataclass
class SweepFrontResult:
    """Designs of the front, each scored by the sweep's evaluator, and the work it took."""

    records: list[dict[str, Any]]        # evaluate_design records (+ "epsilon", "surrogate")
    evaluations: int
    ipopt_evaluations: int
    sweep_evaluations: int

    def front(self) -> list[dict[str, Any]]:
        """The Pareto-optimal records (workspace fraction and minimum stiffness, both maximised).

        Returns
        -------
        list of dict
        """
        pts = [(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0) for r in self.records]
        keep = [i for i, (x, y) in enumerate(pts) if r_ok(self.records[i]) and not any(
            (a >= x and b >= y and (a > x or b > y)) for a, b in pts)]
        return [self.records[i] for i in keep]

    def as_json(self) -> dict[str, Any]:
        """JSON-able summary.

        Returns
        -------
        dict
        """
        return {"evaluations": self.evaluations, "ipopt_evaluations": self.ipopt_evaluations,
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


class _Counter:
    def __init__(self, limit: int | None):
        self.limit, self.ipopt, self.sweep = limit, 0, 0

    @property
    def used(self) -> int:
        return self.ipopt + self.sweep

    def left(self) -> int:
        return 10 ** 9 if self.limit is None else max(self.limit - self.used, 0)


class _Solvers:
    """The surrogate and the two IPOPT solvers, built per iteration cap (options are fixed at build)."""

    def __init__(self, settings: OptimiseSettings, evaluation: EvaluationSettings):
        self.f = sweep_surrogate(settings, evaluation)
        u, eps = ca.MX.sym("u", len(settings.names)), ca.MX.sym("eps")
        F, S, _, _ = self.f(u)
        self.nlps: dict[str, Any] = {"anchor": {"x": u, "f": -F},
                                     "point": {"x": u, "p": eps, "f": -S / 10.0, "g": F - eps}}
        self.cache: dict[tuple[str, int], Any] = {}

    def get(self, kind: str, max_iter: int) -> Any:
        if (kind, max_iter) not in self.cache:
            opts: dict[str, Any] = {"print_level": 0, "sb": "yes", "tol": 1e-6, "acceptable_tol": 1e-4, "max_soc": 0,
                    "accept_every_trial_step": "yes", "hessian_approximation": "exact", "max_iter": max_iter}
            if kind == "point":
                opts.update({"warm_start_init_point": "yes", "mu_init": 1e-4, "warm_start_bound_push": 1e-6,
                             "warm_start_mult_bound_push": 1e-6})
            nlp_opts: dict[str, Any] = {"ipopt": opts, "print_time": False}
            self.cache[kind, max_iter] = ca.nlpsol(f"sweep_front_{kind}", "ipopt", self.nlps[kind], nlp_opts)
        return self.cache[kind, max_iter]


def sweep_front(settings: OptimiseSettings, evaluation: EvaluationSettings, points: int = 8,
                max_evaluations: int | None = None, starts: list[dict[str, float]] | None = None,
                branches: int = 2) -> SweepFrontResult:
    """Trace the front in the sweep's metrics (see the module docstring).

    Parameters
    ----------
    settings : OptimiseSettings
        Variables, bounds, base design, ``starts`` and ``seed`` of the space-filling starts.
    evaluation : EvaluationSettings
        The sweep's evaluator settings (``SweepSpec.settings``): its samples define both metrics.
    points : int
        Most front points after the largest-workspace design.
    max_evaluations : int, optional
        Hard bound on evaluations (IPOPT's NLP evaluations plus the sweep evaluator's calls).
    starts : list of dict, optional
        Starting designs (default: ``settings.starts`` Halton designs in the variable box).
    branches : int
        Fronts traced, from the starts of largest ``F`` that lead to different largest-workspace
        designs (mirror-image geometries are separate local optima).

    Returns
    -------
    SweepFrontResult

    Raises
    ------
    DesignError
        If the budget does not allow one solve and its scoring, or no start holds any pose.
    """
    counter = _Counter(max_evaluations)
    names, lo, hi = settings.names, np.array(settings.lower), np.array(settings.upper)
    if starts is None:
        u_starts = qmc.Halton(d=len(names), scramble=True, seed=np.random.default_rng(settings.seed)).random(
            settings.starts)
    else:
        u_starts = np.clip([(np.array([s[n] for n in names]) - lo) / (hi - lo) for s in starts], 0.0, 1.0)
    if counter.left() < len(u_starts) + 5:
        raise DesignError(f"max_evaluations = {max_evaluations} leaves no room for {len(u_starts)} starts, one "
                          "solve and its scoring", "max_evaluations")
    solvers = _Solvers(settings, evaluation)
    f = solvers.f
    scores = [float(f(u)[0]) for u in u_starts]
    counter.ipopt += len(u_starts)
    if max(scores) <= 0.0:
        raise DesignError("no start holds any of the sweep's sample poses", "starts")

    def solve(kind: str, wanted: int, reserve: int, **args: Any) -> tuple[np.ndarray, Any, bool]:
        # each iteration evaluates one trial point (every trial step is taken), the start one more;
        # keep `reserve` for after
        solver = solvers.get(kind, int(min(wanted, counter.left() - 1 - reserve)))
        sol = solver(**args)
        st = solver.stats()
        counter.ipopt += int(max(st["n_call_nlp_f"], st.get("n_call_nlp_g", 0)))
        return np.array(sol["x"]).ravel(), sol, bool(st["success"])

    records: list[dict[str, Any]] = []

    def score(u: np.ndarray, eps: float | None, surrogate: tuple[float, float]) -> None:
        params = dict(zip(names, (lo + u * (hi - lo)).tolist()))
        counter.sweep += 1
        rec = evaluate_design(params, evaluation)
        rec["epsilon"], rec["surrogate"] = eps, {"F": surrogate[0], "S": surrogate[1]}
        rec["evaluations_used"] = counter.used      # work done when this design was scored
        records.append(rec)

    order = np.argsort(scores)[::-1][:max(branches, 1)]
    anchors: list[np.ndarray] = []
    for k in order:
        if scores[k] <= 0.0 or counter.left() < 5:
            break
        u, _, _ = solve("anchor", ANCHOR_MAX_ITER, 2, x0=u_starts[k], lbx=0.0, ubx=1.0)
        if any(np.max(np.abs(u - a)) < 1e-3 for a in anchors):     # the same branch again
            continue
        anchors.append(u)
        F_star, S_star = (float(v) for v in f(u)[:2])
        counter.ipopt += 1
        score(u, None, (F_star, S_star))
        lam_g: Any = 0.0
        for j in range(1, points + 1):
            if counter.left() < 4:
                break
            eps = F_star * (1.0 - j * STEP)
            x, sol, converged = solve("point", POINT_MAX_ITER, 1, x0=u, p=eps, lbx=0.0, ubx=1.0, lbg=0.0, ubg=math.inf,
                           lam_g0=lam_g, lam_x0=0.0)
            if not np.all(np.isfinite(x)):
                break
            F_j, S_j = float(sol["g"]) + eps, -10.0 * float(sol["f"])
            u, lam_g = x, sol["lam_g"]
            score(u, eps, (F_j, S_j))
            if converged and F_j - eps > INACTIVE_SLACK:    # constraint inactive: this branch's stiffest design
                break
    return SweepFrontResult(records=records, evaluations=counter.used, ipopt_evaluations=counter.ipopt,
                            sweep_evaluations=counter.sweep)

