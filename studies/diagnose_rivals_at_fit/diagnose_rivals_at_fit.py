"""The rival rule's warnings before and after taking evidence at the fitted parameters, on the same logs.

``csjm_opt.diagnose.selection.rivals`` compares the Laplace evidence of the verdict and each rival at their
*fitted* parameters (``log_evidence(..., at_fit=True)``); before, it compared them at the modes of
their linearisations. Each log here is made as in ``diagnose_confusion.py`` (same jobs, seeds and
plants) and diagnosed once with the current code; the record is a confusion-study record (so
``diagnose_confusion.py --summarise`` reads it) plus, for the one diagnosis:

* ``rivals_at_fit``: the unsettled rivals the current rule names (its warnings are in ``warnings``);
* ``rivals_linearised``: the unsettled rivals of the same models with the linearised evidence (the
  rule before), the same skip list;
* ``other_warnings``: the warnings of every other rule.

The summary gives, per plant and kind of log, the share of verdicts with a warning from the other
rules, with the rival rule before, and after; for correctly named singles per effect; and every wrong
verdict, which should carry a warning.

Usage::

    python -m studies.diagnose_rivals_at_fit.diagnose_rivals_at_fit --plants mujoco --kinds none single \
        --first-rig 10 --rigs 3 \
        --multiples 0 3 --out studies/out/mjcover_rivals_mujoco [--ids ID ...] [--summarise]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from studies._runner import finished, read_records, run_and_append  # noqa: E402


def run_one(job: dict) -> dict:
    """One log: the confusion record of the current code, and the rival rule both ways on its models."""
    import csjm_opt.diagnose as dg
    import csjm_opt.diagnose.decision_rule as dec
    from csjm_opt.diagnose.selection.rivals import scored_models, unsettled_rivals
    from csjm_opt.errors import CsjmError
    from studies.diagnose_confusion import diagnose_confusion as dc

    ctxs: list = []
    diags: list = []
    init, diag = dec._Context.__init__, dg.diagnose

    def hooked_init(self, *a, **k):
        init(self, *a, **k)
        ctxs.append(self)

    def hooked_diagnose(*a, **k):
        d = diag(*a, **k)
        diags.append(d)
        return d

    dec._Context.__init__, dg.diagnose = hooked_init, hooked_diagnose
    try:
        rec = dc._run_one(job)
    except CsjmError as exc:
        return {**job, "error": f"{type(exc).__name__}: {exc}"}
    finally:
        dec._Context.__init__, dg.diagnose = init, diag
    d, ctx = diags[-1], ctxs[-1]
    v = d.verdict
    new = v.unsettled_rivals
    models = scored_models(ctx.evidence, d.candidates, d.tests, d.pairs, d.pair_scores)
    old = []
    if d.selected not in ("none", "unexplained"):
        skip = [*v.more_probable_rivals, *v.alternatives,
                *(f"{d.selected}+{c}" for c in v.secondary_alternatives)]
        plain = {k: {kk: vv for kk, vv in m.items() if kk != "log_evidence_at_fit"} for k, m in models.items()}
        old = unsettled_rivals(plain, d.final.name, skip)
    warnings = v.warnings
    rec.update({"rivals_at_fit": [_brief(r) for r in new], "rivals_linearised": [_brief(r) for r in old],
                "other_warnings": warnings[:len(warnings) - len(new)],
                "evidence": {k: {"linearised": m["log_evidence"], "at_fit": m.get("log_evidence_at_fit")}
                             for k, m in models.items()}})
    rec.pop("models", None)           # the per-cycle errors are not needed again (records stay small)
    return rec


def _brief(r: dict) -> dict:
    return {k: r.get(k) for k in ("model", "nats", "nats_linearised", "adds", "heldout_p", "heldout_better",
                                  "closes_gap")}


def _rate(k: int, n: int) -> str:
    return f"{k}/{n} ({k / n:.0%})" if n else "-"


def _group(r: dict) -> str:
    named = {r["selected"], r["secondary"]} - {"none"}
    right = named == set(r["truth"])
    if r["kind"] == "none":
        return "effect-free" + ("" if right else ", named wrong")
    return f"{r['kind']}, " + ("named right" if right else "named wrong")


def summarise(records: list[dict]) -> str:
    """Markdown: warning rates with the rival rule before (linearised) and after (at the fit)."""
    lines = ["| plant: logs | n | warned by other rules | warned, rival rule before (linearised evidence) | "
             "warned, rival rule after (evidence at the fit) |", "|---|---|---|---|---|"]
    groups: dict[str, list[dict]] = {}
    for r in records:
        groups.setdefault(f"{r.get('plant', 'quasistatic')}: {_group(r)}", []).append(r)
        if r["kind"] == "single" and _group(r) == "single, named right":
            groups.setdefault(f"{r.get('plant', 'quasistatic')}: single {r['effects'][0]}, named right",
                              []).append(r)

    def row(key, rs):
        other = [bool(r["other_warnings"]) for r in rs]
        before = [o or bool(r["rivals_linearised"]) for o, r in zip(other, rs)]
        after = [o or bool(r["rivals_at_fit"]) for o, r in zip(other, rs)]
        return (f"| {key} | {len(rs)} | {_rate(sum(other), len(rs))} | {_rate(sum(before), len(rs))} | "
                f"{_rate(sum(after), len(rs))} |")

    for key in sorted(groups, key=lambda k: (k.split(":")[0], " single " in k, k)):
        lines.append(row(key, groups[key]))
    lines += ["", "Logs where the rule before or after names a rival, and every wrong verdict:", "",
              "| log | verdict | other warnings | rivals before (nats linearised) | rivals after (nats at the fit) |",
              "|---|---|---|---|---|"]
    for r in sorted(records, key=lambda r: r["id"]):
        if r["rivals_linearised"] or r["rivals_at_fit"] or "wrong" in _group(r):
            fmt = lambda xs, k: ", ".join(f"{x['model']} ({x[k]:+.1f})" for x in xs) or "-"  # noqa: E731
            lines.append(f"| {r['id']} | {r['selected']} + {r['secondary']} | {len(r['other_warnings'])} | "
                         f"{fmt(r['rivals_linearised'], 'nats_linearised')} | {fmt(r['rivals_at_fit'], 'nats')} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from studies.diagnose_confusion import diagnose_confusion as dc

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plants", nargs="+", default=["mujoco"], choices=["quasistatic", "mujoco"])
    ap.add_argument("--kinds", nargs="+", default=["none", "single"])
    ap.add_argument("--first-rig", type=int, default=10)
    ap.add_argument("--rigs", type=int, default=3)
    ap.add_argument("--none-per-rig", type=int, default=1)
    ap.add_argument("--pair-rigs", type=int, default=1)
    ap.add_argument("--multiples", nargs="+", type=float, default=[0.0, 3.0])
    ap.add_argument("--only", nargs="+", default=None, help="only logs injecting these effects")
    ap.add_argument("--ids", nargs="+", default=None, help="exactly these confusion-study log ids")
    ap.add_argument("--out", required=True)
    ap.add_argument("--summarise", action="store_true")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    path = out.with_suffix(".jsonl")
    done = read_records(path)
    if not args.summarise:
        if args.ids:
            todo = []
            for i in args.ids:
                plant, kind, effs, mult, rig, rep = i.split(":")
                todo.append({"id": i, "kind": kind, "effects": [] if effs == "-" else effs.split("+"),
                             "multiple": float(mult), "rig": int(rig), "rep": int(rep), "cycles": 12, "plant": plant})
        else:
            todo = [j for plant in args.plants
                    for j in dc.jobs(args.rigs, args.none_per_rig, 12, args.pair_rigs, plant, args.first_rig)
                    if j["kind"] in args.kinds and j["multiple"] in args.multiples
                    and (args.only is None or set(j["effects"]) <= set(args.only))]
        todo = [j for j in todo if j["id"] not in done]
        run_and_append(map(run_one, todo), len(todo), path, done, "rival rule before/after", args.no_progress)
    records = [r for r in finished(done, path, "logs") if "truth" in r]
    text = summarise(records)
    out.with_suffix(".md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
