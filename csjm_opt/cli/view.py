"""``csjm view``: one self-contained HTML page of the rig in 3-D at a pose (or a log's cycles)."""

from __future__ import annotations

import argparse

from ._options import (
    check_outputs,
    int_in,
    json_option,
    out_option,
    pose_of,
    pose_option,
    rig_option,
)
from .commands import command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``view`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "view", help=command_help("view"),
        parents=[rig_option(), pose_option(), out_option("VIEW.html", "HTML page to write"),
                 json_option("the numbers shown")],
        description="Write one self-contained HTML page (works offline, no network fetches) showing the rig "
        "in 3-D: base, platform at the pose, joint centre O, holes numbered as in the rig file, cables "
        "coloured by planned tension, the load moment, and the compliance ellipsoid of K. A slider moves "
        "along the straight path from upright and unloaded to the pose and load (or through a log's cycles "
        "with --log). A pose the rig cannot hold still renders and names the cables at their bounds.")
    p.add_argument("--steps", type=int_in(1, 50), default=5,
                   help="frames on the path from upright to the pose (default 5)")
    p.add_argument("--log", metavar="DATA.csv", default=None,
                   help="show a measurement log's cycles instead (each cycle's most loaded row)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm view``: write the page.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        Exit status (0 on success, also for a pose the rig cannot hold).

    Raises
    ------
    InvalidInput
        Unreadable rig or log, an output that cannot be written, a rotation vector outside the principal ball.
    """
    from .._fileio import atomic_write_json
    from ..model.rig import load_rig
    from ..view import log_view, pose_view

    check_outputs([args.rig, args.log], {"-o/--out": args.out, "--json": args.json})
    rig = load_rig(args.rig)
    rotvec, tau = pose_of(args)
    if args.log:
        from ..measurement.logfile import MeasurementLog

        page = log_view(rig, MeasurementLog.from_csv(args.log))
    else:
        page = pose_view(rig, rotvec, tau, args.steps)
    path = page.write(args.out)
    frames = [{"label": lab, "panels": [_numbers(s) for s in f]} for lab, f in zip(page.frame_labels, page.frames)]
    if args.json:
        atomic_write_json(args.json, {"output": str(path), "bytes": len(page), "frames": frames})
    if args.json != "-":
        tail = "" if args.log else f"; at the pose: {page.frames[-1][0].message}"
        print(f"wrote {path} ({len(page) / 1e6:.2f} MB, {len(page.frames)} frame(s)){tail}")
    return 0


def _numbers(s) -> dict:
    from .. import so3

    return {"rotvec": so3.log(s.R).tolist(), "tau_ext": s.tau_ext_A_Nm.tolist(), "feasible": s.feasible,
            "tensions_N": s.tensions_N.tolist(), "at_bounds": {str(i + 1): b for i, b in s.at_bounds.items()},
            "residual_Nm": s.residual_Nm, "message": s.message,
            "K": None if s.K is None else s.K.tolist(),
            "eigenvalues_Nm_per_rad": None if s.eigenvalues_Nm_per_rad is None else s.eigenvalues_Nm_per_rad.tolist()}
