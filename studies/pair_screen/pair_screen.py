"""Is the pair screen safe? Predicted against fitted pair evidence on logs the project did not make.

The diagnosis fits a pair only when its log evidence, predicted one Gauss-Newton step from its singles'
fits (``csjm_opt.diagnose.fitting.model_fits.predicted_pair_evidence``), lies within ``SCREEN_NATS`` of
the best single's. This script turns the screen off (every pair fitted, every prediction still made) and
records, per pair, the prediction and the fitted evidence, so that the margin can be judged: a pair the
screen would drop must lie far below anything a rule reads (``LEAD_NATS`` below the best single), and the
shortfall ``fitted - predicted`` says how far the linearisation can be wrong.

Usage (from the repository root; VALIDATION_DIR holds the folders with ``answers.json``)::

    python -m studies.pair_screen.pair_screen VALIDATION_DIR/mujoco_a VALIDATION_DIR/mujoco_b \
        VALIDATION_DIR/oracle_hard [--workers 2] [--out studies/pair_screen/pair_screen]
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from studies._runner import pool_stream, read_records, run_and_append


def run_one(job: dict) -> dict:
    """Diagnose one case with the screen off: each pair's prediction and fitted evidence."""
    os.environ["CSJM_WORKERS"] = "1"
    import numpy as np

    from csjm_opt.diagnose.selection import decision
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.model.rig import load_rig

    decision.SCREEN_NATS = float("inf")           # nothing screened; the predictions are still made
    rig = load_rig(job["rig"])
    log = MeasurementLog.from_csv(job["train"]).check_cables(rig.n_cables, job["rig"])
    test = MeasurementLog.from_csv(job["test"]).check_cables(rig.n_cables, job["rig"])
    t0 = time.perf_counter()
    js = decision.diagnose(rig, log, test, workers=1).as_json()
    evs = [c["log_evidence"] for c in js["candidates"] if c.get("log_evidence") is not None]
    best = float(np.nanmax(evs))
    pairs = [{"effects": p["effects"], "predicted": p.get("predicted_log_evidence"),
              "fitted": p.get("log_evidence") if p.get("fitted") else None,
              "closes_gap": p.get("closes_gap"), "significant": p.get("significant")}
             for p in js["pairs"] if "predicted_log_evidence" in p]
    return {"id": job["id"], "best_single": best, "verdict": js["verdict"]["selected"],
            "secondary": js["secondary"]["effect"] if isinstance(js["secondary"], dict) else js["secondary"],
            "seconds": time.perf_counter() - t0, "pairs": pairs}


def summarise(records: list[dict], screen_nats: float, lead_nats: float) -> str:
    """Markdown: how far predictions fall short, and whether any pair the screen drops comes near the best."""
    import math

    short, dropped, near = [], 0, []
    n_pred = n_all = 0
    for r in records:
        for p in r["pairs"]:
            n_all += 1
            pr, fi = p["predicted"], p["fitted"]
            if pr is None or fi is None or not math.isfinite(pr):
                continue
            n_pred += 1
            gap = r["best_single"] - pr
            short.append((fi - pr, (fi - pr) / gap if gap > 0 else float("nan"), r["id"], "+".join(p["effects"])))
            if pr < r["best_single"] - screen_nats:
                dropped += 1
                near.append((fi - r["best_single"], r["id"], "+".join(p["effects"])))
    short.sort(reverse=True)
    near.sort(reverse=True)
    lines = [f"{len(records)} logs, {n_all} pairs, {n_pred} with a prediction (no prediction: a settled lead, a "
             f"loading path, link compliance); the screen (predicted more than {screen_nats:g} nats below the best "
             f"single) drops "
             f"{dropped} ({dropped / max(n_all, 1):.0%} of all pairs).", "",
             "Largest shortfalls (fitted evidence minus predicted, nats; share: of the gap the prediction left to "
             "the best single):", "",
             "| shortfall | share of the gap | log | pair |", "|---|---|---|---|"]
    lines += [f"| {s:+.1f} | {q:.2f} | {i} | {p} |" for s, q, i, p in short[:8]]
    shares = sorted((q, s, i, p) for s, q, i, p in short if q == q and s > 0 and s / q >= screen_nats)
    if shares:
        q, s, i, p = shares[-1]
        lines += ["", f"Among pairs the screen drops, the largest share of the gap a fit reached beyond its "
                  f"prediction: **{q:.2f}** ({i}, {p}, {s:+.1f} nats)."]
    lines += ["", f"Dropped pairs nearest the best single (a rule reads pairs within {lead_nats:g} nats):", "",
              "| fitted minus best single | log | pair |", "|---|---|---|"]
    lines += [f"| {s:+.1f} | {i} | {p} |" for s, i, p in near[:8]]
    worst = near[0][0] if near else float("-inf")
    lines += ["", f"**Nearest dropped pair: {worst:+.1f} nats from the best single** "
              f"({'safe' if worst < -lead_nats else 'NOT SAFE'}: the rules read pairs within {lead_nats:g})."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    from csjm_opt.diagnose.decision_rule import LEAD_NATS
    from csjm_opt.diagnose.effects import EFFECTS
    from csjm_opt.diagnose.fitting.model_fits import SCREEN_NATS
    from csjm_opt.diagnose.selection.validation import load_cases

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="studies/pair_screen/pair_screen")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    jobs = [{"id": c.label, "rig": str(c.rig), "train": str(c.train), "test": str(c.test)}
            for f in args.folders for c in load_cases(f, tuple(EFFECTS))]
    out = Path(args.out + ".jsonl")
    done = read_records(out)
    todo = [j for j in jobs if j["id"] not in done]
    run_and_append(pool_stream(run_one, todo, args.workers), len(todo), out, done, "pair screen",
                   args.no_progress)
    md = Path(args.out + ".md")
    tmp = md.with_suffix(".md.tmp")
    tmp.write_text(summarise([done[j["id"]] for j in jobs if j["id"] in done], SCREEN_NATS, LEAD_NATS))
    tmp.replace(md)
    print(md.read_text())


if __name__ == "__main__":
    main()
