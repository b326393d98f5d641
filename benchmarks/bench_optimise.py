"""The front in the sweep's own metrics by optimisation, against the sweep of the same space, in the same run.

The optimiser: ``sweep_front`` (``csjm optimise studies/paper_sweep/paper_sweep.toml --sweep-front
--max-evaluations 22``, a tenth of the sweep): smooth twins of the workspace
fraction and the minimum stiffness on the sweep's 1,000 sample orientations,
trust-region steps on their exact quadratic models, every design scored by the
sweep's evaluator; its time to a front as good as the sweep's is when the
scored designs' hypervolume first reaches the sweep's. The sweep: the same file's 225-design grid. Both are
scored in the sweep's metrics (workspace fraction x minimum stiffness,
hypervolume above (0, 0)); the sweep's time to an equally good front is its
whole grid's time when its front is not better (a grid reaches its front only
when its last design is done). Medians of ``--repeats`` fresh runs. With
``--range-front`` the range x stiffness optimisation (``optimise``) is timed too.
Usage::

    python benchmarks/bench_optimise.py [--repeats 3] [--workers 1] [--range-front]
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
#: A tenth of the sweep's 225 designs.
BUDGET = 22

from csjm_opt.design.optimisation import problem as optimise_problem  # noqa: E402
from csjm_opt.design.optimisation.front import hypervolume, sweep_front  # noqa: E402
from csjm_opt.design.optimisation.runner import optimise  # noqa: E402
from csjm_opt.design.optimisation.settings import read_optimise_file  # noqa: E402
from csjm_opt.design.sweep.runner import run_sweep  # noqa: E402


def _points(records: list[dict]) -> np.ndarray:
    return np.array([(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0) for r in records
                     if r.get("status") == "ok"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--workers", type=int, default=1, help="processes of the sweep")
    parser.add_argument("--range-front", action="store_true", help="also time optimise() (range x stiffness)")
    args = parser.parse_args()

    spec, settings = read_optimise_file(HERE.parent / "studies" / "paper_sweep" / "paper_sweep.toml")
    t_front, t_sweep, t_range, evals, hv_f, hv_s, runs = [], [], [], [], [], [], []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        res = sweep_front(settings, spec.settings, max_evaluations=BUDGET)
        t_front.append(time.perf_counter() - t0)
        evals.append(res.evaluations)
        hv_f.append(hypervolume(_points(res.records)))
        runs.append(res.records)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            sweep = run_sweep(spec, Path(tmp) / "s.jsonl", workers=args.workers, progress=False)
            t_sweep.append(time.perf_counter() - t0)
        hv_s.append(hypervolume(_points(sweep.records)))
        if args.range_front:
            optimise_problem.clear_cache()
            t0 = time.perf_counter()
            optimise(settings, workers=1, progress=False)
            t_range.append(time.perf_counter() - t0)
    f, s = statistics.median(t_front), statistics.median(t_sweep)
    hf, hs = statistics.median(hv_f), statistics.median(hv_s)
    print(f"sweep-metric front by optimisation, --max-evaluations {BUDGET} (median of {args.repeats}): {f:8.1f} s, "
          f"{statistics.median(evals):.0f} design evaluations, hypervolume {hf:.5g}")
    reach = [next((r["elapsed_s"] for k, r in enumerate(recs) if hypervolume(_points(recs[:k + 1])) >= hs), None)
             for recs in runs]
    if all(t is not None for t in reach):
        at = statistics.median(reach)  # type: ignore[type-var]
        print(f"optimisation's time to a front as good as the sweep's (median): {at:8.1f} s "
              f"(optimisation / sweep = {at / s:.2f})")
    else:
        print(f"the optimised front did not reach the sweep's hypervolume in {reach.count(None)} of {len(reach)} runs")
    print(f"sweep, {len(sweep.records)} designs ({args.workers} workers, median of {args.repeats}): {s:8.1f} s, "
          f"hypervolume {hs:.5g}")
    if hs <= hf:
        print(f"the sweep's front is not better than the optimised one: its time to an equally good front is at "
              f"least its whole grid, {s:.1f} s (optimisation / sweep = {f / s:.2f})")
    else:
        print(f"the sweep's front is better (hypervolume {hs:.5g} > {hf:.5g}); optimisation / sweep = {f / s:.2f}")
    if t_range:
        print(f"range x stiffness optimise() (1 process): {statistics.median(t_range):8.1f} s")


if __name__ == "__main__":
    main()
