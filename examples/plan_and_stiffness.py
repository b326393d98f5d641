"""Plan the cable tensions that hold a pose under a load, then the stiffness K there.

    python examples/plan_and_stiffness.py [OUT_DIR]

Writes ``plan_and_stiffness.json`` and ``tensions.png`` into OUT_DIR (default: a new
temporary directory) and prints a summary. Conventions: docs/conventions.md.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")   # this script writes figures to files only

import numpy as np  # noqa: E402

import csjm_opt as co  # noqa: E402
from csjm_opt._plotting import save  # noqa: E402


def main(out_dir: Path) -> dict:
    rig = co.paper_rig()                              # Section IV-A of the paper; or co.load_rig("rigs/paper.toml")
    R = co.so3.exp([0.10, -0.05, 0.0])                # orientation of {A} in {B} (rotation vector, rad)
    tau_ext = np.array([0.3, -0.2, 0.1])              # external moment on the platform, N m in {A}

    plan = co.plan_tensions(rig, R, tau_ext)          # QP: t_min <= T <= t_max, J^T T + tau_load = 0
    K = co.stiffness(rig, R, plan.tensions_N)         # N m/rad, symmetric, positive definite here
    eq = co.solve_equilibrium(rig, plan.rest_lengths_m, tau_ext, R_init=R)   # the rest lengths of the plan

    summary = {
        "tensions_N": plan.tensions_N.tolist(),
        "equilibrium_residual_Nm": plan.equilibrium_residual_Nm,
        "active_bounds": plan.active_bounds,
        "K_Nm_per_rad": K.tolist(),
        "eigenvalues_Nm_per_rad": np.linalg.eigvalsh(K).tolist(),
        # the rest lengths that realise the plan hold the same pose under the same load:
        "forward_statics_pose_error_rad": float(np.linalg.norm(co.so3.log(R.T @ eq.R))),
    }
    (out_dir / "plan_and_stiffness.json").write_text(json.dumps(summary, indent=2))

    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5, 3), layout="constrained")
    ax.bar(np.arange(1, 7), plan.tensions_N)
    ax.axhline(rig.t_min_N, color="k", ls="--", lw=0.8)
    ax.axhline(rig.t_max_N, color="k", ls="--", lw=0.8)
    ax.set_xlabel("cable")
    ax.set_ylabel("tension (N)")
    save(fig, out_dir / "tensions.png")

    print(f"tensions (N): {np.round(plan.tensions_N, 2)}")
    print(f"equilibrium residual: {plan.equilibrium_residual_Nm:.2e} N m")
    print(f"eigenvalues of K (N m/rad): {np.round(summary['eigenvalues_Nm_per_rad'], 2)}")
    print(f"outputs in {out_dir}")
    return summary


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="csjm_example_"))
    out.mkdir(parents=True, exist_ok=True)
    main(out)
