"""Diagnosis speed: 200-row logs with all six candidates (target: under a minute on 2 cores).

Run: python benchmarks/bench_diagnose.py [--cycles 22] [--repeat 1]

Baseline measured in the same run: fitting one candidate (``sensor_bias``) the
direct way, ``scipy.optimize.least_squares`` on *forward-statics* pose
residuals (a full equilibrium solve of every row at every evaluation), against
the linearised fit the package uses; both fits' held-out-free results are
printed so the speed-up is for the same answer.
"""

from __future__ import annotations

import argparse
import sys
import time
from functools import partial

import numpy as np
from scipy.optimize import least_squares
from tqdm import tqdm

import csjm_opt as co
from csjm_opt.diagnose import diagnose
from csjm_opt.diagnose.augmented import AugmentedModel
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fit import fit_model
from csjm_opt.diagnose.residuals import compute_residuals, pose_residuals
from csjm_opt.testbed import simulate_experiment


def forward_fit(model: AugmentedModel, table) -> tuple[np.ndarray, float]:
    """The direct way: least squares on forward-statics residuals (numerical Jacobian)."""
    scales = model.scales

    def res(x):
        sol = model.predict_poses(table.rows, x * scales, table.R_meas)
        z = pose_residuals(sol.R, table.R_meas)
        return np.einsum("nij,nj->ni", table.whiten, z).ravel()

    t0 = time.perf_counter()
    sol = least_squares(res, model.x0() / scales, method="trf", xtol=1e-10, ftol=1e-10)
    return sol.x * scales, time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=22, help="9 rows per cycle (22 -> 198 rows)")
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args()
    rig = co.paper_rig()
    for effect in ("friction", "hole_offsets", "none"):
        log = simulate_experiment(rig, args.cycles, np.random.default_rng(0), effect=effect)
        print(f"log: {len(log)} rows, {len(log.cycle_ids)} cycles, injected effect: {effect}")
        times = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            d = diagnose(rig, log, progress=partial(tqdm, file=sys.stderr))
            times.append(time.perf_counter() - t0)
        j = d.as_json()
        print(f"  diagnose, 6 candidates + nominal refit + second-effect search, grouped 5-fold CV: median "
              f"{np.median(times):.1f} s (target < 60 s) -> selected {j['selected']} (+ {j['secondary']['effect']}), "
              f"gap {1e3 * j['gap']['before_rad']:.2f} -> {1e3 * j['gap']['after_rad']:.2f} mrad")

    log_b = simulate_experiment(rig, args.cycles, np.random.default_rng(1), effect="sensor_bias")
    table = compute_residuals(rig, log_b)
    model = AugmentedModel(rig, [make_effect("sensor_bias", rig)])
    t0 = time.perf_counter()
    lin = fit_model(model, table)
    t_lin = time.perf_counter() - t0
    theta_fwd, t_fwd = forward_fit(model, table)
    print(f"one candidate fit (sensor_bias log, {len(log_b)} rows): linearised {t_lin:.2f} s, "
          f"forward-statics residuals {t_fwd:.2f} s, ratio {t_fwd / t_lin:.1f}x; "
          f"max parameter difference "
          f"{np.abs(lin.theta - theta_fwd).max():.2g} (bias sd {lin.stderr[2:].max():.2g} N m)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
