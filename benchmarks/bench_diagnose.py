"""Diagnosis speed: 200-row logs, the whole vocabulary and the pair search (target: under 5 s on 2 cores),
and ``--suggest 60`` on an ambiguous log (target: under 60 s).

Run: python benchmarks/bench_diagnose.py [--cycles 22] [--repeat 1] [--workers N] [--baseline DIR]
[--cases coulomb_friction ...] [--validation FOLDER/CASE ...] [--commands FOLDER ...] [--no-progress]

``--validation FOLDER/CASE`` times the standard command's diagnosis of a case of a validation folder
(``answers.json``: its train and test logs and rig; e.g. ``mujoco_b/b1_tendon_friction``, 132 + 88
rows), beside the baseline checkout's on the same files when ``--baseline`` is given (verdicts compared), and
the whole standard command ``csjm diagnose TRAIN --rig RIG --test TEST`` in a new process (start, reading the
logs, diagnosis, report) on ``--workers``: what a lab waits for. ``--commands FOLDER ...`` times that command
on every case of validation folders, each case beside the baseline's.

Prints wall and CPU time (the box may be shared: CPU seconds of this process are what
a 2-core machine of one's own would spend, wall time what it took here). The full diagnosis
runs twice: on one core (``workers=1``, wall = CPU on a quiet box) and on ``--workers``
processes (default: the machine's cores; the CPU time of the workers is not this process's,
so only wall time is printed there). Baselines measured in the same run: the singles-only
diagnosis (``secondary=False``) on the same log; with ``--baseline DIR``, the diagnosis of
another checkout of the package (e.g. the previous release) on the same log, in a subprocess, on one
core and on the workers, repeats interleaved with this code's (the ratio old / new of medians). The work
of each one-core diagnosis is counted too, as the rows taken through the moment balance: a count that a
shared machine's load does not move (its seconds drift by 1.3-1.5x between identical runs). And one candidate fitted
the direct way, ``scipy.optimize.least_squares`` on *forward-statics* pose residuals (a full
equilibrium solve of every row at every evaluation), against the linearised fit the package uses.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import resource
import subprocess
import sys
import time
from functools import partial

import numpy as np
from scipy.optimize import least_squares
from tqdm import tqdm

import csjm_opt as co
from csjm_opt.diagnose import diagnose
from csjm_opt.diagnose.data.residuals import compute_residuals, pose_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.diagnose.suggest.experiment import suggest_experiment
from csjm_opt.testbed import simulate_experiment


def forward_fit(model: AugmentedModel, table) -> tuple[np.ndarray, float]:
    """The direct way: least squares on forward-statics residuals (numerical Jacobian)."""
    scales = model.scales

    def res(x):
        sol = model.predict_poses(table.rows, x * scales, table.R_meas)
        z = pose_residuals(sol.R, table.R_meas)
        return np.einsum("nij,nj->ni", table.whiten, z).ravel()

    t0 = time.perf_counter()
    sol = least_squares(res, model.x0() / scales, method="trf", xtol=1e-10, ftol=1e-10)
    return sol.x * scales, time.perf_counter() - t0


def timed(fn) -> tuple[object, float, float]:
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


@contextlib.contextmanager
def counting_rows():
    """Count the rows taken through the moment balance in this process (as the baseline script does)."""
    count = [0]
    evaluate = AugmentedModel.evaluate

    def counted(self, R_m, *args, **kwargs):
        count[0] += len(R_m)
        return evaluate(self, R_m, *args, **kwargs)

    AugmentedModel.evaluate = counted
    try:
        yield count
    finally:
        AugmentedModel.evaluate = evaluate


def children_cpu() -> float:
    """CPU seconds of this process's finished child processes (the diagnosis's workers)."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


BASELINE = """
import json, sys, time
import numpy as np
import csjm_opt as co
from csjm_opt.diagnose import diagnose
from csjm_opt.testbed import simulate_experiment
effect = json.loads(sys.argv[1])
if isinstance(effect, dict):     # a validation case: its files
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.model.rig import load_rig
    rig = load_rig(effect["rig"])
    log, test = MeasurementLog.from_csv(effect["train"]), MeasurementLog.from_csv(effect["test"])
else:
    rig = co.paper_rig()
    log = simulate_experiment(rig, int(sys.argv[2]), np.random.default_rng(0), effect=effect)
    test = None
# the work done, counted where it is done on one core: rows through the moment balance (AugmentedModel.evaluate,
# present in every version timed so far); a forked worker's count stays in the worker
rows_evaluated = [0]
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
_evaluate = AugmentedModel.evaluate
def _counted(self, R_m, *args, **kwargs):
    rows_evaluated[0] += len(R_m)
    return _evaluate(self, R_m, *args, **kwargs)
AugmentedModel.evaluate = _counted
t0, c0 = time.perf_counter(), time.process_time()
d = diagnose(rig, log, test, workers=int(sys.argv[3]) if len(sys.argv) > 3 else None)
j = d.as_json()   # the JSON keys hold across versions (the objects behind them may not)
print(json.dumps([time.perf_counter() - t0, time.process_time() - c0, j["selected"], j["secondary"]["effect"],
                  rows_evaluated[0]]))
"""


def baseline_run(tree: str, effect, cycles: int, workers: int | None = None) -> tuple[float, float, str, int]:
    """Wall and CPU seconds of the diagnosis of the checkout ``tree`` on the same log, its verdict, and its work.

    ``effect``: the injected effect(s) of a simulated log, or a validation case's files
    (``{"train", "test", "rig"}``); ``workers``: the diagnosis's worker processes (default: the cores).
    The work is the number of rows taken through the moment balance in this process (all of them with
    ``workers=1``): a count that the load of a shared machine does not move, where seconds drift by
    1.3-1.5x between identical runs minutes apart.
    """
    env = {**os.environ, "PYTHONPATH": tree}
    extra = [] if workers is None else [str(workers)]
    out = subprocess.run([sys.executable, "-c", BASELINE, json.dumps(effect), str(cycles), *extra], env=env,
                         capture_output=True, text=True, check=True, cwd=tree)
    wall, cpu, sel, sec, rows = json.loads(out.stdout.strip().splitlines()[-1])
    return wall, cpu, f"{sel} + {sec}", int(rows)


#: This checkout (the code timed against ``--baseline``).
HERE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def case_files(folder: str, answer: dict) -> dict[str, str]:
    """A validation case's files (``answers.json`` entry ``answer`` in ``folder``): train and test logs, rig."""
    return {k: os.path.join(folder, answer[k]) for k in ("train", "test", "rig")}


def command_run(tree: str, files: dict, workers: int | None) -> float:
    """Wall seconds of the whole standard command in the checkout ``tree``: start, reading, diagnosis, report."""
    env = {**os.environ, "PYTHONPATH": tree}
    cmd = [sys.executable, "-m", "csjm_opt.cli", "diagnose", files["train"], "--rig", files["rig"], "--test",
           files["test"], "--no-progress"] + ([] if workers is None else ["--workers", str(workers)])
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, capture_output=True, text=True, check=True, cwd=tree)
    return time.perf_counter() - t0


def command_sweep(folder: str, args) -> None:
    """The whole standard command on every case of a validation folder, each beside the baseline's (interleaved).

    One run per case and checkout, on ``--workers`` (wall seconds of a new process each): the median over the
    folder, the median of the per-case ratios, the slowest case, and how many cases finish within 5 s.
    """
    folder = os.path.abspath(folder)
    answers = json.load(open(os.path.join(folder, "answers.json")))
    new, old = [], []
    for case, a in tqdm(answers.items(), desc=os.path.basename(folder), disable=args.no_progress, file=sys.stderr,
                        leave=False):
        files = case_files(folder, a)
        if args.baseline is not None:
            old.append(command_run(args.baseline, files, args.workers))
        new.append((command_run(HERE, files, args.workers), case))
    secs = [t for t, _ in new]
    slow = max(new)
    line = (f"{os.path.basename(folder)}: the whole command on {args.workers or 'all'} cores, {len(new)} cases: "
            f"median {np.median(secs):.1f} s, slowest {slow[0]:.1f} s ({slow[1]}), within 5 s "
            f"{sum(t <= 5.0 for t in secs)}/{len(secs)} (load average {os.getloadavg()[0]:.1f})")
    if old:
        line += (f"; baseline {args.baseline}: median {np.median(old):.1f} s, per-case ratio old / new "
                 f"{np.median([o / t for o, t in zip(old, secs)]):.2f}x (median)")
    print(line)


def validation_case(spec: str, args) -> None:
    """Time the diagnosis of one validation case (both logs, its rig) here and in the baseline checkout.

    Each repeat runs the baseline (a subprocess: the checkout's code) and this code (a subprocess of
    this checkout, the same way) interleaved, on one core (``workers=1``: CPU time is what a quiet core
    would spend) and on ``--workers`` processes (wall time); medians over the repeats.
    """
    folder, case = os.path.split(os.path.abspath(spec))
    answers = json.load(open(os.path.join(folder, "answers.json")))[case]
    files = case_files(folder, answers)
    runs: dict[str, list] = {"new 1": [], "new N": [], "old 1": [], "old N": []}
    commands: dict[str, list] = {"new": [], "old": []}
    for tree in (args.baseline, HERE):       # warm-up: compiled kernels cached, files read once (not timed)
        if tree is not None:
            baseline_run(tree, files, 0, 1)
    for _ in tqdm(range(args.repeat), desc=f"{case}", disable=args.no_progress, file=sys.stderr, leave=False):
        for tag, tree in (("old", args.baseline), ("new", HERE)):
            if tree is None:
                continue
            runs[f"{tag} 1"].append(baseline_run(tree, files, 0, 1))
            runs[f"{tag} N"].append(baseline_run(tree, files, 0, args.workers))
            commands[tag].append(command_run(tree, files, args.workers))
    med = {k: np.median([r[:2] for r in v], axis=0) for k, v in runs.items() if v}
    work = {k: int(np.median([r[3] for r in v])) for k, v in runs.items() if v and k.endswith(" 1")}
    n_rows = sum(1 for k in ("train", "test") for _ in open(files[k])) - 2
    print(f"{case} ({n_rows} rows, load average {os.getloadavg()[0]:.1f}): one core {med['new 1'][0]:.1f} s wall / "
          f"{med['new 1'][1]:.1f} s CPU ({work['new 1']:,} rows through the balance), on {args.workers or 'all'} "
          f"cores {med['new N'][0]:.1f} s wall (target < 5 s on 2 cores) -> {runs['new 1'][-1][2]}; "
          f"the whole command (start, reading, report) {np.median(commands['new']):.1f} s wall"
          + (f" against the baseline's {np.median(commands['old']):.1f} s "
             f"({np.median(commands['old']) / np.median(commands['new']):.2f}x)" if commands["old"] else ""))
    if "old 1" in med:
        same = {r[2] for r in runs["old 1"] + runs["new 1"] + runs["old N"] + runs["new N"]}
        print(f"  baseline {args.baseline}: one core {med['old 1'][0]:.1f} s wall / {med['old 1'][1]:.1f} s CPU, "
              f"on {args.workers or 'all'} cores {med['old N'][0]:.1f} s wall -> {runs['old 1'][-1][2]}; "
              f"{work['old 1']:,} rows through the balance; ratio old / new {med['old 1'][1] / med['new 1'][1]:.2f}x "
              f"CPU on one core ({work['old 1'] / max(work['new 1'], 1):.2f}x rows), "
              f"{med['old N'][0] / med['new N'][0]:.2f}x wall on all cores; verdicts "
              f"{'the same' if len(same) == 1 else 'DIFFER: ' + ', '.join(sorted(same))}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=int, default=22, help="9 rows per cycle (22 -> 198 rows)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--workers", type=int, default=None, help="worker processes (default: the cores)")
    ap.add_argument("--baseline", default=None, help="another checkout of the package to time on the same logs")
    ap.add_argument("--cases", nargs="*", default=["none", "friction+sensor_bias", "coulomb_friction", "hole_offsets"])
    ap.add_argument("--validation", nargs="+", default=[], metavar="FOLDER/CASE",
                    help="validation cases to time (a folder with answers.json, slash, the case's name)")
    ap.add_argument("--commands", nargs="+", default=[], metavar="FOLDER",
                    help="validation folders: the whole standard command on every case, beside the baseline's")
    ap.add_argument("--no-progress", action="store_true")
    ap.add_argument("--no-extras", action="store_true", help="only the diagnosis cases (no --suggest, no direct fit)")
    args = ap.parse_args()
    bar = None if args.no_progress else partial(tqdm, file=sys.stderr, leave=False)
    for spec in args.validation:
        validation_case(spec, args)
    for folder in args.commands:
        command_sweep(folder, args)
    rig = co.paper_rig()
    for case in args.cases:
        effect = case.split("+") if "+" in case else case
        log = simulate_experiment(rig, args.cycles, np.random.default_rng(0), effect=effect)
        full, par, single, old, old_n = [], [], [], [], []
        for _ in range(args.repeat):
            with counting_rows() as rows_new:
                d, wall, cpu = timed(lambda log=log: diagnose(rig, log, progress=bar, workers=1))
            full.append((wall, cpu, rows_new[0]))
            k0 = children_cpu()
            dp, wall_p, cpu_p = timed(lambda log=log: diagnose(rig, log, progress=bar, workers=args.workers))
            par.append((wall_p, cpu_p + children_cpu() - k0))
            if dp.as_json() != d.as_json():
                print(f"  {case}: the diagnosis on workers differs from the serial one", file=sys.stderr)
            _, wall1, cpu1 = timed(lambda log=log: diagnose(rig, log, secondary=False, workers=1))
            single.append((wall1, cpu1))
            if args.baseline:        # on one core (CPU and work, as ``full``) and on the workers (wall, as ``par``)
                old.append(baseline_run(args.baseline, effect, args.cycles, 1))
                old_n.append(baseline_run(args.baseline, effect, args.cycles, args.workers))
        j = d.as_json()
        fw, fc, fr = np.median(full, axis=0)
        sw, sc = np.median(single, axis=0)
        pw, pc = np.median(par, axis=0)
        print(f"{len(log)} rows, injected {case}: singles + pairs on one core {fw:.1f} s wall / {fc:.1f} s CPU "
              f"({fr:,.0f} rows through the balance), "
              f"on {args.workers or 'all'} cores {pw:.1f} s wall / {pc:.1f} s CPU with the workers' "
              f"(target < 5 s on 2 cores; load average {os.getloadavg()[0]:.1f}); singles only "
              f"{sw:.1f} s wall / {sc:.1f} s CPU -> selected {j['selected']} + {j['secondary']['effect']}, "
              f"gap {1e3 * j['gap']['before_rad']:.2f} -> {1e3 * j['gap']['after_rad']:.2f} mrad")
        if old:
            oc, orows = np.median([o[1] for o in old]), np.median([o[3] for o in old])
            ow = np.median([o[0] for o in old_n])
            print(f"  baseline {args.baseline}: one core {oc:.1f} s CPU ({orows:,.0f} rows), on "
                  f"{args.workers or 'all'} cores {ow:.1f} s wall -> {old[-1][2]}; ratio old / new {oc / fc:.2f}x "
                  f"CPU on one core ({orows / max(fr, 1):.2f}x rows), {ow / pw:.2f}x wall on all cores")
    if args.no_extras:
        return 0

    log_s = simulate_experiment(rig, 12, np.random.default_rng(2), effect=["tracker_registration", "sensor_bias"])
    d = diagnose(rig, log_s)
    s, wall, cpu = timed(lambda: suggest_experiment(rig, d, 60, progress=bar))
    sj = s.as_json() if s is not None else {}
    print(f"--suggest 60 after {d.selected} + {d.secondary.effect} on {len(log_s)} rows: {wall:.1f} s wall / "
          f"{cpu:.1f} s CPU (target < 60 s) -> {sj.get('rows', 0)} rows, smallest expected separation "
          f"{sj.get('smallest_expected_separation_sd') or 0:.1f} noise sd")

    log_b = simulate_experiment(rig, args.cycles, np.random.default_rng(1), effect="sensor_bias")
    table = compute_residuals(rig, log_b)
    model = AugmentedModel(rig, [make_effect("sensor_bias", rig)])
    lin, t_lin, _ = timed(lambda: fit_model(model, table))
    theta_fwd, t_fwd = forward_fit(model, table)
    print(f"one candidate fit (sensor_bias log, {len(log_b)} rows): linearised {t_lin:.2f} s, "
          f"forward-statics residuals {t_fwd:.2f} s, ratio {t_fwd / t_lin:.1f}x; max parameter difference "
          f"{np.abs(lin.theta - theta_fwd).max():.2g} (bias sd {lin.stderr[1:].max():.2g} N m)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
