"""``csjm codegen``: the tension planner and K of a rig as self-contained C99 for a real-time controller."""

from __future__ import annotations

import argparse

from .._fileio import atomic_write_json
from ._options import check_outputs, json_option, out_option, rig_option
from .commands import command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``codegen`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "codegen", help=command_help("codegen"),
        parents=[rig_option(), out_option("DIR", "folder to write (created if missing)"), json_option("a summary")],
                       description="Write a C99 library for a 1 kHz controller: cable lengths, J and the "
                       "weight moment at a pose, the bounded tension QP of `csjm plan` (warm start, fixed "
                       "iteration bound, status codes), rest lengths, K; the rig's constants baked in. "
                       "Also an example 1 kHz loop over a trajectory CSV and a Makefile.")
    p.add_argument("--build", action="store_true",
                   help="also compile it with the system C compiler (-std=c99 -Wall -Wextra -Werror -O2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm codegen``: write the rig's C99 planner and K to ``--out``, optionally compile it, print a summary.

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
    RigFileError
        The rig file cannot be read or is malformed.
    InvalidInput
        An output that cannot be written, or a folder that lacks a generated file at ``--build``.
    SolverError
        ``--build``: no C compiler, or the compiler failed.
    """
    from ..codegen import build_shared, generate_c  # CasADi code generation: loaded only for this command
    from ..model.rig import load_rig

    check_outputs([args.rig], {"--json": args.json}, {"-o/--out": args.out})
    rig = load_rig(args.rig)
    code = generate_c(rig, args.out, rig_source=str(args.rig or "paper"))
    lib = str(build_shared(code.out_dir)) if args.build else None
    if args.json:
        atomic_write_json(args.json, {"out_dir": str(code.out_dir), "files": list(code.files),
                                      "rig_sha256": code.rig_sha256, "library": lib})
    if args.json != "-":
        print(f"wrote {len(code.files)} files to {code.out_dir} (rig {args.rig or 'paper'}, sha256 "
              f"{code.rig_sha256[:12]}){'; built ' + lib if lib else ''}; `make -C {code.out_dir}` builds the "
              "library and the example")
    return 0
