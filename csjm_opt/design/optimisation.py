"""Hole-geometry optimisation: multi-start IPOPT, certification rounds, an epsilon-constraint front.

:func:`optimise` solves the NLP of :mod:`csjm_opt.design.optimise_problem`
from several space-filling starts (run on the sweep's worker processes),
certifies the best solution on a dense orientation set
(:mod:`csjm_opt.design.certify`), adds the failing orientations (and the
cable contacts of the current design) to the problem and solves again until
the dense check holds. With ``pareto_with`` it then walks an epsilon-constraint
front: the second objective held at values from the first design's value to
the value it reaches when the first objective is halved, each point
warm-started from the previous design.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from typing import Any

import numpy as np
from scipy.stats import qmc

from ..errors import DesignError
from .certify import certify
from .geometry import GeometryLimits, design_rig
from .optimise_contacts import contacts_near
from .optimise_diagnosis import infeasible, violation
from .optimise_problem import Contact, build_problem
from .optimise_settings import OptimiseSettings
from .sampling import OrientationSampling

_INFEASIBLE = ("Infeasible_Problem_Detected", "Restoration_Failed", "Error_In_Step_Computation")


@dataclasses.dataclass
class OptimisedDesign:
    """One certified design of an optimisation."""

    params: dict[str, float]
    objectives: dict[str, float]
    certified: dict[str, Any]
    epsilon: dict[str, float]
    rounds: int
    ok: bool

    def as_dict(self) -> dict[str, Any]:
        """JSON-able record.

        Returns
        -------
        dict
        """
        return dataclasses.asdict(self)


@dataclasses.dataclass
class OptimisationResult:
    """The designs of an optimisation, what they were certified against, and the work it took."""

    designs: list[OptimisedDesign]
    settings: OptimiseSettings
    evaluations: int
    ipopt_iterations: int
    certified_orientations: int

    def as_json(self) -> dict[str, Any]:
        """The ``result.json`` document.

        Returns
        -------
        dict
        """
        s = self.settings
        return {"objective": s.objective, "pareto_with": s.pareto_with or None, "variables": list(s.names),
                "bounds": {n: [lo, hi] for n, lo, hi in zip(s.names, s.lower, s.upper)}, "base": s.base,
                "requirements": s.requirements.as_dict(), "link": dataclasses.asdict(s.link),
                "certify_orientations": s.certify_orientations, "evaluations": self.evaluations,
                "ipopt_iterations": self.ipopt_iterations, "certified_orientations": self.certified_orientations,
                "designs": [d.as_dict() for d in self.designs]}


class _Budget:
    def __init__(self, limit: int | None):
        self.limit, self.used, self.iterations, self.dense = limit, 0, 0, 0

    def left(self) -> int:
        return 10 ** 9 if self.limit is None else max(self.limit - self.used, 0)


def optimise(settings: OptimiseSettings, max_evaluations: int | None = None, workers: int = 1,
             progress: bool | None = None, starts: list[dict[str, float]] | None = None,
             dask: bool = False, scheduler: str | None = None) -> OptimisationResult:
    """Optimise the hole geometry (see the module docstring).

    Parameters
    ----------
    settings : OptimiseSettings
        From :func:`csjm_opt.design.optimise_settings.read_optimise_file` or built directly.
    max_evaluations : int, optional
        Bound on design evaluations (IPOPT's constraint evaluations plus one per certification),
        checked between solves: no new solve starts once it is reached (a design not yet certified
        is then returned with ``ok = False``).
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
        If a setting is invalid.
    """
    from tqdm import tqdm

    budget = _Budget(max_evaluations)
    points = settings.pareto_points if settings.pareto_with else 1
    bar = tqdm(total=points + 1 if points > 1 else 1, desc="designs", unit="design", file=sys.stderr,
               disable=None if progress is None else not progress)
    try:
        if starts is None:
            starts = _starts(settings)
        else:
            starts = [{n: float(np.clip(p[n], lo, hi)) for n, lo, hi in zip(settings.names, settings.lower,
                                                                           settings.upper)} for p in starts]
        backend = ("dask", scheduler) if dask or scheduler else ("processes", None)
        first = _best_start(settings, starts, {}, budget, workers, backend)
        designs = [first]
        bar.update(1)
        if points > 1 and budget.left() > 0:
            other = settings.pareto_with
            half = {settings.objective: _halved(settings.objective, first.objectives[settings.objective])}
            flipped = settings.replace(objective=other, pareto_with=settings.objective)
            anchor = _certified_solve(flipped, first.params, half, budget)
            bar.update(1)
            lo_v, hi_v = first.objectives[other], anchor.objectives[other] if anchor.ok else first.objectives[other]
            prev = first
            for eps in np.linspace(lo_v, hi_v, points)[1:]:
                if budget.left() <= 0:
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


def sweep_starts(settings: OptimiseSettings, records: list[dict[str, Any]], count: int | None = None,
                 key: str = "workspace_fraction") -> list[dict[str, float]]:
    """The best designs of a sweep as starts: valid records sorted by ``key`` (largest first).

    Parameters
    ----------
    settings : OptimiseSettings
    records : list of dict
        Sweep records (``SweepResult.records`` or the lines of a result file).
    count : int, optional
        How many (default ``settings.starts``).
    key : str
        Record key to rank by.

    Returns
    -------
    list of dict of str to float
        The optimised parameters of each start.

    Raises
    ------
    DesignError
        If no valid record has every optimised parameter.
    """
    ok = [r for r in records if r.get("status") == "ok" and r.get(key) is not None
          and all(n in r["params"] for n in settings.names)]
    if not ok:
        raise DesignError(f"no valid sweep record with {key} and the parameters {list(settings.names)}", "starts")
    ok.sort(key=lambda r: -float(r[key]))
    return [{n: float(r["params"][n]) for n in settings.names} for r in ok[:count or settings.starts]]


def _starts(settings: OptimiseSettings) -> list[dict[str, float]]:
    d = len(settings.names)
    u = qmc.Halton(d=d, scramble=True, seed=np.random.default_rng(settings.seed)).random(settings.starts)
    lo, hi = np.array(settings.lower), np.array(settings.upper)
    return [dict(zip(settings.names, (lo + row * (hi - lo)).tolist())) for row in u]


def _best_start(settings: OptimiseSettings, starts: list[dict[str, float]], epsilon: dict[str, float],
                budget: _Budget, workers: int,
                backend: tuple[str, str | None] = ("processes", None)) -> OptimisedDesign:
    """Solve from every start (on the sweep's worker processes or Dask); certify the best."""
    results: list[tuple[dict[str, float] | None, float, int, str, Any]] = []
    if backend[0] == "dask":
        from ._dask_backend import _run_dask

        got = dict(_run_dask(list(enumerate(starts)), (settings, epsilon), backend[1], max(workers, 1), 10.0,
                             fn=_solve_start))
        results = [got[i] for i in range(len(starts))]
    elif workers > 1 and len(starts) > 1:
        from ._worker_processes import _run_processes

        todo = list(enumerate(starts))
        got = dict(_run_processes(todo, (settings, epsilon), workers, fn=_solve_start))
        results = [got[i] for i in range(len(starts))]
    else:
        results = [_solve_start(p, (settings, epsilon)) for p in starts]
    for _, _, calls, _, _ in results:
        budget.used += calls
    good = [r for r in results if r[0] is not None]
    if not good:
        raise infeasible(results[0][4])
    sign = 1.0 if settings.objective == "size" else -1.0
    best = min(good, key=lambda r: sign * r[1])
    return _certified_solve(settings, best[0], epsilon, budget)  # type: ignore[arg-type]


def _solve_start(start: dict[str, float], payload: tuple[OptimiseSettings, dict[str, float]]) -> tuple:
    """One IPOPT solve on the starting orientation set (a worker-process task)."""
    settings, epsilon = payload
    angles = _initial_angles(settings)
    pb = build_problem(settings, angles, start, [], epsilon)
    sol = pb.solver(x0=pb.x0, p=pb.p, lbx=pb.lbx, ubx=pb.ubx, lbg=pb.lbg, ubg=pb.ubg)
    stats = pb.solver.stats()
    x = np.array(sol["x"]).ravel()
    calls = int(stats.get("n_call_nlp_g", stats["iter_count"]))
    if not stats["success"] and stats["return_status"] != "Maximum_Iterations_Exceeded":
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
    while rounds < settings.max_rounds:
        rounds += 1
        pb = build_problem(settings, angles, params, contacts, epsilon, objective_start=q_obj)
        sol = pb.solver(x0=pb.x0, p=pb.p, lbx=pb.lbx, ubx=pb.ubx, lbg=pb.lbg, ubg=pb.ubg)
        stats = pb.solver.stats()
        budget.used += int(stats.get("n_call_nlp_g", stats["iter_count"]))
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
        budget.used += 1
        budget.dense += check.orientations
        if check.ok or budget.left() <= 0:
            break
        angles = np.unique(np.vstack([angles, check.failing / np.array([values["range"], 1.0, values["range"]])]),
                           axis=0)
        contacts = contacts_near(settings, rig, angles, values["range"])
    assert check is not None
    objectives = _objectives(settings, params, check, values)
    return OptimisedDesign(params=params, objectives=objectives, certified=check.as_dict(), epsilon=dict(epsilon),
                           rounds=rounds, ok=check.ok)


def _scale(name: str) -> float:
    from .optimise_problem import MARGIN_SCALE_N, SIZE_SCALE_M, STIFFNESS_SCALE_NM_PER_RAD

    return {"stiffness": STIFFNESS_SCALE_NM_PER_RAD, "tension_margin": MARGIN_SCALE_N, "range": 1.0,
            "size": SIZE_SCALE_M}[name]


def _values(settings: OptimiseSettings, epsilon: dict[str, float], q_obj: float) -> dict[str, float]:
    req = settings.requirements
    v = {"stiffness": req.min_stiffness_Nm_per_rad, "tension_margin": req.tension_margin_N,
         "range": req.range_scale, "size": math.inf, **epsilon}
    v[settings.objective] = q_obj
    return v


def design_rig_of(settings: OptimiseSettings, params: dict[str, float]) -> Any:
    """The rig of an optimised design: the base parameters, ``params`` and the settings' link.

    Parameters
    ----------
    settings : OptimiseSettings
    params : dict of str to float

    Returns
    -------
    Rig
    """
    limits = GeometryLimits(settings.requirements.min_hole_spacing_m, 0.0)
    return design_rig({**settings.base, **params}, limits).replace(link=settings.link)


def _objectives(settings: OptimiseSettings, params: dict[str, float], check: Any,
                values: dict[str, float]) -> dict[str, float]:
    """Certified objective values: the range scale held, and the worst values over the dense check."""
    rig = design_rig_of(settings, params)
    size = float(max(np.hypot(*rig.platform_holes_A_m[:, :2].T).max(), np.hypot(*rig.base_holes_B_m[:, :2].T).max()))
    return {"range": values["range"],
            "stiffness": values["stiffness"] + check.worst["stiffness"][0],
            "tension_margin": values["tension_margin"] + check.worst["tension"][0],
            "size": size}


__all__ = ["OptimisationResult", "OptimisedDesign", "design_rig_of", "optimise", "sweep_starts"]
