"""The optimiser: symbolic geometry against the numeric one, exact derivatives against finite differences,
a known optimum, certification, and the command line."""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
import pytest

from csjm_opt.cli.app import main
from csjm_opt.design.geometry import design_holes
from csjm_opt.design.optimisation.dense_check import certify
from csjm_opt.design.optimisation.problem import build_problem
from csjm_opt.design.optimisation.runner import design_rig_of
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.design.optimisation.symbols import holes_sym, rotation_sym
from csjm_opt.design.sampling import tilt_torsion_rotations
from csjm_opt.errors import DesignError
from csjm_opt.model.rig import Rig
from tests.design_files import tiny_design_toml

TINY = tiny_design_toml(orientations=100, max_tilt_deg=10.0, max_torsion_deg=5.0,
                        tau_ext=[[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]], optimise="""
objective = "stiffness"
pareto_with = ""
orientations = 4
certify_orientations = 300
starts = 1
""")


def _file(tmp_path, text=TINY, name="tiny.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_symbolic_geometry_matches_numeric():
    params = {"platform_radius_m": 0.05, "platform_gamma_deg": 37.0, "platform_theta0_deg": 12.0,
              "base_gamma_deg": 80.0, "base_radius_m": 0.07, "oo_a_m": 0.07, "A3_dx_m": 0.002, "B5_dz_m": -0.001}
    from csjm_opt.design.geometry import PAPER_DESIGN

    A, B = holes_sym({**PAPER_DESIGN, **params})
    A_ref, B_ref = design_holes(params)
    assert np.allclose(np.array(ca.DM(A)).T, A_ref, atol=1e-15)
    assert np.allclose(np.array(ca.DM(B)).T, B_ref, atol=1e-15)
    angles = (0.4, 2.0, -0.3)
    assert np.allclose(np.array(ca.DM(rotation_sym(*angles))), tilt_torsion_rotations(*map(np.array, angles)),
                       atol=1e-15)


def test_constraint_jacobian_matches_finite_differences(tmp_path):
    _, settings = read_optimise_file(_file(tmp_path))
    settings = settings.replace(objective="range")
    angles = np.array([[0.0, 0.0, 0.0], [0.15, 1.0, 0.05], [0.17, 4.0, -0.08]])
    pb = build_problem(settings, angles, {"platform_radius_m": 0.05}, [], {"stiffness": 2.0})
    x0 = pb.x0.copy()
    x0[pb.objective_index] = 0.7
    xs = ca.MX.sym("x", x0.size)
    jac = ca.Function("jac_g", [xs], [ca.jacobian(pb.constraints_of(xs, pb.p), xs)])
    exact = np.array(jac(x0))
    g = lambda x: np.array(pb.constraints_of(x, pb.p)).ravel()  # noqa: E731
    h = 1e-6
    fd = np.column_stack([(g(x0 + h * e) - g(x0 - h * e)) / (2 * h) for e in np.eye(x0.size)])
    scale = np.maximum(1.0, np.abs(exact))
    assert np.max(np.abs(exact - fd) / scale) < 1e-5
    assert np.linalg.norm(exact[:, : pb.n_design + 1]) > 0   # the design and the scale do act


def test_known_optimum_on_the_bound_certified_and_written_by_the_cli(tmp_path):
    # Larger platform holes give longer moment arms: at these small angles K grows with the radius,
    # so the stiffest design has its radius on the upper bound (checked against a brute-force scan below).
    path = _file(tmp_path)
    out = tmp_path / "out"
    assert main(["optimise", str(path), "--out", str(out), "--no-progress"]) == 0
    doc = json.loads((out / "result.json").read_text())
    (d,) = doc["designs"]
    assert d["ok"]
    assert d["params"]["platform_radius_m"] == pytest.approx(0.06, abs=1e-6)
    assert set(d) >= {"params", "objectives", "certified", "rig_file"} and "requirements" in doc
    rig = Rig.from_toml(out / d["rig_file"])
    assert rig.link is not None and np.isclose(np.hypot(*rig.platform_holes_A_m[0, :2]), 0.06, atol=1e-6)
    # csjm report renders the folder like a sweep result
    assert main(["report", str(out), "--out", str(tmp_path / "rep")]) == 0
    page = (tmp_path / "rep" / "index.md").read_text()
    assert "design_000" in page and (tmp_path / "rep" / "front.png").is_file()
    assert (tmp_path / "rep" / "geometry.png").is_file()
    view = (tmp_path / "rep" / "designs.html").read_text()      # the certified range drawn as a ring
    tilt = d["objectives"]["range"] * doc["requirements"]["max_tilt_deg"]
    assert f"certified tilt {tilt:.1f} deg" in view and "designs.html" in page
    # brute force over the radius: the certified stiffness of a grid never beats the optimum
    _, settings = read_optimise_file(path)
    lam = []
    for r in np.linspace(0.04, 0.06, 5):
        check = certify(design_rig_of(settings, {"platform_radius_m": float(r)}), settings.requirements, 1.0,
                        0.0, 0.0, n=300, seed=settings.seed + 7919)
        lam.append(check.worst["stiffness"][0])
    assert int(np.argmax(lam)) == 4
    assert d["objectives"]["stiffness"] == pytest.approx(lam[-1], rel=1e-3)


def test_infeasible_requirement_exit_2_names_constraint(tmp_path, capsys):
    text = TINY.replace('objective = "stiffness"', 'objective = "range"\nmin_stiffness_Nm_per_rad = 5000.0')
    code = main(["optimise", str(_file(tmp_path, text)), "--out", str(tmp_path / "o"), "--no-progress"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "stiffness" in err[0] and "tilt" in err[0]


@pytest.mark.parametrize("line, key", [("objective = \"speed\"", "optimise.objective"),
                                       ("colour = 3", "optimise.colour"),
                                       ("variables = [\"oo_a_m\"]", "optimise.variables")])
def test_bad_design_file_names_the_key(tmp_path, capsys, line, key):
    text = TINY.replace("[optimise]\n", f"[optimise]\n{line}\n").replace('objective = "stiffness"\n', "", 1) \
        if "objective" in line else TINY.replace("[optimise]\n", f"[optimise]\n{line}\n")
    code = main(["optimise", str(_file(tmp_path, text)), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and key in err[0]
    with pytest.raises(DesignError):
        read_optimise_file(_file(tmp_path, text, "again.toml"))
