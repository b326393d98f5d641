"""The front in the sweep's metrics, the evaluation budget, and the multi-start on processes and Dask."""

from __future__ import annotations

import math

import numpy as np
import pytest

import csjm_opt.design.optimisation.front as front_mod
from csjm_opt.design.design_evaluation import evaluate_design
from csjm_opt.design.feasibility import wrench_margin_Nm
from csjm_opt.design.optimisation.front_model import QuadModel, best_step, model_function
from csjm_opt.design.optimisation.result import design_rig_of
from csjm_opt.design.optimisation.runner import optimise
from csjm_opt.design.optimisation.settings import read_optimise_file
from csjm_opt.design.optimisation.surrogates import MARGIN_SOFTMIN_NM, sweep_surrogate
from csjm_opt.errors import DesignError
from csjm_opt.model.numeric import Model
from tests.design_files import tiny_design_toml

TINY = tiny_design_toml(orientations=60, max_tilt_deg=40.0, max_torsion_deg=20.0,
                        tau_ext=[[0.0, 0.0, 0.0], [1.5, 0.0, 0.0]], optimise="""
objective = "stiffness"
pareto_with = ""
orientations = 4
certify_orientations = 200
starts = 2
""")


@pytest.fixture
def tiny(tmp_path):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    return read_optimise_file(path)


def test_surrogate_margins_match_the_exact_zonotope_test(tiny):
    # the smooth margin differs from the sweep's exact kernel by the soft minimum's bias only, and its sign
    # count is the sweep's workspace fraction
    spec, settings = tiny
    f = sweep_surrogate(settings, spec.settings)
    for r in (0.04, 0.05, 0.06):
        _, _, m, lam = (np.array(v).ravel() for v in f([(r - 0.04) / 0.02]))
        rig = design_rig_of(settings, {"platform_radius_m": r})
        model, Rs = Model(rig), spec.settings.sampling.rotations()
        tau = spec.settings.loads.taus_ext_A_Nm[None] + model.weight_moment(Rs)[:, None]
        exact = wrench_margin_Nm(model.jacobian(Rs), tau, rig.t_min_N, rig.t_max_N).min(axis=1)
        assert np.all(m <= exact + 1e-6) and np.all(m >= exact - MARGIN_SOFTMIN_NM * math.log(30) - 1e-6)
        rec = evaluate_design({"platform_radius_m": r}, spec.settings)
        held = exact >= 1e-3
        assert np.mean(m >= 0) == pytest.approx(rec["workspace_fraction"], abs=np.mean(np.abs(exact) < 1e-3) + 1e-12)
        if np.any(held):   # the eigenvalues are the sweep's where its planner's tensions are the least-squares ones
            assert np.min(lam[held]) == pytest.approx(rec["min_stiffness_Nm_per_rad"], rel=0.05)


def test_surrogate_gradient_matches_finite_differences(tiny):
    spec, settings = tiny
    f = sweep_surrogate(settings, spec.settings)
    import casadi as ca

    u = ca.MX.sym("u")
    F, S, _, _ = f(u)
    jac = ca.Function("j", [u], [ca.jacobian(ca.vertcat(F, S), u)])
    for u0 in (0.3, 0.7):
        h = 1e-6
        fd = (np.array(ca.vertcat(*f(u0 + h)[:2])) - np.array(ca.vertcat(*f(u0 - h)[:2]))).ravel() / (2 * h)
        assert np.allclose(np.array(jac(u0)).ravel(), fd, rtol=1e-4, atol=1e-6)


def test_max_evaluations_is_a_hard_bound_and_every_sweep_call_is_counted(tiny, monkeypatch):
    spec, settings = tiny
    calls, twins = [], []

    def counted(params, evaluation):
        calls.append(params)
        return evaluate_design(params, evaluation)

    real_model_function = front_mod.model_function

    def counted_model_function(*args):
        evaluate = real_model_function(*args)

        def wrapped(u):
            twins.append(np.array(u))
            return evaluate(u)
        return wrapped

    monkeypatch.setattr(front_mod, "evaluate_design", counted)
    monkeypatch.setattr(front_mod, "model_function", counted_model_function)
    for limit in (3, 6, 9, 14):
        calls.clear()
        twins.clear()
        res = front_mod.sweep_front(settings, spec.settings, max_evaluations=limit)
        assert len(calls) + len(twins) <= limit
        assert res.sweep_evaluations == len(calls) == len(res.records) >= 1
        assert res.twin_evaluations == len(twins) >= settings.starts
        assert res.evaluations == res.twin_evaluations + res.sweep_evaluations
        # the reported numbers are the sweep evaluator's own
        for rec in res.records:
            again = evaluate_design(rec["params"], spec.settings)
            assert rec["workspace_fraction"] == again["workspace_fraction"]
    with pytest.raises(DesignError, match="max_evaluations"):
        front_mod.sweep_front(settings, spec.settings, max_evaluations=2)


def test_model_derivatives_match_finite_differences_of_the_twins(tiny):
    spec, settings = tiny
    f = sweep_surrogate(settings, spec.settings)
    evaluate = model_function(settings, spec.settings)
    h = 1e-4
    for u0 in (0.3, 0.7):
        m = evaluate(np.array([u0]))
        F = [float(f(u0 + k * h)[0]) for k in (-1, 0, 1)]
        S = [float(f(u0 + k * h)[1]) for k in (-1, 0, 1)]
        assert m.F == pytest.approx(F[1], abs=1e-12) and m.S == pytest.approx(S[1], abs=1e-12)
        assert m.gF[0] == pytest.approx((F[2] - F[0]) / (2 * h), rel=1e-4, abs=1e-6)
        assert m.HF[0, 0] == pytest.approx((F[2] - 2 * F[1] + F[0]) / h ** 2, rel=1e-3, abs=1e-3)
        assert m.HS[0, 0] == pytest.approx((S[2] - 2 * S[1] + S[0]) / h ** 2, rel=1e-3, abs=1e-3)


def test_model_step_matches_brute_force_on_a_grid():
    # an indefinite model of S and a concave one of F, in two variables: the best step in the box and trust
    # region with F held above a floor, against the best of a fine grid of steps
    rng = np.random.default_rng(3)
    for _ in range(4):
        H = rng.normal(size=(2, 2))
        m = QuadModel(u=rng.uniform(0.2, 0.8, 2), F=0.8, S=10.0, gF=rng.normal(size=2), gS=rng.normal(size=2),
                      HF=-np.eye(2) * 3.0, HS=H + H.T)
        radius, floor = 0.15, 0.8 - 0.05
        d, feasible = best_step(m, "S", radius, floor=("F", floor))
        lo, hi = np.maximum(-m.u, -radius), np.minimum(1 - m.u, radius)
        g = np.stack(np.meshgrid(np.linspace(lo[0], hi[0], 401), np.linspace(lo[1], hi[1], 401)), -1).reshape(-1, 2)
        Fg = m.F + g @ m.gF + 0.5 * np.einsum("ni,ij,nj->n", g, m.HF, g)
        Sg = m.S + g @ m.gS + 0.5 * np.einsum("ni,ij,nj->n", g, m.HS, g)
        ok = Fg >= floor
        assert feasible == bool(ok.any())
        assert np.all(d >= lo - 1e-12) and np.all(d <= hi + 1e-12)
        assert m.predict(d)[0] >= floor - 1e-7
        assert m.predict(d)[1] >= Sg[ok].max() - 1e-6


def test_cli_max_evaluations_bounds_the_sweep_front_and_report_renders_it(tmp_path):
    import json

    from csjm_opt.cli.app import main

    path = tmp_path / "t.toml"
    path.write_text(TINY)
    out = tmp_path / "out"
    assert main(["optimise", str(path), "--out", str(out), "--sweep-front", "--max-evaluations", "10",
                 "--no-progress"]) == 0
    doc = json.loads((out / "result.json").read_text())
    assert doc["evaluations"] <= 10 and doc["front"]
    assert (out / doc["front"][0]["rig_file"]).is_file()
    # csjm report renders the folder like a sweep result: its Pareto front is the records' (brute force here)
    assert main(["report", str(out), "--out", str(tmp_path / "rep")]) == 0
    rep = json.loads((tmp_path / "rep" / "design_report.json").read_text())
    pts = [(r["workspace_fraction"], r["min_stiffness_Nm_per_rad"]) for r in doc["records"]
           if r["status"] == "ok" and r["workspace_fraction"] and r["min_stiffness_Nm_per_rad"] is not None]
    front = {p for p in pts if not any(q[0] >= p[0] and q[1] >= p[1] and q != p for q in pts)}
    assert {(r["workspace_fraction"], r["min_stiffness_Nm_per_rad"]) for r in rep["pareto_front"]} == front
    assert rep["designs"] == len({r["id"] for r in doc["records"]})
    assert (tmp_path / "rep" / "index.html").is_file() and (tmp_path / "rep" / "pareto.png").is_file()


def _same_designs(a, b):
    assert len(a.designs) == len(b.designs)
    for x, y in zip(a.designs, b.designs):
        for k in x.params:
            assert x.params[k] == pytest.approx(y.params[k], rel=1e-9, abs=1e-12)


def test_multistart_on_processes_and_dask_gives_the_serial_designs(tmp_path):
    # the small range of tests/design/optimisation/test_runner.py: its optimum is known (radius on its upper bound)
    path = tmp_path / "small.toml"
    path.write_text(TINY.replace("max_tilt_deg = 40.0", "max_tilt_deg = 10.0").replace(
        "max_torsion_deg = 20.0", "max_torsion_deg = 5.0").replace("[1.5, 0.0, 0.0]", "[0.5, 0.0, 0.0]"))
    _, settings = read_optimise_file(path)
    starts = [{"platform_radius_m": 0.041}, {"platform_radius_m": 0.052}]
    serial = optimise(settings, starts=starts, workers=1, progress=False)
    pooled = optimise(settings, starts=starts, workers=2, progress=False)
    _same_designs(serial, pooled)
    assert serial.designs[0].params["platform_radius_m"] == pytest.approx(0.06, abs=1e-6)
    assert serial.evaluations == pooled.evaluations
    pytest.importorskip("distributed")
    on_dask = optimise(settings, starts=starts, workers=1, dask=True, progress=False)
    _same_designs(serial, on_dask)


def _two_bumps(u: np.ndarray) -> QuadModel:
    """A toy F with two basins: a narrow lower bump (0.86 at (0.15, 0.85)) and a wide higher one (0.87 at
    (0.8, 0.2)); value, exact gradient and Hessian (S is flat)."""
    F, g, H = 0.0, np.zeros(2), np.zeros((2, 2))
    for a, c, s in ((0.86, np.array([0.15, 0.85]), 0.12), (0.87, np.array([0.8, 0.2]), 0.3)):
        r = u - c
        e = a * math.exp(-r @ r / (2 * s * s))
        F += e
        g += -e * r / s ** 2
        H += e * (np.outer(r, r) / s ** 4 - np.eye(2) / s ** 2)
    return QuadModel(np.array(u, float), F, 0.0, g, np.zeros(2), H, np.zeros((2, 2)))


def test_race_ascends_to_the_largest_local_maximum_not_from_the_best_start():
    # the start of largest F sits in the lower bump's basin; the global maximum, found by brute force on a
    # grid, is the other bump's: the race (two starts ascended) must reach it, the best start alone must not
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 401)), -1).reshape(-1, 2)
    values = np.array([_two_bumps(u).F for u in grid])
    u_max = grid[np.argmax(values)]
    starts = [np.array([0.2, 0.8]), np.array([0.5, 0.1]), np.array([0.45, 0.55])]
    assert max(range(3), key=lambda k: _two_bumps(starts[k]).F) == 0      # the best start: the lower basin
    for race, limit in ((2, 22), (1, 22)):
        work = front_mod._Work(limit, _two_bumps, None, None)
        models = [work.twins(u) for u in starts]
        anchors, rest = front_mod.race_starts(work, models, race, 6)
        assert work.twins_n <= limit
        assert len(anchors) + len(rest) == 3
        if race == 2:
            assert np.max(np.abs(anchors[0].u - u_max)) < 0.02
            assert anchors[0].F >= values.max() - 1e-3
            assert len(anchors) == 2 and np.max(np.abs(anchors[1].u - np.array([0.15, 0.85]))) < 0.02
        else:
            assert np.max(np.abs(anchors[0].u - np.array([0.15, 0.85]))) < 0.02


def test_race_stops_an_ascent_that_reaches_a_known_maximum():
    # two starts in the wide bump's basin: the second ascent stops within APART of the first's maximum,
    # so it costs fewer evaluations than the same ascent alone, and the race reports one maximum
    starts = [np.array([0.5, 0.1]), np.array([0.45, 0.55])]
    work = front_mod._Work(None, _two_bumps, None, None)
    anchors, _ = front_mod.race_starts(work, [work.twins(u) for u in starts], 2, 6)
    raced = work.twins_n - 2
    alone = front_mod._Work(None, _two_bumps, None, None)
    solo = [front_mod.ascent(alone, alone.twins(u), "F", front_mod.ANCHOR_STEPS, keep=0) for u in starts]
    assert len(anchors) == 1 and np.max(np.abs(anchors[0].u - solo[0].u)) < 1e-9
    assert np.max(np.abs(solo[1].u - solo[0].u)) < front_mod.APART      # the same maximum, independently
    assert raced < alone.twins_n - 2


def _two_bumps_S(u):
    """The two bumps as the stiffness S (F = 1 everywhere: every design holds poses)."""
    m = _two_bumps(u)
    return QuadModel(m.u, 1.0, m.F, np.zeros(2), m.gF, np.zeros((2, 2)), m.HF)


def test_stiffest_end_is_raced_like_the_first_end():
    # the stiffest evaluated design sits in the lower bump's basin: racing two designs reaches the global
    # maximum of S (brute force on a grid), one alone does not; both maxima are scored
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 401)), -1).reshape(-1, 2)
    u_max = grid[np.argmax([_two_bumps(u).F for u in grid])]
    for race in (2, 1):
        work = front_mod._Work(22, _two_bumps_S, None, None)
        scored = []
        work.score = lambda u, eps, model: scored.append(np.array(u))     # the sweep's evaluator is not needed
        for u in (np.array([0.2, 0.8]), np.array([0.5, 0.1]), np.array([0.45, 0.55])):
            work.twins(u)
        end = front_mod._stiffest(work, work.models[0], race)
        assert work.twins_n <= 22
        if race == 2:
            assert np.max(np.abs(end.u - u_max)) < 0.02
            assert len(scored) == 2
        else:
            assert np.max(np.abs(end.u - np.array([0.15, 0.85]))) < 0.02


def test_hypervolume_is_the_area_of_the_union_of_dominated_rectangles():
    import numpy as np

    from csjm_opt.design.optimisation.front import hypervolume

    rng = np.random.default_rng(5)
    pts = rng.uniform(0.05, 1.0, (7, 2))
    grid = (np.arange(400) + 0.5) / 400                     # midpoint rule over [0, 1]^2
    X, Y = np.meshgrid(grid, grid)
    covered = np.zeros_like(X, bool)
    for x, y in pts:
        covered |= (X <= x) & (Y <= y)
    assert abs(hypervolume(pts) - covered.mean()) < 0.01
    assert hypervolume(np.array([[2.0, 1.0], [1.0, 2.0], [-1.0, 5.0]])) == 3.0
