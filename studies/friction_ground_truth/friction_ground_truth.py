"""Where the fitted friction law and MuJoCo's tendon friction disagree: ground truth from the engine.

For a confusion-study log id (``mujoco:single:coulomb_friction:3:0:0``) the MuJoCo log is made
again at several ramp settings (``--ramps 0.3/2 10/20 30/60``: seconds over which a row's inputs
move / a new cycle's), recording per row MuJoCo's tendon-friction forces (``efc_force`` of the
tendon-friction rows when the wait for rest ends), the noise-free moments and poses. Reported per
setting (Coulomb logs; a pair's second effect is not modelled here, so only the MuJoCo columns are
read on pairs):

* ``inside``: moving cable rows (|change of length| > 20 um) whose friction is inside its band
  (|s| < 0.98): a dry-friction element slides only at its bound;
* ``min-norm``: rms of ``s`` minus the band positions of the least-norm friction forces that hold
  the settled pose within their bounds (MuJoCo's at-rest distribution has no memory of its own);
* ``law (carried)``: the diagnosis's friction model at the TRUE parameters (bands F, stick travel
  factor 0, first state 0), each cycle predicted from the state the noise-free history leaves
  (:func:`csjm_opt.diagnose.fitting.friction_ramp.predict_ramp`): rms pose error against MuJoCo (mrad);
* ``law (one row)``: each row predicted from MuJoCo's own state and pose at the previous row;
* ``vs slowest``: rms pose difference from the last (slowest) setting (mrad).

Usage::

    python -m studies.friction_ground_truth.friction_ground_truth --id mujoco:single:coulomb_friction:3:0:0 --cycles 6 \
        --ramps 0.3/2 1/2 10/20 30/60
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

import numpy as np


def record(job: dict, ramp_s: float, cycle_ramp_s: float) -> dict:
    """Make the job's MuJoCo log at the given ramps; per-row friction forces and noise-free readings."""
    import mujoco

    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.testbed.mujoco import engine as me
    from csjm_opt.testbed.mujoco.plant import as_mujoco
    from csjm_opt.testbed.mujoco.statics import tendon_jacobian
    from studies.diagnose_confusion import diagnose_confusion as dc

    rows: list[dict] = []
    last: dict = {}
    wait, settle, sample = me.Engine._wait, me.Engine.settle, InstrumentNoise.sample

    def _wait(self):
        out = wait(self)
        d = self.d
        f = np.zeros(6)
        for r in range(d.nefc):
            if d.efc_type[r] == mujoco.mjtConstraint.mjCNSTR_FRICTION_TENDON:
                f[d.efc_id[r]] = d.efc_force[r]
        last["f"] = f
        return out

    def _settle(self, row):
        out = settle(self, row)
        bound = self.F0 + self.mu * out.tensions_N if self.capstan else self.F0.copy()
        rows.append(dict(f=last["f"].copy(), bound=bound, L=np.array(self.d.ten_length), T=out.tensions_N,
                         J=tendon_jacobian(self.m, self.d).copy(), net=self.net(self.d.qpos.copy()),
                         R=out.R_tool, settled=out.settled))
        return out

    clean: dict = {}

    def _sample(self, tau, R, rng):
        clean["tau"], clean["R"] = np.array(tau), np.array(R)
        return sample(self, tau, R, rng)

    plant_of = dc.study_plant
    me.Engine._wait, me.Engine.settle, InstrumentNoise.sample = _wait, _settle, _sample  # type: ignore
    dc.study_plant = lambda j, p: as_mujoco(p, friction_ramp_s=ramp_s, cycle_ramp_s=cycle_ramp_s)
    try:
        rig, noise, log, _, _ = dc.simulate_job(job)
    finally:
        me.Engine._wait, me.Engine.settle, InstrumentNoise.sample = wait, settle, sample  # type: ignore
        dc.study_plant = plant_of
    return dict(rig=rig, noise=noise, log=log, rows=rows[-len(log):], tau=clean["tau"])


def least_norm_band(J: np.ndarray, net: np.ndarray, bound: np.ndarray) -> np.ndarray:
    """Band positions of the least-norm friction forces ``f`` with ``J^T f = -net``, ``|f| <= bound``."""
    from scipy.optimize import minimize

    res = minimize(lambda x: x @ x, np.zeros(6), jac=lambda x: 2 * x, method="SLSQP",
                   constraints=[{"type": "eq", "fun": lambda x: J.T @ x + net, "jac": lambda x: J.T}],
                   bounds=[(-b, b) for b in bound], options={"ftol": 1e-14, "maxiter": 500})
    return -res.x / bound


def analyse(rec: dict) -> dict:
    """The columns of the module doc for one recorded log."""
    from csjm_opt.diagnose.data.residuals import compute_residuals, pose_residuals
    from csjm_opt.diagnose.effects.friction import Friction
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel, with_entry
    from csjm_opt.diagnose.fitting.friction_ramp import predict_ramp
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.model import kinematics as kin

    rig, log, rows = rec["rig"], rec["log"], rec["rows"]
    n = len(rows)
    B = np.array([r["bound"] for r in rows])
    s = -np.array([r["f"] for r in rows]) / B
    L = np.array([r["L"] for r in rows])
    dL = np.r_[np.zeros((1, 6)), np.diff(L, axis=0)]
    moving = np.abs(dL) > 20e-6
    s_ln = np.array([least_norm_band(r["J"], r["net"], r["bound"]) for r in rows])
    R_true = np.array([r["R"] for r in rows])
    out = {"rows": n, "unsettled": sum(not r["settled"] for r in rows),
           "inside": f"{int((moving & (np.abs(s) < 0.98)).sum())}/{int(moving.sum())}",
           "min_norm_rms": float(np.sqrt(np.mean((s_ln - s) ** 2))), "R": R_true,
           "tracker_mrad": 1e3 * rec["noise"].angle_sigma_rad}
    T = np.array([r["T"] for r in rows])
    coulomb = np.ptp(B, axis=0).max() < 1e-9
    band = B[0] if coulomb else np.median(B / np.maximum(T, 1e-9), axis=0)
    t = compute_residuals(rig, MeasurementLog.from_arrays(log.cycle, log.rest_lengths_m, rec["tau"], R_true),
                          rec["noise"])
    model = AugmentedModel(rig, [Friction(law="coulomb" if coulomb else "capstan")])
    theta = np.r_[0.0, band, 0.0, 0.0]
    sol, _ = predict_ramp(model, with_entry(model, t.rows, t.R_meas, theta), theta, t.R_meas)
    out["law_carried_mrad"] = 1e3 * float(np.sqrt(np.mean(np.sum(pose_residuals(sol.R, R_true) ** 2, 1))))
    c, _ = kin.cable_terms(R_true, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    l_all = np.asarray(log.rest_lengths_m, float)
    idx = np.arange(1, n)
    one = dataclasses.replace(t.rows.take(idx), cycle=np.arange(n - 1), cable_steps_m=np.zeros((n - 1, 6)),
                              log_steps_m=None, rest_steps_m=l_all[idx] - l_all[idx - 1], entry_state=s[idx - 1],
                              entry_lengths_m=c[idx - 1], entry_rest_m=l_all[idx - 1],
                              entry_tau_A_Nm=rec["tau"][idx - 1], entry_R=R_true[idx - 1])
    sol1, _ = predict_ramp(model, one, theta, R_true[idx])
    out["law_one_row_mrad"] = 1e3 * float(np.sqrt(np.mean(np.sum(pose_residuals(sol1.R, R_true[idx]) ** 2, 1))))
    return out


def main(argv: list[str] | None = None) -> int:
    from csjm_opt.diagnose.data.residuals import pose_residuals

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--id", required=True)
    ap.add_argument("--cycles", type=int, default=6)
    ap.add_argument("--ramps", nargs="+", default=["0.3/2", "10/20", "30/60"])
    args = ap.parse_args(argv)
    p = args.id.split(":")
    job = dict(id=args.id, kind=p[1], effects=p[2].split("+"), multiple=float(p[3]), rig=int(p[4]),
               rep=int(p[5]), cycles=args.cycles, plant=p[0])
    res = {}
    for r in args.ramps:
        a, b = (float(x) for x in r.split("/"))
        res[r] = analyse(record(job, a, b))
    ref = res[args.ramps[-1]]["R"]
    print(f"{args.id}, {args.cycles} cycles; tracker noise {res[args.ramps[-1]]['tracker_mrad']:.3f} mrad\n")
    print("| ramps (s) | unsettled rows | moving cable rows inside the band | s - least-norm s (rms) "
          "| law, carried (mrad) | law, one row from MuJoCo's state (mrad) | vs slowest (mrad) |")
    print("|---|---|---|---|---|---|---|")
    for r, o in res.items():
        d = np.sqrt(np.mean(np.sum(pose_residuals(o["R"], ref) ** 2, 1))) * 1e3
        print(f"| {r} | {o['unsettled']}/{o['rows']} | {o['inside']} | {o['min_norm_rms']:.3f} | "
              f"{o['law_carried_mrad']:.3f} | {o['law_one_row_mrad']:.3f} | {d:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
