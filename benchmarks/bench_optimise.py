"""One optimisation on the paper's design space against the sweep of the same space, in the same run.

The optimiser: ``optimise`` on ``studies/paper_sweep.toml`` with its defaults (4
multi-starts on 2 worker processes, the range objective, a 4-point front against
stiffness, certification on 10,000 orientations per design). The sweep: the
same file's 225-design grid on 2 worker processes, then (to put its designs on
the optimiser's objectives, which is what an equally good front needs) each
valid design's largest guaranteed range scale by bisection
(``studies/optimise_paper.py``'s mapping, 1,000 orientations per step). Both
medians of ``--repeats`` fresh runs (solver caches cleared). Usage::

    python benchmarks/bench_optimise.py [--repeats 3] [--workers 2] [--skip-mapping]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "studies"))

from csjm_opt.design import optimise_problem  # noqa: E402
from csjm_opt.design.geometry import GeometryLimits, design_rig  # noqa: E402
from csjm_opt.design.optimisation import optimise  # noqa: E402
from csjm_opt.design.optimise_settings import read_optimise_file  # noqa: E402
from csjm_opt.design.sweep import run_sweep  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--opt-workers", type=int, default=None,
                        help="processes for the optimiser's starts (default: --workers)")
    parser.add_argument("--skip-mapping", action="store_true")
    args = parser.parse_args()
    from optimise_paper import guaranteed

    spec, settings = read_optimise_file(HERE.parent / "studies" / "paper_sweep.toml")
    t_opt, t_sweep, t_map, evals = [], [], [], []
    for _ in range(args.repeats):
        optimise_problem.clear_cache()
        t0 = time.perf_counter()
        res = optimise(settings, workers=args.opt_workers or args.workers, progress=False)
        t_opt.append(time.perf_counter() - t0)
        evals.append(res.evaluations)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            sweep = run_sweep(spec, Path(tmp) / "s.jsonl", workers=args.workers, progress=False)
            t_sweep.append(time.perf_counter() - t0)
        if not args.skip_mapping:
            limits = GeometryLimits(settings.requirements.min_hole_spacing_m, 0.0)
            t0 = time.perf_counter()
            for r in sweep.records:
                if r["status"] == "ok":
                    rig = design_rig({**settings.base, **r["params"]}, limits).replace(link=settings.link)
                    guaranteed(settings, rig, settings.requirements.min_stiffness_Nm_per_rad)
            t_map.append(time.perf_counter() - t0)
    o, s = statistics.median(t_opt), statistics.median(t_sweep)
    print(f"optimise (paper space, {args.opt_workers or args.workers} workers, median of {args.repeats}): {o:8.1f} s, "
          f"{statistics.median(evals):.0f} design evaluations")
    print(f"sweep, 225 designs ({args.workers} workers, median of {args.repeats}):      {s:8.1f} s  "
          f"(optimise / sweep = {o / s:.2f})")
    if t_map:
        m = statistics.median(t_map)
        print(f"sweep + mapping to guaranteed range (1 process for the mapping):  {s + m:8.1f} s  "
              f"(optimise / (sweep + mapping) = {o / (s + m):.2f})")


if __name__ == "__main__":
    main()
