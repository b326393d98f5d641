"""The optimiser for m cables: symbolic holes against the numeric ones, exact derivatives against finite
differences, the surrogate against the exact zonotope, and a known optimum for a four- and an eight-cable design,
checked by the planner and a brute-force scan."""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest

import csjm_opt as co
from csjm_opt.cli.app import main
from csjm_opt.design.design_evaluation import evaluate_design
from csjm_opt.design.feasibility import wrench_margin_Nm
from csjm_opt.design.geometry import PAPER_DESIGN, design_holes
from csjm_opt.design.optimisation.dense_check import certify
from csjm_opt.design.optimisation.problem import build_problem
from csjm_opt.design.optimisation.result import design_rig_of
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.design.optimisation.surrogates import MARGIN_SOFTMIN_NM, sweep_surrogate
from csjm_opt.design.optimisation.symbols import holes_sym
from csjm_opt.design.sampling import tilt_torsion_rotations
from csjm_opt.errors import DesignError
from csjm_opt.model.numeric import Model
from csjm_opt.model.rig import Rig
from tests.design_files import tiny_design_toml


def _tiny(m: int, **kw) -> str:
    text = tiny_design_toml(orientations=kw.get("orientations", 100), max_tilt_deg=10.0, max_torsion_deg=5.0,
                            tau_ext=[[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]], optimise="""
objective = "stiffness"
pareto_with = ""
orientations = 4
certify_orientations = 300
starts = 1
""")
    text = text.replace("[base]\n", f"[base]\nn_cables = {m}\n")
    if m == 4:   # the pair angles of rigs/four_cable.toml (60 and 20 deg leave four cables no torsion stiffness)
        text = text.replace("platform_gamma_deg = 60.0", "platform_gamma_deg = 40.0").replace(
            "base_gamma_deg = 20.0", "base_gamma_deg = 140.0")
    return text


@pytest.mark.parametrize("m", [4, 5, 7, 8, 12])
def test_symbolic_holes_of_m_cables_match_numeric(m):
    params = {"n_cables": m, "platform_radius_m": 0.05, "platform_gamma_deg": 0.3 * 720 / m,
              "platform_theta0_deg": 12.0, "base_gamma_deg": 0.8 * 720 / m, "base_radius_m": 0.07, "oo_a_m": 0.07,
              "A3_dx_m": 0.002, f"B{m}_dz_m": -0.001}
    A, B = holes_sym({**PAPER_DESIGN, **params})
    A_ref, B_ref = design_holes(params)
    assert A.shape == (3, m)
    np.testing.assert_allclose(np.array(ca.DM(A)).T, A_ref, atol=1e-15)
    np.testing.assert_allclose(np.array(ca.DM(B)).T, B_ref, atol=1e-15)
    # chords: the numeric twin's root finding and the symbolic one agree
    chords = {"n_cables": m, "platform_d12_m": 0.01, "platform_d23_m": 0.04}
    A, _ = holes_sym({**PAPER_DESIGN, **chords})
    np.testing.assert_allclose(np.array(ca.DM(A)).T, design_holes(chords)[0], atol=1e-14)


@pytest.mark.parametrize("m", [4, 8])
def test_constraint_jacobian_of_m_cables_matches_finite_differences(tmp_path, m):
    path = tmp_path / "tiny.toml"
    path.write_text(_tiny(m))
    _, settings = read_optimise_file(path)
    settings = settings.replace(objective="range")
    angles = np.array([[0.0, 0.0, 0.0], [0.15, 1.0, 0.05], [0.17, 4.0, -0.08]])
    pb = build_problem(settings, angles, {"platform_radius_m": 0.05}, [], {"stiffness": 2.0})
    assert pb.n_cables == m
    x0 = pb.x0.copy()
    x0[pb.objective_index] = 0.7
    xs = ca.MX.sym("x", x0.size)
    exact = np.array(ca.Function("jac_g", [xs], [ca.jacobian(pb.constraints_of(xs, pb.p), xs)])(x0))
    g = lambda x: np.array(pb.constraints_of(x, pb.p)).ravel()  # noqa: E731
    h = 1e-6
    fd = np.column_stack([(g(x0 + h * e) - g(x0 - h * e)) / (2 * h) for e in np.eye(x0.size)])
    assert np.max(np.abs(exact - fd) / np.maximum(1.0, np.abs(exact))) < 1e-5
    # the stiffness load's tensions of the problem are the least-squares ones of the numeric model:
    # J^T T0 + tau_load + tau_weight = 0 (the model's own Jacobian, not the symbolic one)
    from csjm_opt.design.optimisation.symbols import pose_constraints

    rig = design_rig_of(settings, {"platform_radius_m": 0.05})
    Rs = tilt_torsion_rotations(*angles.T)
    pf = pose_constraints(1, False, m)
    assert pf.size_in("A") == (3, m)
    for R, a in zip(Rs, angles):
        _, T0 = pf(rig.platform_holes_A_m.T, rig.base_holes_B_m.T,
                   [rig.cable_stiffness_N_per_m[0], rig.t_min_N, rig.t_max_N, rig.platform_mass_kg,
                    rig.com_A_m[2], *rig.gravity_B_m_per_s2], [0.0, 0.0, 1.0, 0.0], a, np.zeros((3, 1)),
                   np.zeros(0))
        T0 = np.array(T0).ravel()
        model = Model(rig)
        J, tau_w = model.jacobian(R[None])[0], model.weight_moment(R[None])[0]
        np.testing.assert_allclose(J.T @ T0 + tau_w, 0.0, atol=1e-9)
        np.testing.assert_allclose(T0 - rig.t_mid_N, J @ np.linalg.lstsq(J, T0 - rig.t_mid_N, rcond=None)[0],
                                   atol=1e-9)   # T0 - t_mid in the range of J: the least-norm correction


@pytest.mark.parametrize("m", [4, 8])
def test_surrogate_of_m_cables_tends_to_the_exact_zonotope(tmp_path, m):
    path = tmp_path / "tiny.toml"
    path.write_text(_tiny(m, orientations=40))
    spec, settings = read_optimise_file(path)
    f = sweep_surrogate(settings, spec.settings)
    pairs = m * (m - 1) // 2 * spec.settings.loads.taus_ext_A_Nm.shape[0]
    for r in (0.04, 0.06):
        _, _, margin, _ = (np.array(v).ravel() for v in f([(r - 0.04) / 0.02]))
        rig = design_rig_of(settings, {"platform_radius_m": r})
        model, Rs = Model(rig), spec.settings.sampling.rotations()
        tau = spec.settings.loads.taus_ext_A_Nm[None] + model.weight_moment(Rs)[:, None]
        exact = wrench_margin_Nm(model.jacobian(Rs), tau, rig.t_min_N, rig.t_max_N).min(axis=1)
        assert np.all(margin <= exact + 1e-6)
        assert np.all(margin >= exact - MARGIN_SOFTMIN_NM * math.log(pairs) - 1e-6)


@pytest.mark.parametrize("m", [4, 8])
def test_known_optimum_of_m_cables_certified_and_held_by_the_planner(tmp_path, m):
    # as for six cables: at small angles K grows with the platform radius, so the stiffest design has its
    # radius on the upper bound; a brute-force scan of certified designs never beats it
    path = tmp_path / "tiny.toml"
    path.write_text(_tiny(m))
    out = tmp_path / "out"
    assert main(["optimise", str(path), "--out", str(out), "--no-progress"]) == 0
    (d,) = json.loads((out / "result.json").read_text())["designs"]
    assert d["ok"] and d["params"]["platform_radius_m"] == pytest.approx(0.06, abs=1e-6)
    rig = Rig.from_toml(out / d["rig_file"])
    assert rig.n_cables == m
    _, settings = read_optimise_file(path)
    lam = [certify(design_rig_of(settings, {"platform_radius_m": float(r)}), settings.requirements, 1.0, 0.0, 0.0,
                   n=300, seed=settings.seed + 7919).worst["stiffness"][0] for r in np.linspace(0.04, 0.06, 5)]
    assert int(np.argmax(lam)) == 4
    assert d["objectives"]["stiffness"] == pytest.approx(lam[-1], rel=1e-3)
    # the planner (active set, not the NLP) holds both loads at the required orientations with the design's
    # stiffness: the smallest eigenvalue at its tensions is at least the certified objective
    Rs = tilt_torsion_rotations(np.radians([0.0, 10.0, 7.0]), np.array([0.0, 1.0, 4.0]), np.radians([0.0, 5.0, -5.0]))
    for R in Rs:
        plan = co.plan_tensions(rig, R, np.zeros(3))
        assert plan.is_valid()
        assert np.linalg.eigvalsh(co.stiffness(rig, R, plan.tensions_N))[0] >= d["objectives"]["stiffness"] - 1e-6
    assert evaluate_design({"platform_radius_m": 0.06, "n_cables": m}, read_optimise_file(path)[0].settings)[
        "status"] == "ok"


def test_the_cable_count_cannot_be_optimised(tmp_path, capsys):
    text = _tiny(6).replace("n_cables = 6\n", "").replace(
        "[parameters.platform_radius_m]", "[parameters.n_cables]\nvalues = [4, 8]\n[parameters.platform_radius_m]")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(DesignError) as exc:
        read_optimise_file(path)
    assert exc.value.key == "optimise.variables"
    assert main(["optimise", str(path), "--out", str(tmp_path / "o"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "n_cables" in err[0] and "bad.toml" in err[0]
