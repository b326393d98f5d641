"""Benchmark: ``csjm identify`` on a large log is linear in its size.

Builds logs of growing size (``--mb``, default 1, 5, 20 and 200 MB) from
simulated, noisy load cycles of the paper rig (20 rows per cycle, the cycles
repeated with fresh noise and new ids), writes them to a temporary folder
(never committed) and times what ``csjm identify LOG --json OUT`` does:
reading and validating the CSV, identifying every cycle, writing the JSON.
Prints the time per size, the time per MB, and the ratio of time per MB at
the largest and the smallest size (1.0 = linear; the old per-cycle pose
recomputation made it grow with the size). The baseline of the same run is
the old method on the smallest log: poses recomputed for the whole log once
per cycle (``log.R[rows]``).

Run: ``python benchmarks/bench_identify_large.py [--mb 1 5 20 200]``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from csjm_opt import cli, paper_rig  # noqa: E402
from csjm_opt.identification.identify_pose import identify_stiffness  # noqa: E402
from csjm_opt.identification.log_identification import identify_cycles  # noqa: E402
from csjm_opt.measurement.instruments import InstrumentNoise  # noqa: E402
from csjm_opt.measurement.logfile import MeasurementLog  # noqa: E402
from csjm_opt.model.numeric import Model  # noqa: E402
from csjm_opt.testbed.scripted import add_noise, load_directions, simulate_log

ROWS_PER_CYCLE = 20


def template(rig, model) -> MeasurementLog:
    rng = np.random.default_rng(0)
    cycles = [(rng.normal(size=3) * 0.1, rng.normal(size=3) * 0.3, load_directions(ROWS_PER_CYCLE - 1, rng) * 1.5)
              for _ in range(4)]
    log, _ = simulate_log(rig, cycles, model)
    return log


def big_log_text(log: MeasurementLog, megabytes: float, rng: np.random.Generator) -> str:
    """Copies of ``log``'s cycles with fresh instrument noise and new ids until ``megabytes`` is reached."""
    noise = InstrumentNoise.paper()
    header, chunks, size, copy = None, [], 0, 0
    while size < megabytes * 1e6:
        noisy = add_noise(log, noise, rng)
        n = len(noisy)
        part = MeasurementLog.from_arrays(noisy.cycle + copy * 1000, noisy.rest_lengths_m, noisy.tau_ext_A_Nm,
                                          noisy.R, sample=np.arange(n) + copy * n)
        text = part.to_text()
        head, body = text.split("\n", 1)
        header = header or head
        chunks.append(body)
        size += len(body)
        copy += 1
    return header + "\n" + "".join(chunks)


def time_cli(path: Path, out: Path) -> float:
    t0 = time.perf_counter()
    with open(os.devnull, "w") as sink, contextlib.redirect_stdout(sink):
        code = cli.main(["identify", str(path), "--json", str(out), "--no-progress"])
    assert code == 0
    return time.perf_counter() - t0


def old_method(log: MeasurementLog, model: Model) -> float:
    """The former loop: ``log.R`` (every row of the log) recomputed once per cycle."""
    t0 = time.perf_counter()
    for c in log.cycle_ids:
        rows = log.cycle_rows(c)
        identify_stiffness(log.R[rows], log.tau_ext_A_Nm[rows], model, cycle=c)
    return time.perf_counter() - t0


def new_method(log: MeasurementLog, rig, model: Model) -> float:
    t0 = time.perf_counter()
    identify_cycles(log, rig, model)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mb", nargs="+", type=float, default=[1, 5, 20, 200])
    args = parser.parse_args()
    rig = paper_rig()
    model = Model(rig)
    base = template(rig, model)
    rng = np.random.default_rng(1)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for mb in args.mb:
            path = Path(tmp) / f"log_{mb:g}MB.csv"
            path.write_text(big_log_text(base, mb, rng))
            size = path.stat().st_size / 1e6
            t = time_cli(path, Path(tmp) / "out.json")
            rows.append((size, t))
            print(f"{size:8.1f} MB: identify {t:7.2f} s ({t / size:.3f} s/MB)", flush=True)
            if mb == args.mb[0]:
                log = MeasurementLog.from_csv(path)
                t_old = old_method(log, model)
                t_new = new_method(log, rig, model)
                print(f"          identification only: old per-cycle loop {t_old:.2f} s, identify_cycles "
                      f"{t_new:.2f} s (ratio {t_old / t_new:.1f}x)")
    (s0, t0), (s1, t1) = rows[0], rows[-1]
    print(f"time per MB, largest / smallest log: {(t1 / s1) / (t0 / s0):.2f} (1.0 = linear)")


if __name__ == "__main__":
    main()
