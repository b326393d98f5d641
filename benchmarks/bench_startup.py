"""Start-up time of the commands: ``csjm plan`` and every ``csjm <cmd> --help``, beside ``python -c pass``.

Usage: python benchmarks/bench_startup.py [--repeat 5] [--json OUT.json]

Each command runs ``--repeat`` times in a fresh process (``python -m csjm_opt.cli``, the code of
this checkout); the median wall time is printed beside the interpreter's own start-up, measured in
the same run. Targets (issue 30, on the quiet 2-core box): ``csjm plan --rotvec 0.1 -0.05 0``
within 0.6 s, every ``--help`` within 0.4 s.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ["plan", "stiffness", "demo", "shape", "preprocess", "identify", "paper", "plan-experiment",
            "diagnose", "simulate", "sweep", "optimise", "report", "export-mjcf", "codegen"]


def _time(argv: list[str], repeat: int) -> tuple[float, list[float]]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(argv, env=env, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), times


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", default=None, help="write the medians as JSON")
    a = ap.parse_args(argv)
    csjm = [sys.executable, "-m", "csjm_opt.cli"]
    cases = {"python -c pass": [sys.executable, "-c", "pass"],
             "import csjm_opt": [sys.executable, "-c", "import csjm_opt"],
             "csjm --help": csjm + ["--help"],
             "csjm plan --rotvec 0.1 -0.05 0": csjm + ["plan", "--rotvec", "0.1", "-0.05", "0"]}
    cases.update({f"csjm {c} --help": csjm + [c, "--help"] for c in COMMANDS})
    _time(csjm + ["plan", "--rotvec", "0.1", "-0.05", "0"], 1)          # warm the numba cache once
    out = {}
    base = None
    print(f"{'command':40s} {'median s':>9s} {'- python':>9s}   target   (load {os.getloadavg()[0]:.1f})")
    for name, cmd in cases.items():
        med, _ = _time(cmd, a.repeat)
        base = med if base is None else base
        target = 0.4 if name.endswith("--help") else 0.6 if name.startswith("csjm plan ") else None
        flag = "" if target is None else ("  ok" if med <= target else "  OVER")
        print(f"{name:40s} {med:9.3f} {med - base:9.3f}   {'' if target is None else f'{target:.1f}'}{flag}")
        out[name] = med
    if a.json:
        Path(a.json).write_text(json.dumps(out, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
