"""The shaping-range objective: the NLP's epigraph against independent LPs (scipy's HiGHS), its design
gradient against finite differences, a brute-forced optimum, the command line, bad keys."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import linprog

from csjm_opt.cli.app import main
from csjm_opt.design.optimisation.problem import build_problem
from csjm_opt.design.optimisation.runner import design_rig_of
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.design.optimisation.shaping import dense_angles, lp_shaping_range
from csjm_opt.design.sampling import tilt_torsion_rotations
from csjm_opt.errors import DesignError
from csjm_opt.model.numeric import Model
from tests.design_files import tiny_design_toml

MARGIN_N = 2.0
TINY = tiny_design_toml(orientations=100, max_tilt_deg=10.0, max_torsion_deg=5.0,
                        tau_ext=[[0.1, -0.05, 0.0], [0.5, 0.0, 0.0]], optimise=f"""
objective = "shaping"
pareto_with = ""
orientations = 4
certify_orientations = 300
starts = 1
tension_margin_N = {MARGIN_N}
""")
ANGLES = np.array([[0.0, 0.0, 0.0], [0.15, 1.0, 0.05], [0.17, 4.0, -0.08], [0.12, 2.5, 0.08]])
AXES = np.eye(3)


@pytest.fixture(scope="module")
def settings(tmp_path_factory):
    path = tmp_path_factory.mktemp("shaping") / "tiny.toml"
    path.write_text(TINY)
    return read_optimise_file(path)[1]


def _linprog_range(settings, radius_m, angles):
    """min over orientations and axes of max - min u^T K(T) u over the held tensions, by HiGHS (one LP each)."""
    rig = design_rig_of(settings, {"platform_radius_m": radius_m})
    model = Model(rig)
    Rs = tilt_torsion_rotations(angles[:, 0], angles[:, 1], angles[:, 2])
    load = np.asarray(settings.requirements.loads, float)[0]
    out = np.empty((len(angles), 3))
    for n, R in enumerate(Rs):
        J = model.jacobian(R)
        K0, Ki = model.stiffness_basis(R[None])
        tau = load + model.weight_moment(R)
        for d, u in enumerate(AXES):
            c = np.einsum("j,ijk,k->i", u, Ki[0], u)
            kw = dict(A_eq=J.T, b_eq=-tau, bounds=[(rig.t_min_N + MARGIN_N, rig.t_max_N - MARGIN_N)] * 6,
                      method="highs")
            lo, hi = linprog(c, **kw), linprog(-c, **kw)
            assert lo.status == 0 and hi.status == 0
            out[n, d] = -hi.fun - lo.fun            # u^T K0 u cancels in the difference
    return out


def _solve_fixed(settings, radius_m, angles=ANGLES):
    """The NLP with the design held at ``radius_m``: (objective N m/rad, its derivative d/d radius, status)."""
    pb = build_problem(settings, angles, {"platform_radius_m": radius_m}, [], {})
    lbx, ubx = pb.lbx.copy(), pb.ubx.copy()
    lbx[0] = ubx[0] = pb.x0[0]
    sol = pb.solver(x0=pb.x0, p=pb.p, lbx=lbx, ubx=ubx, lbg=pb.lbg, ubg=pb.ubg)
    # f = -s / 10 with u = (r - 0.04) / 0.02: the bound's multiplier is -df*/du (KKT: grad f + lam_x = 0)
    ds_dr = float(sol["lam_x"][0]) * 10.0 / 0.02
    return float(sol["x"][pb.objective_index]) * 10.0, ds_dr, pb.solver.stats()["return_status"]


def test_batched_lp_matches_highs(settings):
    rig = design_rig_of(settings, {"platform_radius_m": 0.05})
    ours = lp_shaping_range(rig, ANGLES, settings.requirements.loads[0], MARGIN_N)
    assert np.allclose(ours, _linprog_range(settings, 0.05, ANGLES), rtol=1e-9, atol=1e-9)


def test_epigraph_at_a_fixed_design_is_the_smallest_lp_range(settings):
    for radius in (0.045, 0.055):
        s, _, status = _solve_fixed(settings, radius)
        assert status == "Solve_Succeeded"
        assert s == pytest.approx(_linprog_range(settings, radius, ANGLES).min(), abs=1e-6)


def test_design_gradient_matches_finite_differences(settings):
    r, h = 0.05, 1e-5
    _, ds_dr, _ = _solve_fixed(settings, r)
    fd = (_linprog_range(settings, r + h, ANGLES).min() - _linprog_range(settings, r - h, ANGLES).min()) / (2 * h)
    assert abs(fd) > 1.0                       # the radius does act on the range
    assert ds_dr == pytest.approx(fd, rel=1e-4)


def test_optimum_matches_brute_force_and_cli_certifies_it(tmp_path, settings):
    # brute force over the radius on the optimiser's orientation set: the best grid point is the upper bound
    # (longer moment arms widen the range), so the optimum is known: r = 0.06 and the LP range there
    angles = np.vstack([np.zeros((1, 3)), dense_angles(settings.orientations, 10.0, 5.0, settings.seed)[1:]])
    grid = np.linspace(0.04, 0.06, 5)
    brute = [_linprog_range(settings, float(r), angles).min() for r in grid]
    assert int(np.argmax(brute)) == len(grid) - 1
    pb = build_problem(settings, angles, {"platform_radius_m": 0.045}, [], {})
    sol = pb.solver(x0=pb.x0, p=pb.p, lbx=pb.lbx, ubx=pb.ubx, lbg=pb.lbg, ubg=pb.ubg)
    assert float(sol["x"][0]) == pytest.approx(1.0, abs=1e-6)
    assert float(sol["x"][pb.objective_index]) * 10.0 == pytest.approx(brute[-1], abs=1e-6)
    # the command line: certified on the dense set (300 + R = I, and the pattern search)
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    out = tmp_path / "out"
    assert main(["optimise", str(path), "--out", str(out), "--no-progress"]) == 0
    (d,) = json.loads((out / "result.json").read_text())["designs"]
    assert d["ok"] and d["params"]["platform_radius_m"] == pytest.approx(0.06, abs=1e-6)
    dense = dense_angles(settings.certify_orientations, 10.0, 5.0, settings.seed + 7919)
    on_dense = _linprog_range(settings, 0.06, dense[::10]).min()
    assert d["objectives"]["shaping"] <= on_dense + 1e-6              # the search only lowers it
    assert d["objectives"]["shaping"] <= brute[-1] + 1e-6
    assert d["certified"]["shaping"]["slack"] >= -1e-6
    assert d["objectives"]["shaping"] == pytest.approx(on_dense, rel=0.05)
    # csjm report shows the certified shaping range beside the other objectives
    assert main(["report", str(out), "--out", str(tmp_path / "rep")]) == 0
    table = next(line for line in (tmp_path / "rep" / "index.md").read_text().splitlines()
                 if "shaping range (N m/rad)" in line)
    header = [c.strip() for c in table.strip("| ").split("|")]
    md = (tmp_path / "rep" / "index.md").read_text().splitlines()
    row = next(line for line in md if line.startswith("| design_000"))
    cell = [c.strip() for c in row.strip("| ").split("|")][header.index("shaping range (N m/rad)")]
    assert float(cell) == pytest.approx(d["objectives"]["shaping"], rel=4e-3)   # 3 significant digits


def test_front_with_shaping_and_bad_key(tmp_path, capsys):
    text = TINY.replace('objective = "shaping"', 'objective = "shaping "')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code = main(["optimise", str(path), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "optimise.objective" in err[0]
    path.write_text(TINY.replace('pareto_with = ""', 'pareto_with = "shaping"'))
    with pytest.raises(DesignError, match="pareto_with"):
        read_optimise_file(path)


#: A wider range, where the shaping range shrinks as the set grows: a trade-off between range and shaping.
FRONT = TINY.replace('objective = "shaping"', 'objective = "range"').replace(
    'pareto_with = ""', 'pareto_with = "shaping"\npareto_points = 2').replace(
    "max_tilt_deg = 10.0", "max_tilt_deg = 60.0").replace("max_torsion_deg = 5.0", "max_torsion_deg = 40.0")


def test_epsilon_front_between_range_and_shaping(tmp_path):
    path = tmp_path / "front.toml"
    path.write_text(FRONT)
    out = tmp_path / "out"
    assert main(["optimise", str(path), "--out", str(out), "--no-progress"]) == 0
    designs = json.loads((out / "result.json").read_text())["designs"]
    assert len(designs) == 2 and all(d["ok"] for d in designs)
    first, second = designs
    assert second["epsilon"]["shaping"] > first["objectives"]["shaping"]
    assert second["objectives"]["shaping"] >= second["epsilon"]["shaping"] - 1e-6    # the held value, certified
    assert second["objectives"]["range"] < first["objectives"]["range"]               # paid for in range


def test_unreachable_shaping_range_names_itself(tmp_path):
    # a held shaping range far above what any design reaches: the diagnosis (here at the start point, where
    # the epigraph rows are violated by about the held value) names the shaping range and an orientation,
    # not the hole spacing or the contacts, which come before it in the constraint vector
    from csjm_opt.design.optimisation.diagnosis import violation

    path = tmp_path / "front.toml"
    path.write_text(FRONT)
    held = read_optimise_file(path)[1]             # the front test's settings: its solver is reused
    pb = build_problem(held, ANGLES, {"platform_radius_m": 0.05}, [], {"shaping": 1000.0})
    g = pb.constraints_of(pb.x0, pb.p)
    name, angles, amount = violation(held, ANGLES, pb, pb.x0, {"g": g})
    assert name.startswith("shaping range (smallest LP range about") and angles is not None
    assert amount == pytest.approx(1000.0 / 10.0, rel=1e-9)    # T_hi = T_lo at the start: no range yet


def test_only_the_objectives_shortfall_is_tolerated(settings):
    # the shaping range as the objective may end its rounds short of the value the solve claimed (the
    # certified objective is then the dense value); held as a front's epsilon it is a requirement
    from csjm_opt.design.optimisation.dense_check import Check
    from csjm_opt.design.optimisation.shaping import objective_shortfall_only

    at = (0.0, 0.0, 0.0)
    short = Check(worst={"tension": (0.5, at), "load 2": (0.1, at), "shaping": (-0.05, at)},
                  failing=np.zeros((1, 3)), orientations=10)
    assert not short.ok and objective_shortfall_only(settings, short)
    assert not objective_shortfall_only(settings.replace(objective="range", pareto_with="shaping"), short)
    worse = Check(worst={**short.worst, "tension": (-0.5, at)}, failing=np.zeros((1, 3)), orientations=10)
    assert not objective_shortfall_only(settings, worse)
