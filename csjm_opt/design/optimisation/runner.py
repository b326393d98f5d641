"""Hole-geometry optimisation: multi-start IPOPT, certification rounds, an epsilon-constraint front.

:func:`optimise` solves the NLP of :mod:`csjm_opt.design.optimisation.problem`
from several space-filling starts (run on the sweep's worker processes),
certifies the best solution on a dense orientation set
(:mod:`csjm_opt.design.optimisation.dense_check`), adds the failing orientations (and the
cable contacts of the current design) to the problem and solves again until
the dense check holds. With ``pareto_with`` it then walks an epsilon-constraint
front: the second objective held at values from the first design's value to
the value it reaches when the first objective is halved, each point
warm-started from the previous design.
"""

from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from ...errors import DesignError
from ..sampling import OrientationSampling
from .budget import STOPPED, evaluations_of
from .contacts import contacts_near
from .dense_check import certify
from .diagnosis import infeasible, violation
from .problem import Contact, build_problem
from .result import OptimisationResult, OptimisedDesign, design_rig_of, objectives_of
from .settings import OptimiseSettings
from .shaping import objective_shortfall_only, with_shaping
from .starts import space_filling_starts, sweep_starts

_INFEASIBLE = ("Infeasible_Problem_Detected", "Restoration_Failed", "Error_In_Step_Computation")


class _Budget:
    def __init__(self, limit: int | None):
        self.limit, self.used, self.iterations, self.dense = limit, 0, 0, 0

    def left(self) -> int:
        return 10 ** 9 if self.limit is None else max(self.limit - self.used, 0)

    def for_solve(self) -> int | None:
        """Evaluations the next solve may make (one is kept for its certification); None without a bound."""
        return None if self.limit is None else self.left() - 1


def _run(pb: Any, evaluations: int | None) -> tuple[Any, dict[str, Any], int]:
    """One IPOPT solve of ``pb``, stopped by its iteration callback within ``evaluations`` (a hard bound)."""
    if pb.stop is not None:
        pb.stop.arm(evaluations)
    sol = pb.solver(x0=pb.x0, p=pb.p, lbx=pb.lbx, ubx=pb.ubx, lbg=pb.lbg, ubg=pb.ubg)
    stats = pb.solver.stats()
    return sol, stats, evaluations_of(stats)


def optimise(settings: OptimiseSettings, max_evaluations: int | None = None, workers: int = 1,
             progress: bool | None = None, starts: list[dict[str, float]] | None = None,
             dask: bool = False, scheduler: str | None = None) -> OptimisationResult:
    """Optimise the hole geometry (see the module docstring).

    Parameters
    ----------
    settings : OptimiseSettings
        From :func:`csjm_opt.design.optimisation.settings.read_optimise_file` or built directly.
    max_evaluations : int, optional
        Hard bound on design evaluations (every NLP evaluation by IPOPT, line-search trials included,
        plus one per certification): each solve is stopped within its share by IPOPT's iteration
        callback (:mod:`csjm_opt.design.optimisation.budget`); a design not yet certified when it runs out
        is returned with ``ok = False``.
    workers : int
        Processes for the multi-start (the sweep's worker pool when > 1).
    progress : bool, optional
        Progress bar on stderr (``None``: on a terminal only).
    starts : list of dict, optional
        Starting designs (e.g. :func:`sweep_starts`, a sweep's best); default: ``settings.starts``
        space-filling designs in the variable box.
    dask : bool
        Run the starts on Dask (a local cluster of ``workers`` processes without ``scheduler``).
    scheduler : str, optional
        Address of a running Dask scheduler for the starts, as for a sweep.

    Returns
    -------
    OptimisationResult

    Raises
    ------
    InfeasibleRequirement
        If no design meets the requirements (naming the binding constraint and an orientation).
    DesignError
        If a setting is invalid, or ``max_evaluations`` leaves no room for one solve and its certification.
    """
    from tqdm import tqdm

    budget = _Budget(max_evaluations)
    if max_evaluations is not None and max_evaluations < 4:
        raise DesignError(f"max_evaluations = {max_evaluations} leaves no room for a start, one solve and its "
                          "certification (at least 4)", "max_evaluations")
    points = settings.pareto_points if settings.pareto_with else 1
    bar = tqdm(total=points + 1 if points > 1 else 1, desc="designs", unit="design", file=sys.stderr,
               disable=None if progress is None else not progress)
    try:
        if starts is None:
            starts = space_filling_starts(settings)
        else:
            starts = [{n: float(np.clip(p[n], lo, hi)) for n, lo, hi in zip(settings.names, settings.lower,
                                                                           settings.upper)} for p in starts]
        backend = ("dask", scheduler) if dask or scheduler else ("processes", None)
        first = _best_start(settings, starts, {}, budget, workers, backend)
        designs = [first]
        bar.update(1)
        if points > 1 and budget.left() >= 2:
            other = settings.pareto_with
            half = {settings.objective: _halved(settings.objective, first.objectives[settings.objective])}
            flipped = settings.replace(objective=other, pareto_with=settings.objective)
            anchor = _certified_solve(flipped, first.params, half, budget)
            bar.update(1)
            lo_v, hi_v = first.objectives[other], anchor.objectives[other] if anchor.ok else first.objectives[other]
            prev = first
            for eps in np.linspace(lo_v, hi_v, points)[1:]:
                if budget.left() < 2:       # a solve needs one evaluation and its certification one
                    break
                d = _certified_solve(settings, prev.params, {other: float(eps)}, budget)
                bar.update(1)
                if d.ok and not _same(d, prev):
                    designs.append(d)
                    prev = d
    finally:
        bar.close()
    designs = [d for d in designs if d.ok] or designs[:1]
    return OptimisationResult(designs=designs, settings=settings, evaluations=budget.used,
                              ipopt_iterations=budget.iterations, certified_orientations=budget.dense)


def _same(a: OptimisedDesign, b: OptimisedDesign, rtol: float = 1e-6) -> bool:
    """Whether two front points are one design (no trade-off there: the front has collapsed)."""
    return all(math.isclose(a.params[k], b.params[k], rel_tol=rtol, abs_tol=1e-12) for k in a.params) and all(
        math.isclose(a.objectives[k], b.objectives[k], rel_tol=rtol, abs_tol=1e-9) for k in a.objectives)


def _halved(name: str, value: float) -> float:
    return value * 2.0 if name == "size" else value * 0.5


def _best_start(settings: OptimiseSettings, starts: list[dict[str, float]], epsilon: dict[str, float],
                budget: _Budget, workers: int,
                backend: tuple[str, str | None] = ("processes", None)) -> OptimisedDesign:
    """Solve from every start (on the sweep's worker processes or Dask); certify the best."""
    results: list[tuple[dict[str, float] | None, float, int, str, Any]] = []
    share = None
    if budget.limit is not None:       # the starts share what is left but two (the best one's solve and check)
        starts = starts[:max(min(len(starts), budget.left() - 3), 1)]
        share = max((budget.left() - 2) // len(starts), 1)
    payload = (settings, epsilon, share)
    if backend[0] == "dask":
        from .._dask_backend import _run_dask

        got = dict(_run_dask(list(enumerate(starts)), payload, backend[1], max(workers, 1), 10.0,
                             fn=_solve_start))
        results = [got[i] for i in range(len(starts))]
    elif workers > 1 and len(starts) > 1:
        from .._worker_processes import _run_processes

        todo = list(enumerate(starts))
        got = dict(_run_processes(todo, payload, workers, fn=_solve_start))
        results = [got[i] for i in range(len(starts))]
    else:
        results = [_solve_start(p, payload) for p in starts]
    for _, _, calls, _, _ in results:
        budget.used += calls
    good = [r for r in results if r[0] is not None]
    if not good:
        raise infeasible(results[0][4])
    sign = 1.0 if settings.objective == "size" else -1.0
    best = min(good, key=lambda r: sign * r[1])
    return _certified_solve(settings, best[0], epsilon, budget)  # type: ignore[arg-type]


def _solve_start(start: dict[str, float], payload: tuple[OptimiseSettings, dict[str, float], int | None]) -> tuple:
    """One IPOPT solve on the starting orientation set within ``payload[2]`` evaluations (a worker-process task)."""
    settings, epsilon, evaluations = payload
    angles = _initial_angles(settings)
    pb = build_problem(settings, angles, start, [], epsilon, bounded=evaluations is not None)
    sol, stats, calls = _run(pb, evaluations)
    x = np.array(sol["x"]).ravel()
    if not stats["success"] and stats["return_status"] not in ("Maximum_Iterations_Exceeded", STOPPED):
        return None, math.nan, calls, stats["return_status"], violation(settings, angles, pb, x, sol)
    params = dict(zip(settings.names, np.array(pb.design_of(x[:pb.n_design])).ravel().tolist()))
    return params, float(x[pb.objective_index]), calls, stats["return_status"], None


def _initial_angles(settings: OptimiseSettings) -> np.ndarray:
    req = settings.requirements
    s = OrientationSampling(settings.orientations, req.max_tilt_deg, req.max_torsion_deg, seed=settings.seed)
    return np.vstack([np.zeros((1, 3)), np.column_stack(s.angles())])


def _certified_solve(settings: OptimiseSettings, start: dict[str, float], epsilon: dict[str, float],
                     budget: _Budget) -> OptimisedDesign:
    """Solve, certify, add failing orientations and contacts, solve again (up to ``max_rounds``)."""
    angles = _initial_angles(settings)
    contacts: list[Contact] = []
    params, q_obj = dict(start), None
    check = None
    rounds = 0
    while rounds < settings.max_rounds and budget.left() >= 2:
        rounds += 1
        pb = build_problem(settings, angles, params, contacts, epsilon, objective_start=q_obj,
                           bounded=budget.limit is not None)
        sol, stats, calls = _run(pb, budget.for_solve())
        budget.used += calls
        budget.iterations += int(stats["iter_count"])
        x = np.array(sol["x"]).ravel()
        if stats["return_status"] in _INFEASIBLE:
            raise infeasible(violation(settings, angles, pb, x, sol))
        params = dict(zip(settings.names, np.array(pb.design_of(x[:pb.n_design])).ravel().tolist()))
        q_obj = float(x[pb.objective_index]) * _scale(settings.objective)
        values = _values(settings, epsilon, q_obj)
        rig = design_rig_of(settings, params)
        check = certify(rig, settings.requirements, values["range"], values["stiffness"], values["tension_margin"],
                        n=settings.certify_orientations, seed=settings.seed + 7919)
        if "shaping" in (settings.objective, settings.pareto_with):
            check = with_shaping(check, settings, rig, values)
        budget.used += 1
        budget.dense += check.orientations
        if check.ok or budget.left() <= 0:
            break
        angles = np.unique(np.vstack([angles, check.failing / np.array([values["range"], 1.0, values["range"]])]),
                           axis=0)
        contacts = contacts_near(settings, rig, angles, values["range"])
    assert check is not None
    objectives = objectives_of(settings, params, check, values)
    return OptimisedDesign(params=params, objectives=objectives, certified=check.as_dict(), epsilon=dict(epsilon),
                           rounds=rounds, ok=check.ok or objective_shortfall_only(settings, check))


def _scale(name: str) -> float:
    from .problem import MARGIN_SCALE_N, SIZE_SCALE_M, STIFFNESS_SCALE_NM_PER_RAD

    return {"stiffness": STIFFNESS_SCALE_NM_PER_RAD, "tension_margin": MARGIN_SCALE_N, "range": 1.0,
            "size": SIZE_SCALE_M, "shaping": STIFFNESS_SCALE_NM_PER_RAD}[name]


def _values(settings: OptimiseSettings, epsilon: dict[str, float], q_obj: float) -> dict[str, float]:
    req = settings.requirements
    v = {"stiffness": req.min_stiffness_Nm_per_rad, "tension_margin": req.tension_margin_N,
         "range": req.range_scale, "size": math.inf, "shaping": 0.0, **epsilon}
    v[settings.objective] = q_obj
    return v


__all__ = ["OptimisationResult", "OptimisedDesign", "design_rig_of", "optimise", "sweep_starts"]
