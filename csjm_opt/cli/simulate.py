"""``csjm simulate``: run a protocol (the log format, measured columns empty) on a testbed plant."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from .._fileio import atomic_write_json, atomic_write_text
from ..errors import InvalidInput
from ._options import check_outputs, int_in, json_option, out_option, rig_option
from .commands import TESTBED_DEPRECATED, TESTBED_EFFECTS, TESTBED_PLANTS, command_help

KNOWN = TESTBED_EFFECTS


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``csjm simulate`` parser to ``sub``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``csjm`` parser.
    """
    p = sub.add_parser(
        "simulate", help=command_help("simulate"),
        parents=[rig_option("rig TOML file of the protocol"), out_option("LOG.csv", "measured log to write"),
                 json_option("a summary (with the injected truth)")],
                       description="Run a protocol (the log format with planned rest lengths, intended loads "
                       "and empty measured columns) on a testbed plant with injected effects, and write the "
                       "measured log (instrument noise added). Each cycle starts where the previous one "
                       "settled unless --relaxed.")
    p.add_argument("protocol", metavar="PROTOCOL.csv", help="the protocol to run")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[=SEVERITY]",
                   help=f"inject an effect (repeatable; severity 1 = typical, default 1): one of {', '.join(KNOWN)}")
    p.add_argument("--plant", choices=TESTBED_PLANTS, default="quasi-static",
                   help="the toolkit's quasi-static plant (default) or MuJoCo with the effects in the engine model")
    p.add_argument("--seed", type=int_in(0, 2 ** 32 - 1), default=0, help="seed of the effect draws and noise")
    p.add_argument("--noise", choices=("paper", "none"), default="paper",
                   help="instrument noise: the paper's F/T and tracker (default) or none")
    p.add_argument("--relaxed", action="store_true", help="start every cycle relaxed (friction state reset)")
    p.add_argument("--loading", choices=("ramp", "step"), default="ramp",
                   help="how each row's load reaches the rig: ramped slowly (default) or hung at once and settled "
                        "by the rig's own dynamics, as a lab hangs a weight (MuJoCo: its damping; quasi-static: an "
                        "overdamped path stopped where static friction holds it)")
    p.add_argument("--static-friction-ratio", type=float, default=1.0, metavar="RATIO",
                   help="static over sliding friction, >= 1 (default 1: one bound; above 1 on the quasi-static "
                        "plant with --loading step)")
    p.add_argument("--after", metavar="LOG.csv", default=None,
                   help="a log run just before on the same plant (same --effect and --seed): the protocol "
                   "starts from the state where it settled")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
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
        if name in TESTBED_DEPRECATED:
            print(f"csjm simulate: warning: --effect {name} is now called {TESTBED_DEPRECATED[name]}; the old name "
                  "will go", file=sys.stderr)
            name = TESTBED_DEPRECATED[name]
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


def truth(plant, rig=None) -> dict:
    """The injected parameters of a plant that differ from the nominal one (JSON-ready).

    Effects that change the rig itself (``hole_offsets``, ``mass_com``, ``stiffness_scale``) are
    reported against ``rig``, the nominal rig: the true holes and their offsets (m), mass (kg) and
    centre of mass (m, in {A}), and the cable stiffness (N/m) with its factor.

    Parameters
    ----------
    plant : TestbedPlant or MujocoPlant
    rig : Rig, optional
        The nominal rig (default: the plant's own rig, so no rig differences).

    Returns
    -------
    dict
    """
    from ..testbed.plant import TestbedPlant

    p: TestbedPlant = plant if isinstance(plant, TestbedPlant) else plant.plant
    nominal = TestbedPlant.nominal(p.rig)
    out: dict = {}
    for name in ("hardening_per_m", "friction_mu_beta", "friction_coulomb_N", "joint_friction_Nm",
                 "link_compliance_rad_per_Nm", "sensor_bias_A_Nm", "tracker_rotation_B", "guide_radius_m",
                 "sensor_drift_A_Nm_per_row", "drum_slip_compliance_m_per_N"):
        if not hasattr(p, name):
            continue
        v, v0 = np.asarray(getattr(p, name), float), np.asarray(getattr(nominal, name), float)
        if v.shape != v0.shape or not np.allclose(v, v0, rtol=0, atol=0):
            out[name] = v.tolist()
    if rig is not None:
        true, nom = p.rig, rig
        dA = np.asarray(true.platform_holes_A_m) - np.asarray(nom.platform_holes_A_m)
        dB = np.asarray(true.base_holes_B_m) - np.asarray(nom.base_holes_B_m)
        if np.any(dA != 0) or np.any(dB != 0):
            out["hole_offsets"] = {"platform_holes_A_m": np.asarray(true.platform_holes_A_m).tolist(),
                                   "base_holes_B_m": np.asarray(true.base_holes_B_m).tolist(),
                                   "dA_m": dA.tolist(), "dB_m": dB.tolist()}
        if true.platform_mass_kg != nom.platform_mass_kg or np.any(np.asarray(true.com_A_m) != np.asarray(nom.com_A_m)):
            out["mass_com"] = {"mass_kg": true.platform_mass_kg, "com_A_m": np.asarray(true.com_A_m).tolist(),
                               "mass_ratio": true.platform_mass_kg / nom.platform_mass_kg,
                               "com_shift_A_m": (np.asarray(true.com_A_m) - np.asarray(nom.com_A_m)).tolist()}
        k, k0 = np.asarray(true.cable_stiffness_N_per_m), np.asarray(nom.cable_stiffness_N_per_m)
        if np.any(k != k0):
            out["stiffness_scale"] = {"cable_stiffness_N_per_m": k.tolist(), "factor": (k / k0).tolist()}
    return out


class _LazyBar:
    """A tqdm bar opened at the first row simulated: a protocol refused before any row prints one line only."""

    def __init__(self, **options):
        self.options, self.bar = options, None

    def update(self, n: int = 1) -> None:
        if self.bar is None:
            from tqdm import tqdm

            self.bar = tqdm(**self.options)
        self.bar.update(n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


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
    from ..measurement.instruments import InstrumentNoise
    from ..measurement.logfile import MeasurementLog
    from ..model.rig import load_rig
    from ..testbed.injection import inject, make_plant
    from ..testbed.log_protocol import LogProtocol, read_protocol, simulate_protocol

    check_outputs([args.rig, args.protocol, args.after], {"-o/--out": args.out, "--json": args.json})
    effects = parse_effects(args.effect)
    rig = load_rig(args.rig)
    proto = read_protocol(args.protocol)
    rng = np.random.default_rng(args.seed)
    plant = make_plant(rig, None, 1.0, rng, plant=args.plant, persistent=not args.relaxed, loading=args.loading,
                       static_friction_ratio=args.static_friction_ratio)
    for name, severity in effects:
        plant = inject(plant, name, severity, rng)
    noise = InstrumentNoise.paper() if args.noise == "paper" else InstrumentNoise.none()
    t0 = time.perf_counter()
    after = MeasurementLog.from_csv(args.after).check_cables(rig.n_cables, args.rig or "paper") if args.after \
        else None
    # an identification protocol settles its dead weights in a few passes over the rows: no known total
    total = len(proto) + (len(after) if after is not None else 0) if isinstance(proto, LogProtocol) else None
    bar = _LazyBar(total=total, file=sys.stderr, unit="row", desc=f"simulate ({args.plant})",
                   disable=args.no_progress, mininterval=0.5 if sys.stderr.isatty() else 5.0)
    try:
        log = simulate_protocol(rig, proto, plant, rng=rng, noise=noise, persistent=not args.relaxed, after=after,
                                progress=bar.update)
    finally:
        bar.close()
    seconds = time.perf_counter() - t0
    path = atomic_write_text(args.out, log.to_text())
    summary = {"output": str(path), "protocol": str(args.protocol), "rows": len(log), "cycles": len(log.cycle_ids),
               "plant": args.plant, "persistent": not args.relaxed, "loading": args.loading,
               "static_friction_ratio": args.static_friction_ratio, "noise": args.noise, "seed": args.seed,
               "effects": [{"name": n, "severity": s} for n, s in effects], "truth": truth(plant, rig),
               "seconds": seconds}
    if args.json:
        atomic_write_json(args.json, summary)
    if args.json != "-":
        names = ", ".join(f"{n}={s:g}" for n, s in effects) or "none"
        print(f"wrote {path}: {len(log)} rows in {len(log.cycle_ids)} cycles on the {args.plant} plant "
              f"(effects: {names}; {seconds:.1f} s)")
    return 0
