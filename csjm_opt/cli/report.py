"""``csjm report RESULTS [--sweep SWEEP.toml] [--out DIR] [--top N]``: the design-study report of a sweep."""

from __future__ import annotations

import argparse
from pathlib import Path

from .._fileio import refuse_input_overwrite
from ._options import check_outputs, int_in, out_option
from .commands import command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``report`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "report", help=command_help("report"),
        parents=[out_option("DIR", "report folder (default: RESULTS without its suffix + _report)", required=False)],
                       description="Pareto front of workspace against minimum stiffness, the best designs in a "
                       "table and their hole geometry drawn, from a csjm sweep result file; writes index.html "
                       "(open it in a browser), index.md, figures and design_report.json into a folder.")
    p.add_argument("results", metavar="RESULTS", help="csjm sweep result file (JSON Lines), or a csjm optimise "
                   "output folder (with result.json; a --sweep-front folder renders like a sweep result)")
    p.add_argument("--sweep", metavar="SWEEP.toml", default=None,
                   help="the sweep file of the results: draws the geometry with its [base] parameters and "
                   "evaluates the paper's design with the same settings to mark it")
    p.add_argument("--top", type=int_in(1, 1000), default=8, help="best designs in the table (default 8)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm report``: write the design-study report of a sweep result file.

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
        No result file, an output that cannot be written, or a report file that
        would overwrite an input.
    """
    from ..errors import InvalidInput
    from ..report.design.report import write_design_report

    results = Path(args.results)
    if results.is_dir() and (results / "records.jsonl").is_file():  # csjm optimise --sweep-front: sweep records
        results = results / "records.jsonl"
        out = Path(args.out) if args.out else results.parent.with_name(results.parent.name + "_report")
    elif results.is_dir() and (results / "result.json").is_file():  # a csjm optimise folder
        from ..report.design.optimisation import write_optimisation_report

        out = Path(args.out) if args.out else results.with_name(results.name + "_report")
        check_outputs([results / "result.json"], dirs={"--out": out})
        print(f"report written to {write_optimisation_report(results, out)}")
        return 0
    else:
        if not results.is_file():
            raise InvalidInput(f"no result file {results}", "RESULTS")
        out = Path(args.out) if args.out else results.with_name(results.stem + "_report")
    check_outputs([str(results), args.sweep], dirs={"--out": out})
    for name in ("index.html", "index.md", "design_report.json", "pareto.png", "geometry.png"):
        refuse_input_overwrite(out / name, str(results), args.sweep)
    page = write_design_report(results, out, args.sweep, args.top)
    print(f"report written to {page}")
    return 0
