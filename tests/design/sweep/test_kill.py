"""A sweep killed by any signal resumes to the same results, with no process or lock left behind.

Each case starts ``csjm sweep`` with two workers in a subprocess, waits for
the first results, sends SIGKILL or SIGTERM to the main process only, checks
that every process it started is gone within 5 s, then resumes in-process
without any clean-up and compares with an uninterrupted serial run.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from csjm_opt.design.sweep.runner import TIMING_KEYS, run_sweep
from csjm_opt.design.sweep.spec import SweepSpec

SWEEP = """
[sweep]
method = "grid"
[parameters.platform_d23_m]
min = 0.07
max = 0.12
num = 12
[parameters.oo_b_m]
values = [0.07, 0.09]
[sampling]
orientations = 600
max_tilt_deg = 40.0
[loads]
tau_ext = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]
[metrics]
shaping_poses = 1
"""


def _descendants(pid: int) -> list[int]:
    parent = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parent[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    out, frontier = [], [pid]
    while frontier:
        kids = [p for p, pp in parent.items() if pp in frontier]
        out += kids
        frontier = kids
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _comparable(records: list[dict]) -> dict[str, dict]:
    return {r["id"]: {k: v for k, v in r.items() if k not in TIMING_KEYS and k != "metrics"}
            | {"metrics": {k: v for k, v in (r["metrics"] or {}).items() if k not in TIMING_KEYS}}
            for r in records}


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="uses /proc")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_killed_sweep_resumes_without_cleanup(tmp_path, sig):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SWEEP)
    out = tmp_path / "results.jsonl"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[3])}
    workers: list[int] = []
    proc = subprocess.Popen([sys.executable, "-m", "csjm_opt.cli", "sweep", str(sweep), "--out", str(out),
                             "--workers", "2", "--no-progress"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        while not (out.exists() and out.read_bytes().count(b"\n") >= 2):
            assert proc.poll() is None, "sweep ended before it could be killed"
            assert time.monotonic() < deadline
            time.sleep(0.02)
        workers = _descendants(proc.pid)   # fork server, its workers, resource tracker
        assert len(workers) >= 2, "expected worker processes"
        proc.send_signal(sig)
        proc.wait(timeout=10)
    finally:
        if proc.poll() is None:
            proc.kill()
    deadline = time.monotonic() + 5
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    survivors = [w for w in workers if _alive(w)]
    for w in survivors:  # do not leave them running when the check fails
        os.kill(w, signal.SIGKILL)
    assert not survivors, "workers outlived the killed sweep"
    done = out.read_bytes().count(b"\n")
    spec = SweepSpec.from_toml(sweep)
    assert done < len(spec.designs()), "killed too late to test resumption"

    resumed = run_sweep(spec, out, workers=2, progress=False)   # no manual clean-up
    assert resumed.complete and resumed.skipped >= done - 1
    lines = [json.loads(x) for x in out.read_text().splitlines()]
    assert len({r["id"] for r in lines}) == len(lines) == len(spec.designs())
    reference = run_sweep(spec, tmp_path / "reference.jsonl", workers=1, progress=False)
    assert _comparable(resumed.records) == _comparable(reference.records)


def test_duplicate_lines_are_reported_and_ignored(tmp_path):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(SWEEP.replace("num = 12", "num = 2").replace("orientations = 600", "orientations = 50"))
    spec = SweepSpec.from_toml(sweep)
    out = tmp_path / "results.jsonl"
    first = run_sweep(spec, out, workers=1, progress=False)
    lines = out.read_text().splitlines()
    out.write_text("\n".join(lines + lines[:2]) + "\n")        # two lines pasted twice
    again = run_sweep(spec, out, workers=1, progress=False)
    assert again.duplicates == 2 and again.computed == 0 and again.complete
    assert _comparable(again.records) == _comparable(first.records)
