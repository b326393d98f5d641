"""First ``csjm demo`` step: tensions and stiffness over a ring of tilted poses under the platform's weight."""

from __future__ import annotations

import numpy as np

from .. import _plotting as plots
from .. import so3
from ..model.numeric import Model
from ..planning.planner import plan_tensions_batch
from ..report.document import Cell, Column, Figure, Section, Table, View, quantity_table, sig
from ..view import poses_view
from ._step import DemoContext, StepOutput

NAME = "plan tensions and stiffness"
TILTS_DEG = (5.0, 10.0, 15.0, 20.0)
AZIMUTHS_DEG = (0.0, 60.0, 120.0)
#: Equilibrium residual (N m) below which the plan is exact up to round-off.
ROUND_OFF_NM = 1e-9


def step(ctx: DemoContext) -> StepOutput:
    """Plan tensions and compute K at 13 poses; figure, summary and section."""
    rig, model = ctx.rig, Model(ctx.rig)
    poses = [(0.0, 0.0)] + [(t, a) for t in TILTS_DEG for a in AZIMUTHS_DEG]
    rotvecs = [np.deg2rad(t) * np.array([np.cos(np.deg2rad(a)), np.sin(np.deg2rad(a)), 0.0]) for t, a in poses]
    labels = ["upright"] + [f"tilt {t:.0f} deg @ {a:.0f}" for t, a in poses[1:]]
    Rs = so3.exp(np.array(rotvecs))
    plans = plan_tensions_batch(rig, Rs, np.zeros((len(Rs), 3)))
    T = plans.tensions_N
    K = model.stiffness(Rs, T)
    eig = np.linalg.eigvalsh(K)
    plots.save(plots.tensions_and_ellipsoids(labels, T, K, rig.t_min_N, rig.t_max_N),
               ctx.out_dir / "tensions_and_stiffness.png")
    poses_view(rig, Rs, np.zeros((len(Rs), 3)), labels, title="The paper rig at the demo's poses").write(
        ctx.out_dir / "rig.html")
    rows = [{"pose": lab, "rotvec": rv.tolist(), "tilt_deg": t, "azimuth_deg": a, "tensions_N": ti.tolist(),
             "min_tension_N": float(ti.min()), "max_tension_N": float(ti.max()), "K": k.tolist(),
             "eigenvalues_Nm_per_rad": e.tolist()}
            for lab, rv, (t, a), ti, k, e in zip(labels, rotvecs, poses, T, K, eig)]
    summary = {"poses": rows, "max_equilibrium_residual_Nm": float(plans.equilibrium_residual_Nm.max()),
               "min_eigenvalue_Nm_per_rad": float(eig.min()), "figure": "tensions_and_stiffness.png",
               "view": "rig.html",
               "min_tension_N": float(T.min()), "max_tension_N": float(T.max()),
               "t_min_N": float(rig.t_min_N), "t_max_N": float(rig.t_max_N)}
    return StepOutput(summary, section(summary))


def section(s: dict) -> Section:
    """The report section of :func:`step`'s summary."""
    res, lam = s["max_equilibrium_residual_Nm"], s["min_eigenvalue_Nm_per_rad"]
    tol = 1e-6 * s["t_max_N"]
    in_bounds = s["min_tension_N"] >= s["t_min_N"] - tol and s["max_tension_N"] <= s["t_max_N"] + tol
    ok = res < ROUND_OFF_NM and in_bounds and lam > 0
    verdict = (f"Planned cable tensions at {len(s['poses'])} poses (upright, and tilts of "
               f"{TILTS_DEG[0]:.0f} to {TILTS_DEG[-1]:.0f} deg at {len(AZIMUTHS_DEG)} azimuths) under the "
               f"platform's own weight. Largest equilibrium residual {sig(res, 2)} N m: "
               + ("at round-off, as expected" if res < ROUND_OFF_NM else f"above round-off ({ROUND_OFF_NM:g} N m)")
               + f". Tensions stay {'within' if in_bounds else 'OUTSIDE'} [{s['t_min_N']:g}, {s['t_max_N']:g}] N "
               f"(lowest {sig(s['min_tension_N'])} N, highest {sig(s['max_tension_N'])} N), and K is "
               + (f"positive definite at every pose (smallest eigenvalue {sig(lam)} N m/rad)." if lam > 0 else
                  f"NOT positive definite (smallest eigenvalue {sig(lam)} N m/rad)."))
    facts = quantity_table([
        ("largest equilibrium residual", Cell(res, "sig2", src=("max_equilibrium_residual_Nm",)), "N m",
         f"< {ROUND_OFF_NM:g} (round-off)"),
        ("lowest tension", Cell(s["min_tension_N"], src=("min_tension_N",)), "N", f">= t_min = {s['t_min_N']:g}"),
        ("highest tension", Cell(s["max_tension_N"], src=("max_tension_N",)), "N", f"<= t_max = {s['t_max_N']:g}"),
        ("smallest eigenvalue of K", Cell(lam, src=("min_eigenvalue_Nm_per_rad",)), "N m/rad", "> 0 (stable)"),
    ], expectation=True)
    cols = [Column("pose"), Column("tilt", "deg", "fix0"), Column("azimuth", "deg", "fix0"),
            Column("lowest tension", "N"), Column("highest tension", "N"),
            Column("eigenvalue 1", "N m/rad"), Column("eigenvalue 2", "N m/rad"), Column("eigenvalue 3", "N m/rad")]
    body = [[p["pose"], Cell(p["tilt_deg"], src=("poses", i, "tilt_deg")),
             Cell(p["azimuth_deg"], src=("poses", i, "azimuth_deg")),
             Cell(p["min_tension_N"], src=("poses", i, "min_tension_N")),
             Cell(p["max_tension_N"], src=("poses", i, "max_tension_N"))]
            + [Cell(p["eigenvalues_Nm_per_rad"][k], src=("poses", i, "eigenvalues_Nm_per_rad", k)) for k in range(3)]
            for i, p in enumerate(s["poses"])]
    per_pose = Table(cols, body, "Per pose (every tension and K itself: summary.json)")
    fig = Figure(s["figure"], "Planned tensions per pose (dashed: tension bounds); K's directional stiffness "
                              "u^T K u in the three coordinate planes of {A} at three poses (dashed: the circle of "
                              "the mean eigenvalue, so the anisotropy shows as the gap between curve and circle); "
                              "K's eigenvalues per pose.")
    blocks: list = [facts, per_pose, fig]
    if s.get("view"):
        blocks.insert(0, View(s["view"], "The rig in 3-D at the same poses (slider): cables coloured by planned "
                                         "tension, holes numbered as in the rig file, the compliance ellipsoid of K "
                                         "at the joint centre (long axis = soft direction)."))
    return Section("Tensions and stiffness", verdict, "ok" if ok else "warn", blocks)
