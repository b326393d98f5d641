"""Identify the stiffness K from a measurement log and verify it on held-out rows.

    python examples/identify_from_log.py [OUT_DIR]

A log in the format of docs/conventions.md is simulated on the paper rig (two
identification cycles with the paper's instrument noise) and written to
``OUT_DIR/log.csv``; it is then read back like a real one, K is identified per
cycle (affine least squares with confidence intervals, the paper's (49)-(50),
and a symmetric estimate), the identified K_D predicts the poses of held-out
rows ((61)-(65)), and the convergence figure (the paper's Figure 5) is saved.
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
from csjm_opt.identification import convergence_curve, plot_convergence, verify_log  # noqa: E402
from csjm_opt.testbed.identification import simulate_identification_experiment  # noqa: E402


def main(out_dir: Path) -> dict:
    rig = co.paper_rig()
    log_path = out_dir / "log.csv"
    if not log_path.exists():
        simulate_identification_experiment(rig, 2, np.random.default_rng(0)).to_csv(log_path)
    log = co.MeasurementLog.from_csv(log_path)

    model = co.Model(rig)
    # identify on all rows but the last two of each cycle, verify on those
    held = np.concatenate([log.cycle_rows(c)[-2:] for c in log.cycle_ids])
    train = log.subset(np.setdiff1d(np.arange(len(log)), held))
    estimates = co.identify_log(train, rig, model=model)
    check = verify_log(estimates, log.subset(held), model, use="K_D")

    e = estimates[0]
    curve = convergence_curve(train.R[train.cycle_rows(e.cycle)], train.tau_ext_A_Nm[train.cycle_rows(e.cycle)],
                              model)
    save(plot_convergence(curve).figure, out_dir / "convergence.png")

    summary = {"cycles": [{"cycle": x.cycle, "K": x.K.tolist(), "K_ci": x.K_ci.tolist(),
                           "condition": x.condition, "symmetry_error": x.symmetry_error} for x in estimates],
               "heldout_rms_rad": check.rms_rad}
    (out_dir / "identification.json").write_text(json.dumps(summary, indent=2))
    for x in estimates:
        print(f"cycle {x.cycle}: condition {x.condition:.2f}, K (N m/rad) =\n{np.round(x.K, 2)}")
    print(f"held-out pose error with K_D: rms {1e3 * check.rms_rad:.2f} mrad over {len(held)} rows")
    print(f"outputs in {out_dir}")
    return summary


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="csjm_example_"))
    out.mkdir(parents=True, exist_ok=True)
    main(out)
