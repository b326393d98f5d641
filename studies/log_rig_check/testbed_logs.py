"""The log-vs-rig check on the project's own testbed logs: every effect at its largest plausible size.

Usage: python -m studies.log_rig_check.testbed_logs [--rigs 3] [--cycles 3]

Simulates, on the paper rig and on ``--rigs`` random rigs (the quasi-static plant, the paper's
instrument noise), a log per effect of the vocabulary (and Coulomb friction) at severity 1, 3 and
its plausible maximum (:data:`csjm_opt.testbed.injection.PLAUSIBLE_SEVERITY`), and checks each
against its own rig. Prints the median per-cable tension error over the tolerance per log; the
check must accept them all (an unmodelled effect is not another rig).
"""

from __future__ import annotations

import argparse

import numpy as np

from csjm_opt.errors import CsjmError
from csjm_opt.measurement.rig_fit import log_rig_fit
from csjm_opt.model.rig import paper_rig
from csjm_opt.testbed import random_rig, simulate_experiment
from csjm_opt.testbed.injection import PLAUSIBLE_SEVERITY


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rigs", type=int, default=3)
    ap.add_argument("--cycles", type=int, default=3)
    a = ap.parse_args(argv)
    rigs = [("paper", paper_rig())] + [(f"random {i}", random_rig(np.random.default_rng(i))[0])
                                       for i in range(a.rigs)]
    worst, refused, n = 0.0, [], 0
    for rig_name, rig in rigs:
        for effect, top in PLAUSIBLE_SEVERITY.items():
            for severity in sorted({1.0, 3.0, top}):
                if severity > top:
                    continue
                try:
                    log = simulate_experiment(rig, a.cycles, np.random.default_rng(n), effect=effect,
                                              severity=severity)
                except CsjmError as exc:          # the plant cannot hold this draw: not a log
                    print(f"{rig_name:9s} {effect:22s} x{severity:<5g} (no log: {str(exc)[:60]})")
                    continue
                n += 1
                fit = log_rig_fit(rig, log)
                share = fit.median_N / fit.tolerance_N
                worst = max(worst, share)
                if not fit.ok:
                    refused.append((rig_name, effect, severity))
                print(f"{rig_name:9s} {effect:22s} x{severity:<5g} median {fit.median_N:6.2f} N of "
                      f"{fit.tolerance_N:5.2f} N ({share:4.0%}); stiffness factor {fit.stiffness_factor:.2f}")
    print(f"{n} logs, refused {len(refused)} {refused}; worst median / tolerance {worst:.2f}")
    return 1 if refused else 0


if __name__ == "__main__":
    raise SystemExit(main())
