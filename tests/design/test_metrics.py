"""Design metrics: exact feasibility vs the planner and an LP, margins, shaping range, density."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

import csjm_opt as co
from csjm_opt.design import (
    DesignLoads,
    MetricOptions,
    OrientationSampling,
    design_rig,
    evaluate,
    evaluate_poses,
)
from csjm_opt.design.geometry import GeometryLimits
from csjm_opt.design.metrics import stiffness_affine_parts
from csjm_opt.design.shaping_range import directional_stiffness_range
from csjm_opt.design.sweep.runner import evaluate_design
from csjm_opt.design.sweep.spec import EvaluationSettings

#: The load set of studies/paper_sweep/paper_sweep.toml (N m, {A}, weight excluded).
LOADS = DesignLoads(np.array([[0, 0, 0], [3, 0, 0], [-3, 0, 0], [0, 3, 0], [0, -3, 0], [0, 0, 1], [0, 0, -1.0]]))
ODD_DESIGN = {"platform_radius_m": 0.06, "platform_gamma_deg": 40.0, "base_theta0_deg": 10.0,
              "A2_dz_m": 0.005, "B5_dx_m": -0.004}


def _lp_feasible(J: np.ndarray, tau_load: np.ndarray, rig: co.Rig) -> bool:
    res = linprog(np.zeros(6), A_eq=J.T, b_eq=-tau_load, bounds=[(rig.t_min_N, rig.t_max_N)] * 6,
                  method="highs")
    assert res.status in (0, 2), res.message
    return res.status == 0


@pytest.mark.parametrize("params", [{}, ODD_DESIGN], ids=["paper", "odd"])
def test_feasibility_agrees_with_planner_and_lp_on_every_sample(params):
    rig = design_rig(params)
    model = co.Model(rig)
    Rs = OrientationSampling(n=90, max_tilt_deg=60.0, max_torsion_deg=40.0, seed=3).rotations()
    pm = evaluate_poses(rig, Rs, LOADS, model=model)
    margin = pm.wrench_margin_Nm
    assert np.min(np.abs(margin)) > 1e-6          # no sample sits on the boundary: verdicts are sharp
    verdict = margin >= 0
    assert 0.2 < verdict.all(axis=1).mean() < 0.95  # a test design with both kinds of poses
    for i, R in enumerate(Rs):
        J = model.jacobian(R)
        tau_w = model.weight_moment(R)
        for j, tau in enumerate(LOADS.taus_ext_A_Nm):
            try:
                co.plan_tensions(rig, R, tau, model=model)
                planner = True
            except co.InfeasibleLoad:
                planner = False
            assert planner == verdict[i, j] == _lp_feasible(J, tau + tau_w, rig), (i, j, margin[i, j])
    np.testing.assert_array_equal(pm.feasible, verdict.all(axis=1))


def test_wrench_margin_is_the_signed_distance_to_the_convex_hull_of_box_corners(rig, model):
    """Independent H-representation: qhull of the 64 images J^T T of the tension box corners."""
    Rs = OrientationSampling(n=12, max_tilt_deg=50.0, seed=1).rotations()
    pm = evaluate_poses(rig, Rs, LOADS, model=model)
    corners = rig.t_min_N + (rig.t_max_N - rig.t_min_N) * np.array(list(itertools.product((0, 1), repeat=6)))
    inside = 0
    for i, R in enumerate(Rs):
        hull = ConvexHull(corners @ model.jacobian(R))   # facets: unit normal n, offset c, n.x + c <= 0
        w = -(LOADS.taus_ext_A_Nm + model.weight_moment(R))
        dist = -(w @ hull.equations[:, :3].T + hull.equations[:, 3])   # (loads, facets)
        for j in range(len(w)):
            if dist[j].min() > 0:                        # inside: margin = distance to the boundary
                assert pm.wrench_margin_Nm[i, j] == pytest.approx(dist[j].min(), rel=1e-9, abs=1e-9)
                inside += 1
            else:
                assert pm.wrench_margin_Nm[i, j] < 0
    assert inside > 20


def test_planned_tensions_and_stiffness_match_the_planner(rig, model):
    Rs = OrientationSampling(n=40, max_tilt_deg=45.0, seed=2).rotations()
    pm = evaluate_poses(rig, Rs, LOADS, model=model)
    for i in np.flatnonzero(pm.feasible)[:10]:
        plan = co.plan_tensions(rig, Rs[i], LOADS.taus_ext_A_Nm[0], model=model)
        np.testing.assert_allclose(pm.tensions_N[i], plan.tensions_N, atol=1e-6)
        np.testing.assert_allclose(pm.K[i], co.stiffness(rig, Rs[i], plan.tensions_N), atol=1e-9)


def test_shaping_range_solves_the_lps(rig, model):
    Rs = OrientationSampling(n=6, max_tilt_deg=30.0, seed=4).rotations()
    K0, Ki = stiffness_affine_parts(model, Rs)
    T = np.random.default_rng(1).uniform(5, 150, size=6)
    for R, k0, ki in zip(Rs, K0, Ki):                  # K is affine in the tensions
        np.testing.assert_allclose(k0 + np.einsum("i,ijk->jk", T, ki), co.stiffness(rig, R, T), atol=1e-9)
    J = model.jacobian(Rs)
    tau_load = LOADS.taus_ext_A_Nm[1] + model.weight_moment(Rs)
    U = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0.6, 0, 0.8]])
    lo, hi = directional_stiffness_range(J, tau_load, K0, Ki, rig.t_min_N, rig.t_max_N, U)
    for p in range(len(Rs)):
        for d, u in enumerate(U):
            c = np.einsum("j,ijk,k->i", u, Ki[p], u)
            const = u @ K0[p] @ u
            kw = dict(A_eq=J[p].T, b_eq=-tau_load[p], bounds=[(rig.t_min_N, rig.t_max_N)] * 6, method="highs")
            lp_lo, lp_hi = linprog(c, **kw), linprog(-c, **kw)
            assert lp_lo.status == 0 and lp_hi.status == 0
            assert lo[p, d] == pytest.approx(const + lp_lo.fun, abs=1e-7)
            assert hi[p, d] == pytest.approx(const - lp_hi.fun, abs=1e-7)


def test_paper_design_metrics_are_stable_to_sampling_density(rig):
    """Tolerance (README): 1,000 orientations (three seeds) against a 32,000-orientation reference.

    With the paper sweep's settings (tilt <= 45 deg, |torsion| <= 30 deg, its 7 loads):
    workspace fraction within 0.01 (absolute), tilt cone within 1.5 deg, minimum
    smallest eigenvalue of K within 2.5 %, its median within 0.5 %, largest
    condition number within 8 %.
    """
    fine = evaluate(rig, OrientationSampling(32000, 45.0, 30.0, seed=99), LOADS)
    for seed in range(3):
        coarse = evaluate(rig, OrientationSampling(1000, 45.0, 30.0, seed=seed), LOADS)
        assert abs(coarse.workspace_fraction - fine.workspace_fraction) <= 0.01
        assert abs(coarse.tilt_cone_deg - fine.tilt_cone_deg) <= 1.5
        assert coarse.min_stiffness_Nm_per_rad == pytest.approx(fine.min_stiffness_Nm_per_rad, rel=0.025)
        assert coarse.median_min_stiffness_Nm_per_rad == pytest.approx(fine.median_min_stiffness_Nm_per_rad,
                                                                       rel=0.005)
        assert coarse.max_condition == pytest.approx(fine.max_condition, rel=0.08)
    assert 0.5 < fine.workspace_fraction < 1.0 and fine.stable_fraction == 1.0


def test_metric_laws(rig):
    few = DesignLoads(np.zeros((1, 3)))
    m_few = evaluate(rig, OrientationSampling(300, 45.0, 30.0), few)
    m_all = evaluate(rig, OrientationSampling(300, 45.0, 30.0), LOADS)
    assert m_all.workspace_fraction <= m_few.workspace_fraction    # more loads, never more workspace
    assert m_all.tilt_cone_deg <= m_few.tilt_cone_deg + 1e-9
    # the home pose under no external load: mid-range tensions hold it (3-fold symmetry, com on axis)
    assert m_few.home_tension_margin_N == pytest.approx(0.5 * (rig.t_max_N - rig.t_min_N))
    lo, hi = m_all.shaping_range_Nm_per_rad["z"]
    assert lo <= m_all.median_torsion_stiffness_Nm_per_rad * 1.5 and lo < hi
    metrics = evaluate(rig, OrientationSampling(100), few, MetricOptions(shaping_poses=0))
    assert metrics.shaping_range_Nm_per_rad["x"][0] != 0


def test_invalid_design_is_recorded_not_raised():
    settings = EvaluationSettings(base={}, sampling=OrientationSampling(50), loads=LOADS,
                                  options=MetricOptions(), limits=GeometryLimits())
    record = evaluate_design({"platform_d12_m": 0.0002}, settings)
    assert record["status"] == "invalid" and "platform_holes" in record["error"]
    assert record["workspace_fraction"] is None


def test_shaping_range_agrees_with_the_shaping_modules_lps(rig, model):
    """Cross-check with issue 5's per-pose HiGHS LPs (csjm_opt.shaping.reachable), its own K basis."""
    reachable = pytest.importorskip("csjm_opt.shaping.reachable")
    shaping = pytest.importorskip("csjm_opt.shaping.shaper")
    Rs = OrientationSampling(n=5, max_tilt_deg=35.0, seed=9).rotations()
    K0, Ki = stiffness_affine_parts(model, Rs)
    J = model.jacobian(Rs)
    tau_load = LOADS.taus_ext_A_Nm[3] + model.weight_moment(Rs)
    U = np.eye(3)
    lo, hi = directional_stiffness_range(J, tau_load, K0, Ki, rig.t_min_N, rig.t_max_N, U)
    for p, R in enumerate(Rs):
        ref = reachable.directional_range(shaping.stiffness_basis(rig, R), tau_load[p], U, rig.t_min_N, rig.t_max_N)
        np.testing.assert_allclose(np.column_stack([lo[p], hi[p]]), ref, rtol=1e-7, atol=1e-7)
