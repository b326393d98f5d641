"""``csjm preprocess``, ``csjm identify`` and ``csjm paper`` (Section III-IV of the paper)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from .._fileio import atomic_write_json
from .._limits import MAX_BOOTSTRAP, MAX_EXACT_INT
from ._options import check_outputs, float_in, int_in, json_option, out_option, rig_option
from .commands import command_help

#: Above this many cycles, one line per cycle is printed and the JSON is compact.
LONG_LOG_CYCLES = 50


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``preprocess``, ``identify`` and ``paper`` commands to the ``csjm`` parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The ``csjm`` subparsers the commands are added to.
    """
    p = sub.add_parser(
        "preprocess", help=command_help("preprocess"),
        parents=[rig_option(), out_option("LOG.csv", "measurement log to write"), json_option("a summary")],
                       description="Turn a raw instrument CSV (tracker base points, platform poses "
                       "in the tracker frame, F/T readings in the sensor frame; format in "
                       "docs/guide/input-files.md) into the measurement log of docs/conventions.md: "
                       "least-squares base frame fit, pose in {B} (53)-(54), wrench moved to {A} "
                       "about O (55), weight handled explicitly (56).")
    p.add_argument("raw", metavar="RAW.csv", help="raw instrument CSV")
    p.add_argument("--force", action="store_true", help="replace an existing output file")
    p.add_argument("--origin-tol", type=float_in(0, 1, low_open=True, unit="m"), default=None, metavar="M",
                   help="largest accepted distance between the origins of {A} and {B} (m, default 2e-3)")
    p.add_argument("--ft-includes-weight", action="store_true",
                   help="the F/T moment includes the platform weight: subtract it (56)")
    p.set_defaults(func=run_preprocess)

    p = sub.add_parser(
        "identify", help=command_help("identify"), parents=[rig_option(), json_option()],
                       description="Per cycle (first row = reference): the default estimate K_ml "
                       "(maximum likelihood with tracker and F/T noise, curvature of the moment-rotation "
                       "relation from the rig model) with its interval, the Cramér-Rao bound of K's six "
                       "entries, its own covariance and their ratio; and for comparison K_D by (49), "
                       "K = K_D + K_L with K_L = -1/2 hat(tau_load) (errata 1-2), an affine least-squares "
                       "estimate, a symmetric-constrained estimate K_sym, and the condition number of the "
                       "excitation.")
    p.add_argument("data", metavar="DATA.csv", help="measurement log (format in docs/conventions.md)")
    p.add_argument("--cycle", type=int_in(-MAX_EXACT_INT, MAX_EXACT_INT), default=None, help="only this cycle id")
    p.add_argument("--order", type=int, choices=(1, 2, 3), default=1,
                   help="1: linear fit (paper); 2, 3: add terms up to that degree in dzeta "
                   "(less finite-displacement bias; needs 11 / 21 rows)")
    p.add_argument("--noise", choices=("none", "paper"), default="none",
                   help="'paper': weight and correct with the instrument uncertainties of Tables 1-2; "
                   "'none' (default): K_ml's noise is estimated from the residuals")
    p.add_argument("--tau-sigma", type=float_in(0, 100, low_open=True, unit="N m"), default=None, metavar="NM",
                   help="state the F/T moment noise (N m per axis; with --angle-sigma, overrides --noise)")
    p.add_argument("--angle-sigma", type=float_in(0, 1, unit="rad"), default=None, metavar="RAD",
                   help="state the tracker orientation noise (rad per axis). With --tau-sigma: both noises "
                   "stated. Alone: the F/T noise is estimated and this corrects K_ml's regression dilution "
                   "(default for that: the paper's tracker, Table 1)")
    p.add_argument("--curvature", choices=("model", "none"), default="model",
                   help="K_ml's curvature of the moment-rotation relation: from the rig model and the log's "
                   "rest lengths (default), or none (a linear relation)")
    p.add_argument("--ci-level", type=float_in(0, 1, low_open=True, high_open=True), default=0.95,
                   help="confidence level (default 0.95)")
    p.add_argument("--bootstrap", type=int_in(0, MAX_BOOTSTRAP), default=0, metavar="N",
                   help=f"pairs-bootstrap resamples per cycle (0 to {MAX_BOOTSTRAP})")
    p.add_argument("--max-condition", type=float_in(1, 1e12), default=None,
                   help="largest accepted condition number of the excitation (default 100)")
    p.add_argument("--fit-parameters", choices=("none", "shared", "per-cable"), default="none",
                   help="also fit the cable stiffness (shared or per cable) and rest-length offsets "
                   "over the whole log, with standard deviations")
    p.add_argument("--allow-ill-conditioned", action="store_true",
                   help="return estimates that the excitation does not determine to 20 %% (CI half-width "
                   "over ||K||) anyway, marked ill_conditioned; by default such cycles are refused")
    p.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    p.add_argument("--no-rig-check", action="store_true",
                   help="skip the check that the rig can have produced the log (its first rows' equilibrium)")
    p.add_argument("--figures", metavar="DIR", help="write the Figure 5 convergence curve per cycle")
    p.set_defaults(func=run_identify)

    p = sub.add_parser(
        "paper", help=command_help("paper"), parents=[json_option()],
                       description="Recompute Table 3 (K_D, K_L, K) and Table 4 (estimated poses, E_theta) "
                       "from the paper's printed numbers; report where the printed numbers disagree "
                       "with the equations (errata 1-5).")
    p.set_defaults(func=run_paper)


def run_preprocess(args: argparse.Namespace) -> int:
    """``csjm preprocess``: turn a raw instrument CSV into a measurement log, print the base-fit summary.

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
    DataFileError
        The raw CSV is malformed, or a sample puts the origin of {A} farther than ``--origin-tol``
        from the origin of {B} (naming the line).
    InvalidInput
        An output that cannot be written (or exists without ``--force``).
    RigFileError
        The rig file cannot be read or is malformed.
    """
    from ..measurement.preprocess import DEFAULT_ORIGIN_TOL_M, preprocess_file
    from ..model.rig import load_rig

    check_outputs([args.raw, args.rig], {"-o/--out": args.out, "--json": args.json},
                  overwrite={"-o/--out": args.force})
    rig = load_rig(args.rig)
    tol = DEFAULT_ORIGIN_TOL_M if args.origin_tol is None else args.origin_tol
    log, info = preprocess_file(args.raw, rig, origin_tol_m=tol, ft_includes_weight=args.ft_includes_weight)
    log.to_csv(args.out, overwrite=args.force)
    summary = {"output": str(args.out), "rows": len(log), "cycles": log.cycle_ids, **info}
    if args.json:
        atomic_write_json(args.json, summary)
    if args.json != "-":
        print(f"wrote {args.out}: {len(log)} rows, {len(log.cycle_ids)} cycles; base fit rms "
              f"{info['base_fit_rms_m'] * 1e6:.1f} um, max origin offset {info['max_origin_offset_m'] * 1e3:.3f} mm")
    return 0


def run_identify(args: argparse.Namespace) -> int:
    """``csjm identify``: estimate K per load cycle of a measurement log, print or write the estimates.

    Cycles that cannot be identified are skipped and listed (a warning on stderr) unless all are;
    with ``--figures``, the Figure 5 convergence curve of each cycle is saved as a PNG.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.

    Returns
    -------
    int
        Exit status (0 on success, also when some cycles were skipped).

    Raises
    ------
    UsageError
        ``--tau-sigma`` without ``--angle-sigma``.
    DataFileError
        The measurement log is malformed, or has no ``--cycle``.
    InvalidInput
        An output that cannot be written.
    RigFileError
        The rig file cannot be read or is malformed.
    IllConditionedData
        No cycle (or the ``--cycle`` asked for) can be identified.
    """
    import numpy as np

    from .. import so3
    from .._plotting import save
    from ..identification.cramer_rao import SYM_NAMES
    from ..identification.figures import convergence_curve, plot_convergence
    from ..identification.log_identification import identify_cycles, identify_log
    from ..identification.refusal import MAX_CONDITION
    from ..identification.stiffness_fits import n_parameters
    from ..measurement.instruments import InstrumentNoise
    from ..measurement.logfile import MeasurementLog
    from ..measurement.rig_fit import check_log_rig
    from ..model.numeric import Model
    from ..model.rig import load_rig

    check_outputs([args.data, args.rig], {"--json": args.json}, {"--figures": args.figures})
    rig = load_rig(args.rig)
    log = MeasurementLog.from_csv(args.data).check_cables(rig.n_cables, args.rig or "paper")
    if not args.no_rig_check:
        check_log_rig(rig, log)
    model = Model(rig)
    noise = InstrumentNoise.paper() if args.noise == "paper" else None
    if args.tau_sigma is not None and args.angle_sigma is None:
        from ..errors import UsageError

        raise UsageError("--tau-sigma needs --angle-sigma (state both noises, or only the tracker's)",
                         "--tau-sigma")
    if args.tau_sigma is not None:
        noise = InstrumentNoise((args.tau_sigma,) * 3, args.angle_sigma)
    options = dict(order=args.order, noise=noise, curvature=args.curvature, tracker_sigma_rad=args.angle_sigma,
                   ci_level=args.ci_level,
                   bootstrap=args.bootstrap,
                   max_condition=args.max_condition or MAX_CONDITION,
                   allow_ill_conditioned=args.allow_ill_conditioned)
    progress = None
    if not args.no_progress:
        from functools import partial

        from tqdm import tqdm

        progress = partial(tqdm, file=sys.stderr, disable=None, leave=False, desc="cycles", unit="cycle")
    if args.cycle is None:  # cycles that cannot determine K are reported, not fatal (unless all are)
        estimates, skipped = identify_cycles(log, rig, model, progress=progress, **options)
    else:
        estimates, skipped = identify_log(log, rig, args.cycle, model, progress=progress, check_rig=False,
                                          **options), []
    figures = []
    if args.figures:
        for e in estimates:
            assert e.cycle is not None  # identify_log fills it
            rows = log.cycle_rows(e.cycle)
            curve = convergence_curve(so3.exp(log.rotvec_rad[rows]), log.tau_ext_A_Nm[rows], model,
                                      n_min=n_parameters(args.order) + 1,
                                      **options | {"bootstrap": 0, "allow_ill_conditioned": True})
            ax = plot_convergence(curve, title=f"Cycle {e.cycle}: det K against measurements")
            figures.append(str(save(ax.figure, Path(args.figures) / f"convergence_cycle{e.cycle}.png")))
    out: dict[str, Any] = {"source": str(args.data), "cycles": [e.as_dict() for e in estimates], "skipped": skipped,
           "figures": figures}
    if args.fit_parameters != "none":
        from ..identification.param_fit import fit_parameters

        fit = fit_parameters(log, rig, shared_stiffness=args.fit_parameters == "shared", noise=noise, model=model)
        out["parameters"] = fit.summary()
    if args.json:  # compact (C encoder) for long logs: indented JSON of 10^4 cycles takes a minute
        atomic_write_json(args.json, out, indent=2 if len(estimates) <= LONG_LOG_CYCLES else None)
    if args.json != "-" and len(estimates) > LONG_LOG_CYCLES:  # one line per cycle
        for e in estimates:
            d = np.diag(e.K_ml)
            print(f"cycle {e.cycle}: {e.n_rows} rows, diag K_ml [{d[0]:.3f}, {d[1]:.3f}, {d[2]:.3f}] N m/rad, "
                  f"+-{e.relative_half_width:.1%} of ||K||, condition {e.condition:.3g}"
                  + ("  ILL-CONDITIONED" if e.ill_conditioned else ""))
    elif args.json != "-":
        np.set_printoptions(precision=3, suppress=True)
        for e in estimates:
            print(f"cycle {e.cycle}: {e.n_rows} rows, condition {e.condition:.3g}, symmetry error "
                  f"{e.symmetry_error:.3g}, residual rms {e.residual_rms_Nm:.3g} N m"
                  + ("  ILL-CONDITIONED (returned on request)" if e.ill_conditioned else ""))
            print(f"  K_ml (N m/rad, maximum likelihood, curvature {e.curvature}, noise "
                  f"{'estimated' if e.noise_estimated else 'stated'}) =\n{e.K_ml}\n  +- ({int(e.ci_level * 100)} %)\n"
                  f"{e.ml_quantile * e.K_ml_std}")
            print("  Cramer-Rao bound (std, " + ", ".join(SYM_NAMES) + "): "
                  + " ".join(f"{x:.3g}" for x in np.sqrt(np.diag(e.crlb6)))
                  + f" N m/rad; efficiency (bound / own covariance, trace) {e.efficiency:.2f}")
            print(f"  K (paper (50), affine fit) =\n{e.K}\n  +- ({int(e.ci_level * 100)} %)\n"
                  f"{e.ci_quantile * e.K_std}")
            print(f"  K_sym =\n{e.K_sym}")
            for problem in e.problems():
                print(f"  warning: {problem}")
    if skipped:       # partial results are kept; the refusal is said where a script watching stderr sees it
        print(f"warning: {len(skipped)} of {len(skipped) + len(estimates)} cycles skipped as ill-conditioned "
              f"(cycles {', '.join(str(s['cycle']) for s in skipped[:10])}{' ...' if len(skipped) > 10 else ''}); "
              "--allow-ill-conditioned returns them marked", file=sys.stderr)
    if args.json != "-":
        for s in skipped:
            print(f"cycle {s['cycle']}: skipped: {s['reason']}")
        for name, p in out.get("parameters", {}).get("parameters", {}).items():
            print(f"  {name} = {p['value']:.6g} +- {p['std']:.2g}")
        for f in figures:
            print(f"figure: {f}")
    return 0


def run_paper(args: argparse.Namespace) -> int:
    """``csjm paper``: recompute Tables 3 and 4 from the printed numbers, print or write the check.

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
        The ``--json`` output cannot be written.
    """
    from ..identification.paper_tables import format_report, paper_report

    check_outputs([], {"--json": args.json})
    report = paper_report()
    if args.json:
        atomic_write_json(args.json, report)
    if args.json != "-":
        print(format_report(report))
    return 0
