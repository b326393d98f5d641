"""Benchmark: the MuJoCo testbed plant's time per row, by effect.

Run: ``python benchmarks/bench_mujoco_plant.py [--rigs 0 1] [--cycles 4] [--effects NAME ...]
[--noslip 1000 ...] [--json PATH]``.

Each case is a carried run (cycles starting where the previous one settled) of ``--cycles``
designed load cycles (9 rows each) on random rig ``r`` (``random_rig(default_rng([1234, r]))``,
the rigs of the diagnosis studies), one effect set at severity 3, then one more cycle of the
same rows with dead weights (the rows a suggested experiment adds: their moment follows the
pose, so the engine updates forces every step). Per row: wall time, simulated time, and
whether the wait for rest reached ``max_settle_s`` (recorded as an unsettled row, see
:class:`~csjm_opt.testbed.mujoco.plant.MujocoRow`). Reported per effect set: median and 90th
percentile of the wall time per row, median simulated seconds per row, rows that reached the
bound, and rows the plant refused (:class:`~csjm_opt.errors.NoEquilibrium`). ``--noslip``
and ``--travel-tol`` run each case with each number of noslip iterations and each
``rest_travel_tol_rad`` (0: off, the wait ends on the speed alone, as before that test
existed); the largest pose difference (rad) from the first setting is printed.

Timings on a shared machine are noisy: compare medians and ratios measured in the same run.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from csjm_opt import so3
from csjm_opt.errors import NoEquilibrium
from csjm_opt.testbed import design_cycles, make_plant, random_rig
from csjm_opt.testbed.mujoco.plant import as_mujoco

DEFAULT_EFFECTS = ("none", "coulomb_friction", "friction", "joint_friction",
                   "cable_hardening+link_compliance", "link_compliance+coulomb_friction")


def inputs(rig, cycles: int, seed: int) -> dict:
    """Rows of ``cycles`` designed cycles plus one cycle of the same first-cycle rows with dead weights."""
    cs = design_cycles(rig, cycles, np.random.default_rng(seed))
    cyc = np.concatenate([np.full(len(c.alphas), i) for i, c in enumerate(cs)])
    l = np.concatenate([np.repeat(c.rest_lengths_m[None], len(c.alphas), 0) for c in cs])
    tau = np.concatenate([c.tau_ext_A_Nm for c in cs])
    R0 = np.concatenate([np.repeat(c.R_ref[None], len(c.alphas), 0) for c in cs])
    c = cs[0]
    m = len(c.alphas)
    # dead weights: 0-0.3 kg at 5 cm from O, replacing the fixed moments of the first cycle
    rng = np.random.default_rng(seed + 1)
    mr = np.r_[np.zeros((len(cyc), 3)), rng.uniform(0.0, 0.3, (m, 1)) * rng.normal(size=(m, 3)) * 0.05 / np.sqrt(3)]
    return {"l": np.r_[l, np.repeat(c.rest_lengths_m[None], m, 0)], "tau": np.r_[tau, np.zeros((m, 3))],
            "cycle": np.r_[cyc, np.full(m, cycles)], "R0": np.r_[R0, np.repeat(c.R_ref[None], m, 0)], "mr": mr}


def run_case(rig, effects: list[str], settings: dict, rows: dict, seed: int) -> dict:
    """Time one carried run; per-row wall times from the plant's progress callback."""
    base = make_plant(rig, effects, 3.0, np.random.default_rng(seed))
    mp = as_mujoco(base, **settings)
    stamps = [time.perf_counter()]
    try:
        out = mp.respond_rows(rows["l"], rows["tau"], rows["cycle"], rows["R0"], rows["mr"],
                              progress=lambda k: stamps.append(time.perf_counter()))
    except (NoEquilibrium, ValueError) as exc:      # (ValueError: MuJoCo 4's sparse ten_J in older code)
        return {"error": f"{type(exc).__name__}: {exc}", "wall_s": np.diff(stamps).tolist()}
    # a row whose wait for rest reached the bound (older code has no ``settled`` flag: its wait length shows it)
    bound = [not r.settled if hasattr(r, "settled") else r.seconds_simulated >= 0.999 * mp.max_settle_s for r in out]
    return {"wall_s": np.diff(stamps).tolist(), "sim_s": [r.seconds_simulated for r in out],
            "unsettled": int(sum(bound)),
            "R": [r.R_tool.tolist() for r in out]}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rigs", nargs="+", type=int, default=[0, 1])
    ap.add_argument("--cycles", type=int, default=4)
    ap.add_argument("--effects", nargs="+", default=list(DEFAULT_EFFECTS))
    ap.add_argument("--noslip", nargs="+", type=int, default=[1000])
    ap.add_argument("--travel-tol", nargs="+", type=float, default=[None],
                    help="rest_travel_tol_rad settings (0: off; default: the plant's)")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    out: dict = {}
    print(f"MuJoCo plant, {args.cycles} cycles + 1 dead-weight cycle per rig, rigs {args.rigs}")
    print(f"  {'effects':<34s} {'noslip':>6s} {'travel':>7s} {'median ms':>10s} {'p90 ms':>8s} {'max ms':>8s} "
          f"{'sim s':>6s} {'rows':>5s} {'bound':>5s} {'refused':>7s} {'vs first':>9s}")
    for eff in args.effects:
        effects = [] if eff == "none" else eff.split("+")
        res_by_noslip: dict = {}
        settings = [(ns, tt) for ns in args.noslip for tt in args.travel_tol]
        for ns, tt in settings:
            opts = {"noslip_iterations": ns} if tt is None else {"noslip_iterations": ns, "rest_travel_tol_rad": tt}
            walls, sims, unsettled, refused, R = [], [], 0, 0, {}
            for r in args.rigs:
                rig, _ = random_rig(np.random.default_rng([1234, r]))
                rows = inputs(rig, args.cycles, 100 + r)
                res = run_case(rig, effects, opts, rows, 200 + r)
                walls += res["wall_s"]
                if "error" in res:
                    refused += 1
                    continue
                sims += res["sim_s"]
                unsettled += res["unsettled"]
                R[r] = np.asarray(res["R"])
            res_by_noslip[ns, tt] = R
            first = res_by_noslip[settings[0]]
            diff = max((float(so3.angle_between(R[r], first[r]).max()) for r in R if r in first), default=np.nan)
            w = np.asarray(walls) * 1e3
            if not len(w):            # refused at the first row
                w = np.full(1, np.nan)
            rec = {"median_ms": float(np.median(w)), "p90_ms": float(np.percentile(w, 90)), "max_ms": float(w.max()),
                   "median_sim_s": float(np.median(sims)) if sims else float("nan"), "rows": len(w),
                   "unsettled": unsettled, "refused": refused, "max_pose_diff_rad": diff}
            out[f"{eff}@{ns}@{tt}"] = rec
            label = "plant" if tt is None else f"{tt:.0e}"
            print(f"  {eff:<34s} {ns:6d} {label:>7s} {rec['median_ms']:10.1f} {rec['p90_ms']:8.1f} "
                  f"{rec['max_ms']:8.1f} "
                  f"{rec['median_sim_s']:6.2f} {len(w):5d} {unsettled:5d} {refused:7d} {diff:9.1e}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
