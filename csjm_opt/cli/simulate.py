"""``csjm simulate``: run a protocol (the log format, measured columns empty) on a testbed plant."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from .._fileio import atomic_write_json, atomic_write_text
from ..errors import InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.rig import load_rig
from ..testbed.injection import inject, make_plant
from ..testbed.log_protocol import read_protocol, simulate_protocol
from ..testbed.mujoco.plant import PLANTS
from ..testbed.plant import EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES, TestbedPlant
from ._options import check_outputs, int_in
from .commands import command_help

KNOWN = EFFECT_NAMES + tuple(VARIANT_NAMES) + OUTSIDE_NAMES


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``csjm simulate`` parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``csjm`` parser.
    """
    p = sub.add_parser(
        "simulate", help=command_help("simulate"),
                       description="Run a protocol (the log format with planned rest lengths, intended loads "
                       "and empty measured columns) on a testbed plant with injected effects, and write the "
                       "measured log (instrument noise added). Each cycle starts where the previous one "
                       "settled unless --relaxed.")
    p.add_argument("protocol", metavar="PROTOCOL.csv", help="the protocol to run")
    p.add_argument("--rig", default=None, help="rig TOML file of the protocol (default: the built-in paper rig)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[=SEVERITY]",
                   help=f"inject an effect (repeatable; severity 1 = typical, default 1): one of {', '.join(KNOWN)}")
    p.add_argument("--plant", choices=PLANTS, default="quasi-static",
                   help="the toolkit's quasi-static plant (default) or MuJoCo with the effects in the engine model")
    p.add_argument("--seed", type=int_in(0, 2 ** 32 - 1), default=0, help="seed of the effect draws and noise")
    p.add_argument("--noise", choices=("paper", "none"), default="paper",
                   help="instrument noise: the paper's F/T and tracker (default) or none")
    p.add_argument("--relaxed", action="store_true", help="start every cycle relaxed (friction state reset)")
    p.add_argument("--after", metavar="LOG.csv", default=None,
                   help="a log run just before on the same plant (same --effect and --seed): the protocol "
                   "starts from the state where it settled")
    p.add_argument("-o", "--output", required=True, metavar="LOG.csv", help="measured log to write")
    p.add_argument("--json", metavar="PATH", help="write a summary (with the injected truth) as JSON ('-' = stdout)")
    p.set_defaults(func=run)


def parse_effects(items: list[str]) -> list[tuple[str, float]]:
    """``NAME[=SEVERITY]`` items as ``(name, severity)`` pairs.

    Parameters
    ----------
    items : list of str

    Returns
    -------
    list of (str, float)

    Raises
    ------
    InvalidInput
        Unknown name or a severity that is not a finite number >= 0.
    """
    out = []
    for item in items:
        name, _, sev = item.partition("=")
        name = name.strip()
        if name == "none":
            continue
        if name not in KNOWN:
            raise InvalidInput(f"--effect: unknown effect {name!r}; expected one of {', '.join(KNOWN)}", "--effect")
        try:
            s = float(sev) if sev.strip() else 1.0
        except ValueError:
            raise InvalidInput(f"--effect {item}: severity must be a number", "--effect") from None
        if not (np.isfinite(s) and s >= 0):
            raise InvalidInput(f"--effect {item}: severity must be finite and >= 0", "--effect")
        out.append((name, s))
    return out


def truth(plant) -> dict:
    """The injected parameters of a plant that differ from the nominal one (JSON-ready).

    Parameters
    ----------
    plant : TestbedPlant or MujocoPlant

    Returns
    -------
    dict
    """
    p: TestbedPlant = plant if isinstance(plant, TestbedPlant) else plant.plant
    nominal = TestbedPlant.nominal(p.rig)
    out = {}
    for name in ("hardening_per_m", "friction_mu_beta", "friction_coulomb_N", "joint_friction_Nm",
                 "link_compliance_rad_per_Nm", "sensor_bias_A_Nm", "tracker_rotation_B", "eyelet_radius_m",
                 "sensor_drift_A_Nm_per_row", "drum_slip_compliance_m_per_N"):
        v, v0 = np.asarray(getattr(p, name), float), np.asarray(getattr(nominal, name), float)
        if v.shape != v0.shape or not np.allclose(v, v0, rtol=0, atol=0):
            out[name] = v.tolist()
    return out


def run(args: argparse.Namespace) -> int:
    """Run ``csjm simulate`` with parsed ``args``.

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
        A malformed protocol, one outside the rig's limits or written for another rig (file and line
        named), an unknown effect, or a row the simulated plant cannot hold.
    """
    check_outputs([args.rig, args.protocol, args.after], {"-o/--output": args.output, "--json": args.json})
    effects = parse_effects(args.effect)
    rig = load_rig(args.rig)
    proto = read_protocol(args.protocol)
    rng = np.random.default_rng(args.seed)
    plant = make_plant(rig, None, 1.0, rng, plant=args.plant, persistent=not args.relaxed)
    for name, severity in effects:
        plant = inject(plant, name, severity, rng)
    noise = InstrumentNoise.paper() if args.noise == "paper" else InstrumentNoise.none()
    t0 = time.perf_counter()
    after = MeasurementLog.from_csv(args.after) if args.after else None
    from tqdm import tqdm

    with tqdm(total=len(proto) + (len(after) if after is not None else 0), file=sys.stderr, unit="row",
              desc=f"simulate ({args.plant})", disable=None) as bar:
        log = simulate_protocol(rig, proto, plant, rng=rng, noise=noise, persistent=not args.relaxed, after=after,
                                progress=bar.update)
    seconds = time.perf_counter() - t0
    path = atomic_write_text(args.output, log.to_text())
    summary = {"output": str(path), "protocol": str(args.protocol), "rows": len(log), "cycles": len(log.cycle_ids),
               "plant": args.plant, "persistent": not args.relaxed, "noise": args.noise, "seed": args.seed,
               "effects": [{"name": n, "severity": s} for n, s in effects], "truth": truth(plant),
               "seconds": seconds}
    if args.json:
        atomic_write_json(args.json, summary)
    if args.json != "-":
        names = ", ".join(f"{n}={s:g}" for n, s in effects) or "none"
        print(f"wrote {path}: {len(log)} rows in {len(log.cycle_ids)} cycles on the {args.plant} plant "
              f"(effects: {names}; {seconds:.1f} s)")
    return 0
