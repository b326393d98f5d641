"""``csjm plan``, ``csjm stiffness`` and the CLI's error contract."""

import json

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import cli


def _run(capsys, *argv):
    code = cli.main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_plan_json_has_spec_keys_and_holds_equilibrium(capsys, tmp_path):
    path = tmp_path / "plan.json"
    code, out, _ = _run(capsys, "plan", "--rotvec", "0.1", "-0.05", "0", "--tau", "0.3", "0", "0.1",
                        "--json", str(path))
    assert code == 0 and "tension (N)" in out
    data = json.loads(path.read_text())
    for key in ("tensions_N", "rotvec", "tau_ext", "equilibrium_residual_Nm"):
        assert key in data
    rig = co.paper_rig()
    R = co.so3.exp(data["rotvec"])
    J = co.Model(rig).jacobian(R)
    tau_w = rig.platform_mass_kg * np.cross(rig.com_A_m, R.T @ rig.gravity_B_m_per_s2)
    assert np.linalg.norm(J.T @ np.array(data["tensions_N"]) + np.array(data["tau_ext"]) + tau_w) < 1e-8


def test_stiffness_json_to_stdout_with_rig_file(capsys, tmp_path):
    rig_path = tmp_path / "rig.toml"
    co.paper_rig().to_toml(rig_path)
    code, out, _ = _run(capsys, "stiffness", "--rig", str(rig_path), "--rotvec", "0", "0.1", "0",
                        "--json", "-")
    assert code == 0
    data = json.loads(out)
    K = np.array(data["K"])
    assert K.shape == (3, 3) and np.allclose(K, K.T)
    assert set(("K", "tensions_N", "rotvec", "tau_ext")) <= set(data)
    assert np.allclose(K, co.stiffness(co.paper_rig(), co.so3.exp([0, 0.1, 0]), data["tensions_N"]))


@pytest.mark.parametrize("argv, fragment", [
    (["plan", "--rotvec", "0", "0"], "expected 3 arguments"),
    (["plan", "--rotvec", "0", "0", "0", "--tau", "30", "0", "0"], "outside the wrench-feasible set"),
    (["plan", "--rotvec", "0", "0", "0", "--rig", "/nonexistent/rig.toml"], "cannot read rig file"),
    (["plan", "--rotvec", "0", "0", "nan"], "finite"),
    (["stiffness", "--rotvec", "0", "0", "0", "--solver", "magic"], "unknown QP solver"),
    (["nonsense"], "invalid choice"),
])
def test_bad_input_exits_2_with_one_line(capsys, argv, fragment):
    code, out, err = _run(capsys, *argv)
    assert code == 2
    assert fragment in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_bad_rig_file_names_the_key(capsys, tmp_path):
    text = co.paper_rig().to_toml().replace("t_min = 5.0", "t_min = 500.0")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code, _, err = _run(capsys, "plan", "--rig", str(path), "--rotvec", "0", "0", "0")
    assert code == 2 and "[cables.t_max]" in err and "bad.toml" in err


def test_every_subcommand_has_help(capsys):
    parser = cli.build_parser()
    names = parser._subparsers._group_actions[0].choices.keys()
    assert {"plan", "stiffness", "demo"} <= set(names)
    for name in names:
        with pytest.raises(SystemExit) as info:
            cli.main([name, "--help"])
        assert info.value.code == 0
        assert "usage" in capsys.readouterr().out


def test_stiffness_near_the_boundary_with_default_solver_reports_stability(capsys):
    """Issue 12 item 5: this feasible load was refused by the old OSQP default."""
    code, out, err = _run(capsys, "stiffness", "--rotvec", "0.1", "-0.05", "0", "--tau", "10.80221", "0", "0",
                          "--json", "-")
    assert code == 0 and err == ""
    data = json.loads(out)
    assert data["solver"] == "active_set" and data["stable"] is True
    assert np.linalg.eigvalsh(np.array(data["K"]))[0] > 0
    for solver in ("osqp", "clarabel"):
        code, out, _ = _run(capsys, "plan", "--rotvec", "0.1", "-0.05", "0", "--tau", "10.80221", "0", "0",
                            "--solver", solver, "--json", "-")
        assert code == 0 and json.loads(out)["equilibrium_residual_Nm"] < 1e-8
