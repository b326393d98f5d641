"""The ``csjm diagnose`` command: which unmodelled effect explains the model-rig gap.

Usage: ``csjm diagnose DATA.csv --rig RIG [--test TEST.csv] [--extra MORE.csv] --json OUT [--report DIR]
[--suggest N --protocol OUT.csv [--loads LOADS.toml]]``.

Where the nominal model and the rig disagree, which unmodelled effect explains
it, and how much of the gap it closes on held-out cycles (docs/conventions.md keys and
vocabulary; see :mod:`csjm_opt.diagnose.selection.decision` for the decision rule).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._fileio import atomic_write_json
from ..errors import InvalidInput, UsageError
from ._options import check_outputs, json_option, rig_option, workers_option
from .commands import DIAGNOSIS_EFFECTS, command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``diagnose`` subcommand and its options.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``csjm`` parser.
    """
    p = sub.add_parser(
        "diagnose", help=command_help("diagnose"), parents=[rig_option(), json_option("the diagnosis"),
                                                           workers_option()],
                       description="Compare a measurement log (CSV, docs/conventions.md) with the nominal model of the "
                       "rig: residuals and where they lie, every candidate effect (" + ", ".join(DIAGNOSIS_EFFECTS)
                       + ") fitted jointly with the nominal stiffness scale and pretension and scored on "
                       "held-out cycles, the selected effect (or none) and the gap it closes.")
    p.add_argument("data", metavar="DATA.csv", help="measurement log (format in docs/conventions.md)")
    p.add_argument("--test", metavar="TEST.csv", default=None,
                   help="held-out log (default: grouped cross-validation by cycle)")
    p.add_argument("--report", metavar="DIR", default=None, help="write a Markdown report with figures here")
    p.add_argument("--effects", nargs="+", choices=list(DIAGNOSIS_EFFECTS), default=None,
                   help="candidates to try (default: all)")
    p.add_argument("--prior", action="append", default=[], metavar="NAME=LO:HI",
                   help="override an effect parameter's plausible range (SI units; NAME may be a pattern such "
                        "as 'dA*_m'); repeatable")
    p.add_argument("--extra", metavar="MORE.csv", default=None,
                   help="rows of a further experiment run after DATA.csv (e.g. a suggested protocol, measured): "
                        "appended to the training rows")
    p.add_argument("--suggest", metavar="N", type=int, default=None,
                   help="when the log cannot tell (non-separable alternatives, unexplained, an effect near the "
                        "floor), design up to N rows that best separate the leading hypotheses")
    p.add_argument("--protocol", metavar="OUT.csv", default="suggested_protocol.csv",
                   help="where --suggest writes the protocol (log columns, measured ones empty; default "
                        "%(default)s)")
    p.add_argument("--loads", metavar="LOADS.toml", default=None,
                   help="the lab's load set for --suggest ([[load]] name, mass_kg, point_A_m; default: masses at "
                        "+-x, +-y of the platform reaching 1/3, 2/3 and all of the log's largest moment)")
    p.add_argument("--seed", type=int, default=0, help="seed of --suggest's candidate draw")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-rig-check", action="store_true",
                   help="skip the check that the rig can have produced the logs (their first rows' equilibrium)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Diagnose a measurement log against its rig and write the requested outputs.

    Checks the inputs and outputs (no output may overwrite an input), runs
    :func:`csjm_opt.diagnose.diagnose`, optionally designs a separating experiment
    (``--suggest``), writes the JSON, report and protocol atomically, and prints a summary
    (unless the JSON goes to stdout).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        Exit status 0.

    Raises
    ------
    UsageError
        ``--suggest`` below 3 rows, or a ``--prior`` that is not ``NAME=LO:HI`` with ``LO < HI``.
    InvalidInput
        A ``--report`` folder that would overwrite an input or is not a folder.
    CsjmError
        Unreadable or invalid input files (rig, logs, load set), raised by their loaders.
    """
    from ..diagnose import diagnose
    from ..measurement.logfile import MeasurementLog
    from ..model.rig import load_rig
    from ..report.diagnosis.report import write_report

    inputs = [args.data, args.test, args.rig, args.extra, args.loads]
    outputs = {"--json": args.json}
    if args.suggest is not None:
        if args.suggest < 3:
            raise UsageError(f"--suggest {args.suggest}: at least 3 rows (one load cycle)", "--suggest")
        outputs["--protocol"] = args.protocol
    check_outputs(inputs, outputs, {"--report": args.report})
    if args.report:
        report = Path(args.report)
        for item in inputs:
            if item is not None and Path(item).resolve().parent == report.resolve() \
                    and Path(item).name in ("index.md", "diagnosis.json", "suggestion.md"):
                raise InvalidInput(f"--report {report} would overwrite input {item}", "--report")
        if report.exists() and not report.is_dir():
            raise InvalidInput(f"--report {report} exists and is not a folder", "--report")
    rig = load_rig(args.rig)
    rig_name = args.rig or "paper"
    log = MeasurementLog.from_csv(args.data).check_cables(rig.n_cables, rig_name)
    test = MeasurementLog.from_csv(args.test).check_cables(rig.n_cables, rig_name) if args.test else None
    extra = MeasurementLog.from_csv(args.extra).check_cables(rig.n_cables, rig_name) if args.extra else None
    loads = None
    if args.suggest is not None:
        from ..diagnose.suggest.dead_weights import read_dead_weights

        loads = read_dead_weights(args.loads) if args.loads else None
    progress = None
    if not args.no_progress:
        from functools import partial

        from tqdm import tqdm

        progress = partial(tqdm, file=sys.stderr, disable=None, leave=False)
    diagnosis = diagnose(rig, log, test, effects=args.effects, progress=progress, ranges=_priors(args.prior),
                         extra=extra, workers=args.workers, check_rig=not args.no_rig_check)
    result = diagnosis.as_json()
    suggestion = None
    if args.suggest is not None:
        from .._fileio import atomic_write_text
        from ..diagnose.suggest.experiment import protocol_text, suggest_experiment

        suggestion = suggest_experiment(rig, diagnosis, args.suggest, loads, seed=args.seed, progress=progress)
        result["suggestion"] = suggestion.as_json() if suggestion else None
        if suggestion is not None:
            atomic_write_text(args.protocol, protocol_text(suggestion))
            result["suggestion"]["protocol"] = str(args.protocol)
    if args.json:
        atomic_write_json(args.json, result)
    if args.report:
        write_report(diagnosis, args.report, Path(args.data).name, rig=rig)
        if suggestion is not None:
            from .._fileio import atomic_write_text
            from ..diagnose.suggest.experiment import suggestion_markdown

            atomic_write_text(Path(args.report) / "suggestion.md", suggestion_markdown(suggestion, args.protocol))
    if args.json != "-":
        g = result["gap"]
        sec = result["secondary"]["effect"]
        print(f"selected: {result['selected']}" + (f" + {sec}" if sec != "none" else "")
              + (f" (confounded with {', '.join(result['confounded_with'])})" if result["confounded_with"] else ""))
        print(f"  {result['verdict']['reason']}")
        for w in result["verdict"]["warnings"]:
            print(f"  warning: {w}")
        for note in left_out_notes(result["left_out_rows"]):
            print(f"  note: {note}")
        print(f"gap: {1e3 * g['before_rad']:.3f} -> {1e3 * g['after_rad']:.3f} mrad held-out RMS; noise floor "
              f"{1e3 * result['noise_floor_rad']:.3f} mrad; systematic part explained {g['fraction_explained']:.0%}")
        for c in result["candidates"]:
            if c.get("error"):
                print(f"   {c['effect']:16s} {c['error']}")
                continue
            mark = "*" if c["effect"] == result["selected"] else " "
            print(f" {mark} {c['effect']:16s} held-out {1e3 * c['heldout_rms_rad']:8.3f} mrad  BIC {c['bic']:9.1f}  "
                  f"p {c['p_value']:.2g}{'  significant' if c['significant'] else ''}"
                  f"{'' if c['plausible'] else '  implausible: ' + ', '.join(c['implausible_params'][:4])}")
        if args.suggest is not None:
            if suggestion is None:
                print("suggest: the verdict needs no further experiment (clear, separable, above the floor)")
            else:
                sj = suggestion.as_json()
                print(f"suggest: {sj['rows']} rows in {sj['cycles']} cycles written to {args.protocol}")
                print(f"  why: {suggestion.purpose}")
                for k, v in sj["expected_separation_sd"].items():
                    note = ("; equivalent: no feasible rows of loads through the sensor tell them apart, a "
                            "measurement of another kind must (e.g. a known mass fixed to the platform, measured "
                            "cable tensions)" if k in sj["equivalent"] else "")
                    print(f"  {k}: expected separation {v:.1f} noise sd (this log: "
                          f"{sj['separation_on_log_sd'].get(k, float('nan')):.1f}){note}")
    return 0


def _priors(items: list[str]) -> dict[str, tuple[float, float]]:
    """``["NAME=LO:HI", ...]`` -> ``{NAME: (LO, HI)}``; a malformed item is a usage error."""
    out = {}
    for item in items:
        name, _, rng = item.partition("=")
        lo, _, hi = rng.partition(":")
        try:
            bounds = (float(lo), float(hi))
        except ValueError:
            bounds = (float("nan"), float("nan"))
        if not name or not (bounds[0] < bounds[1]):
            raise UsageError(f"--prior {item!r}: expected NAME=LO:HI with LO < HI (numbers)", "--prior")
        out[name] = bounds
    return out


def left_out_notes(left: list[dict]) -> list[str]:
    """One console note per reason rows were left out of the diagnosis (``left_out_rows`` of the JSON)."""
    notes = []
    for reason, why in (("gross_residual", "the model that fits the log does not come near them and they stand apart "
                                           "(outlier ratio up to {worst:.1f}: a tracker glitch or a force spike?)"),
                        ("ill_conditioned", "the rig file's model is nearly singular at their measured poses (pose "
                                            "noise up to {worst:.0f}x the log's median: a cable slack in the model "
                                            "where the rig held it)")):
        rows = [r for r in left if r.get("reason", "ill_conditioned") == reason]
        if not rows:
            continue
        worst = max(r["outlier_ratio"] if reason == "gross_residual" else
                    r["pose_noise_rad"] / r["median_pose_noise_rad"] for r in rows)
        where = ", ".join(f"{r['log']} sample {r['sample']}" for r in rows[:5]) + ("; ..." if len(rows) > 5 else "")
        notes.append(f"{len(rows)} row(s) left out ({where}): " + why.format(worst=worst))
    return notes
