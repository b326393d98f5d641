"""Confusion matrix of ``csjm diagnose`` on synthetic logs (seeds x severities x effects).

Usage::

    python studies/diagnose_confusion.py [--seeds 3] [--cycles 22] [--severities 0.5 1 2]
                                         [--workers 2] [--out studies/diagnose_confusion]

Writes ``OUT.json`` (one record per run) and ``OUT.md`` (the confusion matrix,
gap closure per effect and severity) for the README.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np


def run_one(job: tuple[str, float, int, int]) -> dict:
    import csjm_opt as co
    from csjm_opt.diagnose import diagnose
    from csjm_opt.testbed import simulate_experiment

    effect, severity, seed, cycles = job
    rig = co.paper_rig()
    rng = np.random.default_rng([seed, int(severity * 100), len(effect)])
    t0 = time.perf_counter()
    log = simulate_experiment(rig, cycles, rng, effect=None if effect == "none" else effect, severity=severity)
    d = diagnose(rig, log, secondary=False).as_json()   # the second-effect search does not change `selected`
    return {"effect": effect, "severity": severity, "seed": seed, "rows": len(log),
            "selected": d["selected"], "confounded_with": d["confounded_with"], "gap": d["gap"],
            "noise_floor_rad": d["noise_floor_rad"], "seconds": time.perf_counter() - t0}


def summarise(records: list[dict]) -> str:
    from csjm_opt.diagnose import VOCABULARY

    lines = ["| true \\ selected | " + " | ".join(VOCABULARY) + " | accuracy |",
             "|---" * (len(VOCABULARY) + 2) + "|"]
    for true in VOCABULARY:
        rs = [r for r in records if r["effect"] == true]
        if not rs:
            continue
        counts = [sum(r["selected"] == s for r in rs) for s in VOCABULARY]
        acc = counts[VOCABULARY.index(true)] / len(rs)
        lines.append(f"| {true} | " + " | ".join(str(c) for c in counts) + f" | {acc:.0%} |")
    total = sum(r["selected"] == r["effect"] for r in records) / len(records)
    lines += ["", f"Overall: {total:.1%} of {len(records)} logs named correctly.", "",
              "| effect | severity | runs | correct | gap before (mrad) | gap after (mrad) | noise floor (mrad) "
              "| fraction of systematic gap closed (min / median) |", "|---|---|---|---|---|---|---|---|"]
    for true in VOCABULARY[1:]:
        for sev in sorted({r["severity"] for r in records if r["effect"] == true}):
            rs = [r for r in records if r["effect"] == true and r["severity"] == sev]
            ok = [r for r in rs if r["selected"] == true]
            fr = [r["gap"]["fraction_explained"] for r in ok]
            lines.append(f"| {true} | {sev:g} | {len(rs)} | {len(ok)} | "
                         f"{1e3 * np.median([r['gap']['before_rad'] for r in rs]):.2f} | "
                         f"{1e3 * np.median([r['gap']['after_rad'] for r in rs]):.2f} | "
                         f"{1e3 * np.median([r['noise_floor_rad'] for r in rs]):.2f} | "
                         + (f"{min(fr):.2f} / {np.median(fr):.2f} |" if fr else "- |"))
    named = [r for r in records if r["effect"] != "none" and r["selected"] == r["effect"]]
    for k in (1, 2):
        big = [r for r in named if r["gap"]["systematic_before_rad"] >= k * r["noise_floor_rad"]]
        if big:
            n80 = sum(r["gap"]["fraction_explained"] >= 0.8 for r in big)
            lines.append(f"\nCorrectly named logs whose systematic gap is >= {k}x the noise floor: {len(big)}; "
                         f"held-out gap closed by >= 80 % of its systematic part in {n80} "
                         f"(min {min(r['gap']['fraction_explained'] for r in big):.2f}).")
    secs = [r["seconds"] for r in records]
    lines += ["", f"Median time per log (simulate + diagnose, {records[0]['rows']} rows): {np.median(secs):.1f} s."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from tqdm import tqdm

    from csjm_opt.diagnose import VOCABULARY

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=22)
    ap.add_argument("--severities", type=float, nargs="+", default=[0.5, 1.0, 2.0])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--effects", nargs="+", default=list(VOCABULARY))
    ap.add_argument("--out", default="studies/diagnose_confusion")
    ap.add_argument("--summarise", action="store_true", help="only re-summarise OUT.json")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if args.summarise:
        text = summarise(json.loads(out.with_suffix(".json").read_text()))
        out.with_suffix(".md").write_text(text)
        print(text)
        return 0
    jobs = [(e, (1.0 if e == "none" else s), seed, args.cycles) for e in args.effects
            for s in (args.severities if e != "none" else [1.0]) for seed in range(args.seeds)]
    jobs += [("none", 1.0, seed, args.cycles) for seed in range(args.seeds, args.seeds * 2)
             if "none" in args.effects]   # effect-free logs get as many runs as a severity level x2
    records = []
    with ProcessPoolExecutor(args.workers) as pool:
        for rec in tqdm(pool.map(run_one, jobs), total=len(jobs), file=sys.stderr, desc="confusion study"):
            records.append(rec)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(records, indent=1) + "\n")
    text = summarise(records)
    out.with_suffix(".md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
