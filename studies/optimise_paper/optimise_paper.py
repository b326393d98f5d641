"""Optimisation on the paper's design space: the optimised front against the sweep, and the paper's design.

Usage::

    python -m studies.optimise_paper.optimise_paper OUTDIR [--sweep studies/paper_sweep/paper_sweep.toml] [--workers 2]

On the design space of ``studies/paper_sweep/paper_sweep.toml`` (the two hexagons' central
angles, 15 x 15 grid) this

1. runs the sweep (resumable, ``OUTDIR/paper_sweep.jsonl``) and ``optimise`` with the
   file's defaults (objective: the guaranteed orientation range, front against the
   smallest stiffness eigenvalue), timing both;
2. maps every sweep design, and the paper's, to the optimiser's two objectives:
   the largest range scale s whose whole set (tilt <= 45 s deg, |torsion| <= 30 s deg)
   meets every requirement (bisection, 1000 Halton orientations per step), and the
   smallest stiffness eigenvalue over that set;
3. compares hypervolumes (reference point (0, 0), both maximised) of the optimised
   front and the sweep's front in those objectives, and in the sweep's own metrics
   (workspace fraction, minimum stiffness over the feasible poses);
4. solves for the stiffest design that guarantees the paper design's range, and
   states what it gains and what it costs;
5. traces the front in the sweep's own metrics (``sweep_front``: workspace
   fraction x minimum stiffness, every design scored by the sweep's evaluator),
   unbounded and with ``--max-evaluations 22`` (a tenth of the sweep), and
   compares its hypervolume with the sweep front's, by evaluations spent; then
   again with 22 evaluations from the other start sets of ``--seeds`` (the
   Halton seed of the space-filling starts; the development set), how often it
   dominates, and from the start sets of ``--check-seeds`` (a check set, seeds
   10-19 by default, not looked at while developing), reported separately.

Writes ``summary.json``, ``summary.md``, ``front.png``, ``front_sweep_metrics.png`` and ``geometry.png``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from csjm_opt._fileio import atomic_write_json, atomic_write_text
from csjm_opt.design.clearance import interference
from csjm_opt.design.design_evaluation import evaluate_design
from csjm_opt.design.geometry import GeometryLimits, design_rig
from csjm_opt.design.optimisation.dense_check import certify, slacks
from csjm_opt.design.optimisation.front import hypervolume, sweep_front
from csjm_opt.design.optimisation.runner import design_rig_of, optimise
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.design.sampling import OrientationSampling, tilt_torsion_rotations
from csjm_opt.design.sweep.runner import run_sweep
from csjm_opt.errors import CsjmError
from csjm_opt.report.design.optimisation import front_figure, geometry_3d_figure

HERE = Path(__file__).resolve().parent
BISECTIONS = 10
MAP_ORIENTATIONS = 1000
#: A tenth of the sweep's 225 designs.
BUDGET = 22


def guaranteed(settings, rig, lam_req: float) -> tuple[float, float]:
    """Largest range scale whose set meets every requirement, and the smallest eigenvalue of K there."""
    req = settings.requirements
    s = OrientationSampling(MAP_ORIENTATIONS, req.max_tilt_deg, req.max_torsion_deg, seed=1)
    base = np.vstack([np.zeros((1, 3)), np.column_stack(s.angles())])

    def check(scale: float) -> tuple[bool, float]:
        a = base * np.array([scale, 1.0, scale])
        sl = slacks(rig, a, req, lam_req, req.tension_margin_N)
        ok = all(np.all(v >= -1e-9) for v in sl.values())
        return ok, float(np.min(sl["stiffness"]) + lam_req)

    ok, lam = check(1e-3)
    if not ok:
        return 0.0, math.nan
    lo, hi = 1e-3, 1.0
    ok1, lam1 = check(1.0)
    if ok1:
        return 1.0, lam1
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        ok, value = check(mid)
        if ok:
            lo, lam = mid, value
        else:
            hi = mid
    return lo, lam


def dense_guaranteed(settings, rig, s_high: float, lam_req: float, steps: int = 8) -> tuple[float, float]:
    """Largest range scale <= s_high passing the optimiser's dense certification, and the stiffness there."""
    req = settings.requirements
    check = certify(rig, req, s_high, lam_req, req.tension_margin_N, n=settings.certify_orientations,
                    seed=settings.seed + 7919)
    if check.ok:
        return s_high, lam_req + check.worst["stiffness"][0]
    lo, hi, lam = 0.0, s_high, math.nan
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        check = certify(rig, req, mid, lam_req, req.tension_margin_N, n=settings.certify_orientations,
                        seed=settings.seed + 7919)
        if check.ok:
            lo, lam = mid, lam_req + check.worst["stiffness"][0]
        else:
            hi = mid
    return lo, lam


def certified_front(settings, rigs: list, points: np.ndarray, lam_req: float) -> tuple[np.ndarray, int]:
    """Re-check the front of ``points`` densely (moving failing points down) until every front point passes."""
    points = points.copy()
    done = np.zeros(len(points), bool)
    checked = 0
    while True:
        front = [i for i in range(len(points)) if points[i, 0] > 0
                 and not np.any((points[:, 0] >= points[i, 0]) & (points[:, 1] >= points[i, 1])
                                & ((points[:, 0] > points[i, 0]) | (points[:, 1] > points[i, 1])))]
        todo = [i for i in front if not done[i]]
        if not todo:
            return points, checked
        for i in todo:
            s, lam = dense_guaranteed(settings, rigs[i], float(points[i, 0]), lam_req)
            points[i] = (s, lam if math.isfinite(lam) else 0.0)
            done[i] = True
            checked += 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--sweep", type=Path, default=HERE.parent / "paper_sweep" / "paper_sweep.toml")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seeds", type=int, default=10, help="start sets (seeds 0..N-1) of the budgeted front")
    parser.add_argument("--check-seeds", default="10-19",
                        help="check set of start sets, FIRST-LAST (seeds not looked at while developing)")
    args = parser.parse_args(argv)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    args.outdir.mkdir(parents=True, exist_ok=True)
    try:
        spec, settings = read_optimise_file(args.sweep)
        t0 = time.perf_counter()
        sweep = run_sweep(spec, args.outdir / "paper_sweep.jsonl", workers=args.workers, progress=True)
        timing = args.outdir / "sweep_seconds.json"
        if sweep.computed == len(sweep.records) or not timing.is_file():
            atomic_write_json(timing, {"seconds": time.perf_counter() - t0, "computed": sweep.computed},
                              overwrite=True)
        t_sweep = json.loads(timing.read_text())["seconds"]
        cached = args.outdir / "optimised.json"
        if cached.is_file():   # a rerun reuses the optimisation (delete the file to redo it)
            doc = json.loads(cached.read_text())
        else:
            t0 = time.perf_counter()
            result = optimise(settings, workers=args.workers, progress=True)
            doc = {**result.as_json(), "seconds": time.perf_counter() - t0}
            atomic_write_json(cached, doc)
        t_opt = doc["seconds"]
    except CsjmError as exc:
        print(f"optimise_paper: error: {exc}", file=sys.stderr)
        return 2
    lam_req = settings.requirements.min_stiffness_Nm_per_rad
    limits = GeometryLimits(settings.requirements.min_hole_spacing_m, 0.0)
    ok = [r for r in sweep.records if r["status"] == "ok"]
    from tqdm import tqdm

    mapped_file = args.outdir / "mapped.json"
    if mapped_file.is_file():
        mapped = json.loads(mapped_file.read_text())
    else:
        t0 = time.perf_counter()
        mapped = []
        for r in tqdm(ok, desc="sweep designs mapped", file=sys.stderr):
            rig = design_rig({**settings.base, **r["params"]}, limits).replace(link=settings.link)
            mapped.append(guaranteed(settings, rig, lam_req))
        atomic_write_json(mapped_file, {"points": mapped, "seconds": time.perf_counter() - t0})
        mapped = json.loads(mapped_file.read_text())
    t_map = mapped["seconds"]
    mapped = mapped["points"]
    mapped_arr = np.nan_to_num(np.array(mapped), nan=0.0)
    rigs = [design_rig({**settings.base, **r["params"]}, limits).replace(link=settings.link) for r in ok]
    front_file = args.outdir / "sweep_front_certified.json"
    if front_file.is_file():
        cert = json.loads(front_file.read_text())
    else:
        t0 = time.perf_counter()
        pts, n_checked = certified_front(settings, rigs, mapped_arr, lam_req)
        cert = {"points": pts.tolist(), "designs_checked": n_checked, "seconds": time.perf_counter() - t0}
        atomic_write_json(front_file, cert)
    certified_arr = np.array(cert["points"])
    paper_rig_ = design_rig({}, limits).replace(link=settings.link)
    paper_s, paper_lam = guaranteed(settings, paper_rig_, lam_req)
    paper_s, paper_lam = dense_guaranteed(settings, paper_rig_, paper_s, lam_req)
    paper_sweep_rec = evaluate_design({}, dataclasses.replace(spec.settings, base={}))
    designs = doc["designs"]
    front = np.array([[d["objectives"]["range"], d["objectives"]["stiffness"]] for d in designs])
    order = np.argsort(front[:, 0])
    monotone = bool(np.all(np.diff(front[order, 1]) <= 1e-9))   # a front: more range, less stiffness
    hv_opt, hv_sweep = hypervolume(front), hypervolume(certified_arr)
    hv_sweep_1000 = hypervolume(mapped_arr)
    # the sweep's own metrics of the optimised designs
    opt_sweep = [evaluate_design(d["params"], spec.settings) for d in designs]
    sw_pts = np.array([[r["workspace_fraction"], r["min_stiffness_Nm_per_rad"] or 0.0] for r in ok])
    op_pts = np.array([[r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0] for r in opt_sweep])
    hv_opt_sw, hv_sweep_sw = hypervolume(op_pts), hypervolume(sw_pts)
    # the front traced in the sweep's own metrics, every design scored by the sweep's evaluator
    fronts = {}
    for label, limit in (("unbounded", None), ("budget", BUDGET)):
        cache = args.outdir / f"sweep_front_{label}.json"
        if not cache.is_file():
            t0 = time.perf_counter()
            res = sweep_front(settings, spec.settings, max_evaluations=limit)
            atomic_write_json(cache, {**res.as_json(), "seconds": time.perf_counter() - t0, "limit": limit})
        fronts[label] = json.loads(cache.read_text())
    sf = fronts["unbounded"]
    sf_pts = [(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0) for r in sf["records"]]
    hv_sf = hypervolume(np.array(sf_pts))
    curve = [(r["evaluations_used"], hypervolume(np.array([p for p, q in zip(sf_pts, sf["records"])
                                                          if q["evaluations_used"] <= r["evaluations_used"]])))
             for r in sf["records"]]
    first_dominating = next((n for n, hv in curve if hv >= hv_sweep_sw), None)
    bf = fronts["budget"]
    # other starting sets (the Halton seed of the starts) under the same budget: how often the front dominates
    def budget_runs(seed_list: list[int]) -> list[dict]:
        rows = []
        for seed in tqdm(seed_list, desc="start sets", file=sys.stderr):
            cache = args.outdir / f"sweep_front_budget_seed{seed}.json"
            if not cache.is_file():
                res = sweep_front(settings.replace(seed=seed), spec.settings, max_evaluations=BUDGET)
                atomic_write_json(cache, res.as_json())
            doc_s = json.loads(cache.read_text())
            pts_s = [(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0) for r in doc_s["records"]]
            first = next((r["evaluations_used"] for k, r in enumerate(doc_s["records"])
                          if hypervolume(np.array(pts_s[:k + 1])) >= hv_sweep_sw), None)
            rows.append({"seed": seed, "evaluations": doc_s["evaluations"],
                         "hypervolume": hypervolume(np.array(pts_s)), "first_dominating_at_evaluations": first})
        return rows

    seeds = budget_runs(list(range(1, args.seeds)))
    first_check, last_check = (int(v) for v in args.check_seeds.split("-"))
    check = budget_runs(list(range(first_check, last_check + 1)))
    hv_budget = hypervolume(np.array([(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0)
                                      for r in bf["records"]]))
    sweep_front_pts = [tuple(p) for p in sw_pts if not np.any((sw_pts[:, 0] >= p[0]) & (sw_pts[:, 1] >= p[1])
                                                              & ((sw_pts[:, 0] > p[0]) | (sw_pts[:, 1] > p[1])))]
    undominated = [(float(p[0]), float(p[1])) for p in sweep_front_pts
                   if not any(a >= p[0] and b >= p[1] for a, b in sf_pts)]
    # the stiffest design at the paper's guaranteed range
    at_paper = optimise(settings.replace(objective="stiffness", pareto_with="", requirements=dataclasses.replace(
        settings.requirements, range_scale=max(paper_s, 1e-3))), workers=args.workers, progress=True)
    best = at_paper.designs[0]
    best_rig = design_rig_of(settings, best.params)
    req = settings.requirements
    Rs = tilt_torsion_rotations(*[np.column_stack(OrientationSampling(
        10000, req.max_tilt_deg * paper_s, req.max_torsion_deg * paper_s, seed=2).angles())[:, k] for k in range(3)])
    clash_paper, clash_best = interference(paper_rig_, Rs), interference(best_rig, Rs)
    summary = {
        "sweep": {"designs": len(sweep.records), "valid": len(ok), "seconds": t_sweep,
                  "hypervolume_range_stiffness": hv_sweep, "hypervolume_workspace_stiffness": hv_sweep_sw,
                  "hypervolume_range_stiffness_1000_orientations_uncertified": hv_sweep_1000,
                  "front_designs_certified": cert["designs_checked"], "front_certification_seconds": cert["seconds"],
                  "best_range": float(mapped_arr[:, 0].max()), "mapping_seconds": t_map},
        "optimised": {"designs": designs, "seconds": t_opt,
                      "evaluations": doc["evaluations"], "ipopt_iterations": doc["ipopt_iterations"],
                      "certified_orientations": doc["certified_orientations"],
                      "all_certified": all(d["ok"] for d in designs), "front_monotone": monotone,
                      "hypervolume_range_stiffness": hv_opt, "hypervolume_workspace_stiffness": hv_opt_sw,
                      "sweep_metrics": [{"workspace_fraction": r["workspace_fraction"],
                                         "min_stiffness_Nm_per_rad": r["min_stiffness_Nm_per_rad"]}
                                        for r in opt_sweep]},
        "sweep_metric_front": {
            "hypervolume": hv_sf, "sweep_hypervolume": hv_sweep_sw, "evaluations": sf["evaluations"],
            "twin_evaluations": sf["twin_evaluations"], "sweep_evaluations": sf["sweep_evaluations"],
            "seconds": sf["seconds"], "hypervolume_by_evaluations": curve,
            "first_dominating_at_evaluations": first_dominating,
            "sweep_front_points_not_dominated": undominated,
            "designs": [{"params": r["params"], "workspace_fraction": r["workspace_fraction"],
                         "min_stiffness_Nm_per_rad": r["min_stiffness_Nm_per_rad"], "epsilon": r["epsilon"],
                         "evaluations_used": r["evaluations_used"]} for r in sf["records"]],
            "other_seeds_budget": seeds, "check_seeds_budget": check,
            "budget": {"limit": BUDGET, "evaluations": bf["evaluations"], "hypervolume": hv_budget,
                       "seconds": bf["seconds"]}},
        "paper_design": {"range": paper_s, "stiffness": paper_lam,
                         "workspace_fraction": paper_sweep_rec["workspace_fraction"],
                         "min_stiffness_Nm_per_rad": paper_sweep_rec["min_stiffness_Nm_per_rad"],
                         "interference": clash_paper.as_dict()},
        "best_at_paper_range": {"params": best.params, "objectives": best.objectives, "ok": best.ok,
                                "interference": clash_best.as_dict(), "evaluations": at_paper.evaluations},
    }
    atomic_write_json(args.outdir / "summary.json", summary)
    ax = front_figure(doc, certified_arr, (paper_s, paper_lam))
    ax.figure.savefig(args.outdir / "front.png", dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.scatter(sw_pts[:, 0], sw_pts[:, 1], s=8, c="0.7", label=f"sweep, {len(sweep.records)} designs")
    fp = np.array(sorted(sweep_front_pts))
    ax.plot(fp[:, 0], fp[:, 1], "o-", c="tab:red", ms=4, label=f"sweep front (hypervolume {hv_sweep_sw:.4g})")
    op = np.array(sf_pts)
    ax.scatter(op[:, 0], op[:, 1], marker="x", c="tab:blue", zorder=3,
               label=f"optimised, {sf['evaluations']} evaluations (hypervolume {hv_sf:.4g})")
    ax.set_xlim(0.78, 0.88)
    ax.set_ylim(12.5, 15.0)
    ax.set_xlabel("workspace fraction (sweep's samples)")
    ax.set_ylabel("min stiffness over feasible poses (N m/rad)")
    ax.legend(fontsize=7)
    fig.savefig(args.outdir / "front_sweep_metrics.png", dpi=120, bbox_inches="tight")
    plt.close(fig)
    d0 = designs[0]
    at = d0["certified"]["tension"]
    R = tilt_torsion_rotations(*(np.radians([at[k]]) for k in ("tilt_deg", "azimuth_deg", "torsion_deg")))[0]
    ax = geometry_3d_figure(design_rig_of(settings, d0["params"]), R, title="largest guaranteed range, at its "
                            "binding orientation")
    ax.figure.savefig(args.outdir / "geometry.png", dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    lines = ["# Optimisation on the paper's design space", "",
             f"sweep: {len(sweep.records)} designs in {t_sweep:.1f} s (mapping to guaranteed range {t_map:.1f} s); "
             f"optimiser: {t_opt:.1f} s, {doc['evaluations']} evaluations ({doc['ipopt_iterations']} IPOPT "
             f"iterations, {doc['certified_orientations']} orientations in certification)", "",
             f"hypervolume (range scale x stiffness): optimised {hv_opt:.4g}, sweep {hv_sweep:.4g} (front designs "
             f"re-checked densely: {cert['designs_checked']}; {hv_sweep_1000:.4g} with 1,000 orientations unchecked)",
             f"hypervolume (workspace fraction x min stiffness, the sweep's metrics): range/stiffness designs "
             f"{hv_opt_sw:.4g}, sweep {hv_sweep_sw:.4g}", "",
             "front in the sweep's own metrics (csjm optimise --sweep-front; every design scored by the sweep's "
             "evaluator):",
             f"  hypervolume {hv_sf:.5g} against the sweep's {hv_sweep_sw:.5g} "
             f"({'dominates' if hv_sf >= hv_sweep_sw else 'does NOT dominate'}) with {sf['evaluations']} "
             f"evaluations ({sf['twin_evaluations']} of the smooth twins, {sf['sweep_evaluations']} by the sweep's "
             "evaluator), "
             f"{sf['seconds']:.1f} s; the sweep used {len(sweep.records)}",
             f"  hypervolume first >= the sweep's at {first_dominating} evaluations; by evaluations: "
             + ", ".join(f"{n}: {hv:.4g}" for n, hv in curve),
             "  sweep front points no optimised design dominates: "
             + ", ".join(f"({a:.3f}, {b:.4f})" for a, b in undominated),
             f"  with --max-evaluations {BUDGET}: {bf['evaluations']} evaluations, hypervolume {hv_budget:.5g}",
             f"  other start sets (seeds 1-{args.seeds - 1}) with --max-evaluations {BUDGET}: "
             f"{sum(s['hypervolume'] >= hv_sweep_sw for s in seeds)} of {len(seeds)} dominate; "
             + ", ".join(f"seed {s['seed']}: {s['hypervolume']:.4f} (first >= at "
                         f"{s['first_dominating_at_evaluations']})" for s in seeds),
             f"  check set (seeds {args.check_seeds}) with --max-evaluations {BUDGET}: "
             f"{sum(s['hypervolume'] >= hv_sweep_sw for s in check)} of {len(check)} dominate; "
             + ", ".join(f"seed {s['seed']}: {s['hypervolume']:.4f} (first >= at "
                         f"{s['first_dominating_at_evaluations']})" for s in check), ""]
    for r in sf["records"]:
        lines.append(f"  - {r['params']}: workspace fraction {r['workspace_fraction']}, min stiffness "
                     f"{r['min_stiffness_Nm_per_rad'] or 0.0:.4f} N m/rad, after {r['evaluations_used']} evaluations")
    lines += ["",
             f"paper's design: range {paper_s:.3f}, stiffness {paper_lam:.3f} N m/rad",
             f"stiffest design at that range: {best.params}, stiffness {best.objectives['stiffness']:.3f} N m/rad, "
             f"tension margin {best.objectives['tension_margin']:.3f} N, certified {best.ok}",
             f"interference paper / best: {clash_paper.as_dict()} / {clash_best.as_dict()}", ""]
    for d in designs:
        lines.append(f"- {d['params']}: {d['objectives']}, certified {d['ok']} in {d['rounds']} rounds")
    atomic_write_text(args.outdir / "summary.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    print(json.dumps({"hv_opt": hv_opt, "hv_sweep": hv_sweep}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
