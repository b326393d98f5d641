"""How long ``csjm plan-experiment`` takes (wall and CPU seconds, medians of a few fresh processes).

Usage::

    python benchmarks/bench_plan_experiment.py [--repeat 3] [--budget 60]

The baseline, measured in the same session, is ``csjm plan --rig paper --rotvec 0 0 0`` (one tension
plan: the cost of starting the command line, importing and compiling). Budget (issue 21): the
planned experiment for 60 loads within 60 s on 2 cores.
"""

from __future__ import annotations

import argparse
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def run_once(cmd: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "csjm_opt.cli", *cmd], check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--budget", type=int, default=60)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        out = str(Path(tmp) / "p.csv")
        plan = [run_once(["plan-experiment", "--budget", str(args.budget), "-o", out, "--force"])
                for _ in range(args.repeat)]
        base = [run_once(["plan", "--rotvec", "0", "0", "0"]) for _ in range(args.repeat)]
    pw, pc = np.median(plan, axis=0)
    bw, bc = np.median(base, axis=0)
    print(f"plan-experiment --budget {args.budget}: wall {pw:6.2f} s, CPU {pc:6.2f} s (medians of {args.repeat})")
    print(f"baseline csjm plan:              wall {bw:6.2f} s, CPU {bc:6.2f} s")
    print(f"ratio (wall): {pw / bw:.1f}x the baseline; budget 60 s: {'met' if pw < 60 else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
