"""What a newcomer meets at the command line: fast --help, one meaning per option, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from csjm_opt.cli import build_parser, main
from csjm_opt.cli.commands import COMMANDS

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
HEAVY = ("numba", "casadi", "scipy", "matplotlib", "qpsolvers", "mujoco", "dask", "distributed")

_PROBE = """
import contextlib, io, json, sys
from csjm_opt.cli import main
HEAVY = %r
out = {}
for argv in %r:
    with contextlib.redirect_stdout(io.StringIO()):
        try:
            main(argv)
        except SystemExit:
            pass
    out[" ".join(argv)] = sorted({m.split(".")[0] for m in sys.modules} & set(HEAVY))
print(json.dumps(out))
"""


def test_no_help_imports_a_numerical_library():
    argvs = [["--help"]] + [[name, "--help"] for name in COMMANDS]
    res = subprocess.run([sys.executable, "-c", _PROBE % (HEAVY, argvs)], capture_output=True, text=True,
                         cwd=ROOT, check=True)
    loaded = json.loads(res.stdout.strip().splitlines()[-1])
    assert loaded == {" ".join(a): [] for a in argvs}


def test_the_parsers_choices_are_the_owners():
    from csjm_opt.cli import commands as c
    from csjm_opt.design._value_checks import MAX_DESIGNS
    from csjm_opt.diagnose.effects import EFFECTS
    from csjm_opt.model.mjcf import ACTUATIONS
    from csjm_opt.shaping.objectives import OBJECTIVES
    from csjm_opt.testbed.mujoco.plant import PLANTS
    from csjm_opt.testbed.plant import DEPRECATED_NAMES, EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES

    assert c.SHAPING_OBJECTIVES == OBJECTIVES and c.MJCF_ACTUATIONS == ACTUATIONS and c.TESTBED_PLANTS == PLANTS
    assert c.DIAGNOSIS_EFFECTS == tuple(EFFECTS) and c.MAX_DESIGNS == MAX_DESIGNS
    assert c.TESTBED_EFFECTS == EFFECT_NAMES + tuple(VARIANT_NAMES) + OUTSIDE_NAMES
    assert c.TESTBED_DEPRECATED == DEPRECATED_NAMES


@pytest.mark.parametrize("name", list(COMMANDS))
def test_shared_options_mean_the_same_everywhere(name):
    parser = build_parser([name, "--help"])
    sub = next(a for a in parser._actions if a.dest == "command").choices[name]
    opts = {s: a for a in sub._actions for s in a.option_strings}
    if "--rig" in opts:
        assert opts["--rig"].default is None and "paper rig" in opts["--rig"].help
    if "--json" in opts:
        assert opts["--json"].metavar == "PATH" and "'-' = stdout" in opts["--json"].help
    if "--workers" in opts:
        assert opts["--workers"].default is None and "CSJM_WORKERS" in opts["--workers"].help
    outs = [a for a in sub._actions if a.dest == "out"]
    if outs:
        assert {"-o", "--out", "--output"} <= set(outs[0].option_strings)
        assert "--output" not in sub.format_help()                # the old spelling works, hidden


def test_a_usage_error_is_one_line_with_the_command_once(capsys):
    assert main(["plan-experiment", "--budget", "10", "-o", "x.csv", "--poses", "-0.15,0,0"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("csjm: error: plan-experiment: ") and err.count("csjm") == 1 and "\n" not in err


def test_a_negative_pose_is_taken_like_a_rotvec():
    args = build_parser(["plan-experiment"]).parse_args(
        ["plan-experiment", "--budget", "10", "-o", "p.csv", "--pose", "-0.15", "0", "0", "--pose", "0", "-0.1", "0",
         "--poses=-0.2,0,0"])
    from csjm_opt.cli.plan_experiment import _poses

    assert _poses(args.poses, args.pose).tolist() == [[-0.15, 0, 0], [0, -0.1, 0], [-0.2, 0, 0]]


def test_a_log_of_another_rig_is_refused_with_one_line_that_suggests_rig(capsys, tmp_path):
    log = DATA / "b1_none_first33.csv"
    assert main(["identify", str(log)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--rig" in err and "b1_none_first33.csv" in err
    assert main(["diagnose", str(log), "--no-progress", "--workers", "1"]) == 2
    assert "--rig" in capsys.readouterr().err
    out = tmp_path / "k.json"
    assert main(["identify", str(log), "--rig", str(DATA / "rig_b1.toml"), "--allow-ill-conditioned",
                 "--no-progress", "--json", str(out)]) == 0


def test_optimise_prints_units_and_clips_round_off_at_a_bound():
    from csjm_opt.cli.optimise import format_objectives

    text = format_objectives({"range": 0.003635, "tension_margin": -9.337e-09, "stiffness": 12.5, "size": 0.0812})
    assert text == ("range scale 0.003635 of the required orientation set, tension margin 0 N, "
                    "minimum stiffness 12.5 N m/rad, size (largest hole radius) 81.2 mm")
