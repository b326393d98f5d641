"""``csjm optimise``: hole-geometry optimisation on a sweep file's vocabulary, certified designs as rig files."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ._options import check_outputs, int_in, json_option, out_option, workers_option
from .commands import command_help

#: Most design evaluations a run may be given.
MAX_EVALUATIONS = 10_000_000
#: Objective name -> (label, unit, factor to the printed unit).
UNITS = {"range": ("range scale", "of the required orientation set", 1.0),
         "stiffness": ("minimum stiffness", "N m/rad", 1.0),
         "tension_margin": ("tension margin", "N", 1.0),
         "size": ("size (largest hole radius)", "mm", 1e3),
         "shaping": ("shaping range", "N m/rad", 1.0)}
#: A certified value this close to zero is zero (round-off of the certification's solves), in its unit.
ZERO_TOL = 1e-6


def format_objectives(objectives: dict[str, float]) -> str:
    """The objectives of a design with their units, round-off at a bound printed as 0.

    Parameters
    ----------
    objectives : dict
        Name -> value (SI: N m/rad, N, m).

    Returns
    -------
    str
        E.g. ``range scale 0.003635 of the required orientation set, tension margin 0 N``.
    """
    parts = []
    for name, value in objectives.items():
        label, unit, factor = UNITS.get(name, (name, "", 1.0))
        v = float(value) * factor
        v = 0.0 if abs(v) < ZERO_TOL else v
        parts.append(f"{label} {v:.4g}" + (f" {unit}" if unit else ""))
    return ", ".join(parts)


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``csjm optimise`` parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``csjm`` parser.
    """
    p = sub.add_parser(
        "optimise", help=command_help("optimise"),
        parents=[out_option("DIR", "output folder (created)"),
                 workers_option(), json_option("result.json (also written in DIR)")],
        description="Optimise the swept parameters of a sweep file (same names and bounds) with IPOPT "
        "and exact derivatives: every orientation of the required set holds every load with tensions in "
        "range and a stiffness of at least the stated value, no cable touches another or the link. "
        "Objective and requirements come from the optional [optimise] section (docs/guide/optimisation.md). "
        "Every returned design is certified on a dense orientation set; DIR gets design_000.toml, ... "
        "(rig files) and result.json.")
    p.add_argument("sweep", metavar="DESIGN.toml", help="sweep file (with an optional [optimise] section)")
    p.add_argument("--max-evaluations", type=int_in(1, MAX_EVALUATIONS), default=None, metavar="N",
                   help="hard bound on design evaluations (every point IPOPT evaluates, line-search trials "
                   "included, plus certifications; with --sweep-front every evaluation of the smooth twins and "
                   "every scoring by the sweep's evaluator)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run the starts on the Dask scheduler at ADDRESS (e.g. tcp://host:8786)")
    p.add_argument("--dask", action="store_true", help="run the starts on a local Dask cluster")
    p.add_argument("--starts-from", metavar="RESULTS", default=None,
                   help="start from the best designs (largest workspace) of a csjm sweep result file "
                   "instead of space-filling designs")
    p.add_argument("--sweep-front", action="store_true",
                   help="trace the front in the sweep's own metrics (workspace fraction, minimum stiffness) "
                   "instead: smooth twins of both on the sweep's samples, every design scored by the sweep's "
                   "evaluator; DIR also gets records.jsonl, a sweep result file (csjm report DIR renders it)")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``csjm optimise`` with parsed ``args``.

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
    CsjmError
        A bad design file (the key named), or a requirement no design meets (``InfeasibleRequirement``,
        naming the binding constraint and an orientation where it binds).
    """
    from .._fileio import atomic_write_json
    from ..design.optimisation.runner import design_rig_of, optimise
    from ..design.optimisation.settings import read_optimise_file

    out = Path(args.out)
    check_outputs([args.sweep, args.starts_from], {"--json": args.json}, dirs={"--out": out})
    spec, settings = read_optimise_file(args.sweep)
    if args.sweep_front:
        return _sweep_front(args, spec, settings, out)
    starts = None
    if args.starts_from:
        from ..design.optimisation.runner import sweep_starts
        from ..design.sweep.store import read_records

        starts = sweep_starts(settings, read_records(args.starts_from)[0])
    from ._options import workers_of

    result = optimise(settings, max_evaluations=args.max_evaluations, workers=workers_of(args),
                      progress=False if args.no_progress else None, starts=starts, dask=args.dask,
                      scheduler=args.scheduler)
    out.mkdir(parents=True, exist_ok=True)
    doc = result.as_json()
    for k, d in enumerate(result.designs):
        name = f"design_{k:03d}.toml"
        design_rig_of(settings, d.params).to_toml(out / name, overwrite=True)
        doc["designs"][k]["rig_file"] = name
    atomic_write_json(out / "result.json", doc)
    if args.json:
        atomic_write_json(args.json, doc)
    stream = sys.stderr if args.json == "-" else sys.stdout
    for k, d in enumerate(result.designs):
        print(f"design_{k:03d}: {format_objectives(d.objectives)}; {'certified' if d.ok else 'NOT certified'} on "
              f"{settings.certify_orientations} + local-search orientations", file=stream)
    used = (f"{result.evaluations} of {args.max_evaluations} evaluations used" if args.max_evaluations
            else f"{result.evaluations} evaluations")
    print(f"{len(result.designs)} designs, {used}, written to {out}", file=stream)
    return 0


def _sweep_front(args: argparse.Namespace, spec: Any, settings: Any, out: Path) -> int:
    """``--sweep-front``: the front in the sweep's metrics, its designs as rig files, its records as a sweep file."""
    import json

    from .._fileio import atomic_write_json, atomic_write_text
    from ..design.optimisation.front import sweep_front
    from ..design.optimisation.runner import design_rig_of

    result = sweep_front(settings, spec.settings, max_evaluations=args.max_evaluations)
    out.mkdir(parents=True, exist_ok=True)
    doc = result.as_json()
    for k, rec in enumerate(doc["front"]):
        rec["rig_file"] = name = f"design_{k:03d}.toml"
        design_rig_of(settings, rec["params"]).to_toml(out / name, overwrite=True)
    # every scored design as a csjm sweep result file: csjm report DIR renders it like a sweep
    atomic_write_text(out / "records.jsonl", "".join(json.dumps(r, sort_keys=True, allow_nan=False) + "\n"
                                                     for r in result.records), overwrite=True)
    doc["records_file"] = "records.jsonl"
    atomic_write_json(out / "result.json", doc)
    if args.json:
        atomic_write_json(args.json, doc)
    stream = sys.stderr if args.json == "-" else sys.stdout
    for rec in doc["front"]:
        print(f"{rec['rig_file']}: workspace fraction {rec['workspace_fraction']:.4g}, minimum stiffness "
              f"{rec['min_stiffness_Nm_per_rad']:.4g} N m/rad (the sweep's evaluator)", file=stream)
    used = (f"{result.evaluations} of {args.max_evaluations} evaluations used" if args.max_evaluations
            else f"{result.evaluations} evaluations")
    print(f"{len(doc['front'])} front designs, {used} ({result.twin_evaluations} of the "
          f"smooth twins, {result.sweep_evaluations} by the sweep's evaluator), written to {out}", file=stream)
    return 0
