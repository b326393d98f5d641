"""Every validation log checked against its own rig and against every other rig.

Usage: python -m studies.log_rig_check.log_rig_check studies/validation_shared/logs [-o OUT.md]

Runs :func:`csjm_opt.measurement.rig_fit.log_rig_fit` on each log of the validation set made
outside the project (three folders, 94 logs) with each of the six rig files and the
paper rig, and writes a table: the median per-cable tension error (N) and whether the
check accepts. The own rig must accept every log.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import sys

from csjm_opt.measurement import MeasurementLog
from csjm_opt.measurement.rig_fit import log_rig_fit
from csjm_opt.model.rig import Rig, paper_rig


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("validation", help="the validation set's folder (oracle_hard/, mujoco_a/, mujoco_b/)")
    ap.add_argument("-o", "--out", default=None, help="markdown table to write (default: stdout)")
    a = ap.parse_args(argv)
    rigs = {os.path.relpath(f, a.validation): Rig.from_toml(f)
            for f in sorted(glob.glob(os.path.join(a.validation, "*", "*.toml")))}
    rigs["paper (built in)"] = paper_rig()
    names = list(rigs)
    lines = ["| log | own rig | " + " | ".join(names) + " |", "|---" * (len(names) + 2) + "|"]
    own_fail, wrong_pass, wrong_total = [], [], 0
    worst_own = 0.0
    for folder in ("oracle_hard", "mujoco_a", "mujoco_b"):
        answers = json.load(open(os.path.join(a.validation, folder, "answers.json")))
        for case in answers.values():
            own = f"{folder}/{case['rig']}"
            for split in ("train", "test"):
                log = MeasurementLog.from_csv(os.path.join(a.validation, folder, case[split]))
                cells = []
                for name, rig in rigs.items():
                    fit = log_rig_fit(rig, log)
                    is_own = name == own
                    cells.append(f"{'**' if is_own else ''}{fit.median_N:.1f}{'' if fit.ok else ' x'}"
                                 f"{'**' if is_own else ''}")
                    if is_own:
                        worst_own = max(worst_own, fit.median_N / fit.tolerance_N)
                        if not fit.ok:
                            own_fail.append(case[split])
                    else:
                        wrong_total += 1
                        if fit.ok:
                            wrong_pass.append((case[split], name))
                lines.append(f"| {folder}/{case[split]} | {own} | " + " | ".join(cells) + " |")
    summary = [
        f"Own rig refused: {len(own_fail)} of 94 logs {own_fail}; worst own median / tolerance "
        f"{worst_own:.2f}.",
        f"Other rig accepted: {len(wrong_pass)} of {wrong_total} (log, rig) pairs (the same rig under "
        "two names counts here too: mujoco_a/rig_paper.toml and the built-in paper rig).",
        "", "Cells: median per-cable tension error of the first 33 rows (N); ` x`: refused; "
        "**bold**: the log's own rig.", "",
    ]
    text = "\n".join(summary + lines) + "\n"
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    else:
        sys.stdout.write(text)
    return 1 if own_fail else 0


if __name__ == "__main__":
    raise SystemExit(main())
