"""``csjm demo``: the main job on the built-in paper rig, or on any valid rig file (``--rig``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._fileio import atomic_write_json
from ..errors import InvalidInput
from ._options import check_outputs, int_in, json_option, out_option, rig_option
from .commands import command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``demo`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "demo", help=command_help("demo"),
        parents=[out_option("DIR", "report folder (default: ./csjm_report)", required=False, default="csjm_report"),
                 json_option("the summary"),
                 rig_option("rig TOML file; any valid rig, any number of cables")],
                       description="Plan tensions, compute and shape stiffness, simulate an "
                       "experiment, identify K, verify, diagnose; writes a report folder: index.html (open it "
                       "in a browser), README.md (the same in Markdown), figures, summary.json, and the "
                       "sub-reports experiment/index.html and diagnosis/index.html.")
    p.add_argument("--seed", type=int_in(0, 2 ** 63 - 1), default=0, help="random seed of the simulated experiment")
    p.add_argument("--quick", action="store_true",
                   help="every step shortened (smaller experiments, no second-effect search): ~10-20 s")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm demo``: run the demo pipeline into ``--out`` and print the time of each step.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        Exit status (0 on success).

    Raises
    ------
    InvalidInput
        An output that cannot be written, or a ``--json`` path that is one of the
        report's own files.
    """
    from ..demo import pipeline as demo
    from ..model.rig import load_rig

    check_outputs([args.rig], {"--json": args.json}, {"--out": args.out})  # before the work, not after it
    rig = load_rig(args.rig) if args.rig else None
    if args.json and args.json != "-" and Path(args.json).resolve().parent == Path(args.out).resolve() \
            and Path(args.json).name in ("summary.json", "README.md", "index.html"):
        raise InvalidInput(f"--json {args.json} is a file the report writes; choose another name", "--json")
    summary = demo.run(args.out, seed=args.seed, quick=args.quick, rig=rig, progress=sys.stderr.isatty())
    if args.json:
        atomic_write_json(args.json, summary)
    if args.json != "-":
        print(f"report written to {args.out}/index.html (also README.md; numbers in summary.json), "
              f"{len(summary)} steps")
        for name, result in summary.items():
            print(f"  {name}: {result.get('seconds', '?')} s")
    return 0
