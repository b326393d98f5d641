"""The ``csjm validate`` command: the diagnosis checked against a folder of logs with known answers.

Usage: ``csjm validate FOLDER [--json OUT] [--keep DIR] [--cases NAME ...] [--workers N] [--no-progress]``.

Every case of ``FOLDER/answers.json`` is diagnosed with the standard command
(``csjm diagnose TRAIN --rig RIG --test TEST``, no per-set options) and scored by its accept
rule (:mod:`csjm_opt.diagnose.selection.validation`). All inputs are read and checked before the first
diagnosis: a folder without ``answers.json``, a missing file, or a log that does not belong to
its case's rig stops the command with one line (exit 2) and nothing written.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from .._fileio import atomic_write_json
from ..errors import InvalidInput
from ._options import check_outputs, json_option, workers_option
from .commands import command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``validate`` subcommand and its options.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``csjm`` parser.
    """
    p = sub.add_parser("validate", help=command_help("validate"),
                       parents=[json_option("the scores and verdicts"), workers_option()],
                       description="Diagnose every case of FOLDER/answers.json with the standard command "
                       "(csjm diagnose TRAIN --rig RIG --test TEST) and score it by its accept rule (exact, "
                       "no_effect, not_confident): the share right per folder, and every verdict.")
    p.add_argument("folder", metavar="FOLDER", help="validation folder holding answers.json and the files it names")
    p.add_argument("--keep", metavar="DIR", default=None,
                   help="also write each case's full diagnosis JSON here (DIR/CASE.json)")
    p.add_argument("--cases", nargs="+", metavar="NAME", default=None, help="only these cases (names in answers.json)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def _load(cases):
    """Rig and logs of every case, read and checked before any diagnosis (one error stops the command)."""
    from ..diagnose.data.extra import check_rows_belong
    from ..measurement.logfile import MeasurementLog
    from ..model.rig import load_rig

    loaded = []
    for c in cases:
        rig = load_rig(str(c.rig))
        train, test = MeasurementLog.from_csv(str(c.train)), MeasurementLog.from_csv(str(c.test))
        for log, path in ((train, c.train), (test, c.test)):
            check_rows_belong(rig, log, f"case {c.name}: {path}")
        loaded.append((c, rig, train, test))
    return loaded


def run(args: argparse.Namespace) -> int:
    """Validate the diagnosis on a folder and write the requested outputs.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        Exit status 0 (the scores are the output; a low score is not an error).

    Raises
    ------
    InvalidInput
        No ``answers.json``, an unknown case in ``--cases``, a malformed answer, a missing file, or a
        log that does not belong to its rig.
    CsjmError
        Unreadable rig or log files, raised by their loaders.
    """
    from ..diagnose import VOCABULARY, diagnose
    from ..diagnose.selection.validation import accepted, load_cases, summarise, verdict_line

    cases = load_cases(args.folder, VOCABULARY)
    if args.cases:
        unknown = [n for n in args.cases if n not in {c.name for c in cases}]
        if unknown:
            raise InvalidInput(f"--cases: no case {unknown[0]!r} in {args.folder}/answers.json", "--cases")
        cases = [c for c in cases if c.name in args.cases]
    inputs = [str(p) for c in cases for p in (c.rig, c.train, c.test)] + [f"{args.folder}/answers.json", args.folder]
    check_outputs(inputs, {"--json": args.json}, {"--keep": args.keep})
    loaded = _load(cases)
    bar = None
    if not args.no_progress:
        from tqdm import tqdm

        bar = tqdm(total=len(loaded), desc="validate: cases", file=sys.stderr, disable=None)
    scored = []
    for c, rig, train, test in loaded:
        t0 = time.perf_counter()
        result = diagnose(rig, train, test, workers=args.workers).as_json()
        if args.keep:
            atomic_write_json(Path(args.keep) / f"{c.name}.json", result)
        right = accepted(c.accept, c.effects, result)
        scored.append({"folder": c.folder, "case": c.name, "effects": list(c.effects), "accept": c.accept,
                       "right": right, "verdict": verdict_line(result), "selected": result["selected"],
                       "secondary": result["secondary"].get("effect", "none"),
                       "warnings": result["verdict"].get("warnings", []),
                       "seconds": time.perf_counter() - t0})
        if bar is not None:
            bar.update(1)
            bar.set_postfix_str(f"{sum(s['right'] for s in scored)}/{len(scored)} right")
    if bar is not None:
        bar.close()
    summary = summarise(scored)
    out = {"folder": str(args.folder), "command": "csjm diagnose TRAIN --rig RIG --test TEST",
           "score": summary, "cases": scored}
    if args.json:
        atomic_write_json(args.json, out)
    if args.json != "-":
        for s in scored:
            mark = "ok  " if s["right"] else "MISS"
            want = "+".join(s["effects"]) or "-"
            print(f"{mark} {s['case']:28s} want {want} ({s['accept']}), got {s['verdict']}  [{s['seconds']:.1f} s]")
        for folder, f in summary.items():
            print(f"{folder}: {f['right']}/{f['cases']} right ({f['share']:.0%})")
    return 0
