"""Planner speed for m = 4, 6, 8, 12 cables, and m = 6 against the code before the m-cable change.

Run: python benchmarks/bench_cables.py [--baseline DIR] [--poses 200000] [--calls 200000] [--repeats 2]

For each m, in a fresh process: one-pose ``plan_tensions`` (median of 3000 calls, us), a batch of
``--poses`` poses along a trajectory (``plan_tensions_batch``, median of 5, poses/s) and the
generated C planner (``--calls`` cold random feasible cases timed inside C: p50 and p99, us).
m = 6 is the paper rig; the others are pattern rigs (evenly spaced platform holes, base holes
twisted +-35 deg alternately, as tests/test_n_cables.py). ``--baseline DIR`` (e.g. a checkout of
main before the change) measures m = 6 with ``PYTHONPATH=DIR`` too; baseline and current runs
alternate ``--repeats`` times so both see the same machine load, and the table gives medians.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def pattern_rig(m: int):
    import csjm_opt as co

    if m == 6:
        return co.paper_rig()
    platform = np.arange(m) * 360.0 / m
    twist = 35.0 * np.where(np.arange(m) % 2 == 0, 1.0, -1.0)
    return co.Rig.from_dict({
        "geometry": {"pattern": {"count": m, "platform_radius": 0.06, "base_radius": 0.08, "platform_height": 0.08,
                                 "base_height": -0.08, "platform_angles_deg": platform.tolist(),
                                 "base_angles_deg": (platform + twist).tolist()}},
        "cables": {"stiffness": [4600.0] * m, "t_min": 5.0, "t_max": 150.0},
        "platform": {"mass": 0.45, "com": [0.0, 0.0, 0.081], "gravity": [0.0, 0.0, -9.81]}})


def measure(m: int, n_poses: int, n_calls: int) -> dict:
    """The three timings of one m in this process (the code on ``sys.path``)."""
    import csjm_opt as co
    from csjm_opt.codegen import SOLVED, generate_c, load

    rig = pattern_rig(m)
    R = co.so3.exp([0.2, -0.1, 0.05])
    tau = np.array([0.4, -0.25, 0.15])
    for _ in range(50):
        co.plan_tensions(rig, R, tau)
    times = np.empty(3000)
    for i in range(times.size):
        t0 = time.perf_counter()
        co.plan_tensions(rig, R, tau)
        times[i] = time.perf_counter() - t0
    t = np.linspace(0, 4 * np.pi, n_poses)
    Rs = co.so3.exp(np.column_stack([0.3 * np.sin(t), 0.3 * np.cos(1.3 * t), 0.2 * np.sin(0.7 * t)]))
    taus = np.column_stack([0.6 * np.sin(3 * t), 0.6 * np.cos(2 * t), 0.2 * np.sin(t)])
    co.plan_tensions_batch(rig, Rs[:5000], taus[:5000])
    batch = []
    for _ in range(5):
        t0 = time.perf_counter()
        co.plan_tensions_batch(rig, Rs, taus)
        batch.append(time.perf_counter() - t0)
    rng = np.random.default_rng(0)
    with tempfile.TemporaryDirectory() as d:
        generate_c(rig, d)
        lib = load(d)
        Rc = co.so3.random_rotations(n_calls, rng, max_angle=0.5)
        tc = rng.normal(size=(n_calls, 3)) * 0.3
        ok = lib.plan_many(Rc, tc).status == SOLVED
        ns, _, _ = lib.time_plan_calls(Rc[ok], tc[ok])
    return {"m": m, "plan_us": 1e6 * float(np.median(times)), "batch_poses_per_s": n_poses / float(np.median(batch)),
            "c_p50_us": float(np.percentile(ns, 50)) / 1e3, "c_p99_us": float(np.percentile(ns, 99)) / 1e3,
            "c_calls": int(ok.sum())}


def run_child(path: Path, m: int, args) -> dict:
    env = dict(os.environ, PYTHONPATH=str(path))
    out = subprocess.run([sys.executable, __file__, "--child", str(m), "--poses", str(args.poses), "--calls",
                          str(args.calls)], env=env, cwd=str(path), capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--baseline", default=None, help="checkout of the code before the change (m = 6 only)")
    ap.add_argument("--poses", type=int, default=200_000)
    ap.add_argument("--calls", type=int, default=200_000)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--child", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child is not None:
        print(json.dumps(measure(args.child, args.poses, args.calls)))
        return
    runs: dict[str, list[dict]] = {}
    for _ in range(args.repeats):
        if args.baseline:
            runs.setdefault("baseline m=6", []).append(run_child(Path(args.baseline), 6, args))
        for m in (4, 6, 8, 12):
            runs.setdefault(f"m={m}", []).append(run_child(ROOT, m, args))
    keys = ("plan_us", "batch_poses_per_s", "c_p50_us", "c_p99_us")
    med = {name: {k: float(np.median([r[k] for r in rs])) for k in keys} for name, rs in runs.items()}
    print(f"{'':14s} {'plan (us)':>10s} {'batch (poses/s)':>16s} {'C p50 (us)':>11s} {'C p99 (us)':>11s}"
          f"   (medians of {args.repeats} runs)")
    for name, v in med.items():
        print(f"{name:14s} {v['plan_us']:10.2f} {v['batch_poses_per_s']:16,.0f} {v['c_p50_us']:11.3f} "
              f"{v['c_p99_us']:11.3f}")
    six = med["m=6"]
    if args.baseline:
        base = med["baseline m=6"]
        print(f"m = 6 now / before: plan {six['plan_us'] / base['plan_us']:.2f}x time, batch "
              f"{six['batch_poses_per_s'] / base['batch_poses_per_s']:.2f}x throughput, C p99 "
              f"{six['c_p99_us'] / base['c_p99_us']:.2f}x")
    twelve = med["m=12"]
    print(f"m = 12 / m = 6: plan {twelve['plan_us'] / six['plan_us']:.2f}x, batch time "
          f"{six['batch_poses_per_s'] / twelve['batch_poses_per_s']:.2f}x, "
          f"C p99 {twelve['c_p99_us'] / six['c_p99_us']:.2f}x  (goal: within 3x)")


if __name__ == "__main__":
    main()
