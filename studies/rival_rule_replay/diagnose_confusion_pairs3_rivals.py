"""Warnings naming rivals the log does not rule out (csjm_opt.diagnose.selection.rivals), on confusion-study records.

Each record of ``diagnose_confusion.py`` keeps a per-model summary (``models``: log evidence,
plausibility, gap closure, per-cycle held-out MSE), so the rival rule can be evaluated on stored
logs, whichever code made them. For every named verdict this script lists the unsettled rivals
and reports, per kind of log, how often a verdict carries a warning with and without the rule:

* correctly named single effects and effect-free logs (the rule should rarely fire there);
* wrong pair verdicts (named set != injected set): each should carry a warning.

Usage::

    python -m studies.rival_rule_replay.diagnose_confusion_pairs3_rivals RECORDS.jsonl [...] \
        [--out studies/diagnose_confusion_pairs3_rivals]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path


def rivals_of(r: dict) -> list[dict]:
    """Unsettled rivals of the record's verdict (none for ``none``/``unexplained`` or a record without models)."""
    from csjm_opt.diagnose.selection.rivals import unsettled_rivals

    models = r.get("models")
    verdict = (r.get("gap") or {}).get("model")
    if not models or r["selected"] in ("none", "unexplained") or verdict not in models:
        return []
    ms = {n: {"log_evidence": m.get("log_evidence"), "cycle_mse": m.get("cycle_mse") or [],
              "plausible": bool(m.get("plausible") and m.get("fitted", True)), "closes_gap": bool(m.get("closes_gap"))}
          for n, m in models.items() if n != "nominal_refit" and m.get("cycle_mse")}
    if verdict not in ms:
        return []
    skip = [*r.get("alternatives", []), *(f"{r['selected']}+{c}" for c in r.get("secondary_alternatives", []))]
    return unsettled_rivals(ms, verdict, skip)


def old_warnings(r: dict) -> list[str]:
    """The record's warnings other than the rival rule's (records made with the rule carry both)."""
    return [w for w in r.get("warnings", []) if "may be present too; the log does not decide" not in w
            and "the log does not single out" not in w and "yardsticks disagree" not in w]


def _rate(k: int, n: int) -> str:
    return f"{k}/{n} ({k / n:.0%})" if n else "-"


def summarise(records: list[dict]) -> str:
    """Markdown: warning rates with and without the rival rule, and the wrong verdicts' warnings."""
    lines = ["| logs | n | warned (other rules) | warned (with rival rule) | warned by the rival rule alone |",
             "|---|---|---|---|---|"]
    groups: dict[str, list[dict]] = {}
    for r in records:
        named = {r["selected"], r["secondary"]} - {"none"}
        right = named == set(r["truth"])
        if r["kind"] == "none":
            key = "effect-free"
        elif r["kind"] == "single":
            key = "single, named right" if right else "single, named wrong"
        elif r["kind"] == "pair":
            key = "pair, both named right" if right else "pair, named wrong"
        else:
            key = r["kind"]
        groups.setdefault(f"{r.get('plant', 'quasistatic')}: {key}", []).append(r)
    detail = []
    for key in sorted(groups):
        rs = groups[key]
        riv = [rivals_of(r) for r in rs]
        old = [bool(old_warnings(r)) for r in rs]
        new = [o or bool(v) for o, v in zip(old, riv)]
        lines.append(f"| {key} | {len(rs)} | {_rate(sum(old), len(rs))} | {_rate(sum(new), len(rs))} | "
                     f"{_rate(sum(n and not o for o, n in zip(old, new)), len(rs))} |")
        for r, v, o in zip(rs, riv, old):
            if v or ("wrong" in key):
                detail.append(f"| {r['id']} | {r['selected']} + {r['secondary']} | {'yes' if o else 'no'} | "
                              + (", ".join(f"{x['model']} ({x['nats']:+.1f} nats, p = {x['heldout_p']:.2f})"
                                           for x in v) or "-") + " |")
    lines += ["", "| log | verdict | other warning | unsettled rivals (evidence vs verdict, held-out p) |",
              "|---|---|---|---|", *detail]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("records", nargs="+")
    ap.add_argument("--out", default=None, help="write the summary to OUT.md")
    args = ap.parse_args(argv)
    records = [json.loads(line) for p in args.records for line in Path(p).read_text().splitlines()
               if line.strip()]
    records = [r for r in records if "truth" in r and "models" in r]
    text = summarise(records)
    if args.out:
        Path(args.out).with_suffix(".md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
