"""``csjm shape``: tensions that hold a pose and bring K closest to a target (stiffness shaping)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from .._fileio import atomic_write_json
from ..errors import InvalidInput
from ._options import (
    check_outputs,
    finite_float,
    json_option,
    pose_of,
    pose_option,
    quantity,
    rig_option,
)
from .commands import SHAPING_OBJECTIVES, command_help


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``shape`` command to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "shape", help=command_help("shape"), parents=[rig_option(), pose_option(required=True), json_option()],
                       description="Choose the cable tensions (t_min <= t <= t_max) that hold the pose "
                       "under the load and bring the stiffness K (N m/rad, docs/conventions.md) closest to "
                       "a target: weighted Frobenius (default), principal ('eigen') or directional objective. "
                       "Reports the achieved K, the residual, whether the target is reached and the active "
                       "bounds; --reachable adds the reachable range of each eigenvalue of K.")
    p.add_argument("--target", nargs=9, type=quantity("stiffness_Nm_per_rad"), required=True, metavar="K",
                   help="target K row by row: K11 K12 K13 K21 ... K33 (N m/rad; symmetrised)")
    p.add_argument("--weights", nargs="+", type=quantity("weight"), default=None, metavar="W",
                   help="frobenius: 9 elementwise weights; eigen: 3; directional: one per direction")
    p.add_argument("--objective", choices=SHAPING_OBJECTIVES, default="frobenius")
    p.add_argument("--direction", nargs=3, type=finite_float, action="append", metavar=("UX", "UY", "UZ"),
                   help="a direction in {A} for --objective directional (repeatable)")
    p.add_argument("--solver", default="osqp", help="qpsolvers backend or 'active_set' (default osqp)")
    p.add_argument("--reachable", action="store_true", help="also compute the reachable eigenvalue ranges")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``csjm shape``: shape K toward the target, print the tensions and achieved K, write the JSON.

    Warns on stderr (exit status still 0) when the achieved K is not positive definite.

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
        A zero or huge ``--direction``, a wrong number of ``--weights``, an output
        that cannot be written, or a rotation vector outside the principal ball.
    InfeasibleLoad
        No tensions within the bounds hold the pose under the load.
    """
    from .. import so3
    from ..model.numeric import Model
    from ..model.rig import load_rig
    from ..shaping.shaper import shape_stiffness

    check_outputs([args.rig], {"--json": args.json})
    for d in args.direction or ():
        if not 1e-9 < float(np.linalg.norm(d)) < 1e9:
            raise InvalidInput(f"--direction: expected a non-zero direction of moderate length, got {d}",
                               "--direction")
    rig = load_rig(args.rig)
    rotvec, tau = pose_of(args)
    K_target = np.array(args.target, float).reshape(3, 3)
    weights = None
    if args.weights is not None:
        weights = np.array(args.weights, float)
        if args.objective == "frobenius":
            if weights.size != 9:
                raise InvalidInput(f"--weights: expected 9 values for the frobenius objective, got {weights.size}",
                                   "--weights")
            weights = weights.reshape(3, 3)
    R = so3.exp(rotvec)
    res = shape_stiffness(rig, R, tau, K_target, weights=weights, objective=args.objective,
                          directions=np.array(args.direction) if args.direction else None, solver=args.solver,
                          model=Model(rig))
    out = {"rotvec": rotvec.tolist(), "tau_ext": tau.tolist(), **res.as_dict()}
    lam_min = float(np.linalg.eigvalsh(0.5 * (res.K + res.K.T))[0])
    out["stable"] = lam_min > 0
    if args.reachable:
        from ..shaping.reachable import reachable_set

        out["reachable"] = reachable_set(rig, R, tau).as_dict()
    if args.json:
        atomic_write_json(args.json, out)
    if args.json != "-":
        print("cable   tension (N)")
        for i, t in enumerate(res.tensions_N):
            print(f"  {i + 1}    {t:11.4f}")
        print("achieved K (N m/rad):")
        for row in res.K:
            print("  " + "  ".join(f"{v:10.4f}" for v in row))
        print(f"{res.objective.name} residual {res.residual:.4g} N m/rad "
              f"({'target reached' if res.exact else 'target not reachable: constrained optimum'}); "
              f"active bounds: {', '.join(res.active_bounds) or 'none'}; "
              f"equilibrium residual {res.equilibrium_residual_Nm:.2e} N m")
        if args.reachable:
            for i, (lo, hi) in enumerate(out["reachable"]["eigen_ranges_Nm_per_rad"]):
                print(f"  lambda_{i + 1} reachable in [{lo:.3f}, {hi:.3f}] N m/rad")
    if lam_min <= 0:
        print(f"csjm: warning: the achieved K is not positive definite (smallest eigenvalue {lam_min:.4g} "
              "N m/rad): the pose is unstable under this load", file=sys.stderr)
    return 0
