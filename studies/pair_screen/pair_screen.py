"""Is the pair screen safe? The diagnosis with and without it on logs the project did not make.

The diagnosis fits a pair only when its log evidence, predicted one Gauss-Newton step from its singles'
fits (``csjm_opt.diagnose.fitting.model_fits.predicted_pair_evidence``), lies within ``SCREEN_NATS`` of
the best single's and the first effect's. This script diagnoses each log twice, with the screen and without
it (every pair fitted, every prediction still made), and records both verdicts with their warnings, and
per pair the prediction and the fitted evidence: the screen must change nothing a lab reads, and a pair it
drops must lie far below anything a rule reads.

Usage (from the repository root; the folders with ``answers.json`` are in ``studies/validation_shared/logs``)::

    python -m studies.pair_screen.pair_screen studies/validation_shared/logs/mujoco_a \
        studies/validation_shared/logs/mujoco_b studies/validation_shared/logs/oracle_hard [--workers 2]
"""

from __future__ import annotations

import argparse
import os
import time

from studies._runner import run_and_summarise


def run_one(job: dict) -> dict:
    """Diagnose one case with the screen on, then off: which pairs it drops, their fitted evidence, both verdicts."""
    os.environ["CSJM_WORKERS"] = "1"
    import numpy as np

    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.model_fits import pair_step
    from csjm_opt.diagnose.selection import decision
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.model.rig import load_rig

    rig = load_rig(job["rig"])
    log = MeasurementLog.from_csv(job["train"]).check_cables(rig.n_cables, job["rig"])
    test = MeasurementLog.from_csv(job["test"]).check_cables(rig.n_cables, job["rig"])
    screen_nats = decision.SCREEN_NATS
    t0 = time.perf_counter()
    on = decision.diagnose(rig, log, test, workers=1).as_json()
    t1 = time.perf_counter()
    decision.SCREEN_NATS = float("inf")           # nothing screened; the predictions are still made
    try:
        off = decision.diagnose(rig, log, test, workers=1).as_json()
    finally:
        decision.SCREEN_NATS = screen_nats
    t2 = time.perf_counter()
    evs = [c["log_evidence"] for c in off["candidates"] if c.get("log_evidence") is not None]
    fitted_on = {frozenset(p["effects"]) for p in on["pairs"] if p.get("fitted")}
    verdict_model = (off.get("gap") or {}).get("model")
    models = {c["effect"]: c.get("log_evidence") for c in off["candidates"]}
    models.update({"+".join(p["effects"]): p.get("log_evidence") for p in off["pairs"] if p.get("fitted")})
    pairs = [{"effects": p["effects"], "predicted": p.get("predicted_log_evidence"),
              "fitted": p.get("log_evidence") if p.get("fitted") else None,
              "dropped": bool(p.get("fitted")) and frozenset(p["effects"]) not in fitted_on,
              "step": pair_step([make_effect(e, rig) for e in p["effects"]])}
             for p in off["pairs"] if "predicted_log_evidence" in p]
    return {"id": job["id"], "best_single": float(np.nanmax(evs)),
            "verdict_evidence": models.get(verdict_model) if verdict_model else None,
            "on": {k: on["verdict"][k] for k in ("selected", "warnings")} | {"secondary": on["secondary"]["effect"]},
            "off": {k: off["verdict"][k] for k in ("selected", "warnings")} | {"secondary": off["secondary"]["effect"]},
            "seconds_on": t1 - t0, "seconds_off": t2 - t1, "pairs": pairs}


def _verdict_evidence(record: dict) -> float:
    """The verdict's log evidence in a record, the best single's without a named verdict."""
    return record["best_single"] if record["verdict_evidence"] is None else record["verdict_evidence"]


def summarise(records: list[dict], lead_nats: float) -> str:
    """Markdown: whether the screened diagnosis says what the unscreened one says, and how far below the dropped lie."""
    import statistics

    import numpy as np

    same = [r for r in records if r["on"] == r["off"]]
    lines = [f"**{len(same)}/{len(records)} logs: the screened diagnosis gives the same verdict, second effect and "
             f"warnings as the diagnosis that fits every pair.**", ""]
    for r in records:
        if r["on"] != r["off"]:
            lost = [w for w in r["off"]["warnings"] if w not in r["on"]["warnings"]]
            extra = [w for w in r["on"]["warnings"] if w not in r["off"]["warnings"]]
            lines.append(f"- {r['id']}: {r['off']['selected']}+{r['off']['secondary']} -> "
                         f"{r['on']['selected']}+{r['on']['secondary']}; warnings lost {len(lost)}, added {len(extra)}"
                         + (f" (first lost: {lost[0][:160]})" if lost else ""))
    n_all = sum(len(r["pairs"]) for r in records)
    # a rule reads a pair against the verdict (a rival within EVIDENCE_MIN of it, or above it); without a named
    # verdict, against the best single
    dropped = [(p["fitted"] - _verdict_evidence(r), r["id"],
                "+".join(p["effects"]), p["fitted"] - p["predicted"])
               for r in records for p in r["pairs"] if p["dropped"] and p["fitted"] is not None]
    dropped.sort(reverse=True)
    lines += ["", f"{len(records)} logs, {n_all} pairs; the screen drops {len(dropped)} "
              f"({len(dropped) / max(n_all, 1):.0%}).", "",
              "Dropped pairs nearest the verdict's evidence (the best single's without a named verdict; a rule reads "
              f"pairs within {lead_nats:g} nats of the verdict):", "",
              "| fitted minus the verdict | log | pair | fitted minus predicted |", "|---|---|---|---|"]
    lines += [f"| {d:+.1f} | {i} | {p} | {s:+.1f} |" for d, i, p, s in dropped[:8]]
    # how far a fit reaches beyond its step, as a share of the gap the step left below the screen's anchor (the
    # verdict's evidence, or the best single's: the anchor in the diagnosis is the lower of them and the first effect)
    lines += ["", "Fits' reach beyond their steps, as a share of the gap the step left below the anchor (pairs "
              "predicted more than 60 nats below it; the largest):", "",
              "| step | pairs | largest share | log | pair |", "|---|---|---|---|---|"]
    for step in ("tight", "loose", "own_fit"):
        shares = [((p["fitted"] - p["predicted"]) / gap, r["id"], "+".join(p["effects"]))
                  for r in records for p in r["pairs"]
                  if p.get("step") == step and p["fitted"] is not None and p["predicted"] is not None
                  and (gap := min(r["best_single"], _verdict_evidence(r)) - p["predicted"]) > 60]
        if shares:
            top = max(shares)
            lines.append(f"| {step} | {len(shares)} | {top[0]:.0%} | {top[1]} | {top[2]} |")
    # an own-fit step (cable friction's pairs, from the friction single's fit) can fall far short of its fit: its margin
    # is set by the pairs that matter, those fitted within 60 nats of the verdict or above it: how far below the
    # screen's anchor their steps lay
    near = sorted(((min(r["best_single"], _verdict_evidence(r)) - p["predicted"], p["fitted"] - _verdict_evidence(r),
                    r["id"], "+".join(p["effects"]))
                   for r in records for p in r["pairs"]
                   if p.get("step") == "own_fit" and p["fitted"] is not None and p["predicted"] is not None
                   and np.isfinite(p["predicted"]) and p["fitted"] > _verdict_evidence(r) - 60), reverse=True)
    if near:
        lines += ["", f"Own-fit steps (cable friction's pairs) of the {len(near)} pairs fitted within 60 nats of the "
                  "verdict or above it: how far below the screen's anchor the step lay (the largest; the screen drops "
                  "an own-fit pair only `SCREEN_NATS + OWN_FIT_SCREEN_NATS` below it):", "",
                  "| anchor minus predicted | fitted minus the verdict | log | pair |", "|---|---|---|---|"]
        lines += [f"| {a:.1f} | {d:+.1f} | {i} | {p} |" for a, d, i, p in near[:5]]
    on = [r["seconds_on"] for r in records]
    off = [r["seconds_off"] for r in records]
    ratio = statistics.median(o / n for o, n in zip(off, on))
    lines += ["", f"Time per log on one core (median): {statistics.median(on):.1f} s screened, "
              f"{statistics.median(off):.1f} s every pair fitted ({ratio:.2f}x per log)."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    from csjm_opt.diagnose.decision_rule import LEAD_NATS
    from csjm_opt.diagnose.effects import EFFECTS
    from csjm_opt.diagnose.selection.validation import load_cases

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="studies/pair_screen/pair_screen")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    jobs = [{"id": c.label, "rig": str(c.rig), "train": str(c.train), "test": str(c.test)}
            for f in args.folders for c in load_cases(f, tuple(EFFECTS))]
    run_and_summarise(run_one, jobs, args.out, "pair screen", args.workers, args.no_progress,
                      lambda rs: summarise(rs, LEAD_NATS))


if __name__ == "__main__":
    main()
