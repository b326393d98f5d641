"""Generated C planner: time per plan call inside C (p50, p99, max) against the Python planner (same run).

Run: python benchmarks/bench_codegen.py [--calls 1000000] [--python-calls 3000] [--dir DIR]

Each C call is timed with clock_gettime(CLOCK_MONOTONIC) around csjm_plan_tensions_R, in a
C loop (csjm_host.c), so the figures hold the call only (the cost of a pair of clock readings
is printed; it is included in every figure). Cases, on the paper rig:

* cold: random poses (up to 46 deg) and feasible loads, each call from a cold start;
* warm: a smooth 1 kHz trajectory, each call warm-started from the previous step;
* infeasible: random loads outside the wrench-feasible set (the distance is computed);
* fallback: max_iter = 1 forces the exhaustive KKT search on every call that the
  first active-set guess does not settle (a worst-case path).

The Python planner (csjm_opt.plan_tensions, compiled numba kernels) is timed per call on the
same cold cases; the ratio is its median over the C median.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numpy as np

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.codegen import INFEASIBLE, SOLVED, generate_c, load


def cases(rig, n: int, rng, scale: float, max_angle: float = 0.8):
    Rs = so3.random_rotations(n, rng, max_angle=max_angle)
    taus = rng.normal(size=(n, 3))
    taus *= (scale * rng.random(n) ** (1 / 3) / np.linalg.norm(taus, axis=1))[:, None]
    return Rs, taus


def trajectory(n: int, dt_s: float = 1e-3):
    t = np.arange(n) * dt_s
    s = np.sin(np.pi * t)
    Rs = so3.exp(np.c_[np.radians(15) * s, np.radians(-10) * np.sin(0.5 * np.pi * t), np.radians(20) * s])
    taus = 3.0 * np.c_[np.sin(2 * np.pi * 0.7 * t), np.cos(2 * np.pi * 0.4 * t), 0.3 * np.sin(2 * np.pi * 0.2 * t)]
    return Rs, taus


def report(name: str, ns: np.ndarray, extra: str = "") -> float:
    p50, p99, p999 = np.percentile(ns, [50, 99, 99.9])
    print(f"  {name:<34s} n={ns.size:>8d}  p50 {p50:7.0f} ns  p99 {p99:7.0f} ns  p99.9 {p999:7.0f} ns  "
          f"max {ns.max():10.0f} ns {extra}")
    return float(p50)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--calls", type=int, default=1_000_000)
    ap.add_argument("--python-calls", type=int, default=3000)
    ap.add_argument("--dir", default=None, help="generated folder to reuse (default: a temporary one)")
    args = ap.parse_args()
    rig = co.paper_rig()
    out = args.dir or tempfile.mkdtemp(prefix="csjm-codegen-")
    generate_c(rig, out)
    lib = load(out)
    rng = np.random.default_rng(0)
    n = args.calls

    Rs, taus = cases(rig, n, rng, 0.3 * 7.16)         # 0.3 of the paper rig's load scale: feasible
    c = lib.plan_many(Rs, taus)
    keep = c.status == SOLVED
    Rs, taus = Rs[keep], taus[keep]
    print(f"C plan call, timed inside C (a pair of clock readings costs "
          f"{lib.time_plan_calls(Rs[:10], taus[:10])[1]:.0f} ns), paper rig:")
    ns, _, failed = lib.time_plan_calls(Rs, taus)
    p50_cold = report("cold, random poses and loads", ns)
    p99_cold = float(np.percentile(ns, 99))
    Rt, tt = trajectory(n)
    ns, _, failed = lib.time_plan_calls(Rt, tt, warm_start=True)
    report("warm, 1 kHz trajectory", ns, f"(not solved: {failed})")
    Ri, ti = cases(rig, 200_000, rng, 3 * 7.16)
    bi = lib.plan_many(Ri, ti)
    inf = bi.status == INFEASIBLE
    ns, _, _ = lib.time_plan_calls(Ri[inf], ti[inf])
    report("infeasible loads (distance found)", ns)
    m = min(200_000, keep.sum())
    fb = lib.plan_many(Rs[:m], taus[:m], max_iter=1)
    forced = fb.fallback == 1
    ns, _, _ = lib.time_plan_calls(Rs[:m][forced], taus[:m][forced], max_iter=1)
    report("exhaustive fallback (max_iter=1)", ns, f"({forced.sum()} of {m} calls)")

    k = args.python_calls
    times = np.empty(k)
    for i in range(20):
        co.plan_tensions(rig, Rs[i], taus[i])
    for i in range(k):
        t0 = time.perf_counter()
        co.plan_tensions(rig, Rs[i], taus[i])
        times[i] = time.perf_counter() - t0
    py_ns = times * 1e9
    print("Python csjm_opt.plan_tensions, same cold cases:")
    p50_py = report("cold, random poses and loads", py_ns)
    print(f"  ratio Python/C (medians) = {p50_py / p50_cold:.0f}x;  C p99 {p99_cold / 1000:.2f} us (goal <= 2 us)")
    print("Iteration bound (from csjm_qp.c, not measured): max_iter (default 12) active-set iterations, "
          "then 30 support evaluations, 240 two-variable box least squares and 233 3x3 KKT solves.")


if __name__ == "__main__":
    main()
