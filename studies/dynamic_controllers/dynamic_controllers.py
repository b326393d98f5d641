"""Study: controllers with dynamics on MuJoCo and on the quasi-static plant.

The paper rig follows a tilt-and-torsion reference (10 deg about x, 15 deg
about z, 0.5 Hz) at 1 kHz while a moment the controllers do not measure,
``[0.3, -0.2, 0.1]`` N m in {A}, steps on mid-run. Controllers (see
``csjm_opt/report/mujoco_step.py``): tension planning for the pose alone, plus
the inverse-dynamics moment, plus SO(3) PID feedback, stiffness shaping
toward a stiff target, and shaping with the inverse-dynamics moment. Every
controller runs on both plants. Then a soft-to-stiff switch of the shaping
target is checked in MuJoCo: K measured by perturbation against the K
commanded.

Run: ``python -m studies.dynamic_controllers.dynamic_controllers [--out DIR] [--duration S]``;
writes ``dynamic_controllers.json``, ``dynamic_controllers.png`` and prints
the Markdown table of ``docs/guide/mujoco.md``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from csjm_opt._fileio import atomic_write_json
from csjm_opt._plotting import save
from csjm_opt.demo.mujoco_step import compare, plot_errors, stiffness_switch
from csjm_opt.model.rig import paper_rig


def table(rows: list[dict]) -> str:
    lines = ["| plant | controller | RMS before step (mrad) | peak after step (mrad) | RMS final 10 % (mrad) "
             "| min tension margin (N) |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['plant'].replace('_', '-')} | {r['controller']} | {1e3 * r['rms_before_step_rad']:.4g} | "
                     f"{1e3 * r['peak_after_step_rad']:.3g} | {1e3 * r['rms_final_rad']:.3g} | "
                     f"{r['min_tension_margin_N']:.1f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="studies/out/dynamic_controllers")
    ap.add_argument("--duration", type=float, default=3.0, help="run length (s); the step comes at half")
    args = ap.parse_args(argv)
    rig = paper_rig()
    out = Path(args.out)
    rows, logs = compare(rig, args.duration, 0.5 * args.duration)
    ax = plot_errors(logs, 0.5 * args.duration)
    ax.set_title("paper rig: tilt-and-torsion tracking, unknown moment step (dashed)")
    save(ax.figure, out / "dynamic_controllers.png")
    switch = stiffness_switch(rig)
    atomic_write_json(out / "dynamic_controllers.json", {"runs": rows, "stiffness_switch": switch,
                                                         "duration_s": args.duration})
    print(table(rows))
    for phase, r in switch.items():
        print(f"stiffness switch, {phase} phase: |K_mujoco - K_commanded| / |K| = {r['relative_error']:.2e} "
              f"(uncorrected {r['uncorrected_relative_error']:.2e}); eigenvalues "
              f"{[round(x, 2) for x in r['eigenvalues_Nm_per_rad']]} N m/rad")
    return 0


if __name__ == "__main__":
    sys.exit(main())
