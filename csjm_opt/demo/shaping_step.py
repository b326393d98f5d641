"""The shaping part of ``csjm demo``: shape K at a paper pose, reachable set, short closed loop.

Also holds :func:`soft_stiff_targets`, shared with ``studies/soft_stiff_switch/soft_stiff_switch.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .. import so3
from .._fileio import atomic_write_json
from .._plotting import save
from .._validate import as_rotation
from ..control.closed_loop import plot_closed_loop, plot_closed_loop_stiffness, simulate
from ..control.controllers import StiffnessShapingController
from ..control.load_profiles import Constant, Sinusoid, Step
from ..model.numeric import Model
from ..model.rig import Rig
from ..report.document import Cell, Column, Figure, Section, Table, quantity_table, sig
from ..shaping.figures import plot_reachable_set
from ..shaping.reachable import reachable_set, tension_lp
from ..shaping.shaper import shape_stiffness, stiffness_basis
from ._step import DemoContext, StepOutput

#: Table 3's original pose R0 with erratum 3 applied (element (3,2) = -0.300).
PAPER_R0 = np.array([[0.992, -0.060, -0.111], [0.090, 0.952, 0.292], [0.088, -0.300, 0.950]])
#: A moderate external moment for the demo (N m, in {A}).
DEMO_TAU_EXT = np.array([0.2, -0.5, 0.1])


def soft_stiff_targets(rig: Rig, R: np.ndarray, tau_ext: np.ndarray, direction: ArrayLike = (1.0, 0.0, 0.0),
                       margin: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Two reachable targets (N m/rad) at ``R`` under ``tau_ext``: softest and stiffest along ``direction``.

    Each is K at feasible tensions: those minimising (maximising) the
    directional stiffness ``u^T K u`` (an exact LP, :mod:`csjm_opt.shaping.reachable`),
    pulled ``margin`` of the way toward the mid-range plan so that they are
    not on the boundary of the feasible set.
    """
    from ..planning.planner import plan_tensions

    basis = stiffness_basis(rig, R)
    tau_load = tau_ext + basis.tau_weight_A_Nm
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    g = np.einsum("j,ijk,k->i", u, basis.G, u)
    T_mid = plan_tensions(rig, R, tau_ext).tensions_N
    T_soft = tension_lp(g, basis.J, tau_load, rig.t_min_N, rig.t_max_N)
    T_stiff = tension_lp(-g, basis.J, tau_load, rig.t_min_N, rig.t_max_N)
    return (basis.K((1 - margin) * T_soft + margin * T_mid), basis.K((1 - margin) * T_stiff + margin * T_mid))


#: Closed-loop disturbance of the demo: a step and a sinusoid about x (N m, Hz).
STEP_NM, SINE_NM, SINE_HZ = 0.15, 0.05, 10.0


def run_demo(rig: Rig, out_dir: Path, R: np.ndarray | None = None, tau_ext: np.ndarray | None = None,
             duration_s: float = 0.3, dt_s: float = 1e-3, n_samples: int = 1500) -> dict:
    """Shaping example, reachable-set figure and a short closed loop; returns a JSON-able summary.

    Parameters
    ----------
    rig : Rig
    out_dir : Path
        Folder for the figures and ``shaping_summary.json``.
    R : (3, 3) array, optional
        Pose to shape at (default: Table 3's R0, corrected).
    tau_ext : (3,) array, optional
        External moment (N m, {A}); default :data:`DEMO_TAU_EXT`.
    duration_s, dt_s : float
        Closed-loop duration and step.
    n_samples : int
        Random tension samples of the reachable set (besides its vertices).

    Returns
    -------
    dict
        JSON-able summary (figure paths relative to ``out_dir``).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    R = as_rotation(PAPER_R0 if R is None else R)
    tau = DEMO_TAU_EXT if tau_ext is None else np.asarray(tau_ext, float)
    model = Model(rig)

    # 1. shaping: a reachable target (from feasible tensions) and an unreachable isotropic one
    K_soft, K_stiff = soft_stiff_targets(rig, R, tau)
    reach = shape_stiffness(rig, R, tau, K_stiff, model=model)
    rs = reachable_set(rig, R, tau, n_samples=n_samples)
    iso = 1.15 * rs.eigen_ranges[2, 1] * np.eye(3)           # stiffer than any eigenvalue can be
    unreach = shape_stiffness(rig, R, tau, iso, model=model)

    # 2. reachable set figure, with the two shaped results marked
    ax_eig, _ = plot_reachable_set(rs, rig.t_min_N, rig.t_max_N, {"shaped (reachable target)": reach.K,
                                                                   "shaped (isotropic target)": unreach.K})
    fig_reach = save(ax_eig.figure, out_dir / "reachable_set.png")

    # 3. closed loop: hold R, step + sinusoidal disturbance about x, soft/stiff (about x) switching at half time
    half = duration_s / 2
    target = lambda t: K_soft if t < half else K_stiff                         # noqa: E731
    load = Constant(tau) + Step(0.2 * duration_s, np.array([STEP_NM, 0.0, 0.0]))
    load = load + Sinusoid(np.array([SINE_NM, 0.0, 0.0]), SINE_HZ)
    ctrl = StiffnessShapingController(rig, R, target)
    log = simulate(rig, ctrl, load, duration_s, dt_s)
    figs = [save(plot_closed_loop(log, rig.t_min_N, rig.t_max_N)[0].figure, out_dir / "closed_loop.png"),
            save(plot_closed_loop_stiffness(log)[0].figure, out_dir / "closed_loop_K.png")]
    summ = log.summary()

    summary = {
        "pose_rotvec_rad": so3.log(R).tolist(),
        "tau_ext_Nm": tau.tolist(),
        "reachable_target_residual_Nm_per_rad": reach.residual,
        "reachable_target_exact": reach.exact,
        "soft_Kxx_Nm_per_rad": float(K_soft[0, 0]),
        "stiff_Kxx_Nm_per_rad": float(K_stiff[0, 0]),
        "isotropic_target_Nm_per_rad": float(iso[0, 0]),
        "isotropic_target_residual_Nm_per_rad": unreach.residual,
        "isotropic_target_exact": unreach.exact,
        "isotropic_active_bounds": ", ".join(unreach.active_bounds) or "none",
        "eigen_ranges_Nm_per_rad": rs.eigen_ranges.tolist(),
        "closed_loop_steps": summ["steps"],
        "closed_loop_max_pose_error_rad": summ["max_pose_error_rad"],
        "closed_loop_final_pose_error_rad": summ["final_pose_error_rad"],
        "closed_loop_final_stiffness_error_Nm_per_rad": summ["final_stiffness_error_Nm_per_rad"],
        "closed_loop_median_step_us": 1e6 * summ["median_step_time_s"],
        "reachable_target_K_Nm_per_rad": reach.K.tolist(),
        "isotropic_nearest_eigenvalues_Nm_per_rad": np.linalg.eigvalsh(unreach.K).tolist(),
        "isotropic_target_over_max_eigenvalue": float(iso[0, 0] / rs.eigen_ranges[2, 1]),
        "closed_loop_dt_s": dt_s,
        "closed_loop_switch_s": half,
        "closed_loop_disturbance": {"step_Nm": STEP_NM, "step_at_s": 0.2 * duration_s,
                                    "sinusoid_amplitude_Nm": SINE_NM, "sinusoid_Hz": SINE_HZ, "axis": "x"},
        "closed_loop_static_estimate_rad": (STEP_NM + SINE_NM) / float(K_soft[0, 0]),
        "shaping": {"reachable": reach.as_dict(), "isotropic": unreach.as_dict()},
        "reachable_set": rs.as_dict(),
        "closed_loop": summ,
        "figures": [p.relative_to(out_dir).as_posix() for p in [fig_reach, *figs]],
    }
    atomic_write_json(out_dir / "shaping_summary.json", summary)
    return summary


# ------------------------------------------------------------------ demo step and report section
NAME = "stiffness shaping and closed loop"


def step(ctx: DemoContext) -> StepOutput:
    """The demo step: :func:`run_demo` into ``shaping/`` (smaller reachable set and loop when quick)."""
    summary = run_demo(ctx.rig, ctx.out_dir / "shaping", duration_s=0.2 if ctx.quick else 0.3,
                       n_samples=400 if ctx.quick else 1500)
    return StepOutput(summary, section(summary).rebase("shaping"))


def section(s: dict) -> Section:
    """The report section of :func:`run_demo`'s summary (paths relative to its folder)."""
    lam = s["isotropic_nearest_eigenvalues_Nm_per_rad"]
    ranges = s["eigen_ranges_Nm_per_rad"]
    reach_ok = bool(s["reachable_target_exact"])
    iso_ok = not s["isotropic_target_exact"]
    verdict = (f"At Table 3's pose under {sig(float(np.linalg.norm(s['tau_ext_Nm'])))} N m, a target built from "
               "feasible "
               f"tensions (K_xx = {sig(s['stiff_Kxx_Nm_per_rad'])} N m/rad) is met to "
               f"{sig(s['reachable_target_residual_Nm_per_rad'], 2)} N m/rad: "
               + ("exact, as expected for a reachable target. " if reach_ok else "NOT exact, unexpected. ")
               + f"Isotropic {sig(s['isotropic_target_Nm_per_rad'])} N m/rad is "
               + (f"not reachable here, as expected ({sig(100 * (s['isotropic_target_over_max_eigenvalue'] - 1), 2)}% "
                  f"above the largest reachable eigenvalue {sig(ranges[2][1])}): "
                  f"{_cables_at_bounds(s['isotropic_active_bounds'])}; the nearest K has eigenvalues "
                  f"{', '.join(sig(x) for x in lam)} N m/rad." if iso_ok else "reached, which should not happen."))
    facts = quantity_table([
        ("reachable target: K_xx", Cell(s["stiff_Kxx_Nm_per_rad"], src=("stiff_Kxx_Nm_per_rad",)), "N m/rad", ""),
        ("reachable target: Frobenius error",
         Cell(s["reachable_target_residual_Nm_per_rad"], "sig2", src=("reachable_target_residual_Nm_per_rad",)),
         "N m/rad", "~0 (exact)"),
        ("isotropic target", Cell(s["isotropic_target_Nm_per_rad"], src=("isotropic_target_Nm_per_rad",)),
         "N m/rad", "above the reachable range"),
        ("isotropic target: Frobenius error",
         Cell(s["isotropic_target_residual_Nm_per_rad"], src=("isotropic_target_residual_Nm_per_rad",)),
         "N m/rad", "> 0 (unreachable)"),
        ("isotropic target: cables at a bound", s["isotropic_active_bounds"], "", "some at t_min or t_max"),
    ] + [(f"nearest K: eigenvalue {k + 1}", Cell(x, src=("isotropic_nearest_eigenvalues_Nm_per_rad", k)),
          "N m/rad", "") for k, x in enumerate(lam)], expectation=True)
    reach = Table([Column("eigenvalue of K"), Column("lowest reachable", "N m/rad"),
                   Column("highest reachable", "N m/rad")],
                  [[f"{k + 1}", Cell(lo, src=("eigen_ranges_Nm_per_rad", k, 0)),
                    Cell(hi, src=("eigen_ranges_Nm_per_rad", k, 1))] for k, (lo, hi) in enumerate(ranges)],
                  "Reachable set at this pose and load (all tensions in [t_min, t_max])")
    figs = {name.split(".")[0]: name for name in s["figures"]}
    shaping = Section("Stiffness shaping and closed loop", verdict, "ok" if reach_ok and iso_ok else "warn",
                      [facts, reach])
    if "reachable_set" in figs:
        shaping.add(Figure(figs["reachable_set"], "Reachable eigenvalues of K and directional stiffness in the "
                                                  "x-y plane, with the two shaped results marked."))
    shaping.subsections.append(_closed_loop_section(s, figs))
    return shaping


def _closed_loop_section(s: dict, figs: dict) -> Section:
    d = s["closed_loop_disturbance"]
    err, est = s["closed_loop_max_pose_error_rad"], s["closed_loop_static_estimate_rad"]
    period_us = 1e6 * s["closed_loop_dt_s"]
    ok = err <= 1.5 * est and s["closed_loop_median_step_us"] < period_us
    verdict = (f"Held the pose for {s['closed_loop']['duration_s']:.2f} s ({s['closed_loop_steps']} steps) under a "
               f"{d['step_Nm']:g} N m step and a {d['sinusoid_amplitude_Nm']:g} N m, {d['sinusoid_Hz']:g} Hz "
               f"disturbance about x, switching from soft (K_xx {sig(s['soft_Kxx_Nm_per_rad'])}) to stiff "
               f"(K_xx {sig(s['stiff_Kxx_Nm_per_rad'])} N m/rad) at {s['closed_loop_switch_s']:g} s. Largest "
               f"pose error {sig(err, 3, 1e3)} mrad against the static estimate (step + amplitude) / K_xx,soft = "
               f"{sig(est, 3, 1e3)} mrad; final stiffness error "
               f"{sig(s['closed_loop_final_stiffness_error_Nm_per_rad'], 2)}"
               f" N m/rad; median controller step {sig(s['closed_loop_median_step_us'], 2)} us "
               + ("(real time at 1 kHz needs < 1000 us)." if period_us == 1000 else f"(period {sig(period_us)} us)."))
    facts = quantity_table([
        ("largest pose error", Cell(err, scale=1e3, src=("closed_loop_max_pose_error_rad",)), "mrad",
         f"about {sig(est, 3, 1e3)} (static estimate)"),
        ("final pose error", Cell(s["closed_loop_final_pose_error_rad"], scale=1e3,
                                  src=("closed_loop_final_pose_error_rad",)), "mrad", ""),
        ("final stiffness error", Cell(s["closed_loop_final_stiffness_error_Nm_per_rad"], "sig2",
                                       src=("closed_loop_final_stiffness_error_Nm_per_rad",)), "N m/rad", "~0"),
        ("tension range", f"{sig(s['closed_loop']['min_tension_N'])} to {sig(s['closed_loop']['max_tension_N'])}",
         "N", "within the bounds"),
        ("median controller step", Cell(s["closed_loop_median_step_us"], "sig2", src=("closed_loop_median_step_us",)),
         "us", f"< {sig(period_us)} (real time)"),
    ], expectation=True)
    sec = Section("Closed loop", verdict, "ok" if ok else "warn", [facts])
    for key, caption in (("closed_loop", "Pose error, external moment and tensions over time."),
                         ("closed_loop_K", "Stiffness achieved against the target over time.")):
        if key in figs:
            sec.add(Figure(figs[key], caption))
    return sec


def _cables_at_bounds(active: str) -> str:
    if not active or active == "none":
        return "no cable at a bound"
    n = len(active.split(","))
    return f"{n} cable{'s' if n > 1 else ''} at a tension bound ({active})"
