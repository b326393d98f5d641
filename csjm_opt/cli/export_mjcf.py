"""``csjm export-mjcf``: a MuJoCo model (MJCF) of a rig, rest lengths planned for a pose and load."""

from __future__ import annotations

import argparse

import numpy as np

from .._fileio import atomic_write_json, atomic_write_text
from ._options import (
    check_outputs,
    float_in,
    json_option,
    out_option,
    pose_of,
    pose_option,
    rig_option,
)
from .commands import MJCF_ACTUATIONS, command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``export-mjcf`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "export-mjcf", help=command_help("export-mjcf"),
        parents=[rig_option(), pose_option(), out_option("FILE.xml", "MJCF file to write"), json_option("a summary")],
                       description="Write a MuJoCo model of the rig: ball joint at O, one pull-only tendon "
                       "spring per cable with rest lengths planned for the pose and load, the platform's mass and "
                       "inertia, base sites fixed, load motors in {A}. Frames: world = {B}, body "
                       "'platform' = {A}; the ball joint's qpos is R as (w, x, y, z).")
    p.add_argument("--actuation", choices=MJCF_ACTUATIONS, default="spring",
                   help="cables as pull-only springs (default), winch actuators (ctrl = rest length) "
                   "or tension motors (ctrl = tension)")
    p.add_argument("--timestep", type=float_in(0.0, 0.1, low_open=True, unit="s"), default=5e-4,
                   help="engine step (s; default 5e-4)")
    p.add_argument("--integrator", default="RK4", choices=("RK4", "implicitfast", "implicit", "Euler"),
                   help="MuJoCo integrator (default RK4)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm export-mjcf``: write the rig's MJCF model, rest lengths planned for the pose and load.

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
        An output that cannot be written, or a rotation vector outside the principal ball.
    InfeasibleLoad
        No tensions within the bounds hold the pose under the load.
    """
    from .. import so3
    from ..model.rig import load_rig
    from ..planning.mjcf_export import export_mjcf

    check_outputs([args.rig], {"-o/--out": args.out, "--json": args.json})
    rig = load_rig(args.rig)
    rotvec, tau = pose_of(args)
    xml = export_mjcf(rig, so3.exp(rotvec), tau, actuation=args.actuation, timestep_s=args.timestep,
                      integrator=args.integrator)
    path = atomic_write_text(args.out, xml)
    if args.json:
        atomic_write_json(args.json, {"output": str(path), "rotvec": rotvec.tolist(), "tau_ext": tau.tolist(),
                                      "actuation": args.actuation, "timestep_s": args.timestep,
                                      "integrator": args.integrator})
    if args.json != "-":
        print(f"wrote {path} (pose rotvec {np.round(rotvec, 4).tolist()} rad, load {np.round(tau, 4).tolist()} N m, "
              f"{args.actuation} actuation)")
    return 0
