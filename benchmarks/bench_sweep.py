"""Designs per second of a geometry sweep: serial, parallel (processes, Dask) and an SLSQP baseline.

Fixed work per design: 1,000 orientations (tilt <= 45 deg, |torsion| <= 30
deg, scrambled Halton), the 7-load set of ``studies/paper_sweep/paper_sweep.toml``, all
metrics (feasibility, tilt cone refinement, planned tensions, K and its
eigenvalues at every feasible orientation, shaping range at 16 poses).

Baseline, measured in the same run: a straightforward loop over orientations
and loads calling ``scipy.optimize.minimize(method="SLSQP")`` on the tension
QP (feasible when it succeeds with equilibrium residual < 1e-6 N m), then K
at the feasible orientations. It is too slow to run on whole designs, so it
is timed on a subset of orientations and extrapolated linearly to 1,000
(stated in the output). Usage::

    python benchmarks/bench_sweep.py [--designs 120] [--repeats 3] [--dask] [--slsqp-orientations 40]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

import csjm_opt as co
from csjm_opt.design import OrientationSampling, design_rig
from csjm_opt.design.sweep.runner import run_sweep
from csjm_opt.design.sweep.spec import SweepSpec

LOADS = [[0, 0, 0], [3, 0, 0], [-3, 0, 0], [0, 3, 0], [0, -3, 0], [0, 0, 1], [0, 0, -1]]


def bench_spec(designs: int) -> SweepSpec:
    return SweepSpec.from_dict({
        "sweep": {"method": "lhs", "designs": designs, "seed": 0},
        "parameters": {"platform_d23_m": {"min": 0.07, "max": 0.12}, "base_d12_m": {"min": 0.1, "max": 0.16},
                       "oo_a_m": {"min": 0.06, "max": 0.1}, "platform_theta0_deg": {"min": -20.0, "max": 20.0}},
        "sampling": {"orientations": 1000, "max_tilt_deg": 45.0, "max_torsion_deg": 30.0},
        "loads": {"tau_ext": LOADS}, "metrics": {"shaping_poses": 16}}, "bench")


def time_sweep(spec: SweepSpec, repeats: int, **kwargs) -> tuple[float, float]:
    """Median designs/s over ``repeats`` fresh runs: (end to end, excluding backend start-up)."""
    rates, steady = [], []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            result = run_sweep(spec, Path(tmp) / "r.jsonl", progress=False, **kwargs)
            assert result.computed == len(spec.designs())
            rates.append(result.designs_per_second)
            steady.append(_steady_rate(Path(tmp) / "r.jsonl"))
    return statistics.median(rates), statistics.median(steady)


def _steady_rate(path: Path) -> float:
    """Designs/s from the per-design compute times (no pool or cluster start-up), per worker."""
    import json

    seconds = [json.loads(line)["seconds"] for line in path.read_text().splitlines()]
    return len(seconds) / sum(seconds)


def slsqp_seconds_per_design(n_orientations: int) -> tuple[float, int]:
    """Per-orientation SLSQP loop on a subset; returns (seconds extrapolated to 1,000, feasible count)."""
    rig = design_rig({})
    model = co.Model(rig)
    Rs = OrientationSampling(1000, 45.0, 30.0).rotations()[:n_orientations]
    loads = np.array(LOADS, float)
    start = time.perf_counter()
    feasible = 0
    for R in Rs:
        J = model.jacobian(R)
        tau_w = model.weight_moment(R)
        ok, T0 = True, None
        for tau in loads:
            tau_load = tau + tau_w
            res = minimize(lambda t: 0.5 * np.sum((t - rig.t_mid_N) ** 2), rig.t_mid_N,
                           jac=lambda t: t - rig.t_mid_N, method="SLSQP",
                           bounds=[(rig.t_min_N, rig.t_max_N)] * 6,
                           constraints=[{"type": "eq", "fun": lambda t, tl=tau_load, J=J: J.T @ t + tl,
                                         "jac": lambda t, J=J: J.T}], options={"ftol": 1e-12, "maxiter": 200})
            if not (res.success and np.linalg.norm(J.T @ res.x + tau_load) < 1e-6):
                ok = False
                break
            if T0 is None:
                T0 = res.x
        if ok:
            feasible += 1
            np.linalg.eigvalsh(co.stiffness(rig, R, T0))
    elapsed = time.perf_counter() - start
    return elapsed * 1000 / n_orientations, feasible


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--designs", type=int, default=120)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--slsqp-orientations", type=int, default=40)
    parser.add_argument("--dask", action="store_true", help="also time a local Dask cluster (2 workers)")
    args = parser.parse_args()
    spec = bench_spec(args.designs)
    print(f"{args.designs} designs x 1,000 orientations x {len(LOADS)} loads, median of {args.repeats} runs; "
          f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f} (other work skews the ratios)")
    serial, serial_steady = time_sweep(spec, args.repeats, workers=1)
    print(f"serial (1 process)        : {serial:7.1f} designs/s  ({1000 / serial_steady:.1f} ms/design compute)")
    parallel, _ = time_sweep(spec, args.repeats, workers=2)
    print(f"parallel (2 processes)    : {parallel:7.1f} designs/s  (x{parallel / serial:.2f} vs serial, "
          "pool start-up included)")
    if args.dask:
        from distributed import LocalCluster

        cold, _ = time_sweep(spec, 1, workers=2, dask=True)
        print(f"Dask LocalCluster (2 proc): {cold:7.1f} designs/s  (cluster start-up included)")
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cl:
            time_sweep(bench_spec(4), 1, scheduler=cl.scheduler_address)          # warm the workers
            warm, _ = time_sweep(spec, args.repeats, scheduler=cl.scheduler_address)
        print(f"Dask, running cluster     : {warm:7.1f} designs/s  (--scheduler ADDRESS, 2 worker processes)")
    per_design, feasible = slsqp_seconds_per_design(args.slsqp_orientations)
    print(f"SLSQP loop baseline       : {1 / per_design:7.3f} designs/s  (measured on {args.slsqp_orientations} "
          f"orientations, {feasible} feasible, extrapolated x{1000 / args.slsqp_orientations:.0f} to 1,000; "
          "1 process)")
    print(f"speed-up vs SLSQP         : x{serial * per_design:.0f} serial, x{parallel * per_design:.0f} parallel")
    print(f"aim >= 20 designs/s on 2 cores: {'met' if parallel >= 20 else 'NOT met'}")


if __name__ == "__main__":
    main()
