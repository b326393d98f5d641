"""The planner for m = 4, 5, 6, 8, 12 cables against an independent QP solver, and the C against Python.

Run: python -m studies.n_cables_equivalence.n_cables_equivalence [--cases 5000] [--c-cases 100000] [--out PATH]

1. Per m, ``--cases`` random poses (rotation vectors of norm up to ~0.45 rad) and loads (normal,
   scale 0.3 or 10 N m, so a share is infeasible) on a pattern rig (tests/test_n_cables.py's
   layout; m = 6 is the paper rig): ``csjm_opt.plan_tensions`` against Clarabel (interior point,
   through qpsolvers, tolerances 1e-13) on the QP built here from the geometry (scipy rotations,
   not the package's kernels). Counted: status agreement (both solved / both infeasible; a
   disagreement where the planner's distance to the feasible set is below 1e-7 N m is reported
   apart, as a boundary case) and the largest relative objective gap
   ``|f - f_clarabel| / max(f_clarabel, 1)``.
2. For m = 4 and 8, ``--c-cases`` cases through the generated C (``plan_many``, cold) and
   ``plan_tensions_batch``: the largest tension difference (N) on the rows both solve, and status
   agreement.

Writes a JSON summary (with the command, commit and date).
"""

from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
import qpsolvers
from scipy.spatial.transform import Rotation
from tqdm import tqdm

import csjm_opt as co
from csjm_opt.codegen import INFEASIBLE, SOLVED, generate_c, load

ROOT = Path(__file__).resolve().parents[2]


def pattern_rig(m: int) -> co.Rig:
    if m == 6:
        return co.paper_rig()
    platform = np.arange(m) * 360.0 / m
    twist = 35.0 * np.where(np.arange(m) % 2 == 0, 1.0, -1.0)
    return co.Rig.from_dict({
        "geometry": {"pattern": {"count": m, "platform_radius": 0.06, "base_radius": 0.08, "platform_height": 0.08,
                                 "base_height": -0.08, "platform_angles_deg": platform.tolist(),
                                 "base_angles_deg": (platform + twist).tolist()}},
        "cables": {"stiffness": [4600.0 + 50.0 * i for i in range(m)], "t_min": 5.0, "t_max": 150.0},
        "platform": {"mass": 0.45, "com": [0.0, 0.0, 0.081], "gravity": [0.0, 0.0, -9.81]}})


def clarabel(rig: co.Rig, R: np.ndarray, tau: np.ndarray):
    m = rig.n_cables
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    v = B - A @ R.T
    J = np.cross(A, (v @ R) / np.linalg.norm(v, axis=1)[:, None])
    tau_w = np.cross(rig.platform_mass_kg * rig.com_A_m, R.T @ rig.gravity_B_m_per_s2)
    t_ref = np.full(m, 0.5 * (rig.t_min_N + rig.t_max_N))
    problem = qpsolvers.Problem(np.eye(m), -t_ref, None, None, J.T, -(tau + tau_w), np.full(m, rig.t_min_N),
                                np.full(m, rig.t_max_N))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = qpsolvers.solve_problem(problem, solver="clarabel", tol_gap_abs=1e-13, tol_gap_rel=1e-13,
                                      tol_feas=1e-13, tol_ktratio=1e-10)
    return sol, t_ref


def against_clarabel(m: int, n: int, rng: np.random.Generator) -> dict:
    rig = pattern_rig(m)
    agree = boundary = disagree = feasible = 0
    worst = 0.0
    for _ in tqdm(range(n), desc=f"m = {m} vs Clarabel", file=sys.stderr, mininterval=2):
        R = Rotation.from_rotvec(rng.normal(size=3) * 0.15).as_matrix()
        tau = rng.normal(size=3) * rng.choice([0.3, 10.0])
        sol, t_ref = clarabel(rig, R, tau)
        try:
            T = co.plan_tensions(rig, R, tau).tensions_N
        except co.InfeasibleLoad as exc:
            if not sol.found:
                agree += 1
            elif exc.distance_Nm < 1e-7:
                boundary += 1
            else:
                disagree += 1
            continue
        if not sol.found:
            disagree += 1
            continue
        agree += 1
        feasible += 1
        f, f_ref = 0.5 * np.sum((T - t_ref) ** 2), 0.5 * np.sum((sol.x - t_ref) ** 2)
        worst = max(worst, abs(f - f_ref) / max(f_ref, 1.0))
    return {"m": m, "cases": n, "status_agree": agree, "boundary_cases": boundary, "status_disagree": disagree,
            "feasible": feasible, "max_relative_objective_gap": worst}


def c_against_python(m: int, n: int, rng: np.random.Generator) -> dict:
    rig = pattern_rig(m)
    Rs = Rotation.from_rotvec(rng.normal(size=(n, 3)) * 0.15).as_matrix()
    taus = rng.normal(size=(n, 3)) * np.where(rng.random(n) < 0.05, 10.0, 0.3)[:, None]
    with tempfile.TemporaryDirectory() as d:
        generate_c(rig, d)
        c = load(d).plan_many(Rs, taus)
    ok = c.status == SOLVED
    py = co.plan_tensions_batch(rig, Rs[ok], taus[ok])
    mismatch = int(np.sum(~np.isin(c.status, [SOLVED, INFEASIBLE])))
    for i in tqdm(np.flatnonzero(~ok), desc=f"m = {m}: C infeasible rows", file=sys.stderr, mininterval=2):
        try:
            co.plan_tensions(rig, Rs[i], taus[i])
            mismatch += 1
        except co.InfeasibleLoad:
            pass
    return {"m": m, "cases": n, "solved": int(ok.sum()), "infeasible": int((c.status == INFEASIBLE).sum()),
            "status_mismatch": mismatch,
            "max_abs_tension_difference_N": float(np.abs(py.tensions_N - c.tensions_N[ok]).max())}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--cases", type=int, default=5000)
    ap.add_argument("--c-cases", type=int, default=100_000)
    ap.add_argument("--out", default=str(ROOT / "studies" / "n_cables_equivalence" / "n_cables_equivalence.json"))
    args = ap.parse_args()
    rng = np.random.default_rng(2026)
    qp = [against_clarabel(m, args.cases, rng) for m in (4, 5, 6, 8, 12)]
    cc = [c_against_python(m, args.c_cases, rng) for m in (4, 8)]
    for r in qp:
        print(f"m = {r['m']:2d}: {r['cases']} cases, status agree {r['status_agree']}, boundary {r['boundary_cases']}, "
              f"disagree {r['status_disagree']}; feasible {r['feasible']}, max relative objective gap "
              f"{r['max_relative_objective_gap']:.2e}")
    for r in cc:
        print(f"C m = {r['m']}: {r['cases']} cases ({r['solved']} solved, {r['infeasible']} infeasible), status "
              f"mismatches {r['status_mismatch']}, max |T_C - T_py| {r['max_abs_tension_difference_N']:.2e} N")
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    Path(args.out).write_text(json.dumps({
        "command": " ".join([Path(sys.argv[0]).name, *sys.argv[1:]]), "commit": commit,
        "date": datetime.date.today().isoformat(), "planner_vs_clarabel": qp, "c_vs_python": cc}, indent=2) + "\n")


if __name__ == "__main__":
    main()
