"""``csjm sweep``: run a hole-geometry design sweep described in a TOML file."""

from __future__ import annotations

import argparse
import sys

from .._fileio import atomic_write_json
from ._options import check_outputs, int_in, json_option, out_option, workers_option
from .commands import MAX_DESIGNS, command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``sweep`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "sweep", help=command_help("sweep"),
        parents=[out_option("RESULTS", "result file (JSON Lines; created, or resumed when it exists)"),
                 workers_option(), json_option("the designs and speed")],
        description="Evaluate every design of a sweep description (TOML; see studies/paper_sweep/paper_sweep.toml "
        "and docs/guide/design.md): wrench-feasible workspace, stiffness, tension and wrench margins, "
        "shaping range. Results are appended to RESULTS (JSON Lines) as designs finish; "
        "running again with the same RESULTS resumes, skipping finished designs.")
    p.add_argument("sweep", metavar="SWEEP.toml", help="sweep description")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run on the Dask distributed scheduler at ADDRESS (e.g. tcp://host:8786)")
    p.add_argument("--dask", action="store_true",
                   help="run on Dask; without --scheduler, start a local Dask cluster")
    p.add_argument("--limit", type=int_in(1, MAX_DESIGNS), default=None, metavar="N",
                   help="stop after computing N designs (run again to continue)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm sweep``: evaluate (or resume) the designs of a sweep file into ``--out``.

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
    DesignError
        An invalid sweep file, ``--workers`` or ``--limit``.
    InvalidInput
        An output that cannot be written or that names an input.
    """
    from ..design.sweep.runner import run_sweep
    from ..design.sweep.spec import SweepSpec
    from ..errors import DesignError

    check_outputs([args.sweep], {"--out": args.out})
    check_outputs([args.sweep, args.out], {"--json": args.json})
    spec = SweepSpec.from_toml(args.sweep)
    if args.workers is not None and args.workers < 1:
        raise DesignError(f"expected an integer >= 1, got {args.workers}", "--workers")
    if args.limit is not None and args.limit < 1:
        raise DesignError(f"expected an integer >= 1, got {args.limit}", "--limit")
    result = run_sweep(spec, args.out, workers=args.workers, scheduler=args.scheduler, dask=args.dask,
                       progress=False if args.no_progress else None, stop_after=args.limit)
    ok = [r for r in result.records if r["status"] == "ok"]
    best = max(ok, key=lambda r: (r["workspace_fraction"] or 0.0), default=None)
    print(f"{len(result.records)} designs ({result.computed} computed, {result.skipped} from "
          f"{args.out}), {len(result.records) - len(ok)} invalid, "
          f"{result.designs_per_second:.1f} designs/s"
          + ("" if result.complete else f"; {len(spec.designs()) - len(result.records)} designs left, "
             "run again to continue"), file=sys.stderr if args.json == "-" else sys.stdout)
    if result.duplicates:
        print(f"note: {result.duplicates} repeated lines in {args.out} ignored (first record of each design kept)",
              file=sys.stderr)
    if best is not None and args.json != "-":
        print(f"largest workspace: {best['workspace_fraction']:.3f} at {best['params']}")
    if args.json:
        atomic_write_json(args.json, result.as_json())
    return 0
