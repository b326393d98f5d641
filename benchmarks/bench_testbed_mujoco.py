"""Benchmark: time to simulate one 198-row diagnosis log on each testbed plant.

Run: ``python benchmarks/bench_testbed_mujoco.py [--repeats N] [--effects NAME ...] [--static-friction-ratio R]
[--json PATH]``.

A log is 22 load cycles of 9 rows (``simulate_experiment(rig, 22, ..., steps=4)``,
cycles persisting: each starts where the previous one settled) on the paper
rig, with no effect or one effect at severity 3. Reported per effect: the
median wall time over ``--repeats`` logs (same designs for both plants) on the
quasi-static plant (the baseline, measured in the same run) and on the MuJoCo
plant, and their ratio; and the MuJoCo plant with step loading (each load hung at once and
settled by the rig's dynamics, static over sliding friction ``--static-friction-ratio``, default
1.5) in rows per second beside the default ramped loading's (target: 2 rows/s with friction);
and the quasi-static plant with the same step loading (its overdamped path, ``qs step``).
Timings on a shared machine are noisy: compare the ratios (the load average is printed).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model.rig import paper_rig
from csjm_opt.testbed import make_plant, simulate_experiment

DEFAULT_EFFECTS = ("none", "coulomb_friction", "link_compliance", "cable_hardening", "joint_friction")


def time_log(rig, effect: str, plant: str, seed: int, **options) -> float:
    """Wall time (s) of one 198-row log (``options``: the MuJoCo plant's loading and friction ratio)."""
    truth = make_plant(rig, effect, 3.0, np.random.default_rng(seed), plant=plant, **options)
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
    ap.add_argument("--static-friction-ratio", type=float, default=1.5)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    step = {"loading": "step", "static_friction_ratio": args.static_friction_ratio}
    rig = paper_rig()
    time_log(rig, "none", "quasi-static", 0)              # warm-up (compiled kernels, CasADi model)
    time_log(rig, "none", "mujoco", 0)
    out = {}
    print(f"198-row log, paper rig, median of {args.repeats} (s; rows/s of the MuJoCo plant ramped and step-loaded, "
          f"static friction x{args.static_friction_ratio:g}; load average {os.getloadavg()[0]:.1f}):")
    print(f"  {'effect':<20s} {'quasi-static':>12s} {'mujoco':>10s} {'ratio':>8s} {'step':>10s} {'rows/s':>8s} "
          f"{'step rows/s':>12s} {'qs step':>8s} {'qs step/ramp':>13s}")
    for effect in args.effects:
        seeds = range(1, args.repeats + 1)
        qs = float(np.median([time_log(rig, effect, "quasi-static", s) for s in seeds]))
        mj = float(np.median([time_log(rig, effect, "mujoco", s) for s in seeds]))
        st = float(np.median([time_log(rig, effect, "mujoco", s, **step) for s in seeds]))
        qs_st = float(np.median([time_log(rig, effect, "quasi-static", s, **step) for s in seeds]))
        out[effect] = {"quasi_static_s": qs, "mujoco_s": mj, "ratio": mj / qs, "mujoco_step_s": st,
                       "rows_per_s": 198 / mj, "step_rows_per_s": 198 / st, "quasi_static_step_s": qs_st,
                       "quasi_static_step_ratio": qs_st / qs}
        print(f"  {effect:<20s} {qs:12.2f} {mj:10.2f} {mj / qs:8.1f} {st:10.2f} {198 / mj:8.2f} {198 / st:12.2f} "
              f"{qs_st:8.2f} {qs_st / qs:13.1f}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
