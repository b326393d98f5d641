"""``csjm plan`` and ``csjm stiffness``: tensions and K at one pose."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

import numpy as np

from .._fileio import atomic_write_json
from ._options import check_outputs, json_option, pose_of, pose_option, quantity, rig_option
from .commands import command_help

if TYPE_CHECKING:
    from ..model.rig import Rig
    from ..planning.plans import TensionPlan


def add_plan_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``plan`` and ``stiffness`` besides the shared ones: reference tension, solver.

    ``--rig``, ``--json``, ``--rotvec`` and ``--tau`` come from the shared parent parsers.
    """
    p.add_argument("--t-ref", type=quantity("tension_N"), default=None,
                   help="reference tension of the objective (N; default mid-range)")
    p.add_argument("--solver", default="active_set",
                   help="'active_set' (default: exact, compiled) or a qpsolvers backend such as osqp or "
                   "clarabel (answer polished exactly and checked)")


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``plan`` and ``stiffness`` commands to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the command is added to.
    """
    p = sub.add_parser(
        "plan", help=command_help("plan"), parents=[rig_option(), pose_option(required=True), json_option()],
                       description="Plan the cable tensions (QP, t_min <= t <= t_max) that hold "
                       "the platform at a pose under an external moment plus its own weight.")
    add_plan_arguments(p)
    p.set_defaults(func=run_plan)
    p = sub.add_parser(
        "stiffness", help=command_help("stiffness"),
        parents=[rig_option(), pose_option(required=True), json_option()],
                       description="Plan tensions for the pose and load, then the stiffness K "
                       "(N m/rad; Levi-Civita Hessian of the cable energy, convention of docs/conventions.md).")
    add_plan_arguments(p)
    p.set_defaults(func=run_stiffness)


def _plan(args: argparse.Namespace) -> tuple[TensionPlan, Rig, np.ndarray, np.ndarray]:
    """The plan at the command's pose and load.

    The default solver plans without the compiled kernels
    (:func:`csjm_opt.planning.one_shot.plan_tensions_uncompiled`, the same answer
    to round-off): loading numba would cost a second for a 50 us job.
    """
    from .. import so3
    from ..model.rig import load_rig

    check_outputs([args.rig], {"--json": args.json})
    rig = load_rig(args.rig)
    rotvec, tau = pose_of(args)
    if args.solver == "active_set":
        from ..planning.one_shot import plan_tensions_uncompiled

        plan = plan_tensions_uncompiled(rig, so3.exp(rotvec), tau, t_ref_N=args.t_ref)
    else:
        from ..planning.planner import plan_tensions

        plan = plan_tensions(rig, so3.exp(rotvec), tau, t_ref_N=args.t_ref, solver=args.solver)
    return plan, rig, rotvec, tau


def _plan_json(plan: TensionPlan, rotvec: np.ndarray, tau: np.ndarray) -> dict:
    return {"tensions_N": plan.tensions_N.tolist(), "rotvec": rotvec.tolist(), "tau_ext": tau.tolist(),
            "equilibrium_residual_Nm": plan.equilibrium_residual_Nm,
            "tau_weight_Nm": plan.tau_weight_A_Nm.tolist(),
            "bound_margins_N": plan.bound_margins_N.tolist(), "active_bounds": plan.active_bounds,
            "solver": plan.solver}


def _print_plan(plan: TensionPlan) -> None:
    print("cable   tension (N)   margin (N)")
    for i, (t, m) in enumerate(zip(plan.tensions_N, plan.bound_margins_N)):
        print(f"  {i + 1}    {t:11.4f}   {m:10.4f}")
    print(f"equilibrium residual: {plan.equilibrium_residual_Nm:.2e} N m; "
          f"weight moment {np.round(plan.tau_weight_A_Nm, 4).tolist()} N m; "
          f"active bounds: {', '.join(plan.active_bounds) or 'none'}")


def run_plan(args: argparse.Namespace) -> int:
    """``csjm plan``: plan the tensions at the pose and load, print them and write the JSON.

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
    plan, _, rotvec, tau = _plan(args)
    if args.json:
        atomic_write_json(args.json, _plan_json(plan, rotvec, tau))
    if args.json != "-":
        _print_plan(plan)
    return 0


def run_stiffness(args: argparse.Namespace) -> int:
    """``csjm stiffness``: plan the tensions, then K (N m/rad) and its eigenvalues.

    Warns on stderr (exit status still 0) when K is not positive definite.

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
    from ..model.joint_stiffness import stiffness

    plan, rig, rotvec, tau = _plan(args)
    K = stiffness(rig, plan.R, plan.tensions_N, tau_ext_A_Nm=tau)
    eig = np.linalg.eigvalsh(K)
    stable = bool(eig[0] > 0)
    if args.json:
        out = _plan_json(plan, rotvec, tau)
        out.update({"K": K.tolist(), "eigenvalues_Nm_per_rad": eig.tolist(), "stable": stable})
        atomic_write_json(args.json, out)
    if args.json != "-":
        _print_plan(plan)
        print("K (N m/rad):")
        for row in K:
            print("  " + "  ".join(f"{x:10.4f}" for x in row))
        print(f"eigenvalues: {np.round(eig, 4).tolist()}"
              + ("" if stable else "  (not positive definite: unstable pose)"))
    if not stable:
        print(f"csjm: warning: K is not positive definite (smallest eigenvalue {eig[0]:.4g} N m/rad): "
              "the pose is unstable under this load", file=sys.stderr)
    return 0
