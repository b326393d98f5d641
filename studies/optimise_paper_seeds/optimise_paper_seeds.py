"""The budgeted front in the sweep's metrics over start sets: how often it dominates the sweep's front.

Usage::

    python -m studies.optimise_paper_seeds.optimise_paper_seeds OUT.jsonl --seeds 20-29
        [--sweep studies/paper_sweep/paper_sweep.toml]

Per start set (the Halton seed of the space-filling starts) runs ``sweep_front`` with
``--max-evaluations 22`` (a tenth of the sweep) on the paper's design space and appends
one JSON line: seed, hypervolume of the scored designs (workspace fraction x minimum
stiffness above (0, 0)), evaluations used, when it first reached the sweep front's
hypervolume, and the scored designs. Seeds already in OUT.jsonl are skipped. The sweep's
hypervolume is recomputed in the run (the 225-design grid, about 4 s).
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

from csjm_opt.design.optimisation.front import hypervolume, sweep_front  # noqa: E402
from csjm_opt.design.optimisation.settings import read_optimise_file  # noqa: E402
from csjm_opt.design.sweep.runner import run_sweep  # noqa: E402
from studies.optimise_paper.optimise_paper import BUDGET  # noqa: E402


def _pts(records: list[dict]) -> np.ndarray:
    return np.array([(r["workspace_fraction"] or 0.0, r["min_stiffness_Nm_per_rad"] or 0.0) for r in records
                     if r.get("status") == "ok"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--seeds", default="20-29", help="FIRST-LAST")
    parser.add_argument("--sweep", type=Path, default=HERE.parent / "paper_sweep" / "paper_sweep.toml")
    args = parser.parse_args(argv)
    spec, settings = read_optimise_file(args.sweep)
    with tempfile.TemporaryDirectory() as tmp:
        hv_sweep = hypervolume(_pts(run_sweep(spec, Path(tmp) / "s.jsonl", workers=1, progress=False).records))
    done = {json.loads(line)["seed"] for line in args.out.read_text().splitlines()} if args.out.is_file() else set()
    first, last = (int(v) for v in args.seeds.split("-"))
    for seed in range(first, last + 1):
        if seed in done:
            continue
        res = sweep_front(settings.replace(seed=seed), spec.settings, max_evaluations=BUDGET)
        recs = res.records
        reach = next((r["evaluations_used"] for k, r in enumerate(recs) if hypervolume(_pts(recs[:k + 1])) >= hv_sweep),
                     None)
        row = {"seed": seed, "hypervolume": hypervolume(_pts(recs)), "sweep_hypervolume": hv_sweep,
               "dominates": hypervolume(_pts(recs)) >= hv_sweep, "evaluations": res.evaluations,
               "twin_evaluations": res.twin_evaluations, "first_dominating_at_evaluations": reach,
               "scored": [[r["params"][n] for n in settings.names] + [r["workspace_fraction"],
                          r["min_stiffness_Nm_per_rad"], r["evaluations_used"]] for r in recs]}
        with args.out.open("a") as fh:
            fh.write(json.dumps(row) + "\n")
        print(f"seed {seed}: hypervolume {row['hypervolume']:.4f} ({'dominates' if row['dominates'] else 'misses'}), "
              f"first at {reach}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
