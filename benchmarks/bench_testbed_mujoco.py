"""Benchmark: time to simulate one 198-row diagnosis log on each testbed plant.

Run: ``python benchmarks/bench_testbed_mujoco.py [--repeats N] [--effects NAME ...] [--json PATH]``.

A log is 22 load cycles of 9 rows (``simulate_experiment(rig, 22, ..., steps=4)``,
cycles persisting: each starts where the previous one settled) on the paper
rig, with no effect or one effect at severity 3. Reported per effect: the
median wall time over ``--repeats`` logs (same designs for both plants) on the
quasi-static plant (the baseline, measured in the same run) and on the MuJoCo
plant, and their ratio. Timings on a shared machine are noisy: compare the
ratios.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model.rig import paper_rig
from csjm_opt.testbed import make_plant, simulate_experiment

DEFAULT_EFFECTS = ("none", "coulomb_friction", "link_compliance", "cable_hardening", "joint_friction")


def time_log(rig, effect: str, plant: str, seed: int) -> float:
    """Wall time (s) of one 198-row log."""
    truth = make_plant(rig, effect, 3.0, np.random.default_rng(seed), plant=plant)
    t0 = time.perf_counter()
    log = simulate_experiment(rig, 22, np.random.default_rng(seed), effect=truth, steps=4,
                              noise=InstrumentNoise.paper())
    seconds = time.perf_counter() - t0
    assert len(log) == 198
    return seconds


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--effects", nargs="+", default=list(DEFAULT_EFFECTS))
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    rig = paper_rig()
    time_log(rig, "none", "quasi-static", 0)              # warm-up (compiled kernels, CasADi model)
    time_log(rig, "none", "mujoco", 0)
    out = {}
    print(f"198-row log, paper rig, median of {args.repeats} (s):")
    print(f"  {'effect':<20s} {'quasi-static':>12s} {'mujoco':>10s} {'ratio':>8s}")
    for effect in args.effects:
        qs = float(np.median([time_log(rig, effect, "quasi-static", s) for s in range(1, args.repeats + 1)]))
        mj = float(np.median([time_log(rig, effect, "mujoco", s) for s in range(1, args.repeats + 1)]))
        out[effect] = {"quasi_static_s": qs, "mujoco_s": mj, "ratio": mj / qs}
        print(f"  {effect:<20s} {qs:12.2f} {mj:10.2f} {mj / qs:8.1f}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
