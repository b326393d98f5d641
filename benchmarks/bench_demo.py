"""How long ``csjm demo`` takes, quick and full, per step (wall and CPU seconds; medians of a few runs).

Usage::

    python benchmarks/bench_demo.py [--repeat 3]

Each run is a fresh process (``csjm demo --json -``), so import and compile
caches count as a user sees them (numba caches warm after the first run ever).
The ratio quick/full is measured in the same session. Budgets: quick < 20 s,
full < 60 s on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def run_once(quick: bool) -> tuple[float, float, dict]:
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "csjm_opt.cli", "demo", "--out", str(Path(tmp) / "r"), "--json", "-"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        out = subprocess.run(cmd + (["--quick"] if quick else []), check=True, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, json.loads(out.stdout)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args(argv)
    results = {}
    for quick in (True, False):
        runs = [run_once(quick) for _ in range(args.repeat)]
        steps = {name: float(np.median([r[2][name]["seconds"] for r in runs])) for name in runs[0][2]}
        results["quick" if quick else "full"] = (float(np.median([r[0] for r in runs])),
                                                 float(np.median([r[1] for r in runs])), steps)
    for label, (wall, cpu, steps) in results.items():
        print(f"{label:5s}: wall {wall:6.1f} s, CPU {cpu:6.1f} s (medians of {args.repeat})")
        for name, sec in steps.items():
            print(f"        {name:40s} {sec:6.2f} s")
    print(f"quick / full wall-time ratio: {results['quick'][0] / results['full'][0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
