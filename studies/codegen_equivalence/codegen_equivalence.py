"""The generated C planner against the Python planner on many random poses and loads and many rigs.

Run: python -m studies.codegen_equivalence.codegen_equivalence [--paper 200000] [--rigs 10] [--per-rig 20000]
     [--out studies/codegen_equivalence/codegen_equivalence.json]

For the paper rig and ``--rigs`` random rigs (csjm_opt.testbed.rigs.draw_rig), generate and compile
the C, plan random poses (up to 0.8 rad) and loads (a ball of 0.4 of the rig's load scale for most
rows, 1.5 for 3 %, so some are infeasible) in one C loop, and compare every row with the Python
planner: the solved rows with plan_tensions_batch (which raises if a row is in fact infeasible),
the infeasible rows with plan_tensions (which must raise InfeasibleLoad with the same distance).
K is compared with csjm_opt.stiffness_batch on the planned tensions. Writes a JSON summary.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile

import numpy as np
from tqdm import tqdm

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.codegen import INFEASIBLE, SOLVED, generate_c, load
from csjm_opt.errors import InfeasibleLoad
from csjm_opt.model.joint_stiffness import stiffness_batch
from csjm_opt.planning import plan_tensions_batch
from csjm_opt.testbed.rigs import draw_rig


def load_scale_Nm(rig) -> float:
    return 0.5 * (rig.t_max_N - rig.t_min_N) * float(np.mean(np.linalg.norm(rig.platform_holes_A_m, axis=1)))


def one_rig(rig, n: int, rng, label: str) -> dict:
    with tempfile.TemporaryDirectory() as d:
        generate_c(rig, d)
        lib = load(d)
        Rs = so3.random_rotations(n, rng, max_angle=0.8)
        taus = rng.normal(size=(n, 3))
        radius = np.where(rng.random(n) < 0.03, 1.5, 0.4) * load_scale_Nm(rig)
        taus *= (radius * rng.random(n) ** (1 / 3) / np.linalg.norm(taus, axis=1))[:, None]
        c = lib.plan_many(Rs, taus)
        ok = c.status == SOLVED
        py = plan_tensions_batch(rig, Rs[ok], taus[ok])
        dT = float(np.abs(py.tensions_N - c.tensions_N[ok]).max())
        dl = float(np.abs(py.rest_lengths_m - c.rest_lengths_m[ok]).max())
        K_c = lib.stiffness_many(Rs[ok], c.tensions_N[ok])
        K_py = stiffness_batch(rig, Rs[ok], py.tensions_N, check_bounds=False)
        dK = float(np.max(np.abs(K_c - K_py) / np.abs(K_py).max(axis=(1, 2))[:, None, None]))
        status_mismatch, d_rel = 0, 0.0
        for i in tqdm(np.flatnonzero(~ok), desc=f"{label}: infeasible rows", file=sys.stderr, leave=False):
            try:
                co.plan_tensions(rig, Rs[i], taus[i])
                status_mismatch += 1
            except InfeasibleLoad as exc:
                d_rel = max(d_rel, abs(c.distance_Nm[i] - exc.distance_Nm) / exc.distance_Nm)
        status_mismatch += int(np.sum(~np.isin(c.status, [SOLVED, INFEASIBLE])))
    return {"rig": label, "rows": n, "infeasible": int(np.sum(c.status == INFEASIBLE)),
            "status_mismatches": status_mismatch, "max_abs_dT_N": dT, "max_abs_dl_m": dl,
            "max_rel_dK": dK, "max_rel_distance": d_rel, "fallback_rows": int(np.sum(c.fallback > 0)),
            "max_iterations": int(c.iterations.max())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--paper", type=int, default=200_000)
    ap.add_argument("--rigs", type=int, default=10)
    ap.add_argument("--per-rig", type=int, default=20_000)
    ap.add_argument("--out", default="studies/codegen_equivalence/codegen_equivalence.json")
    args = ap.parse_args()
    rng = np.random.default_rng(2026)
    rows = [one_rig(co.paper_rig(), args.paper, rng, "paper")]
    for k in tqdm(range(args.rigs), desc="random rigs", file=sys.stderr):
        rows.append(one_rig(draw_rig(rng), args.per_rig, rng, f"random{k}"))
    total = {"rows": sum(r["rows"] for r in rows), "infeasible": sum(r["infeasible"] for r in rows),
             "status_mismatches": sum(r["status_mismatches"] for r in rows),
             **{key: max(r[key] for r in rows) for key in ("max_abs_dT_N", "max_abs_dl_m", "max_rel_dK",
                                                          "max_rel_distance", "max_iterations")}}
    with open(args.out, "w") as f:
        json.dump({"per_rig": rows, "total": total}, f, indent=1)
    for r in rows + [dict(total, rig="ALL")]:
        print(f"{r['rig']:>9s} rows {r['rows']:>7d} infeasible {r['infeasible']:>5d} status mismatches "
              f"{r['status_mismatches']}  |dT| {r['max_abs_dT_N']:.2e} N  |dl| {r['max_abs_dl_m']:.2e} m  "
              f"dK {r['max_rel_dK']:.2e}  d(distance) {r['max_rel_distance']:.2e}")


if __name__ == "__main__":
    main()
