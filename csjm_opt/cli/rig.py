"""``csjm rig show RIG``: a rig's holes (expanded from its pattern) as a table, and a drawing."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from .._fileio import atomic_write_json
from ..model.rig import load_rig
from ..model.tension_closure import stated_range_rotvecs
from ._options import check_outputs
from .commands import command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``rig`` command (sub-command ``show``) to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser("rig", help=command_help("rig"),
                       description="Inspect a rig file (coordinates or a [geometry.pattern]); it is read and "
                       "checked exactly as every other command reads it.")
    actions = p.add_subparsers(dest="action", metavar="ACTION", parser_class=type(p))
    actions.required = True
    s = actions.add_parser("show", help="print the holes (pattern expanded) and draw the rig",
                           description="Print the rig's holes A_i in {A} and B_i in {B} (mm), cable stiffness, "
                           "bounds and stated range; with -o, draw the rig (PNG: 3D and top view).")
    s.add_argument("rig", metavar="RIG", help="rig TOML file, or 'paper' for the built-in rig")
    s.add_argument("-o", "--output", metavar="FILE.png", default=None, help="drawing of the rig (PNG)")
    s.add_argument("--json", metavar="PATH", help="write the expanded rig as JSON ('-' = stdout)")
    s.set_defaults(func=run_show)


def run_show(args: argparse.Namespace) -> int:
    """``csjm rig show``: print the holes, optionally draw the rig and write JSON.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        0.

    Raises
    ------
    CsjmError
        A rig file that cannot be read or is refused (file and key named), or an unwritable output.
    """
    check_outputs([args.rig], {"-o/--output": args.output, "--json": args.json})
    rig = load_rig(args.rig)
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    k = rig.cable_stiffness_N_per_m
    out = sys.stderr if args.json == "-" else sys.stdout
    print(f"rig {args.rig}: {rig.n_cables} cables, tensions in [{rig.t_min_N:g}, {rig.t_max_N:g}] N, "
          f"platform {rig.platform_mass_kg:g} kg", file=out)
    print(f"{'cable':>5} {'A_x':>9} {'A_y':>9} {'A_z':>9} {'B_x':>9} {'B_y':>9} {'B_z':>9} {'k (N/m)':>10}"
          "   (holes in mm)", file=out)
    for i in range(rig.n_cables):
        row = " ".join(f"{1e3 * v:9.3f}" for v in (*A[i], *B[i]))
        print(f"{i + 1:>5} {row} {k[i]:10.6g}", file=out)
    tilt = rig.workspace_tilt_deg
    print("stated range: " + ("the zero pose" if not tilt else f"tilts up to {tilt:g} deg")
          + f" ({len(stated_range_rotvecs(tilt))} poses checked for tension closure at load)", file=out)
    if args.output:
        from .._plotting import rig_drawing, save

        save(rig_drawing(A, B, title=f"{args.rig}: {rig.n_cables} cables"), args.output)
        print(f"drawing: {args.output}", file=out)
    if args.json:
        atomic_write_json(args.json, {"rig": str(args.rig), "n_cables": rig.n_cables,
                                      "platform_holes_m": np.asarray(A).tolist(),
                                      "base_holes_m": np.asarray(B).tolist(), "stiffness_N_per_m": k.tolist(),
                                      "t_min_N": rig.t_min_N, "t_max_N": rig.t_max_N,
                                      "workspace_tilt_deg": tilt})
    return 0
