"""Log reading speed and memory: ``MeasurementLog.from_csv`` against numpy.loadtxt and the csv module.

Run: ``python benchmarks/bench_logread.py [--mb 1 20 200] [--repeat 3]``

Writes logs of the given sizes to a temporary folder (never committed): rows
as ``MeasurementLog.to_text`` writes them (17-digit ``repr`` numbers, unique
sample ids, 20-row cycles), half of them with a ``note`` column. For each size
it prints the median wall time over ``--repeat`` runs, the rate in MB/s, the
ratio to numpy.loadtxt and the median CPU time (the box is shared) of

* ``from_csv``: the package's reader (all checks: header, every cell, bounds,
  unique ids, consecutive cycles; errors naming line and column);
* ``numpy.loadtxt``: the baseline of the same run, numbers only, no checks
  (its C parser, numpy >= 1.23);
* ``csv + float``: the csv module with ``float`` per cell, no checks (sizes up
  to ``--slow-mb``);
* ``strict``: the package's row-by-row reader, the only path before the
  compiled one (sizes up to ``--slow-mb``);

and the peak memory of ``from_csv`` in a fresh process, as a multiple of the
file size: the rise of its peak resident set over the reading (``VmHWM`` after
a reset through ``/proc/self/clear_refs``, Linux) and the peak of
``tracemalloc`` (Python and numpy allocations).
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from csjm_opt.measurement._log_reader import COLUMNS, read_log_strict
from csjm_opt.measurement.logfile import MeasurementLog

ROOT = Path(__file__).resolve().parents[1]
BLOCK_ROWS = 20_000


def write_log(path: Path, megabytes: float, note: bool, seed: int = 0) -> int:
    """A log of about ``megabytes`` MB; returns its size in bytes."""
    rng = np.random.default_rng(seed)
    V = np.hstack([0.1 + 0.1 * rng.random((BLOCK_ROWS, 6)), rng.normal(size=(BLOCK_ROWS, 3)),
                   rng.normal(size=(BLOCK_ROWS, 3)) * 0.1])
    bodies = [",".join(map(repr, row)) + (",ok" if note else "") for row in V.tolist()]
    size, i = 0, 0
    with open(path, "w", newline="\n") as f:
        f.write(",".join(COLUMNS) + (",note" if note else "") + "\n")
        while size < megabytes * 1e6:
            rows = min(BLOCK_ROWS, max(1, int((megabytes * 1e6 - size) / (len(bodies[0]) + 12))))
            chunk = "".join(f"{i + k},{(i + k) // 20},{bodies[k]}\n" for k in range(rows))
            f.write(chunk)
            size += len(chunk)
            i += rows
    return path.stat().st_size


def median_time(fn, repeat: int) -> tuple[float, float]:
    """Median wall and CPU seconds of ``fn()``."""
    times = []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        times.append((time.perf_counter() - t0, time.process_time() - c0))
    wall, cpu = np.median(np.array(times), axis=0)
    return float(wall), float(cpu)


def csv_float(path: Path) -> None:
    with open(path, newline="") as f:
        reader = csv.reader(f)
        next(reader)
        [[float(c) for c in row[:14]] for row in reader]


_PEAK = """
import json, sys, tracemalloc
from csjm_opt.measurement.logfile import MeasurementLog
MeasurementLog.from_text("{header}\\n0,0,0.1,0.1,0.1,0.1,0.1,0.1,0,0,0,0,0,0\\n")   # load the compiled code

def status(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1]) * 1024

with open("/proc/self/clear_refs", "w") as f:
    f.write("5")                         # the peak resident set starts again from the current one
before = status("VmRSS:")
tracemalloc.start()
log = MeasurementLog.from_csv(sys.argv[1])
traced = tracemalloc.get_traced_memory()[1]
tracemalloc.stop()
print(json.dumps([status("VmHWM:") - before, traced]))
"""


def peak_ratios(path: Path, size: int) -> tuple[float, float]:
    """Rise of the peak resident set, and the tracemalloc peak, over ``from_csv`` in a fresh process,
    per byte of the file (Linux: needs ``/proc/self/clear_refs``)."""
    code = _PEAK.format(header=",".join(COLUMNS))
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True,
                         cwd=ROOT)
    rss, traced = json.loads(out.stdout)
    return rss / size, traced / size


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mb", type=float, nargs="+", default=[1, 20, 200])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--slow-mb", type=float, default=20, help="largest size for the csv and strict readers")
    args = ap.parse_args()
    MeasurementLog.from_text(",".join(COLUMNS) + "\n0,0,0.1,0.1,0.1,0.1,0.1,0.1,0,0,0,0,0,0\n")  # compile
    print(f"{'size':>8s} {'note':>5s} {'reader':<14s} {'median s':>9s} {'MB/s':>8s} {'vs loadtxt':>11s} "
          f"{'CPU s':>7s} {'MB/CPU s':>9s}")
    with tempfile.TemporaryDirectory() as tmp:
        for mb in args.mb:
            for note in (False, True):
                path = Path(tmp) / f"log_{mb:g}_{int(note)}.csv"
                size = write_log(path, mb, note)
                MB = size / 1e6
                times = {"from_csv": median_time(lambda p=path: MeasurementLog.from_csv(p), args.repeat),
                         "numpy.loadtxt": median_time(lambda p=path: np.loadtxt(
                             p, delimiter=",", skiprows=1, usecols=range(14), comments=None), args.repeat)}
                if mb <= args.slow_mb:
                    times["csv + float"] = median_time(lambda p=path: csv_float(p), args.repeat)
                    times["strict"] = median_time(lambda p=path: read_log_strict(p.read_text(), str(p)),
                                                  args.repeat)
                for name, (t, cpu) in times.items():
                    print(f"{MB:7.1f}M {'yes' if note else 'no':>5s} {name:<14s} {t:9.3f} {MB / t:8.1f} "
                          f"{times['numpy.loadtxt'][0] / t:10.2f}x {cpu:7.3f} {MB / cpu:9.1f}", flush=True)
                rss, traced = peak_ratios(path, size)
                print(f"{'':>8s} {'':>5s} peak memory of from_csv: {rss:.2f} x the file size (resident set), "
                      f"{traced:.2f} x (tracemalloc)", flush=True)
                path.unlink()


if __name__ == "__main__":
    main()
