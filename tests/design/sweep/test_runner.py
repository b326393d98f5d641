"""Sweep description, crash-safe result file, resumption, parallel and Dask backends."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from csjm_opt.design.sweep.runner import TIMING_KEYS, run_sweep
from csjm_opt.design.sweep.spec import SweepSpec
from csjm_opt.design.sweep.store import ResultStore, read_records
from csjm_opt.errors import DesignError

REPO = Path(__file__).resolve().parents[3]

SMALL = {
    "sweep": {"method": "grid"},
    "base": {"oo_a_m": 0.08},
    "parameters": {"platform_d23_m": {"values": [0.08, 0.095, 0.11]},
                   "base_d12_m": {"min": 0.11, "max": 0.14, "num": 2}},
    "sampling": {"orientations": 200, "max_tilt_deg": 45.0, "max_torsion_deg": 30.0},
    "loads": {"tau_ext": [[0, 0, 0], [3, 0, 0], [0, -3, 0]]},
    "metrics": {"shaping_poses": 4},
}


def _spec(**changes) -> SweepSpec:
    data = json.loads(json.dumps(SMALL))
    for section, table in changes.items():
        data.setdefault(section, {}).update(table)
    return SweepSpec.from_dict(data, "small.toml")


def _strip(records: list[dict]) -> list[dict]:
    """Records without timings (the only machine-dependent fields)."""
    out = []
    for r in records:
        r = json.loads(json.dumps(r))
        for key in TIMING_KEYS:
            r.pop(key, None)
            if r.get("metrics"):
                r["metrics"].pop(key, None)
        out.append(r)
    return out


# ------------------------------------------------------------------ sweep file
def test_grid_lhs_and_random_designs():
    grid = _spec().designs()
    assert len(grid) == 6 and grid[0] == {"platform_d23_m": 0.08, "base_d12_m": 0.11}
    assert {d["base_d12_m"] for d in grid} == {0.11, 0.14}
    lhs = _spec(sweep={"method": "lhs", "designs": 10, "seed": 4},
                parameters={"platform_d23_m": {"min": 0.07, "max": 0.12},
                            "base_d12_m": {"min": 0.1, "max": 0.2, "log": True}}).designs()
    x = np.array([[d["platform_d23_m"], d["base_d12_m"]] for d in lhs])
    assert len(lhs) == 10 and np.all((x[:, 0] >= 0.07) & (x[:, 0] <= 0.12))
    # Latin hypercube: exactly one design in each of the 10 strata of each parameter
    assert sorted(np.floor((x[:, 0] - 0.07) / 0.005).astype(int)) == list(range(10))
    strata = np.floor(np.log(x[:, 1] / 0.1) / (np.log(2) / 10)).astype(int)
    assert sorted(strata) == list(range(10))
    again = _spec(sweep={"method": "lhs", "designs": 10, "seed": 4},
                  parameters={"platform_d23_m": {"min": 0.07, "max": 0.12},
                              "base_d12_m": {"min": 0.1, "max": 0.2, "log": True}}).designs()
    assert again == lhs
    rnd = _spec(sweep={"method": "random", "designs": 5},
                parameters={"platform_d23_m": {"min": 0.07, "max": 0.12},
                            "base_d12_m": {"min": 0.1, "max": 0.2}}).designs()
    assert len(rnd) == 5


@pytest.mark.parametrize("changes, key", [
    ({"sweep": {"method": "sobol"}}, "sweep.method"),
    ({"sweep": {"method": "lhs"}}, "sweep.designs"),
    ({"sweep": {"designs": 3}}, "sweep.designs"),
    ({"parameters": {"oo_b_m": {"min": 0.1, "max": 0.05, "num": 3}}}, "parameters.oo_b_m.min"),
    ({"parameters": {"oo_b_m": {"min": 0.05, "max": 0.1}}}, "parameters.oo_b_m.num"),
    ({"parameters": {"oo_b": {"values": [0.1]}}}, "parameters.oo_b"),
    ({"parameters": {"oo_a_m": {"values": [0.1]}}}, "base.oo_a_m"),
    ({"parameters": {"platform_holes": {"values": [1]}}}, "parameters.platform_holes"),
    ({"base": {"platform_radius_m": 0.05}}, "base.platform_radius_m"),
    ({"sampling": {"orientations": 0}}, "sampling.orientations"),
    ({"sampling": {"max_tilt_deg": 200.0}}, "sampling.max_tilt_deg"),
    ({"sampling": {"density": 3}}, "sampling.density"),
    ({"loads": {"tau_ext": [[1, 2]]}}, "loads.tau_ext"),
    ({"metrics": {"shaping_poses": -1}}, "metrics.shaping_poses"),
    ({"extra": {"a": 1}}, "extra"),
])
def test_bad_sweep_descriptions_name_the_key(changes, key):
    with pytest.raises(DesignError) as info:
        _spec(**changes)
    assert info.value.key == key and f"[{key}]" in str(info.value) and "small.toml" in str(info.value)


def test_bad_toml_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text("[sweep\nmethod = 1\n")
    with pytest.raises(DesignError, match="not valid TOML"):
        SweepSpec.from_toml(path)
    with pytest.raises(DesignError, match="cannot read"):
        SweepSpec.from_toml(tmp_path / "missing.toml")


def test_shipped_paper_sweep_parses_and_contains_the_papers_circles():
    spec = SweepSpec.from_toml(REPO / "studies" / "paper_sweep" / "paper_sweep.toml")
    assert len(spec.designs()) >= 50
    assert spec.settings.base["platform_radius_m"] == pytest.approx(0.05795, abs=1e-5)


# ------------------------------------------------------------------ resumption
def test_interrupted_sweep_resumes_without_recomputing(tmp_path):
    spec = _spec()
    out = tmp_path / "r.jsonl"
    first = run_sweep(spec, out, workers=1, progress=False, stop_after=2)
    assert first.computed == 2 and not first.complete
    with open(out, "ab") as fh:              # a write cut short by a crash: half a record, no newline
        fh.write(b'{"id": "abc", "params": {"platform_d23_m": 0.1')
    records, end = read_records(out)
    assert len(records) == 2 and end < out.stat().st_size
    finished = {r["id"] for r in records}
    resumed = run_sweep(spec, out, workers=1, progress=False)
    assert resumed.skipped == 2 and resumed.computed == 4 and resumed.complete
    lines = out.read_text().splitlines()
    assert len(lines) == 6 and all(json.loads(line)["id"] for line in lines)   # the partial line is gone
    assert len({json.loads(line)["id"] for line in lines}) == 6
    assert finished <= {json.loads(line)["id"] for line in lines[:2]}          # not rewritten
    fresh = run_sweep(spec, tmp_path / "fresh.jsonl", workers=1, progress=False)
    assert _strip(resumed.records) == _strip(fresh.records)
    again = run_sweep(spec, out, workers=1, progress=False)
    assert again.computed == 0 and again.skipped == 6


def test_killed_sweep_leaves_a_valid_file_and_resumes(tmp_path):
    toml = tmp_path / "s.toml"
    toml.write_text('[parameters.platform_d23_m]\nmin = 0.07\nmax = 0.12\nnum = 24\n'
                    '[sampling]\norientations = 1500\nmax_tilt_deg = 45.0\n')
    out = tmp_path / "r.jsonl"
    env = {**os.environ, "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen([sys.executable, "-m", "csjm_opt.cli", "sweep", str(toml), "--out", str(out),
                             "--workers", "1", "--no-progress"], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and (not out.exists() or out.read_bytes().count(b"\n") < 3):
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    records, end = read_records(out)
    done = len(records)
    assert 3 <= done < 24, "the sweep should have been killed midway"
    spec = SweepSpec.from_toml(toml)
    resumed = run_sweep(spec, out, workers=1, progress=False)
    assert resumed.skipped == done and resumed.computed == 24 - done
    assert [json.loads(line)["index"] for line in out.read_text().splitlines()] == list(range(24))


def test_result_file_of_another_sweep_or_corrupt_is_refused(tmp_path):
    out = tmp_path / "r.jsonl"
    run_sweep(_spec(), out, workers=1, progress=False, stop_after=1)
    with pytest.raises(DesignError, match="other settings"):
        run_sweep(_spec(sampling={"orientations": 100}), out, workers=1, progress=False)
    lines = out.read_bytes()
    out.write_bytes(b"not json\n" + lines)
    with pytest.raises(DesignError, match="line 1"):
        run_sweep(_spec(), out, workers=1, progress=False)


def test_a_running_sweep_locks_its_result_file(tmp_path):
    out = tmp_path / "r.jsonl"
    with ResultStore(out, "digest"):
        with pytest.raises(DesignError, match="in use"):
            ResultStore(out, "digest")


# ------------------------------------------------------------------ backends
def test_process_pool_and_dask_give_the_same_records_as_serial(tmp_path):
    from distributed import LocalCluster

    spec = _spec()
    serial = run_sweep(spec, tmp_path / "serial.jsonl", workers=1, progress=False)
    pool = run_sweep(spec, tmp_path / "pool.jsonl", workers=2, progress=False)
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster:
        dask = run_sweep(spec, tmp_path / "dask.jsonl", scheduler=cluster.scheduler_address, progress=False)
    assert dask.computed == pool.computed == serial.computed == 6
    assert _strip(dask.records) == _strip(serial.records) == _strip(pool.records)
    assert all(r["status"] == "ok" for r in serial.records)


def test_unreachable_scheduler_is_a_clear_error(tmp_path):
    with pytest.raises(DesignError, match="Dask scheduler"):
        run_sweep(_spec(), tmp_path / "r.jsonl", scheduler="tcp://127.0.0.1:9", progress=False,
                  connect_timeout_s=1.0)


def test_study_script_makes_figures_and_places_the_paper(tmp_path):
    import importlib.util

    path = REPO / "studies" / "paper_sweep" / "paper_sweep.py"
    spec = importlib.util.spec_from_file_location("paper_sweep_study", path)
    study = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(study)
    toml = tmp_path / "s.toml"
    toml.write_text('[base]\nplatform_radius_m = 0.058\nbase_radius_m = 0.075\n'
                    '[parameters.platform_gamma_deg]\nvalues = [10.0, 60.0]\n'
                    '[parameters.base_gamma_deg]\nvalues = [20.0, 116.0]\n'
                    '[sampling]\norientations = 100\n[metrics]\nshaping_poses = 2\n')
    assert study.main([str(tmp_path / "out"), "--sweep", str(toml), "--workers", "1"]) == 0
    for name in ("heatmaps.png", "pareto.png", "summary.json", "summary.md", "paper_sweep.jsonl"):
        assert (tmp_path / "out" / name).stat().st_size > 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["paper_design"]["params"]["base_gamma_deg"] == pytest.approx(116.199, abs=1e-3)
    # Pareto mask law: nothing on the front is dominated, everything off it is
    x, y = np.array([1.0, 2.0, 2.0, 0.5]), np.array([3.0, 1.0, 2.0, 0.5])
    np.testing.assert_array_equal(study.pareto_mask(x, y), [True, False, True, False])


@pytest.mark.parametrize("startup_s, uses_pool", [(0.0, True), (1e9, False)])
def test_automatic_workers_choose_the_pool_only_when_it_pays(tmp_path, monkeypatch, startup_s, uses_pool):
    """``workers=None``: designs timed here first; the pool only if the rest outlasts its start-up."""
    from csjm_opt.design.sweep import runner as sweep_module

    calls = []
    real = sweep_module._run_processes

    def spy(todo, settings, workers):
        calls.append(len(todo))
        yield from real(todo, settings, workers)

    monkeypatch.setattr(sweep_module, "_TIMED_DESIGNS", 2)
    monkeypatch.setattr(sweep_module, "POOL_STARTUP_S", startup_s)
    monkeypatch.setenv("CSJM_WORKERS", "2")          # the one default (tests set 1: serial everywhere)
    monkeypatch.setattr(sweep_module, "_run_processes", spy)
    spec = _spec()
    auto = run_sweep(spec, tmp_path / "auto.jsonl", progress=False)
    serial = run_sweep(spec, tmp_path / "serial.jsonl", workers=1, progress=False)
    assert calls == ([4] if uses_pool else [])
    assert auto.computed == 6 and _strip(auto.records) == _strip(serial.records)
