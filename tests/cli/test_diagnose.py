"""``csjm diagnose``: documented JSON, report folder, bad logs, inputs never overwritten."""

from __future__ import annotations

import json

import numpy as np
import pytest

from csjm_opt.cli import main
from csjm_opt.testbed import simulate_experiment


@pytest.fixture(scope="module")
def logs(tmp_path_factory, rig):
    d = tmp_path_factory.mktemp("diag")
    rng = np.random.default_rng(40)
    train = simulate_experiment(rig, 6, rng, effect="sensor_bias", severity=1.5)
    test = simulate_experiment(rig, 3, rng, effect=None, first_cycle=100)
    return train.to_csv(d / "data.csv"), test.to_csv(d / "test.csv")


def test_json_and_report(logs, tmp_path, capsys):
    data, _ = logs
    out = tmp_path / "out.json"
    rc = main(["diagnose", str(data), "--json", str(out), "--report", str(tmp_path / "rep"),
               "--effects", "sensor_bias", "cable_hardening", "--no-progress"])
    assert rc == 0
    j = json.loads(out.read_text())
    assert set(j["baseline"]) >= {"heldout_rms_rad", "train_rms_rad"}
    assert set(j["gap"]) >= {"before_rad", "after_rad", "fraction_explained"}
    for c in j["candidates"]:
        assert set(c) >= {"effect", "heldout_rms_rad", "params", "bic"}
    assert j["selected"] == "sensor_bias"
    assert isinstance(j["localisation"], dict) and j["noise_floor_rad"] > 0
    for name in ("index.md", "diagnosis.json", "residual_map.png", "hysteresis.png", "candidates.png",
                 "before_after.png"):
        assert (tmp_path / "rep" / name).stat().st_size > 0
    assert "selected: sensor_bias" in capsys.readouterr().out


def test_test_file_is_the_heldout_set(logs, tmp_path):
    data, test = logs
    out = tmp_path / "o.json"
    assert main(["diagnose", str(data), "--test", str(test), "--json", str(out), "--effects", "sensor_bias",
                 "--no-progress"]) == 0
    j = json.loads(out.read_text())
    assert j["heldout"] == "test file" and j["rows"]["test"] == 27


def test_bad_log_is_a_clear_error(tmp_path, capsys, logs):
    data, _ = logs
    lines = data.read_text().splitlines()
    lines[3] = lines[3].replace(lines[3].split(",")[9], "abc", 1)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(lines) + "\n")
    assert main(["diagnose", str(bad), "--json", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad.csv:4" in err and "not a number" in err
    assert not (tmp_path / "x.json").exists()


def test_input_is_never_overwritten(logs, capsys):
    data, test = logs
    before = data.read_bytes()
    assert main(["diagnose", str(data), "--json", str(data)]) == 2
    assert main(["diagnose", str(data), "--test", str(test), "--json", str(test)]) == 2
    assert data.read_bytes() == before
    assert "refusing to overwrite" in capsys.readouterr().err


def test_one_cycle_without_test_file_is_refused(tmp_path, rig, capsys):
    log = simulate_experiment(rig, 1, np.random.default_rng(41))
    path = log.to_csv(tmp_path / "one.csv")
    assert main(["diagnose", str(path), "--json", str(tmp_path / "o.json"), "--no-progress"]) == 2
    assert "at least 2 cycles" in capsys.readouterr().err


def test_demo_step_contract(rig, tmp_path):
    from csjm_opt.demo.diagnose_step import run_demo

    out = run_demo(rig, tmp_path / "diagnosis", np.random.default_rng(42), effect="sensor_bias",
                   severity=1.5, n_cycles=6, secondary=False)
    json.dumps(out)                                   # JSON-able
    assert out["injected"] == "sensor_bias" and out["selected"] in out["candidates"] | {"none": 0}
    assert (tmp_path / "diagnosis" / out["report"]).exists() and (tmp_path / "diagnosis" / out["log"]).exists()


def test_suggest_writes_a_protocol_and_extra_reads_it_back(logs, tmp_path, capsys):
    """--suggest writes the protocol (measured columns empty); --extra takes a measured log of it."""
    data, _ = logs
    out, proto = tmp_path / "s.json", tmp_path / "proto.csv"
    assert main(["diagnose", str(data), "--json", str(out), "--effects", "sensor_bias", "tracker_registration",
                 "--suggest", "20", "--protocol", str(proto), "--report", str(tmp_path / "rep"), "--no-progress"]) == 0
    j = json.loads(out.read_text())
    assert "suggestion" in j
    if j["suggestion"] is not None:
        assert "Suggested experiment" in (tmp_path / "rep" / "suggestion.md").read_text()
        lines = proto.read_text().splitlines()
        assert lines[0].startswith("sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz,load_kg")
        assert 3 <= len(lines) - 1 <= 20 and len(lines) - 1 == j["suggestion"]["rows"]
        assert all(row.split(",")[8:14] == [""] * 6 for row in lines[1:])
    capsys.readouterr()


def test_suggest_refuses_bad_inputs_without_writing(logs, tmp_path, capsys, rig):
    data, _ = logs
    before = data.read_text()
    # the protocol would overwrite the data
    assert main(["diagnose", str(data), "--suggest", "20", "--protocol", str(data), "--no-progress"]) == 2
    assert capsys.readouterr().err.count("\n") == 1 and data.read_text() == before
    # a load set with a bad key
    loads = tmp_path / "loads.toml"
    loads.write_text('[[load]]\nmass_kg = "heavy"\npoint_A_m = [0.05, 0.0, 0.0]\n')
    assert main(["diagnose", str(data), "--suggest", "20", "--loads", str(loads), "--protocol",
                 str(tmp_path / "p.csv"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mass_kg" in err and not (tmp_path / "p.csv").exists()
    # a load set the rig cannot hold
    loads.write_text('[[load]]\nmass_kg = 500.0\npoint_A_m = [0.05, 0.0, 0.0]\n')
    assert main(["diagnose", str(data), "--effects", "sensor_bias", "tracker_registration", "--suggest", "20",
                 "--loads", str(loads), "--protocol", str(tmp_path / "p.csv"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot hold" in err
    assert not (tmp_path / "p.csv").exists()


def test_extra_log_from_another_rig_is_refused(logs, tmp_path, capsys):
    from csjm_opt.testbed import random_rig

    data, _ = logs
    other, _ = random_rig(np.random.default_rng([1234, 3]))
    foreign = simulate_experiment(other, 2, np.random.default_rng(5), steps=2).to_csv(tmp_path / "more.csv")
    before = foreign.read_text()
    assert main(["diagnose", str(data), "--extra", str(foreign), "--json", str(tmp_path / "o.json"),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "another rig" in err
    assert foreign.read_text() == before and not (tmp_path / "o.json").exists()


def test_workers_below_one_is_refused_in_one_line(logs, tmp_path, capsys):
    data, _ = logs
    assert main(["diagnose", str(data), "--workers", "0", "--json", str(tmp_path / "x.json"),
                 "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "workers" in err
    assert not (tmp_path / "x.json").exists()


def test_a_row_left_out_is_named_on_the_console_and_in_the_json(tmp_path, rig, capsys):
    """A force spike in one row: the console says which row was left out and why, the JSON lists it."""
    from csjm_opt.measurement.logfile import MeasurementLog

    log = simulate_experiment(rig, 6, np.random.default_rng(41), effect="sensor_bias", severity=3.0)
    tau = np.array(log.tau_ext_A_Nm, float)
    tau[10, 1] -= 0.6
    path = MeasurementLog.from_arrays(log.cycle, log.rest_lengths_m, tau, log.R, sample=log.sample).to_csv(
        tmp_path / "spike.csv")
    out = tmp_path / "out.json"
    assert main(["diagnose", str(path), "--effects", "sensor_bias", "mass_com", "--json", str(out),
                 "--no-progress"]) == 0
    left = json.loads(out.read_text())["left_out_rows"]
    assert [(r["log"], r["sample"], r["reason"]) for r in left] == [("log", int(log.sample[10]), "gross_residual")]
    out = capsys.readouterr().out
    assert f"note: 1 row(s) left out (log sample {int(log.sample[10])}): the model that fits the log does not" in out
