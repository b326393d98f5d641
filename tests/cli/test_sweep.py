"""``csjm sweep``: docs/conventions.md command line and JSON, resumption, errors (exit 2, one line)."""

from __future__ import annotations

import json

import pytest

from csjm_opt import cli

SWEEP = """
[sweep]
method = "grid"
[parameters.platform_d23_m]
values = [0.08, 0.095]
[parameters.oo_b_m]
min = 0.07
max = 0.09
num = 2
[sampling]
orientations = 150
max_tilt_deg = 40.0
[loads]
tau_ext = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]
[metrics]
shaping_poses = 2
"""


def _run(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def _without_timings(designs: list[dict]) -> list[dict]:
    return [{**d, "metrics": {k: v for k, v in d["metrics"].items() if k != "seconds"}} for d in designs]


@pytest.fixture
def sweep_file(tmp_path):
    path = tmp_path / "sweep.toml"
    path.write_text(SWEEP)
    return path


def test_sweep_json_has_spec_keys_and_resumes(capsys, tmp_path, sweep_file):
    out, js = tmp_path / "results.jsonl", tmp_path / "results.json"
    code, stdout, _ = _run(capsys, "sweep", sweep_file, "--out", out, "--json", js, "--workers", "1")
    assert code == 0 and "4 designs (4 computed" in stdout
    data = json.loads(js.read_text())
    assert data["designs_per_second"] > 0 and len(data["designs"]) == 4
    for d in data["designs"]:
        assert set(d["params"]) == {"platform_d23_m", "oo_b_m"}
        assert 0 <= d["workspace_fraction"] <= 1 and d["min_stiffness_Nm_per_rad"] > 0
    assert [d["params"] for d in data["designs"]] == [
        {"platform_d23_m": a, "oo_b_m": b} for a in (0.08, 0.095) for b in (0.07, 0.09)]
    assert len(out.read_text().splitlines()) == 4
    code, stdout, _ = _run(capsys, "sweep", sweep_file, "--out", out, "--json", "-", "--workers", "1")
    again = json.loads(stdout)
    assert code == 0 and again["computed"] == 0 and again["skipped"] == 4
    assert [d["workspace_fraction"] for d in again["designs"]] == [d["workspace_fraction"] for d in data["designs"]]


def test_sweep_on_a_local_dask_cluster(capsys, tmp_path, sweep_file):
    code, _, _ = _run(capsys, "sweep", sweep_file, "--out", tmp_path / "local.jsonl", "--json",
                      tmp_path / "local.json", "--workers", "1")
    assert code == 0
    code, _, err = _run(capsys, "sweep", sweep_file, "--out", tmp_path / "dask.jsonl", "--json",
                        tmp_path / "dask.json", "--dask", "--workers", "1")
    assert code == 0, err
    local, dask = (json.loads((tmp_path / f"{n}.json").read_text())["designs"] for n in ("local", "dask"))
    assert _without_timings(local) == _without_timings(dask)


@pytest.mark.parametrize("text, needle", [
    ("[parameters.oo_b_m]\nvalues = []\n", "[parameters.oo_b_m.values]"),
    ("[parameters.oo_b_m]\nvalues = [0.1]\n[loads]\ntau_ext = [[1, 2]]\n", "[loads.tau_ext]"),
    ("[parameters]\n", "[parameters]"),
    ("[parameters.oo_b_m\n", "not valid TOML"),
])
def test_bad_sweep_files_exit_2_with_one_line(capsys, tmp_path, text, needle):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code, _, err = _run(capsys, "sweep", path, "--out", tmp_path / "r.jsonl")
    assert code == 2 and needle in err and err.count("\n") == 1 and "Traceback" not in err


def test_refuses_to_overwrite_its_input_and_bad_options(capsys, tmp_path, sweep_file):
    code, _, err = _run(capsys, "sweep", sweep_file, "--out", sweep_file)
    assert code == 2 and "input" in err
    code, _, err = _run(capsys, "sweep", sweep_file, "--out", tmp_path / "r.jsonl", "--workers", "0")
    assert code == 2 and "--workers" in err
    code, _, err = _run(capsys, "sweep", tmp_path / "missing.toml", "--out", tmp_path / "r.jsonl")
    assert code == 2 and "cannot read" in err
    code, _, err = _run(capsys, "sweep", sweep_file)
    assert code == 2 and "--out" in err
    assert sweep_file.read_text() == SWEEP


def test_limit_splits_a_sweep_and_a_larger_grid_reuses_finished_designs(capsys, tmp_path, sweep_file):
    out = tmp_path / "r.jsonl"
    code, stdout, _ = _run(capsys, "sweep", sweep_file, "--out", out, "--limit", "3", "--workers", "1")
    assert code == 0 and "3 computed" in stdout and "1 designs left" in stdout
    code, stdout, _ = _run(capsys, "sweep", sweep_file, "--out", out, "--workers", "1")
    assert code == 0 and "(1 computed, 3 from" in stdout
    bigger = tmp_path / "bigger.toml"
    bigger.write_text(SWEEP.replace("values = [0.08, 0.095]", "values = [0.08, 0.095, 0.11]"))
    code, stdout, _ = _run(capsys, "sweep", bigger, "--out", out, "--workers", "1")
    assert code == 0 and "6 designs (2 computed, 4 from" in stdout
    code, _, err = _run(capsys, "sweep", sweep_file, "--out", out, "--limit", "0")
    assert code == 2 and "--limit" in err
