"""Stiffness model speed: compiled kernel vs CasADi map / JIT vs finite-difference K (same run).

Run: python benchmarks/bench_model.py [--poses 10000]
Baseline: what a user would write otherwise, the finite-difference Hessian of
the cable energy on SO(3), vectorised over all poses in numpy (36 energy
evaluations per pose). Compares CasADi ``map`` (serial and threaded) and a
JIT-compiled C version of the same function (needs a C compiler; skipped if
none), and checks they agree.
"""

from __future__ import annotations

import argparse

import casadi as ca
import numpy as np
from _common import median_time, row  # noqa: E402

import csjm_opt as co  # noqa: E402
from csjm_opt.model.casadi_model import build_functions  # noqa: E402


def fd_stiffness(rig, Rs, T, h=1e-4):
    """Finite-difference Levi-Civita Hessian of the cable energy, vectorised over poses."""
    A, B, k = rig.platform_holes_A_m, rig.base_holes_B_m, rig.cable_stiffness_N_per_m
    c0 = np.linalg.norm(B[None] - np.einsum("nij,kj->nki", Rs, A), axis=2)
    l = c0 - T / k

    def energy(z):
        Rz = Rs @ co.so3.exp(np.broadcast_to(z, (Rs.shape[0], 3)))
        c = np.linalg.norm(B[None] - np.einsum("nij,kj->nki", Rz, A), axis=2)
        return 0.5 * np.sum(k * (c - l) ** 2, axis=1)

    E = np.eye(3) * h
    H = np.empty((Rs.shape[0], 3, 3))
    for i in range(3):
        for j in range(3):
            H[:, i, j] = (energy(E[i] + E[j]) - energy(E[i] - E[j]) - energy(-E[i] + E[j])
                          + energy(-E[i] - E[j])) / (4 * h * h)
    return H


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--poses", type=int, default=10_000)
    args = ap.parse_args()
    rig = co.paper_rig()
    model = co.Model(rig)
    n = args.poses
    rng = np.random.default_rng(0)
    Rs = co.so3.random_rotations(n, rng, max_angle=0.35)
    T = co.plan_tensions_batch(rig, Rs, rng.normal(size=(n, 3)) * 0.5).tensions_N

    f = build_functions()["stiffness"]
    consts = (rig.cable_stiffness_N_per_m.reshape(6, 1), rig.platform_holes_A_m.T, rig.base_holes_B_m.T)
    R_h = np.ascontiguousarray(Rs.transpose(1, 0, 2).reshape(3, 3 * n))
    variants = {"CasADi map, serial": f.map(n, "serial"), "CasADi map, 2 threads": f.map(n, "thread", 2)}
    try:
        mx = f.mx_in()
        jit = ca.Function("stiffness_jit", mx, f.call(mx), f.name_in(), f.name_out(),
                          {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O2"], "verbose": False}})
        jit.call([np.eye(3), np.ones(6), *consts])
        variants["JIT C, map serial"] = jit.map(n, "serial")
    except RuntimeError as exc:  # no C compiler
        print(f"(JIT variant skipped: {exc})")

    print(f"K for {n:,} poses (paper rig, planned tensions), median of 7:")
    results = {}
    K_ref = model.stiffness(Rs, T)
    for name, fm in variants.items():
        t = median_time(lambda fm=fm: fm.call([R_h, T.T, *consts]), 7, 1)
        K = np.array(fm.call([R_h, T.T, *consts])[0]).reshape(3, n, 3).transpose(1, 0, 2)
        assert np.allclose(K, K_ref, atol=1e-9)
        results[name] = t
        print(row(name, t, n))
    t_model = median_time(lambda: model.stiffness(Rs, T), 7, 1)
    print(row("csjm_opt Model.stiffness (numba kernel)", t_model, n))
    fast = co.Model(rig, compiled=True)
    assert np.allclose(fast.casadi("stiffness", Rs, T)[0], K_ref, atol=1e-9)
    t_fast = median_time(lambda: fast.casadi("stiffness", Rs, T), 7, 1)
    print(row("csjm_opt Model(compiled=True).casadi (JIT map)", t_fast, n))
    t_fd = median_time(lambda: fd_stiffness(rig, Rs, T), 3, 1)
    print(row("baseline: finite-difference K (numpy, vectorised)", t_fd, n))
    err = np.abs(fd_stiffness(rig, Rs[:200], T[:200]) - K_ref[:200]).max()
    best = min(results, key=results.get)
    print(f"  fastest CasADi variant: {best}; Model.stiffness {n / t_model:,.0f} poses/s "
          f"({results[best] / t_model:.0f}x the fastest CasADi variant); "
          f"{t_fd / t_model:.1f}x faster than finite differences (max |dK| {err:.1e} N m/rad)")

    R = Rs[0]
    t1 = median_time(lambda: model.stiffness(R, T[0]), 300)
    t1_fd = median_time(lambda: fd_stiffness(rig, Rs[:1], T[:1]), 100)
    print(f"\none pose: Model.stiffness {t1 * 1e6:.1f} us, finite differences {t1_fd * 1e6:.1f} us "
          f"({t1_fd / t1:.1f}x)")


if __name__ == "__main__":
    main()
