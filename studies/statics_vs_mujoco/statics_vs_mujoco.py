"""Study: forward statics against MuJoCo when one cable is lengthened (10-50 mm).

For ``--cases`` random poses (rotation vectors within +-0.25 rad) and loads
(+-0.3 N m per axis) of the paper rig, tensions are planned, one random
cable is lengthened by 10-50 mm, and:

* MuJoCo settles from the planned pose, or the platform falls over (more than
  90 deg away): :func:`csjm_opt.testbed.mujoco.reference.settle`, the tests'
  reference (ball-joint damping ``--damping``, default 1 N m s/rad:
  overdamped; RK4 at 1 ms; then Newton steps on MuJoCo's own net moment
  polish the pose to round-off, and a settled pose must be a stable one);
* ``solve_equilibrium`` from the planned pose, with and without the energy
  descent (``globalise``).

Counts: cases MuJoCo settles, found by the statics (same pose to 1e-6 rad),
found by plain Newton alone; cases that fall over, refused. Also the median
time of a solve on the normal path (all taut, warm start at the answer) with
and without globalisation enabled (it must not slow that path).

Run: ``python -m studies.statics_vs_mujoco.statics_vs_mujoco [--cases N] [--seed S] [--damping C]``.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.testbed.mujoco.reference import settle


def angle(Ra, Rb):
    return float(np.linalg.norm(so3.log(Ra.T @ Rb)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--damping", type=float, default=1.0, help="ball-joint damping in MuJoCo (N m s/rad)")
    args = ap.parse_args(argv)
    rig, rng = co.paper_rig(), np.random.default_rng(args.seed)
    counts = dict(settled=0, found=0, plain_found=0, plain_wrong_pose=0, fell=0, refused=0)
    angles = []
    for _ in range(args.cases):
        R, tau = so3.exp(rng.uniform(-0.25, 0.25, 3)), rng.uniform(-0.3, 0.3, 3)
        l = co.rest_lengths_for(rig, R, co.plan_tensions(rig, R, tau).tensions_N)
        l[rng.integers(6)] += rng.uniform(0.010, 0.050)
        R_mj, _, settled = settle(rig, l, R, tau, damping=args.damping)
        if settled:
            counts["settled"] += 1
            angles.append(np.degrees(angle(R, R_mj)))
            try:
                counts["found"] += angle(co.solve_equilibrium(rig, l, tau, R_init=R).R, R_mj) <= 1e-6
            except co.NoEquilibrium:
                pass
            try:
                ok = angle(co.solve_equilibrium(rig, l, tau, R_init=R, globalise=False).R, R_mj) <= 1e-6
                counts["plain_found"] += ok
                counts["plain_wrong_pose"] += not ok
            except co.NoEquilibrium:
                pass
        else:
            counts["fell"] += 1
            try:
                co.solve_equilibrium(rig, l, tau, R_init=R)
            except co.NoEquilibrium:
                counts["refused"] += 1
    print(f"{args.cases} cases: MuJoCo settles in {counts['settled']} (0-{max(angles):.0f} deg from the start), "
          f"falls over (or finds no stable rest) in {counts['fell']}")
    print(f"settled: forward statics finds the same pose in {counts['found']}/{counts['settled']}; plain Newton "
          f"alone in {counts['plain_found']} (wrong pose in {counts['plain_wrong_pose']}, refused in "
          f"{counts['settled'] - counts['plain_found'] - counts['plain_wrong_pose']})")
    print(f"fell over: refused (NoEquilibrium) in {counts['refused']}/{counts['fell']}")
    # the normal path: all taut, warm start near the answer
    R, tau = so3.exp([0.1, -0.05, 0.08]), np.array([0.2, -0.1, 0.05])
    l = co.rest_lengths_for(rig, R, co.plan_tensions(rig, R, tau).tensions_N)
    R0 = R @ so3.exp([1e-3, -2e-3, 1e-3])
    times = {}
    for g in (False, True):
        solver = co.model.EquilibriumSolver(rig, globalise=g)
        solver.solve(l, tau, R0)
        ts = []
        for _ in range(2000):
            t0 = time.perf_counter()
            solver.solve(l, tau, R0)
            ts.append(time.perf_counter() - t0)
        times[g] = float(np.median(ts))
    print(f"normal path (EquilibriumSolver.solve, warm start 2.4 mrad away): {1e6 * times[True]:.1f} us with "
          f"globalisation enabled, {1e6 * times[False]:.1f} us without (ratio {times[True] / times[False]:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
