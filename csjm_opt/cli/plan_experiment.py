"""``csjm plan-experiment``: an identification experiment planned for a small Cramér-Rao bound of K."""

from __future__ import annotations

import argparse
import sys

from .._fileio import atomic_write_json
from ._options import check_outputs, int_in, json_option, out_option, rig_option, rotvec_component
from .commands import command_help

#: Largest budget accepted (loads).
MAX_BUDGET = 2000


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``plan-experiment`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "plan-experiment", help=command_help("plan-experiment"),
        parents=[rig_option(), out_option("PROTOCOL.csv", "protocol to write"), json_option()],
                       description="Choose the pretension (rest lengths), dead weights, attachment points and "
                       "directions of an identification experiment with BUDGET loads, within the rig's limits "
                       "(tensions in bounds, stable, within the tracker's range), to minimise the A- or "
                       "D-criterion of the Cramér-Rao bound of K. Writes the protocol (the measurement-log "
                       "format with the measured columns empty; docs/guide/input-files.md) and prints the "
                       "predicted 95 % interval per entry of K, and the same for the paper's protocol "
                       "with the same budget.")
    p.add_argument("--budget", type=int_in(1, MAX_BUDGET), required=True, metavar="N", help="number of loads")
    p.add_argument("--loads", default=None, metavar="LOADS.toml",
                   help="weights, attachment points, directions, pretensions, tracker range "
                   "(format in docs/guide/identification.md; default from the rig)")
    p.add_argument("--pose", nargs=3, type=rotvec_component, action="append", default=None,
                   metavar=("RX", "RY", "RZ"),
                   help="a reference pose as a rotation vector (rad), as --rotvec elsewhere; repeatable: one "
                   "cycle each, the budget split (default: the home pose)")
    p.add_argument("--poses", nargs="+", default=None, metavar="RX,RY,RZ",
                   help="the same as comma-separated triples (a negative first value needs '=': "
                   "--poses=-0.15,0,0)")
    p.add_argument("--criterion", choices=("A", "D"), default="A", help="A: trace, D: log det of the bound")
    p.add_argument("--no-pairs", action="store_true", help="do not spend the budget on +- load pairs")
    p.add_argument("--seed", type=int_in(0, 2 ** 31 - 1), default=0, help="seed of the paper protocol's draw")
    p.add_argument("--force", action="store_true", help="replace an existing output file")
    p.set_defaults(func=run)


def _poses(values: list[str] | None, triples: list[list[float]] | None = None):
    import numpy as np

    from ..errors import UsageError
    from ._options import check_rotvec

    if values is None and not triples:
        return None
    out = [check_rotvec(t, "--pose") for t in triples or ()]
    for v in values or ():
        parts = v.split(",")
        if len(parts) != 3:
            raise UsageError(f"--poses: expected RX,RY,RZ, got {v!r}", "--poses")
        try:
            out.append(check_rotvec([rotvec_component(x) for x in parts], "--poses"))
        except argparse.ArgumentTypeError as exc:
            raise UsageError(f"--poses: {exc}", "--poses") from None
    return np.array(out)


def run(args: argparse.Namespace) -> int:
    """``csjm plan-experiment``: plan the experiment, write its protocol, print the predicted intervals.

    The paper's protocol with the same budget is planned for comparison; when the rig cannot hold
    it, the comparison is left out (``null`` in the JSON) and the plan is still written.

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
    UsageError
        A ``--poses`` entry that is not three comma-separated components.
    InvalidInput
        An output that cannot be written (or exists without ``--force``), a rotation vector outside
        the principal ball, or a bad load-set file.
    RigFileError
        The rig file cannot be read or is malformed.
    DesignError
        The rig cannot hold enough of the load set to identify K.
    """
    import numpy as np

    from ..errors import DesignError
    from ..identification.cramer_rao import SYM_NAMES
    from ..identification.experiment_design import paper_protocol, plan_experiment
    from ..identification.experiment_loads import ExperimentLoads
    from ..measurement.instruments import InstrumentNoise
    from ..model.numeric import Model
    from ..model.rig import load_rig

    check_outputs([args.rig, args.loads], {"-o/--out": args.out, "--json": args.json},
                  overwrite={"-o/--out": args.force})
    rig = load_rig(args.rig)
    loads = ExperimentLoads.from_toml(args.loads, rig) if args.loads else ExperimentLoads.default(rig)
    poses = _poses(args.poses, args.pose)
    noise, model = InstrumentNoise.paper(), Model(rig)
    plan = plan_experiment(rig, args.budget, loads, poses, noise, args.criterion, not args.no_pairs, model)
    try:
        paper = paper_protocol(rig, args.budget, np.random.default_rng(args.seed),
                               None if poses is None else poses[0], loads=loads, noise=noise, model=model)
    except DesignError:    # the comparison is not runnable on this rig; the plan still is
        paper = None
    plan.protocol.to_csv(args.out, overwrite=args.force)
    hw_plan = plan.ci_half_width()
    hw_paper = paper.ci_half_width() if paper is not None else None
    ratio = float(hw_paper[0].mean() / hw_plan[0].mean()) if hw_paper is not None else None
    per_entry = (hw_paper[0] / hw_plan[0]) if hw_paper is not None else None
    wider = [n for n, r in zip(SYM_NAMES, per_entry) if r < 1.0] if per_entry is not None else []
    pretension = np.atleast_1d(np.asarray(plan.pretension_N, float))
    out = {"output": str(args.out), "planned": plan.as_dict(),
           "paper_protocol": paper.as_dict() if paper is not None else None,
           "entries": list(SYM_NAMES), "narrower_by": ratio,
           "narrower_by_entry": per_entry.tolist() if per_entry is not None else None,
           "wider_than_paper": wider}
    if args.json:
        atomic_write_json(args.json, out)
    if args.json != "-":
        print(f"wrote {args.out}: {len(plan.protocol)} rows ({args.budget} loads, "
              f"{len(plan.rotvec_ref)} reference pose(s)), pretension "
              f"{', '.join(f'{t:.1f}' for t in pretension)} N")
        print("predicted 95 % half-width (N m/rad)  " + "  ".join(f"{n:>6}" for n in SYM_NAMES))
        for c, hw in enumerate(hw_plan):
            print(f"  planned, cycle {c}:                 " + "  ".join(f"{x:6.3f}" for x in hw))
        if hw_paper is None or per_entry is None:
            print("  paper protocol, same budget:       not admissible on this rig (25 N pretension)")
        else:
            print("  paper protocol, same budget:       " + "  ".join(f"{x:6.3f}" for x in hw_paper[0]))
            print("  paper / planned (first pose):      " + "  ".join(f"{r:5.2f}x" for r in per_entry))
            if wider:
                print(f"planned intervals are narrower for {6 - len(wider)} of 6 entries; WIDER than the paper "
                      f"protocol's for {', '.join(wider)} (ratios above; mean ratio {ratio:.2f}x)")
            else:
                print(f"planned intervals are narrower for every entry: {per_entry.min():.2f}x to "
                      f"{per_entry.max():.2f}x (first pose)")
    sys.stdout.flush()
    return 0
