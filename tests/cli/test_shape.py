"""``csjm shape`` (csjm_opt/cli_shape.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import cli, so3
from csjm_opt.cli import app as cli_main
from csjm_opt.cli import shape as cli_shape


def _parser():
    p = cli_main._Parser(prog="csjm")
    sub = p.add_subparsers(dest="command", parser_class=cli_main._Parser)
    cli_shape.register(sub)
    return p


ARGS = ["shape", "--rotvec", "0.1", "-0.05", "0.02", "--tau", "0.3", "-0.2", "0.1"]


def test_shape_json_reachable_target(tmp_path, rig, model, capsys):
    R = so3.exp(np.array([0.1, -0.05, 0.02]))
    tau = np.array([0.3, -0.2, 0.1])
    plan = co.plan_tensions(rig, R, tau, model=model)
    K = model.stiffness(R, plan.tensions_N + np.linalg.svd(model.jacobian(R).T)[2][3:].T @ [10.0, -5.0, 8.0])
    out = tmp_path / "shape.json"
    args = _parser().parse_args(ARGS + ["--target", *map(str, K.ravel()), "--reachable", "--json", str(out)])
    assert args.func(args) == 0
    data = json.loads(out.read_text())
    assert data["exact"] is True and np.allclose(data["K"], K, atol=1e-6)
    assert len(data["tensions_N"]) == 6 and data["rotvec"] == [0.1, -0.05, 0.02]
    assert len(data["reachable"]["eigen_ranges_Nm_per_rad"]) == 3
    assert "target reached" in capsys.readouterr().out


def test_shape_errors():
    with pytest.raises(co.InfeasibleLoad):
        args = _parser().parse_args(["shape", "--rotvec", "0", "0", "0", "--tau", "30", "0", "0",
                                     "--target", *["20"] * 9])
        args.func(args)
    with pytest.raises(co.InvalidInput):
        args = _parser().parse_args(ARGS + ["--target", *["20"] * 9, "--weights", "1", "2"])
        args.func(args)
    with pytest.raises(cli.UsageError):
        _parser().parse_args(ARGS + ["--target", "1", "2"])
