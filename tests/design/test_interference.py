"""Interference distances against brute force, exit angles against a closed form, the [link] rig section."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from csjm_opt.design.clearance import (
    interference,
    point_segment_distance,
    pose_interference,
    segment_distance,
)
from csjm_opt.design.sampling import tilt_torsion_rotations
from csjm_opt.errors import RigFileError
from csjm_opt.model.link import DEFAULT_LINK, Link
from csjm_opt.model.rig import Rig, paper_rig


def _brute(p0, p1, q0, q1):
    """Minimum over a 101 x 101 grid of (s, t), then a bounded local refine (convex: reaches the minimum)."""
    s = np.linspace(0, 1, 101)
    P = p0 + s[:, None] * (p1 - p0)
    Q = q0 + s[:, None] * (q1 - q0)
    D = np.linalg.norm(P[:, None] - Q[None], axis=-1)
    i, j = np.unravel_index(np.argmin(D), D.shape)

    def f(x):
        g = p0 + x[0] * (p1 - p0) - q0 - x[1] * (q1 - q0)
        return g @ g

    res = minimize(f, [s[i], s[j]], bounds=[(0, 1), (0, 1)], method="L-BFGS-B",
                   options={"ftol": 1e-30, "gtol": 1e-16, "maxiter": 1000})
    return min(np.sqrt(res.fun), D[i, j])


def test_segment_distance_matches_brute_force_to_1e_9():
    rng = np.random.default_rng(3)
    cases = [rng.normal(size=(4, 3)) * 0.05 for _ in range(30)]
    a, b = rng.normal(size=3) * 0.05, rng.normal(size=3) * 0.05
    cases.append(np.array([a, b, a + [0, 0, 0.01], b + [0, 0, 0.01]]))            # parallel
    cases.append(np.array([a, b, a + 0.3 * (b - a), a + 2.0 * (b - a)]))          # collinear, overlapping
    cases.append(np.array([a, b, b + [0.01, 0, 0], b + [0.02, 0.01, 0]]))          # sharing an end region
    for p0, p1, q0, q1 in cases:
        d, s, t = segment_distance(p0, p1, q0, q1)
        assert abs(d - _brute(p0, p1, q0, q1)) < 1e-9
        assert abs(np.linalg.norm(p0 + s * (p1 - p0) - q0 - t * (q1 - q0)) - d) < 1e-15


def test_segment_distance_closed_forms_and_degenerate_points():
    # skew perpendicular lines 0.02 apart, crossing inside both segments
    d, s, t = segment_distance([-1, 0, 0], [1, 0, 0], [0, -1, 0.02], [0, 1, 0.02])
    assert d == pytest.approx(0.02, abs=1e-15) and s == pytest.approx(0.5) and t == pytest.approx(0.5)
    # a point segment against a segment: point-line distance
    d, _, _ = segment_distance([0.3, 0.4, 0], [0.3, 0.4, 0], [0, 0, 0], [1, 0, 0])
    assert d == pytest.approx(0.4, abs=1e-15)
    assert point_segment_distance([2.0, 1.0, 0.0], [0, 0, 0], [1, 0, 0]) == pytest.approx(np.sqrt(2.0))


def test_link_clearance_matches_brute_force_over_cable_points():
    rig = paper_rig()
    Rs = tilt_torsion_rotations(np.array([0.0, 0.5, 0.7]), np.array([0.0, 1.0, 4.0]), np.array([0.0, 0.3, -0.4]))
    p = pose_interference(rig, Rs)
    link = DEFAULT_LINK
    s = np.linspace(0, 1, 20001)
    for n, R in enumerate(Rs):
        for i in range(6):
            top, bot = R @ rig.platform_holes_A_m[i], rig.base_holes_B_m[i]
            pts = top + s[:, None] * (bot - top)
            # rod axis is the z axis between -rod_length and 0: distance in closed form per point
            z = np.clip(pts[:, 2], -link.rod_length_m, 0.0)
            rod = np.linalg.norm(pts - np.column_stack([0 * z, 0 * z, z]), axis=1) - link.rod_radius_m
            ball = np.linalg.norm(pts, axis=1) - link.ball_radius_m
            brute = min(rod.min(), ball.min())
            # the sampled minimum is above the exact one by at most the sampling error (spacing^2 scale)
            assert p.link_clearance_m[n, i] <= brute + 1e-12
            assert brute - p.link_clearance_m[n, i] < 1e-7
    # cable-cable distances: the same brute force as for two segments
    for n, R in enumerate(Rs[:2]):
        top = R @ rig.platform_holes_A_m.T
        d_brute = _brute(top[:, 1], rig.base_holes_B_m[1], top[:, 2], rig.base_holes_B_m[2])
        assert abs(p.cable_distance_m[n, 5] - d_brute) < 1e-9   # pair (2, 3) is the 6th pair


def test_exit_angles_at_home_pose_closed_form():
    rig = paper_rig()
    p = pose_interference(rig, np.eye(3)[None])
    c = rig.base_holes_B_m - rig.platform_holes_A_m
    expected = np.degrees(np.arctan2(np.hypot(c[:, 0], c[:, 1]), -c[:, 2]))
    assert np.allclose(p.exit_angle_deg[0, :, 0], expected, atol=1e-12)
    assert np.allclose(p.exit_angle_deg[0, :, 1], expected, atol=1e-12)
    w = interference(rig, np.eye(3)[None])
    assert w.min_cable_distance_m == pytest.approx(0.005, abs=1e-12)   # B2B3 = 5 mm, cables diverge upwards
    assert w.min_cable_distance_pair == (2, 3)


def test_rig_link_section_round_trip_and_errors(tmp_path):
    rig = paper_rig()
    assert rig.link is None and rig.link_or_default == DEFAULT_LINK
    assert "[link]" not in rig.to_toml()
    custom = rig.replace(link=Link(rod_radius_m=0.006, rod_length_m=0.05, ball_radius_m=0.009))
    path = tmp_path / "rig.toml"
    custom.to_toml(path)
    back = Rig.from_toml(path)
    assert back.link == custom.link
    data = custom.as_dict()
    data["link"] = {"rod_radius": 0.006, "rod_size": 1.0}
    with pytest.raises(RigFileError, match=r"link\.rod_size"):
        Rig.from_dict(data)
    data["link"] = {"ball_radius": -1.0}
    with pytest.raises(RigFileError, match=r"link\.ball_radius"):
        Rig.from_dict(data)


def test_sweep_records_interference_and_applies_the_rule():
    from csjm_opt.design.design_evaluation import evaluate_design
    from csjm_opt.design.sweep.spec import SweepSpec

    data = {"base": {}, "parameters": {"oo_a_m": {"values": [0.08]}},
            "sampling": {"orientations": 40, "max_tilt_deg": 20.0, "max_torsion_deg": 10.0},
            "metrics": {"shaping_poses": 0}}
    plain = SweepSpec.from_dict(data)
    rec = evaluate_design({"oo_a_m": 0.08}, plain.settings)
    assert rec["status"] == "ok"
    m = rec["metrics"]
    # the paper's cables 2 and 3 start 5 mm apart at the base and part upwards: never farther than 5 mm
    assert 0 < m["min_cable_distance_m"] <= 0.005 + 1e-12
    assert m["min_link_clearance_m"] > 0 and 0 < m["max_exit_angle_deg"] < 90
    strict = SweepSpec.from_dict({**data, "metrics": {"shaping_poses": 0, "min_cable_distance_m": 0.006}})
    assert strict.settings.digest() != plain.settings.digest()
    rec = evaluate_design({"oo_a_m": 0.08}, strict.settings)
    assert rec["status"] == "invalid" and "metrics.min_cable_distance_m" in rec["error"]


def test_certify_finds_failures_the_optimiser_never_saw():
    from csjm_opt.design.optimisation.dense_check import certify, slacks
    from csjm_opt.design.optimisation.settings import Requirements

    rig = paper_rig()
    req = Requirements(max_tilt_deg=45.0, max_torsion_deg=30.0, loads=np.array([[0.0, 0.0, 0.0], [3.0, 0, 0]]),
                       min_cable_distance_m=0.0, min_link_clearance_m=0.0, max_exit_angle_deg=90.0)
    # the paper's design does not hold the whole 45 deg / 30 deg range (sweep: workspace 0.8 or so)
    check = certify(rig, req, 1.0, 0.0, 0.0, n=400, seed=5)
    assert not check.ok and len(check.failing)
    sl = slacks(rig, check.failing, req, 0.0, 0.0)
    assert np.all(np.min(np.stack(list(sl.values())), axis=0) < 0)   # each returned orientation fails
    worst = min(check.worst.values())
    assert worst[0] < 0
    # a small range holds everywhere
    assert certify(rig, req, 0.2, 0.0, 0.0, n=400, seed=5).ok


def test_certified_tensions_are_the_planners_where_no_bound_is_active():
    from csjm_opt.design.metrics import DesignLoads, MetricOptions, evaluate_poses
    from csjm_opt.design.optimisation.dense_check import slacks
    from csjm_opt.design.optimisation.settings import Requirements

    rig = paper_rig()
    req = Requirements(max_tilt_deg=30.0, max_torsion_deg=20.0, loads=np.zeros((1, 3)))
    rng = np.random.default_rng(0)
    angles = np.column_stack([rng.uniform(0, 0.5, 40), rng.uniform(0, 6.28, 40), rng.uniform(-0.3, 0.3, 40)])
    sl = slacks(rig, angles, req, 0.0, 0.0)
    inside = sl["tension"] > 1e-6
    assert inside.sum() > 10
    pm = evaluate_poses(rig, tilt_torsion_rotations(*angles.T), DesignLoads(np.zeros((1, 3))), MetricOptions(0))
    # the planner's (active-set QP) smallest eigenvalue equals the certification's at those poses
    assert np.allclose(pm.eig_Nm_per_rad[inside, 0], sl["stiffness"][inside], rtol=1e-8, atol=1e-8)
