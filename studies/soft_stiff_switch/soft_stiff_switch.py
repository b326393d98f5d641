"""Study: hold a pose while switching between a soft and a stiff stiffness target under a disturbance.

The paper rig holds the (errata-corrected) pose R0 of Table 3 under a constant
external moment. A disturbance about the {A} x axis (load steps, "impacts",
plus a sinusoid) acts on it; the stiffness-shaping controller reads the
(noisy) pose and moment at 1 kHz, shapes the tensions toward the current
target and commands rest lengths; the target alternates between the softest
and the stiffest reachable K along x (exact LPs, see
``csjm_opt.demo.shaping_step.soft_stiff_targets``). Because the controller acts
one step after the load changes, every disturbance step deflects the pose
once by about ``K^-1 dtau`` before the pose is restored: the deflection is
larger in the soft phases, which is what a compliant joint is for.

Run: ``python -m studies.soft_stiff_switch.soft_stiff_switch [--out DIR] [--duration S] [--dt S]
[--period S] [--no-noise]``; writes figures and ``summary.json`` into DIR
(default ``studies/out/soft_stiff_switch``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from csjm_opt import so3
from csjm_opt._fileio import atomic_write_json
from csjm_opt._plotting import save
from csjm_opt._validate import as_rotation
from csjm_opt.control.closed_loop import plot_closed_loop, plot_closed_loop_stiffness, simulate
from csjm_opt.control.controllers import StiffnessShapingController
from csjm_opt.control.load_profiles import Constant, Sinusoid, Step
from csjm_opt.demo.shaping_step import DEMO_TAU_EXT, PAPER_R0, soft_stiff_targets
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model.rig import paper_rig
from csjm_opt.shaping.figures import plot_reachable_set
from csjm_opt.shaping.reachable import reachable_set


def disturbance(duration_s: float, amplitude_Nm: float = 0.15, every_s: float = 0.125):
    """Alternating load steps about x every ``every_s`` plus a 3 Hz sinusoid (N m, in {A})."""
    load = Sinusoid([0.3 * amplitude_Nm, 0.0, 0.0], 3.0)
    for i, t0 in enumerate(np.arange(every_s / 2, duration_s, every_s)):
        load = load + Step(float(t0), [amplitude_Nm * (1 if i % 2 == 0 else -1), 0.0, 0.0])
    return load


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="studies/out/soft_stiff_switch", help="output folder")
    ap.add_argument("--duration", type=float, default=2.0, help="simulated time (s)")
    ap.add_argument("--dt", type=float, default=1e-3, help="control period (s)")
    ap.add_argument("--period", type=float, default=0.5, help="time between target switches (s)")
    ap.add_argument("--no-noise", action="store_true", help="noise-free instruments")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rig = paper_rig()
    R = as_rotation(PAPER_R0)
    K_soft, K_stiff = soft_stiff_targets(rig, R, DEMO_TAU_EXT, direction=(1.0, 0.0, 0.0))
    stiff_phase = lambda t: int(t // args.period) % 2 == 1                     # noqa: E731
    target = lambda t: K_stiff if stiff_phase(t) else K_soft                   # noqa: E731
    load = Constant(DEMO_TAU_EXT) + disturbance(args.duration)
    noise = InstrumentNoise.none() if args.no_noise else InstrumentNoise.paper()
    ctrl = StiffnessShapingController(rig, R, target, integral_gain=0.0)
    log = simulate(rig, ctrl, load, args.duration, args.dt, noise=noise, rng=np.random.default_rng(1))
    figs = [save(plot_closed_loop(log, rig.t_min_N, rig.t_max_N)[0].figure, out / "soft_stiff_switch.png"),
            save(plot_closed_loop_stiffness(log)[0].figure, out / "soft_stiff_switch_K.png")]
    rs = reachable_set(rig, R, DEMO_TAU_EXT, n_samples=1500)
    ax_eig, _ = plot_reachable_set(rs, rig.t_min_N, rig.t_max_N, {"soft target": K_soft, "stiff target": K_stiff})
    figs.append(save(ax_eig.figure, out / "reachable_set.png"))

    # per-phase deflection of the pose about x (the disturbance axis) and achieved K_xx
    zeta = so3.log(np.swapaxes(log.R_ref, 1, 2) @ log.R)
    stiff = np.array([stiff_phase(t) for t in log.t_s])
    phases = {}
    for name, mask in (("soft", ~stiff), ("stiff", stiff)):
        mask = mask.copy()
        mask[0] = False
        phases[name] = {"K_xx_target_Nm_per_rad": float((K_stiff if name == "stiff" else K_soft)[0, 0]),
                        "K_xx_achieved_mean_Nm_per_rad": float(np.mean(log.K[mask, 0, 0])),
                        "max_deflection_x_rad": float(np.max(np.abs(zeta[mask, 0]))),
                        "rms_pose_error_rad": float(np.sqrt(np.mean(log.pose_error_rad[mask] ** 2)))}
    summary = {"closed_loop": log.summary(), "phases": phases,
               "deflection_ratio_soft_over_stiff": phases["soft"]["max_deflection_x_rad"]
               / phases["stiff"]["max_deflection_x_rad"],
               "figures": [p.name for p in figs], "noise": not args.no_noise}
    atomic_write_json(out / "summary.json", summary)
    print(f"wrote {len(figs)} figures and summary.json to {out}")
    for name, ph in phases.items():
        print(f"  {name:5s}: K_xx target {ph['K_xx_target_Nm_per_rad']:.1f}, achieved "
              f"{ph['K_xx_achieved_mean_Nm_per_rad']:.1f} N m/rad; max deflection about x "
              f"{1e3 * ph['max_deflection_x_rad']:.2f} mrad")
    return 0


if __name__ == "__main__":
    sys.exit(main())
