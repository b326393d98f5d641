"""The two testbed plants (quasi-static and MuJoCo) side by side over random rigs.

For each random rig (:func:`csjm_opt.testbed.random_rig`) and each effect (severity 3, the
same draws on both plants), one persistent log of ``--cycles`` load cycles is simulated
noise-free on both plants. Reported per effect: the effect's size (largest pose change
against the nominal plant) and the largest disagreement between the plants, in mrad and as
a share of the effect; the number of rows the MuJoCo plant certified by the friction LP; the
wall time. The figure shows one cycle's hysteresis loop (tilt along the load direction
against the load fraction) on both plants, with Coulomb friction and without.

Usage::

    python -m studies.testbed_plants.testbed_plants [--rigs 3] [--cycles 4]
        [--out studies/testbed_plants/testbed_plants]

Writes ``OUT.md`` (the table) and ``OUT.png`` (the figure).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

EFFECTS = ("hole_offsets", "friction", "coulomb_friction", "joint_friction", "cable_hardening", "link_compliance",
           "mass_com", "stiffness_scale", "sensor_bias", "tracker_registration", "drum_slip")


def inputs(rig, cycles: int, seed: int):
    """Rows of ``cycles`` designed load cycles: (rest lengths, loads, cycle ids, start poses, designs)."""
    from csjm_opt.testbed import design_cycles

    designs = design_cycles(rig, cycles, np.random.default_rng(seed))
    cycle = np.concatenate([np.full(len(c.alphas), i) for i, c in enumerate(designs)])
    l = np.concatenate([np.repeat(c.rest_lengths_m[None], len(c.alphas), 0) for c in designs])
    tau = np.concatenate([c.tau_ext_A_Nm for c in designs])
    R0 = np.concatenate([np.repeat(c.R_ref[None], len(c.alphas), 0) for c in designs])
    return (l, tau, cycle, R0), designs


def compare(n_rigs: int, cycles: int) -> list[dict]:
    """One record per rig and effect."""
    from tqdm import tqdm

    from csjm_opt import so3
    from csjm_opt.testbed import as_mujoco, make_plant, random_rig

    out = []
    bar = tqdm(total=n_rigs * len(EFFECTS), file=sys.stderr, desc="plants")
    for r in range(n_rigs):
        rig, _ = random_rig(np.random.default_rng([1234, r]))
        args, _ = inputs(rig, cycles, r)
        nominal = make_plant(rig, None, 1.0, np.random.default_rng(0)).respond(*args)
        for effect in EFFECTS:
            plant = make_plant(rig, effect, 3.0, np.random.default_rng([r, 5]))
            t0 = time.perf_counter()
            R_q = plant.respond(*args)
            t1 = time.perf_counter()
            rows = as_mujoco(plant).respond_rows(*args)
            t2 = time.perf_counter()
            R_m = np.stack([row.R_tool for row in rows])
            # readings-only effects (bias, registration) leave the pose alone: compare the readings
            size = max(so3.angle_between(a, b) for a, b in zip(plant.measured_pose(R_q), nominal))
            gap = max(so3.angle_between(a, b) for a, b in zip(R_m, R_q))
            out.append({"rig": r, "effect": effect, "rows": len(R_q), "size_rad": float(size), "gap_rad": float(gap),
                        "certified": sum(row.certificate is not None and row.certificate.certified for row in rows),
                        "friction_rows": sum(row.certificate is not None for row in rows),
                        "seconds_quasi_static": t1 - t0, "seconds_mujoco": t2 - t1})
            bar.update(1)
    bar.close()
    return out


def table(records: list[dict]) -> str:
    """Markdown table, one line per effect (worst case over rigs)."""
    lines = [f"{len({r['rig'] for r in records})} random rigs, {records[0]['rows']} rows each (persistent cycles), "
             "effects at severity 3, noise-free:", "",
             "| effect | effect size (mrad, min-max) | max disagreement (mrad) | share of the effect | "
             "friction rows certified | s per log (quasi-static / MuJoCo) |", "|---|---|---|---|---|---|"]
    for effect in EFFECTS:
        rs = [r for r in records if r["effect"] == effect]
        sizes = [r["size_rad"] for r in rs]
        share = max(r["gap_rad"] / max(r["size_rad"], 1e-12) for r in rs)
        fr = sum(r["friction_rows"] for r in rs)
        cert = f"{sum(r['certified'] for r in rs)}/{fr}" if fr else "-"
        lines.append(f"| {effect} | {1e3 * min(sizes):.2f}-{1e3 * max(sizes):.2f} | "
                     f"{1e3 * max(r['gap_rad'] for r in rs):.2g} | {share:.1%} | {cert} | "
                     f"{np.median([r['seconds_quasi_static'] for r in rs]):.2f} / "
                     f"{np.median([r['seconds_mujoco'] for r in rs]):.2f} |")
    return "\n".join(lines) + "\n"


def figure(path: Path) -> None:
    """Hysteresis of one load cycle (paper rig) on both plants, with and without Coulomb friction."""
    import dataclasses

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from csjm_opt import so3
    from csjm_opt.model.rig import paper_rig
    from csjm_opt.testbed import TestbedPlant, as_mujoco, design_cycles

    rig = paper_rig()
    c = design_cycles(rig, 1, np.random.default_rng(3), steps=6)[0]
    m = len(c.alphas)
    args = (np.repeat(c.rest_lengths_m[None], 2 * m, 0), np.tile(c.tau_ext_A_Nm, (2, 1)), np.repeat([0, 1], m),
            np.repeat(c.R_ref[None], 2 * m, 0))
    u = c.dtau_A_Nm / np.linalg.norm(c.dtau_A_Nm)
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    coulomb = dataclasses.replace(TestbedPlant.nominal(rig), friction_coulomb_N=np.full(6, 1.5))
    runs = [("no friction", TestbedPlant.nominal(rig), "k", "-"),
            ("Coulomb 1.5 N, quasi-static (rho 0.1)", coulomb, "C0", "-"),
            ("Coulomb 1.5 N, MuJoCo frictionloss", as_mujoco(coulomb), "C1", "--")]
    for label, plant, color, ls in runs:
        R = plant.respond(*args)
        turn = np.array([so3.log(c.R_ref.T @ Ri) @ u for Ri in R]) * 1e3
        alphas = np.r_[c.alphas, c.alphas]
        ax.plot(alphas, turn, ls, color=color, marker="o", ms=3, label=label)
    ax.set_xlabel("load fraction (two cycles, up and down)")
    ax.set_ylabel("turn along the load direction (mrad)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rigs", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=4)
    ap.add_argument("--out", default="studies/testbed_plants/testbed_plants")
    args = ap.parse_args(argv)
    out = Path(args.out)
    text = table(compare(args.rigs, args.cycles))
    out.with_suffix(".md").write_text(text)
    figure(out.with_suffix(".png"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
