"""``csjm validate``: accept rules, scores per folder, bad folders refused with nothing written."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest

import csjm_opt as co
import csjm_opt.diagnose as dg
from csjm_opt.cli.app import main
from csjm_opt.diagnose.selection.validation import accepted, confident
from csjm_opt.testbed.injection import make_plant
from csjm_opt.testbed.simulate import simulate_experiment


def _result(selected, secondary="none", warnings=(), plausible=True):
    return {"selected": selected, "secondary": {"effect": secondary}, "verdict": {"warnings": list(warnings)},
            "candidates": [{"effect": selected, "plausible": plausible}]}


def test_accept_rules_as_the_readme_states():
    assert accepted("exact", ["mass_com"], _result("mass_com"))
    assert accepted("exact", ["mass_com"], _result("hole_offsets", "mass_com"))       # the secondary counts
    assert not accepted("exact", ["hole_offsets", "mass_com"], _result("hole_offsets"))
    assert accepted("exact", [], _result("none"))
    assert not accepted("exact", [], _result("unexplained"))
    assert accepted("no_effect", [], _result("unexplained")) and accepted("no_effect", [], _result("none"))
    assert not accepted("no_effect", [], _result("sensor_bias", warnings=["x"]))
    assert accepted("not_confident", [], _result("unexplained"))
    assert accepted("not_confident", [], _result("stiffness_scale", warnings=["sensor_gain fits too"]))
    assert accepted("not_confident", [], _result("stiffness_scale", plausible=False))
    assert not accepted("not_confident", [], _result("stiffness_scale"))
    assert not confident(_result("none"))


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("val") / "lab"
    root.mkdir()
    rig = co.paper_rig()
    (root / "rig.toml").write_text(rig.to_toml())
    rng = np.random.default_rng(2)
    for name, effect in (("bias", "sensor_bias"), ("clean", None)):
        plant = make_plant(rig, effect, 3.0, rng)          # one rig: train and test share the injected effect
        simulate_experiment(rig, 4, rng, plant).to_csv(root / f"{name}_train.csv")
        simulate_experiment(rig, 3, rng, plant, first_cycle=10).to_csv(root / f"{name}_test.csv")
    answers = {"bias": {"effects": ["sensor_bias"], "accept": "exact", "rig": "rig.toml",
                        "train": "bias_train.csv", "test": "bias_test.csv", "injected": {}},
               "clean": {"effects": [], "accept": "no_effect", "rig": "rig.toml",
                         "train": "clean_train.csv", "test": "clean_test.csv", "injected": {}}}
    (root / "answers.json").write_text(json.dumps(answers))
    return root


@pytest.fixture
def quick(monkeypatch):
    """The standard diagnosis on two candidates only (the full vocabulary takes minutes; the scoring is the test)."""
    monkeypatch.setattr(dg, "diagnose", functools.partial(dg.diagnose, effects=["sensor_bias", "mass_com"],
                                                          secondary=False))


def test_validate_scores_every_case(folder, tmp_path, quick, capsys):
    out = tmp_path / "v.json"
    assert main(["validate", str(folder), "--json", str(out), "--no-progress", "--workers", "1"]) == 0
    res = json.loads(out.read_text())
    by = {c["case"]: c for c in res["cases"]}
    assert by["bias"]["selected"] == "sensor_bias" and by["bias"]["right"]
    assert by["clean"]["right"] == (by["clean"]["selected"] in ("none", "unexplained"))
    assert res["score"]["lab"]["cases"] == 2
    assert "lab:" in capsys.readouterr().out


def test_validate_refuses_a_folder_without_answers(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    out = tmp_path / "v.json"
    assert main(["validate", str(tmp_path / "empty"), "--json", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "answers.json" in err[0]
    assert not out.exists()


def test_validate_refuses_a_log_of_another_rig(folder, tmp_path, capsys):
    other = tmp_path / "other"
    other.mkdir()
    for f in folder.iterdir():
        (other / f.name).write_bytes(f.read_bytes())
    rig = co.paper_rig()
    foreign = rig.replace(platform_holes_A_m=1.6 * np.asarray(rig.platform_holes_A_m))   # a larger platform
    simulate_experiment(foreign, 3, np.random.default_rng(0)).to_csv(other / "clean_test.csv", overwrite=True)
    before = (other / "answers.json").read_bytes()
    assert main(["validate", str(other), "--json", str(tmp_path / "v.json"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "clean" in err[0] and "another rig" in err[0]
    assert not (tmp_path / "v.json").exists() and (other / "answers.json").read_bytes() == before


def test_validate_refuses_bad_answers_and_overwriting_them(folder, tmp_path, capsys):
    assert main(["validate", str(folder), "--json", str(folder / "answers.json"), "--no-progress"]) == 2
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "answers.json").write_text(json.dumps({"x": {"effects": [], "accept": "roughly", "rig": "r",
                                                         "train": "a", "test": "b"}}))
    assert main(["validate", str(bad), "--no-progress"]) == 2
    assert "accept rule" in capsys.readouterr().err
    assert main(["validate", str(folder), "--cases", "nope", "--no-progress"]) == 2
