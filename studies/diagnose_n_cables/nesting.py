"""Study: how much of a hole-offset injection can drive offsets reproduce, rig by rig (first order)?

A hole moved along its cable changes that cable's length as a rest-length offset does: to first order,
drive offsets (m numbers) are m of the 6 m hole-offset directions. On a 12-cycle experiment of each
shipped rig (nominal plant, no noise needed: the question is one of geometry) the whitened data
Jacobian of the model nominal + hole offsets + drive offsets is taken at the nominal parameters
(:func:`csjm_opt.diagnose.fitting.gauss_newton.data_jacobian`), the common rest-length nuisance
projected out of both blocks. Reported per rig:

* the cosines of the principal angles between the drive-offset span and the hole-offset span (1: the
  drive direction lies in the hole span);
* the Fisher block correlation of the two blocks with their priors
  (:func:`csjm_opt.diagnose.selection.pairs.block_correlation`, the diagnosis's separability measure);
* for hole offsets drawn as the testbed draws them (every coordinate i.i.d. Gaussian), the expected
  share of their pose signal (chi^2) inside the drive span, ``tr(J_h^T P_d J_h) / tr(J_h^T J_h)``,
  and what it leaves at an injection of 3x the floor: ``3 sqrt(1 - share)`` floors (RMS) that drive
  offsets cannot reproduce.

Usage::

    python -m studies.diagnose_n_cables.nesting [--rigs paper eight_cable four_cable] [--cycles 12]

Writes ``nesting.md`` beside this script.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent


def measure(rig_name: str, cycles: int) -> dict:
    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.effects.drive_offsets import DriveOffsets
    from csjm_opt.diagnose.effects.hole_offsets import HoleOffsets
    from csjm_opt.diagnose.fitting.augmented import N_NUISANCE, AugmentedModel
    from csjm_opt.diagnose.fitting.gauss_newton import data_jacobian
    from csjm_opt.diagnose.selection.pairs import block_correlation
    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.model.rig import Rig
    from csjm_opt.testbed import simulate_experiment

    rig = Rig.from_toml(ROOT / "rigs" / f"{rig_name}.toml")
    m = rig.n_cables
    noise = InstrumentNoise.paper()
    log = simulate_experiment(rig, cycles, np.random.default_rng(1), noise=InstrumentNoise.none())
    table = compute_residuals(rig, log, noise)
    model = AugmentedModel(rig, [HoleOffsets(m), DriveOffsets(m)])
    J = data_jacobian(model, table, model.x0())
    hole = np.arange(N_NUISANCE, N_NUISANCE + 6 * m)
    drive = np.arange(N_NUISANCE + 6 * m, model.n_params)
    Qn, _ = np.linalg.qr(J[:, :N_NUISANCE])
    Jh, Jd = (X - Qn @ (Qn.T @ X) for X in (J[:, hole], J[:, drive]))

    def basis(X: np.ndarray) -> np.ndarray:
        U, s, _ = np.linalg.svd(X, full_matrices=False)
        return U[:, s > 1e-6 * s[0]]

    Ud, Uh = basis(Jd), basis(Jh)
    cos = np.linalg.svd(Ud.T @ Uh, compute_uv=False)
    prior = model.prior_sd
    info = J.T @ J + np.diag(np.where(np.isfinite(prior), (model.scales / prior) ** 2, 0.0))
    share = float(np.trace(Jh.T @ Ud @ (Ud.T @ Jh)) / np.trace(Jh.T @ Jh))
    return {"rig": rig_name, "m": m, "rows": len(log), "drive_rank": Ud.shape[1], "hole_rank": Uh.shape[1],
            "cos_min": float(cos.min()), "cos_max": float(cos.max()),
            "block_correlation": block_correlation(info, hole, drive),
            "share_in_drive_span": share, "distinct_floors_at_3x": 3.0 * np.sqrt(max(1.0 - share, 0.0))}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rigs", nargs="*", default=["paper", "eight_cable", "four_cable", "five_cable", "twelve_cable"])
    ap.add_argument("--cycles", type=int, default=12)
    args = ap.parse_args(argv)
    from tqdm import tqdm

    rows = [measure(r, args.cycles) for r in tqdm(args.rigs, desc="rigs", file=sys.stderr)]
    lines = ["# Drive offsets inside the hole-offset span (first order), rig by rig", "",
             "Made by `python -m studies.diagnose_n_cables.nesting` (see its docstring).", "",
             "| rig | m | rows | drive directions | principal-angle cosines (min-max) | Fisher block corr. "
             "| share of an i.i.d. hole draw in the drive span | distinct part at 3x (floors) |",
             "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['rig']} | {r['m']} | {r['rows']} | {r['drive_rank']} "
                     f"| {r['cos_min']:.5f}-{r['cos_max']:.5f} | {r['block_correlation']:.4f} "
                     f"| {r['share_in_drive_span']:.1%} | {r['distinct_floors_at_3x']:.2f} |")
    text = "\n".join(lines) + "\n"
    (HERE / "nesting.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
