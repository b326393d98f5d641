"""Tension planning speed: csjm_opt vs scipy SLSQP with a numpy Jacobian (same run).

Run: python benchmarks/bench_planner.py [--poses 10000] [--slsqp-sample 400]
Prints medians and ratios. The 10,000-pose SLSQP loop is timed on a random
sample of poses and scaled to 10,000 (said in the output).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _common import median_time, row, slsqp_plan  # noqa: E402

import csjm_opt as co  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--poses", type=int, default=10_000)
    ap.add_argument("--slsqp-sample", type=int, default=400)
    args = ap.parse_args()
    rig = co.paper_rig()
    rng = np.random.default_rng(0)
    R = co.so3.exp([0.2, -0.1, 0.05])
    tau = np.array([0.8, -0.5, 0.3])

    print("one pose (Jacobian included), median of 200:")
    t_auto = median_time(lambda: co.plan_tensions(rig, R, tau), 200)
    t_osqp = median_time(lambda: co.plan_tensions(rig, R, tau, solver="osqp"), 200)
    t_slsqp = median_time(lambda: slsqp_plan(rig, R, tau), 200)
    x = co.plan_tensions(rig, R, tau, ).tensions_N
    print(row("csjm_opt plan_tensions (default: compiled active set)", t_auto))
    print(row("csjm_opt plan_tensions(solver='osqp') via qpsolvers", t_osqp))
    print(row("baseline: numpy J + scipy SLSQP", t_slsqp))
    print(f"  ratio default/SLSQP = {t_auto / t_slsqp:.3f}  (target <= 0.2);  "
          f"osqp/SLSQP = {t_osqp / t_slsqp:.2f};  max |dT| = {np.abs(x - slsqp_plan(rig, R, tau)).max():.1e} N")

    n = args.poses
    t = np.linspace(0, 4 * np.pi, n)
    Rs = co.so3.exp(np.column_stack([0.3 * np.sin(t), 0.3 * np.cos(1.3 * t), 0.2 * np.sin(0.7 * t)]))
    taus = np.column_stack([1.5 * np.sin(3 * t), 1.5 * np.cos(2 * t), 0.5 * np.sin(t)])
    batch = co.plan_tensions_batch(rig, Rs, taus)
    t_batch = median_time(lambda: co.plan_tensions_batch(rig, Rs, taus), 7, 1)
    sample = rng.choice(n, size=min(args.slsqp_sample, n), replace=False)
    t0 = time.perf_counter()
    ref = np.array([slsqp_plan(rig, Rs[i], taus[i]) for i in sample])
    t_loop = (time.perf_counter() - t0) * n / len(sample)
    print(f"\n{n:,} poses along a trajectory (loads up to 1.5 N m):")
    print(row("csjm_opt plan_tensions_batch (median of 7)", t_batch, n))
    print(row(f"baseline: SLSQP loop (timed on {len(sample)}, scaled)", t_loop, n))
    print(f"  speed-up = {t_loop / t_batch:,.0f}x  (target >= 100x);  fallback rows: {batch.fallbacks};  "
          f"max residual {batch.equilibrium_residual_Nm.max():.1e} N m;  "
          f"max |dT| vs SLSQP {np.abs(batch.tensions_N[sample] - ref).max():.1e} N")
    shared_qp_comparison(rig)
    infeasible_distance(rig, R)


def shared_qp_comparison(rig) -> None:
    """The tension QP solved by the specialised kernel and by the general dense PDAS kernel."""
    from csjm_opt.planning import kernels as kernels

    model = co.Model(rig)
    R = co.so3.exp([0.2, -0.1, 0.05])
    _, J, tau_w = model.pose_terms(R)
    b = -(np.array([0.8, -0.5, 0.3]) + tau_w)
    t_ref, lo, hi = rig.t_mid_N, np.full(6, rig.t_min_N), np.full(6, rig.t_max_N)
    P, q, A = np.eye(6), -t_ref, np.ascontiguousarray(J.T)
    T = np.empty(6)

    def special():
        kernels.solve_one(J, b, t_ref, rig.t_min_N, rig.t_max_N, np.zeros(6, np.bool_), np.zeros(6, np.bool_), T, 40)

    def general():
        return kernels.pdas(P, q, A, b, lo, hi, np.zeros(6, np.bool_), np.zeros(6, np.bool_), 40, 1e-10)

    special()
    x = general()[0]
    assert np.allclose(x, T, atol=1e-9)
    t_s, t_g = median_time(special, 2000, 50), median_time(general, 2000, 50)
    print(f"\none tension QP, cold start: specialised solve_one {t_s * 1e6:.2f} us, general pdas "
          f"{t_g * 1e6:.2f} us ({t_g / t_s:.1f}x): the planner keeps the specialised solver")



def infeasible_distance(rig, R) -> None:
    """An infeasible load: the exact distance (facets + faces) vs scipy's bounded least squares."""
    from scipy.optimize import lsq_linear

    model = co.Model(rig)
    tau = np.array([30.0, 0.0, 0.0])
    J, tau_load = model.jacobian(R), tau + model.weight_moment(R)

    def planner():
        try:
            co.plan_tensions(rig, R, tau)
        except co.InfeasibleLoad as exc:
            return exc.distance_Nm
        raise AssertionError("the load was expected to be infeasible")

    def bvls():
        res = lsq_linear(J.T, -tau_load, bounds=(rig.t_min_N, rig.t_max_N), method="bvls", tol=1e-14)
        return np.linalg.norm(J.T @ res.x + tau_load)

    t_p, t_b = median_time(planner, 200, 5), median_time(bvls, 200, 5)
    print(f"\nan infeasible load (plan_tensions raises InfeasibleLoad with its distance), median of 200: "
          f"{t_p * 1e6:.1f} us; scipy lsq_linear(bvls) for the distance alone {t_b * 1e6:.1f} us "
          f"({t_b / t_p:.1f}x); distances {planner():.6g} / {bvls():.6g} N m")


if __name__ == "__main__":
    main()
