"""The shaping range as the objective on the paper's design space: the optimum, the paper's design, the sweep's best.

Usage::

    python -m studies.optimise_paper_shaping.optimise_paper_shaping OUTDIR
        [--sweep studies/paper_sweep/paper_sweep.toml] [--workers 1]

On the design space of ``studies/paper_sweep/paper_sweep.toml`` (the two hexagons' central
angles), at the paper design's certified range scale (``paper_design.range`` of
``studies/optimise_paper/optimise_paper.json``: tilt <= 45 s deg, |torsion| <= 30 s deg, the
sweep's seven loads, the ``[optimise]`` defaults otherwise), this

1. runs ``optimise`` with ``objective = "shaping"`` (no front), timing it;
2. scores the optimum, the paper's design and every design of the sweep's 15 x 15
   grid with the same number, the certified shaping range: the smallest, over the
   dense certification set (10,000 Halton orientations and R = I, plus a pattern
   search from the worst) and the axes x, y, z, of the exact LP range
   ``max - min u^T K(T) u`` over the tensions that hold the stiffness load
   (:func:`csjm_opt.design.optimisation.shaping.shaping_check`); and certifies each grid
   design against the same requirements (:func:`csjm_opt.design.optimisation.dense_check.certify`),
   so "the sweep's best" is the best grid design that also meets them;
3. reports the sweep's own shaping metric (median over 16 held poses of the LP's
   smallest and largest values per axis) for the optimum and the paper's design,
   to show that it is another quantity.

Writes ``OUTDIR/shaping.json`` and prints a summary.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from csjm_opt._fileio import atomic_write_json
from csjm_opt.design.design_evaluation import evaluate_design
from csjm_opt.design.geometry import GeometryLimits, design_rig
from csjm_opt.design.optimisation.dense_check import certify
from csjm_opt.design.optimisation.runner import design_rig_of, optimise
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.design.optimisation.shaping import dense_angles, shaping_check
from csjm_opt.errors import CsjmError

HERE = Path(__file__).resolve().parent


def score(settings, rig, scale: float) -> dict:
    """Certified shaping range of ``rig`` at range ``scale`` and whether it meets the requirements there."""
    req = settings.requirements
    tilt, tors = req.max_tilt_deg * scale, req.max_torsion_deg * scale
    angles = dense_angles(settings.certify_orientations, tilt, tors, settings.seed + 7919)
    worst, where, _, _, _ = shaping_check(rig, angles, np.asarray(req.loads, float)[0], req.tension_margin_N,
                                          math.radians(tilt), math.radians(tors))
    check = certify(rig, req, scale, req.min_stiffness_Nm_per_rad, req.tension_margin_N,
                    n=settings.certify_orientations, seed=settings.seed + 7919)
    return {"shaping_Nm_per_rad": worst, "at_deg": [math.degrees(v) for v in where], "certified": check.ok,
            "failing": sorted(k for k, (v, _) in check.worst.items() if v < -1e-6)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--sweep", type=Path, default=HERE.parent / "paper_sweep" / "paper_sweep.toml")
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args(argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    from tqdm import tqdm

    try:
        spec, settings = read_optimise_file(args.sweep)
        paper_json = HERE.parent / "optimise_paper" / "optimise_paper.json"
        paper_s = json.loads(paper_json.read_text())["paper_design"]["range"]
        settings = settings.replace(objective="shaping", pareto_with="", requirements=dataclasses.replace(
            settings.requirements, range_scale=paper_s))
        cached = args.outdir / "optimised_shaping.json"
        if cached.is_file():
            doc = json.loads(cached.read_text())
        else:
            t0 = time.perf_counter()
            result = optimise(settings, workers=args.workers, progress=True)
            doc = {**result.as_json(), "seconds": time.perf_counter() - t0}
            atomic_write_json(cached, doc)
    except CsjmError as exc:
        print(f"optimise_paper_shaping: error: {exc}", file=sys.stderr)
        return 2
    best = doc["designs"][0]
    limits = GeometryLimits(settings.requirements.min_hole_spacing_m, 0.0)
    paper_rig = design_rig({}, limits).replace(link=settings.link)
    opt = score(settings, design_rig_of(settings, best["params"]), paper_s)
    paper = score(settings, paper_rig, paper_s)
    axes = {a.name: a for a in spec.axes}
    grid_file = args.outdir / "grid_shaping.json"
    if grid_file.is_file():
        grid = json.loads(grid_file.read_text())
    else:
        t0 = time.perf_counter()
        values = {n: np.asarray(axes[n].values, float) if axes[n].values else np.linspace(axes[n].low, axes[n].high, 15)
                  for n in settings.names}
        grid = {"designs": [], "seconds": 0.0}
        for combo in tqdm(list(itertools.product(*values.values())), desc="grid designs", file=sys.stderr):
            params = dict(zip(values, map(float, combo)))
            try:
                rig = design_rig_of(settings, params)
            except CsjmError as exc:
                grid["designs"].append({"params": params, "invalid": str(exc)})
                continue
            grid["designs"].append({"params": params, **score(settings, rig, paper_s)})
        grid["seconds"] = time.perf_counter() - t0
        atomic_write_json(grid_file, grid)
    valid = [g for g in grid["designs"] if "invalid" not in g]
    held = [g for g in valid if g["certified"]]
    best_any = max(valid, key=lambda g: g["shaping_Nm_per_rad"])
    best_held = max(held, key=lambda g: g["shaping_Nm_per_rad"]) if held else None
    median_paper = evaluate_design({}, dataclasses.replace(spec.settings, base={}))["metrics"]
    median_opt = evaluate_design(best["params"], spec.settings)["metrics"]
    median = {k: (m or {}).get("shaping_range_Nm_per_rad") for k, m in (("paper", median_paper),
                                                                        ("optimum", median_opt))}
    summary = {"range_scale": paper_s, "optimiser": {
        "params": best["params"], "objectives": best["objectives"], "ok": best["ok"], "rounds": best["rounds"],
        "certified": best["certified"], "seconds": doc["seconds"], "evaluations": doc["evaluations"],
        "ipopt_iterations": doc["ipopt_iterations"], "rescored": opt},
        "paper_design": paper, "grid": {"designs": len(grid["designs"]), "valid": len(valid),
                                        "meeting_requirements": len(held), "seconds": grid["seconds"],
                                        "best_any": best_any, "best_meeting_requirements": best_held},
        "sweep_median_metric": median}
    atomic_write_json(args.outdir / "shaping.json", summary, overwrite=True)
    print(f"range scale {paper_s:.4f} (tilt <= {45 * paper_s:.1f} deg, torsion <= {30 * paper_s:.1f} deg)")
    print(f"optimum {best['params']}: certified shaping {best['objectives'].get('shaping'):.4f} N m/rad, "
          f"ok {best['ok']}, {best['rounds']} rounds, {doc['evaluations']} evaluations, {doc['seconds']:.1f} s; "
          f"rescored {opt['shaping_Nm_per_rad']:.4f} at {opt['at_deg']}")
    print(f"paper design: {paper['shaping_Nm_per_rad']:.4f} N m/rad at {paper['at_deg']}, "
          f"meets the requirements {paper['certified']} {paper['failing']}")
    print(f"grid: {len(valid)} valid of {len(grid['designs'])}, {len(held)} meet the requirements "
          f"({grid['seconds']:.0f} s); best of all {best_any['params']} {best_any['shaping_Nm_per_rad']:.4f} "
          f"(meets {best_any['certified']}); best meeting them "
          + (f"{best_held['params']} {best_held['shaping_Nm_per_rad']:.4f}" if best_held else "none"))
    print(f"sweep's median metric (lo, hi per axis): paper {median['paper']}, optimum {median['optimum']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
