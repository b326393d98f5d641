"""Does one glitched row change the diagnosis? Logs made elsewhere, each with one row spoiled as labs see it.

Each case of the validation folders is diagnosed as given (the standard command: training log, rig file, test
log) and again with one training row spoiled, in two ways a lab meets: a force/torque spike (the logged moment
``--spike-Nm`` off along a random direction) and a tracker glitch (the logged orientation turned by
``--glitch-rad`` about a random axis). The row and the direction are drawn from the case's name, so every code
version spoils the same row the same way. Recorded per log: the verdict, second effect, warnings, the accept
rule's judgement, the noise floor and the rows the diagnosis left out; the summary compares each spoiled log
with its clean one.

Usage (from the repository root; the folders with ``answers.json`` are in ``studies/validation_shared/logs``)::

    python -m studies.gross_outliers.gross_outliers studies/validation_shared/logs/mujoco_a \
        studies/validation_shared/logs/mujoco_b studies/validation_shared/logs/oracle_hard [--workers 2]
"""

from __future__ import annotations

import argparse
import os
import zlib

from studies._runner import run_and_summarise

SPOILS = ("clean", "moment", "pose")


def spoiled(log, kind: str, name: str, spike_Nm: float, glitch_rad: float):
    """``(log with one training row spoiled, that row's sample id)``; the clean log and None for ``"clean"``."""
    import numpy as np

    from csjm_opt import so3
    from csjm_opt.measurement.logfile import MeasurementLog

    if kind == "clean":
        return log, None
    rng = np.random.default_rng([zlib.crc32(name.encode()), SPOILS.index(kind)])
    i = int(rng.integers(len(log)))
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    tau, R = np.array(log.tau_ext_A_Nm, float), np.array(log.R, float)
    if kind == "moment":
        tau[i] += spike_Nm * axis
    else:
        R[i] = R[i] @ so3.exp(glitch_rad * axis)
    return MeasurementLog.from_arrays(log.cycle, log.rest_lengths_m, tau, R, sample=log.sample), int(log.sample[i])


def run_one(job: dict) -> dict:
    """Diagnose one case with one of its training rows spoiled (or none), as the standard command does."""
    os.environ["CSJM_WORKERS"] = "1"
    from csjm_opt.diagnose import diagnose
    from csjm_opt.diagnose.selection.validation import accepted
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.model.rig import load_rig

    rig = load_rig(job["rig"])
    log = MeasurementLog.from_csv(job["train"]).check_cables(rig.n_cables, job["rig"])
    test = MeasurementLog.from_csv(job["test"]).check_cables(rig.n_cables, job["rig"])
    log, sample = spoiled(log, job["kind"], job["case"], job["spike_Nm"], job["glitch_rad"])
    j = diagnose(rig, log, test, workers=1).as_json()
    return {**job, "spoiled_sample": sample, "selected": j["selected"], "secondary": j["secondary"]["effect"],
            "warnings": j["verdict"]["warnings"], "right": accepted(job["accept"], job["effects"], j),
            "noise_floor_rad": j["noise_floor_rad"],
            "left_out": [[r["log"], r["sample"], r.get("reason", "ill_conditioned")] for r in j["left_out_rows"]],
            "outlier_ratio_max": j.get("outlier_ratio_max", {})}


def summarise(records: list[dict]) -> str:
    """Markdown: per kind of spoil, how many verdicts stay the clean log's, how many are right, the floor's growth."""
    import statistics

    clean = {r["case"]: r for r in records if r["kind"] == "clean"}
    lines = ["| logs | spoiled row left out | verdict, second effect and warnings as the clean log's | "
             "same verdict and second effect | right by the accept rule | noise floor over the clean log's "
             "(median, largest) |", "|---|---|---|---|---|---|"]
    right = sum(r["right"] for r in clean.values())
    lines.append(f"| clean | - | - | - | {right}/{len(clean)} | - |")
    changed = []
    for kind in SPOILS[1:]:
        rs = [r for r in records if r["kind"] == kind and r["case"] in clean]
        if not rs:
            continue
        found = sum(["log", r["spoiled_sample"], "gross_residual"] in r["left_out"] for r in rs)
        same = [r for r in rs if (r["selected"], r["secondary"], r["warnings"]) ==
                (clean[r["case"]]["selected"], clean[r["case"]]["secondary"], clean[r["case"]]["warnings"])]
        same_v = sum((r["selected"], r["secondary"]) ==
                     (clean[r["case"]]["selected"], clean[r["case"]]["secondary"]) for r in rs)
        ratio = [r["noise_floor_rad"] / clean[r["case"]]["noise_floor_rad"] for r in rs]
        lines.append(f"| {kind} | {found}/{len(rs)} | {len(same)}/{len(rs)} | {same_v}/{len(rs)} | "
                     f"{sum(r['right'] for r in rs)}/{len(rs)} | {statistics.median(ratio):.2f}, {max(ratio):.2f} |")
        changed += [f"- {kind} `{r['case']}`: {clean[r['case']]['selected']}+{clean[r['case']]['secondary']} "
                    f"({len(clean[r['case']]['warnings'])} warnings) -> {r['selected']}+{r['secondary']} "
                    f"({len(r['warnings'])}); right {clean[r['case']]['right']} -> {r['right']}" for r in rs
                    if r not in same]
    return "\n".join(lines + ([""] + ["Spoiled logs whose verdict, second effect or warnings moved:", ""] + changed
                              if changed else [])) + "\n"


def main(argv: list[str] | None = None) -> None:
    from csjm_opt.diagnose.effects import EFFECTS
    from csjm_opt.diagnose.selection.validation import load_cases

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--spike-Nm", type=float, default=0.5, help="force/torque spike (N m; the sensor noise: 0.02)")
    ap.add_argument("--glitch-rad", type=float, default=0.03, help="tracker glitch (rad; the tracker noise: 3e-4)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="studies/gross_outliers/gross_outliers")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    jobs = [{"id": f"{c.label}:{k}", "case": c.label, "kind": k, "rig": str(c.rig), "train": str(c.train),
             "test": str(c.test), "accept": c.accept, "effects": list(c.effects), "spike_Nm": args.spike_Nm,
             "glitch_rad": args.glitch_rad}
            for f in args.folders for c in load_cases(f, tuple(EFFECTS)) for k in SPOILS]
    run_and_summarise(run_one, jobs, args.out, "gross outliers", args.workers, args.no_progress, summarise)


if __name__ == "__main__":
    main()
