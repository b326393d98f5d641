"""Throughput against batch size: plans, K and design sweeps, each against a baseline of the same run.

Run: python benchmarks/bench_scaling.py [--max-poses 1000000] [--figure docs/performance_scaling.png]
     [--json results.json] [--quick]

* Plans: ``co.plan_tensions_batch`` on n poses along a trajectory (loads up to
  1.5 N m), n = 1 ... max-poses; baseline a loop of scipy SLSQP (numpy J), timed
  on a sample of poses and scaled linearly (said in the output).
* K: ``co.stiffness_batch`` (checked, compiled, parallel above 4,096 poses);
  baseline the CasADi ``map`` of the symbolic model (the code-generation path),
  measured up to ``--max-casadi-poses`` (a map is linear in n).
* Memory: tracemalloc peak of each call (numpy buffers, inputs excluded) per
  pose at every size, and the process's peak RSS at the end.
* Sweeps: designs/s of ``run_sweep`` for designs x orientations, serial (the
  baseline), a 2-process pool and a Dask LocalCluster with 2 workers.

Prints medians and ratios, a Markdown table, and saves a figure.
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
from _common import median_time, slsqp_plan  # noqa: E402

import csjm_opt as co  # noqa: E402
from csjm_opt.design.sweep.runner import run_sweep  # noqa: E402
from csjm_opt.design.sweep.spec import SweepSpec  # noqa: E402

LOADS = [[0, 0, 0], [3, 0, 0], [-3, 0, 0], [0, 3, 0], [0, -3, 0], [0, 0, 1], [0, 0, -1]]


def trajectory(n: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.linspace(0, 4 * np.pi, n)
    Rs = co.so3.exp(np.column_stack([0.3 * np.sin(t), 0.3 * np.cos(1.3 * t), 0.2 * np.sin(0.7 * t)]))
    taus = np.column_stack([1.5 * np.sin(3 * t), 1.5 * np.cos(2 * t), 0.5 * np.sin(t)])
    return np.ascontiguousarray(Rs), taus


def repeats_for(n: int) -> int:
    return int(np.clip(200_000 // max(n, 1), 3, 200))


def peak_bytes(fn) -> int:
    tracemalloc.start()
    tracemalloc.reset_peak()
    fn()
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak


def bench_poses(rig: co.Rig, sizes: list[int], max_casadi: int, slsqp_sample: int) -> list[dict]:
    model = co.Model(rig)
    Rs_all, taus_all = trajectory(sizes[-1])
    sample = np.random.default_rng(0).choice(sizes[-1], size=slsqp_sample, replace=False)
    t0 = time.perf_counter()
    for i in sample:
        slsqp_plan(rig, Rs_all[i], taus_all[i])
    slsqp_per_pose = (time.perf_counter() - t0) / slsqp_sample
    rows = []
    for n in sizes:
        Rs, taus = trajectory(n)
        plans = co.plan_tensions_batch(rig, Rs, taus)
        T = plans.tensions_N
        r = repeats_for(n)

        def plan(Rs=Rs, taus=taus):
            return co.plan_tensions_batch(rig, Rs, taus)

        def stiffness(Rs=Rs, T=T):
            return co.stiffness_batch(rig, Rs, T, model=model)

        def casadi(Rs=Rs, T=T):
            return model.casadi("stiffness", Rs, T)

        t_plan, t_K = median_time(plan, r, 1), median_time(stiffness, r, 1)
        row = {"n": n, "plan_s": t_plan, "K_s": t_K, "slsqp_s": slsqp_per_pose * n,
               "plan_peak_bytes": peak_bytes(plan), "K_peak_bytes": peak_bytes(stiffness),
               "fallbacks": plans.fallbacks}
        if n <= max_casadi:
            row["casadi_s"] = median_time(casadi, max(1, r // 4), 1)
            if n >= 2:
                (K_ref,) = model.casadi("stiffness", Rs, T)
                K = co.stiffness_batch(rig, Rs, T, model=model)
                row["K_rel_err"] = float(np.abs(K - K_ref).max() / np.abs(K_ref).max())
        rows.append(row)
        casadi = f"{n / row['casadi_s']:>12,.0f}" if "casadi_s" in row else f"{'-':>12}"
        print(f"  n={n:>9,}  plan {n / t_plan:>12,.0f}/s  SLSQP {1 / slsqp_per_pose:>8,.0f}/s  "
              f"K {n / t_K:>12,.0f}/s  CasADi map {casadi}/s  "
              f"mem plan {row['plan_peak_bytes'] / n:,.0f} B/pose, K {row['K_peak_bytes'] / n:,.0f} B/pose",
              flush=True)
    return rows


def bench_single(rig: co.Rig) -> dict:
    model = co.Model(rig)
    R = co.so3.exp([0.2, -0.1, 0.05])
    tau = np.array([0.8, -0.5, 0.3])
    T = co.plan_tensions(rig, R, tau).tensions_N
    return {"plan_us": 1e6 * median_time(lambda: co.plan_tensions(rig, R, tau), 2000, 50),
            "slsqp_us": 1e6 * median_time(lambda: slsqp_plan(rig, R, tau), 100, 5),
            "K_us": 1e6 * median_time(lambda: co.stiffness(rig, R, T, model=model), 5000, 50),
            "K_casadi_us": 1e6 * median_time(lambda: model.casadi("stiffness", R, T), 500, 20),
            "pose_terms_us": 1e6 * median_time(lambda: model.pose_terms(R), 5000, 50)}


def sweep_spec(designs: int, orientations: int) -> SweepSpec:
    return SweepSpec.from_dict({
        "sweep": {"method": "lhs", "designs": designs, "seed": 0},
        "parameters": {"platform_d23_m": {"min": 0.07, "max": 0.12}, "base_d12_m": {"min": 0.1, "max": 0.16}},
        "sampling": {"orientations": orientations, "max_tilt_deg": 45.0, "max_torsion_deg": 30.0},
        "loads": {"tau_ext": LOADS}, "metrics": {"shaping_poses": 16}}, "bench")


def time_sweep(spec: SweepSpec, **kwargs) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        result = run_sweep(spec, Path(tmp) / "r.jsonl", progress=False, **kwargs)
        return result.designs_per_second


def bench_sweeps(designs: list[int], orientations: list[int], dask: bool) -> list[dict]:
    rows = []
    for m in orientations:
        for d in designs:
            spec = sweep_spec(d, m)
            row = {"designs": d, "orientations": m, "serial": time_sweep(spec, workers=1),
                   "processes": time_sweep(spec, workers=2)}
            if dask and d == designs[-1]:
                row["dask"] = time_sweep(spec, dask=True, workers=2)
            rows.append(row)
            extra = f"  Dask(2) {row['dask']:7.1f}" if "dask" in row else ""
            print(f"  {d:>4} designs x {m:>5} orientations: serial {row['serial']:7.1f}  "
                  f"pool(2) {row['processes']:7.1f} designs/s{extra}", flush=True)
    return rows


def paper_sweep_rate(path: Path, repeats: int) -> list[float]:
    spec = SweepSpec.from_toml(path)
    return [time_sweep(spec, workers=2) for _ in range(repeats)]


def figure(poses: list[dict], sweeps: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    n = np.array([r["n"] for r in poses])
    a.loglog(n, n / np.array([r["plan_s"] for r in poses]), "o-", label="plan_tensions_batch")
    a.loglog(n, n / np.array([r["K_s"] for r in poses]), "s-", label="stiffness_batch")
    nc = np.array([r["n"] for r in poses if "casadi_s" in r])
    a.loglog(nc, nc / np.array([r["casadi_s"] for r in poses if "casadi_s" in r]), "s--", label="K: CasADi map")
    a.loglog(n, n / np.array([r["slsqp_s"] for r in poses]), "o--", label="plan: SLSQP loop")
    a.set_xlabel("poses per call")
    a.set_ylabel("poses / s")
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=8)
    for m in sorted({r["orientations"] for r in sweeps}):
        rs = [r for r in sweeps if r["orientations"] == m]
        d = [r["designs"] for r in rs]
        line, = b.semilogx(d, [r["processes"] for r in rs], "o-", label=f"pool(2), {m} orientations")
        b.semilogx(d, [r["serial"] for r in rs], "o--", color=line.get_color(), label=f"serial, {m}")
    b.set_xlabel("designs per sweep")
    b.set_ylabel("designs / s")
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--max-poses", type=int, default=1_000_000)
    ap.add_argument("--max-casadi-poses", type=int, default=100_000)
    ap.add_argument("--slsqp-sample", type=int, default=100)
    ap.add_argument("--figure", type=Path, default=Path("performance_scaling.png"))
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--no-dask", action="store_true")
    ap.add_argument("--quick", action="store_true", help="small sizes only (a smoke run)")
    args = ap.parse_args()
    rig = co.paper_rig()
    sizes = [n for n in (1, 10, 100, 1_000, 10_000, 100_000, 1_000_000) if n <= args.max_poses]
    designs, orientations = ([4, 16], [250]) if args.quick else ([8, 32, 128], [250, 1000, 4000])

    print("one pose (medians):")
    single = bench_single(rig)
    print(f"  plan_tensions {single['plan_us']:.1f} us (SLSQP {single['slsqp_us']:.0f} us, "
          f"{single['slsqp_us'] / single['plan_us']:.0f}x);  stiffness {single['K_us']:.2f} us "
          f"(CasADi call {single['K_casadi_us']:.1f} us, {single['K_casadi_us'] / single['K_us']:.0f}x);  "
          f"Model.pose_terms {single['pose_terms_us']:.2f} us")
    print("batches (medians):")
    poses = bench_poses(rig, sizes, args.max_casadi_poses, args.slsqp_sample)
    print("sweeps (designs/s, one run each):")
    sweeps = bench_sweeps(designs, orientations, not args.no_dask)
    paper_toml = Path(__file__).resolve().parents[1] / "studies" / "paper_sweep" / "paper_sweep.toml"
    paper = [] if args.quick else paper_sweep_rate(paper_toml, 3)
    if paper:
        print(f"  studies/paper_sweep/paper_sweep.toml (225 designs x 1000 orientations x 7 loads, pool(2)): "
              f"median {statistics.median(paper):.0f} designs/s of {[round(p) for p in paper]}")
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS of this process: {rss:,.0f} MB")

    print("\n| poses | plan /s | SLSQP loop /s | plan / SLSQP | K /s | CasADi map /s | K / CasADi | "
          "plan B/pose | K B/pose |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in poses:
        n = r["n"]
        cas = f"{n / r['casadi_s']:,.0f} | {r['casadi_s'] / r['K_s']:.0f}x" if "casadi_s" in r else "- | -"
        print(f"| {n:,} | {n / r['plan_s']:,.0f} | {n / r['slsqp_s']:,.0f} | {r['slsqp_s'] / r['plan_s']:,.0f}x | "
              f"{n / r['K_s']:,.0f} | {cas} | {r['plan_peak_bytes'] / n:,.0f} | {r['K_peak_bytes'] / n:,.0f} |")
    print("\n| designs x orientations | serial /s | pool(2) /s | pool / serial | Dask(2) /s |")
    print("|---|---:|---:|---:|---:|")
    for r in sweeps:
        dask = f"{r['dask']:.1f}" if "dask" in r else "-"
        print(f"| {r['designs']} x {r['orientations']} | {r['serial']:.1f} | {r['processes']:.1f} | "
              f"{r['processes'] / r['serial']:.2f}x | {dask} |")
    figure(poses, sweeps, args.figure)
    print(f"\nfigure: {args.figure}")
    if args.json:
        args.json.write_text(json.dumps({"single": single, "poses": poses, "sweeps": sweeps,
                                         "paper_sweep_designs_per_s": paper, "peak_rss_MB": rss}, indent=1))


if __name__ == "__main__":
    main()
