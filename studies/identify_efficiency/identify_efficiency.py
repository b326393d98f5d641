"""Study: K_ml at its Cramér-Rao bound, and planned experiments against the paper's protocol.

For ``--rigs`` random rigs (:func:`csjm_opt.testbed.rigs.random_rig`, each with its own
instrument noise) two designs of ``--budget`` loads are made: the paper's protocol (one pose,
25 N pretension, U(3, 15) N dead weights in random directions at four points) and a planned
one (:func:`csjm_opt.identification.experiment_design.plan_experiment`, A-criterion). Each is
run ``--logs`` times on the testbed's plant (fresh noise each time) and identified with
``identify_log`` (K_ml, the default; the noise stated, and again estimated from the data).
The truth is the cable stiffness at the reference equilibrium of the plant. One rig is also
run with MuJoCo as the plant (dead weights as ``xfrc_applied`` forces at their points; the pose
settled by Newton steps on MuJoCo's own net moment).

Acceptance figures (issue 21), pooled over all logs of the testbed rigs:
efficiency ``mean trace(bound) / mean ||e||^2``; bias of each entry in standard errors
(errors normalised by the reported bound); 95 % coverage per entry; trace of the Monte Carlo
covariance over the mean trace of the bound; planned against paper interval widths
(predicted and realised, mean over the six entries). Also the paper's estimators (K, K_sym)
on the same logs, and K_ml with a rig model whose cable stiffness is 20 % low.

Run: ``python -m studies.identify_efficiency.identify_efficiency [--rigs 10] [--logs 20] [--budget 40] [--seed 0]``
Writes ``studies/identify_efficiency/identify_efficiency.json`` and ``docs/guide/img/identify_efficiency.png``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

from csjm_opt import so3
from csjm_opt.identification.cramer_rao import sym_entries
from csjm_opt.identification.experiment_design import paper_protocol, plan_experiment
from csjm_opt.identification.log_identification import identify_log
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed.plant import TestbedPlant
from csjm_opt.testbed.protocol_runner import dead_weight_moments, run_protocol, settle_protocol
from csjm_opt.testbed.rigs import random_rig

ROOT = Path(__file__).resolve().parents[2]


# ----------------------------------------------------------------- MuJoCo as the plant
def mujoco_settle(rig, protocol):
    """True poses and dead-weight moments of every protocol row, settled in MuJoCo."""
    import mujoco

    from csjm_opt.testbed.mujoco.reference import build, rotation, settle

    l = protocol.rest_lengths_m[0]
    R_ref, _, ok = settle(rig, l, np.eye(3), np.zeros(3))
    assert ok, "MuJoCo reference does not settle"
    m, d = build(rig, l, R_ref, np.zeros(3))
    d.ctrl[:] = 0.0
    q_ref = d.qpos.copy()

    def net(q, f, p):
        d.qpos[:] = q
        d.qvel[:] = 0.0
        R = rotation(q)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        d.xfrc_applied[1, :3] = f
        d.xfrc_applied[1, 3:] = np.cross(R @ p - d.xipos[1], f)   # force at the point, not at the COM
        mujoco.mj_forward(m, d)
        return d.qfrc_smooth.copy()

    def step(q, z):
        q2 = q.copy()
        mujoco.mj_integratePos(m, q2, z, 1.0)
        return q2

    Rs = []
    for f, p in zip(protocol.force_B_N, protocol.point_A_m):
        q = q_ref.copy()

        def jac(q, f=f, p=p):
            return np.column_stack([(net(step(q, 1e-7 * e), f, p) - net(step(q, -1e-7 * e), f, p)) / 2e-7
                                    for e in np.eye(3)])

        for _ in range(50):
            Q = net(q, f, p)
            if np.abs(Q).max() < 1e-12:
                break
            z = -np.linalg.solve(jac(q), Q)
            z *= min(1.0, 0.05 / np.linalg.norm(z))
            q = step(q, z)
        assert np.abs(net(q, f, p)).max() < 1e-9 and np.all(np.linalg.eigvals(-jac(q)).real > 0)
        Rs.append(rotation(q))
    R = np.array(Rs)
    return R, dead_weight_moments(R, protocol.force_B_N, protocol.point_A_m)


def noisy_log(protocol, R_true, tau, noise, rng):
    n = len(protocol)
    tau_m = tau + rng.normal(size=(n, 3)) * np.asarray(noise.tau_sigma_Nm)
    R_m = R_true @ so3.exp(rng.normal(size=(n, 3)) * noise.angle_sigma_rad)
    return MeasurementLog.from_arrays(protocol.cycle, protocol.rest_lengths_m, tau_m, R_m,
                                      extra=protocol.extra_columns())


# ----------------------------------------------------------------- statistics
def record(log, rig, noise, K_true, wrong_rig=None):
    e = identify_log(log, rig, noise=noise, allow_ill_conditioned=True)[0]
    u = identify_log(log, rig, noise=None, allow_ill_conditioned=True)[0]
    out = {"ml": sym_entries(e.K_ml) - K_true, "crlb": np.diag(e.crlb6).tolist(),
           "cover": e.covers(sym_full(K_true), "K_ml"), "cover_est": u.covers(sym_full(K_true), "K_ml"),
           "ml_est": sym_entries(u.K_ml) - K_true, "sym": sym_entries(e.K_sym) - K_true,
           "paper": sym_entries(e.K) - K_true, "efficiency_reported": e.efficiency}
    out["cover"] = [bool(out["cover"][i, j]) for i, j in IDX]
    out["cover_est"] = [bool(out["cover_est"][i, j]) for i, j in IDX]
    if wrong_rig is not None:
        out["wrong"] = sym_entries(identify_log(log, wrong_rig, noise=noise, allow_ill_conditioned=True)[0].K_ml) \
            - K_true
    return out


IDX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def sym_full(s):
    K = np.zeros((3, 3))
    for v, (i, j) in zip(s, IDX):
        K[i, j] = K[j, i] = v
    return K


def summarise(recs, key="ml"):
    e = np.array([r[key] for r in recs])
    B = np.array([r["crlb"] for r in recs])
    z = e / np.sqrt(B)
    se = z.std(0, ddof=1) / np.sqrt(len(z))
    return {"logs": len(e), "efficiency": float(B.sum(1).mean() / (e ** 2).sum(1).mean()),
            "efficiency_normalised": float(1.0 / np.mean((e ** 2).sum(1) / B.sum(1))),
            "bias_in_se": (z.mean(0) / se).round(2).tolist(),
            "coverage": np.mean([r["cover"] for r in recs], 0).round(3).tolist() if key == "ml" else None,
            "coverage_noise_estimated": np.mean([r["cover_est"] for r in recs], 0).round(3).tolist()
            if key == "ml" else None,
            "rms_over_bound_std": np.sqrt((z ** 2).mean(0)).round(3).tolist()}


def realised_half_width(errors):
    """Mean over the six entries of 1.96 x each entry's RMS error (comparable with the predicted half-widths)."""
    return float(np.mean(1.96 * np.sqrt(np.mean(np.square(errors), axis=0))))


def mc_vs_bound(groups):
    """Sum over designs of trace(MC covariance) over the sum of mean trace(bound)."""
    mc = sum(np.trace(np.cov(np.array([r["ml"] for r in g]).T)) for g in groups)
    bd = sum(np.mean([np.sum(r["crlb"]) for r in g]) for g in groups)
    return float(mc / bd)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rigs", type=int, default=10)
    ap.add_argument("--logs", type=int, default=20)
    ap.add_argument("--budget", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-mujoco", action="store_true")
    ap.add_argument("--mujoco-logs", type=int, default=100, help="logs per design with MuJoCo as the plant")
    ap.add_argument("--sweep", type=int, nargs="*", default=[12, 24, 40, 60, 90])
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    res = {"args": vars(args), "rigs": []}
    groups = {"paper": [], "planned": []}
    widths = {"paper_pred": [], "planned_pred": [], "paper_real": [], "planned_real": []}
    wrong = []
    bar = tqdm(total=args.rigs * 2 * args.logs, file=sys.stderr, desc="logs")
    rigs = []
    for r in range(args.rigs):
        rig, noise = random_rig(rng)
        rigs.append((rig, noise))
        designs = {"paper": paper_protocol(rig, args.budget, rng, noise=noise),
                   "planned": plan_experiment(rig, args.budget, noise=noise)}
        entry = {"rig": r, "noise": [list(noise.tau_sigma_Nm), noise.angle_sigma_rad]}
        for name, des in designs.items():
            l = des.protocol.rest_lengths_m[0]
            K_true = sym_entries(solve_equilibrium(rig, l, R_init=np.eye(3)).K)
            wr = rig.replace(cable_stiffness_N_per_m=0.8 * np.asarray(rig.cable_stiffness_N_per_m)) \
                if name == "paper" else None
            recs = []
            for _ in range(args.logs):
                recs.append(record(run_protocol(rig, des.protocol, rng, noise), rig, noise, K_true, wr))
                bar.update()
            groups[name].append(recs)
            if wr is not None:
                wrong += recs
            widths[f"{name}_pred"].append(float(des.ci_half_width().mean()))
            widths[f"{name}_real"].append(realised_half_width([x["ml"] for x in recs]))
            entry[name] = {"pretension_N": des.pretension_N, "K_true": K_true.tolist(),
                           "pred_half_width": des.ci_half_width()[0].tolist(), **summarise(recs)}
        res["rigs"].append(entry)
    bar.close()
    everything = [x for g in groups.values() for recs in g for x in recs]
    res["pooled"] = summarise(everything)
    all_groups = [g for gs in groups.values() for g in gs]
    res["pooled"]["mc_trace_over_bound"] = mc_vs_bound(all_groups)
    per = [summarise(g) for g in all_groups]
    res["per_design"] = {"efficiency": [round(x["efficiency"], 3) for x in per],
                         "mc_trace_over_bound": [round(mc_vs_bound([g]), 3) for g in all_groups],
                         "entries_with_bias_over_2se": int(sum(np.sum(np.abs(x["bias_in_se"]) > 2) for x in per)),
                         "entries_tested": 6 * len(per)}
    res["paper_estimators"] = {"K_sym": summarise(everything, "sym"), "K_(50)": summarise(everything, "paper"),
                               "K_ml_noise_estimated": summarise(everything, "ml_est")}
    res["wrong_rig_model_k_minus_20pct"] = summarise(wrong, "wrong")
    res["planned_vs_paper"] = {
        "predicted_ratio_per_rig": (np.array(widths["paper_pred"]) / widths["planned_pred"]).round(2).tolist(),
        "realised_ratio_per_rig": (np.array(widths["paper_real"]) / widths["planned_real"]).round(2).tolist()}
    for k in ("predicted", "realised"):
        v = res["planned_vs_paper"][f"{k}_ratio_per_rig"]
        res["planned_vs_paper"][f"{k}_ratio_mean"] = float(np.mean(v))
        res["planned_vs_paper"][f"{k}_ratio_min"] = float(np.min(v))
    if not args.no_mujoco:
        res["mujoco"] = run_mujoco(rigs[0], args, rng)
    res["sweep"] = sweep(rigs[0], args, rng)
    out = ROOT / "studies" / "identify_efficiency" / "identify_efficiency.json"
    out.write_text(json.dumps(res, indent=1, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o)))
    figure(res, ROOT / "docs" / "guide" / "img" / "identify_efficiency.png")
    p = res["pooled"]
    print(f"pooled over {p['logs']} logs on {args.rigs} rigs: efficiency {p['efficiency']:.3f}, "
          f"bias/SE {p['bias_in_se']}, coverage {p['coverage']}, MC/bound trace {p['mc_trace_over_bound']:.3f}")
    print("planned vs paper:", res["planned_vs_paper"])
    if "mujoco" in res:
        print("mujoco:", res["mujoco"])
    return 0


def run_mujoco(rig_noise, args, rng):
    rig, noise = rig_noise
    out = {}
    for name, des in {"paper": paper_protocol(rig, args.budget, rng, noise=noise),
                      "planned": plan_experiment(rig, args.budget, noise=noise)}.items():
        R_true, tau = mujoco_settle(rig, des.protocol)
        R_tb, _ = settle_protocol(TestbedPlant(rig), des.protocol)
        out[f"{name}_mujoco_vs_testbed_max_rad"] = float(np.max(np.linalg.norm(
            so3.log(np.swapaxes(R_tb, 1, 2) @ R_true), axis=1)))
        K_true = sym_entries(solve_equilibrium(rig, des.protocol.rest_lengths_m[0], R_init=np.eye(3)).K)
        recs = [record(noisy_log(des.protocol, R_true, tau, noise, rng), rig, noise, K_true)
                for _ in tqdm(range(args.mujoco_logs), file=sys.stderr, desc=f"mujoco {name}")]
        out[name] = summarise(recs) | {"mc_trace_over_bound": mc_vs_bound([recs])}
    return out


def sweep(rig_noise, args, rng):
    rig, noise = rig_noise
    out = {"budget": [], "paper_pred": [], "planned_pred": [], "paper_real": [], "planned_real": []}
    for b in tqdm(args.sweep, file=sys.stderr, desc="budget sweep"):
        out["budget"].append(b)
        for name, des in {"paper": paper_protocol(rig, b, rng, noise=noise),
                          "planned": plan_experiment(rig, b, noise=noise)}.items():
            K_true = sym_entries(solve_equilibrium(rig, des.protocol.rest_lengths_m[0], R_init=np.eye(3)).K)
            e = [record(run_protocol(rig, des.protocol, rng, noise), rig, noise, K_true)["ml"] for _ in range(12)]
            out[f"{name}_pred"].append(float(des.ci_half_width().mean()))
            out[f"{name}_real"].append(realised_half_width(e))
    return out


def figure(res, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = res["sweep"]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(s["budget"], s["paper_pred"], "-", color="C0", label="paper protocol: bound")
    ax.loglog(s["budget"], s["paper_real"], "o", color="C0", label="paper protocol: realised (K_ml)")
    ax.loglog(s["budget"], s["planned_pred"], "-", color="C1", label="planned: bound")
    ax.loglog(s["budget"], s["planned_real"], "s", color="C1", label="planned: realised (K_ml)")
    ax.set_xlabel("budget (loads)")
    ax.set_ylabel("95 % half-width, mean over K's six entries (N m/rad)")
    ax.set_title("Bound and realised error against budget (random rig 0)")
    from matplotlib.ticker import ScalarFormatter

    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(ScalarFormatter())
        axis.set_minor_formatter(ScalarFormatter())
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")


if __name__ == "__main__":
    sys.exit(main())
