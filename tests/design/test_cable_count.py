"""The design layer for m cables: hole pairs against the rig file's pattern, m as a sweep axis, the zonotope,
the shaping range and cable interference for m != 6, each against an independent computation."""

from __future__ import annotations

import itertools
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from csjm_opt.design.clearance import cable_pairs, pose_interference
from csjm_opt.design.design_evaluation import evaluate_design
from csjm_opt.design.feasibility import wrench_margin_Nm
from csjm_opt.design.geometry import design_holes, design_rig
from csjm_opt.design.metrics import evaluate, stiffness_affine_parts
from csjm_opt.design.sampling import OrientationSampling, tilt_torsion_rotations
from csjm_opt.design.shaping_range import directional_stiffness_range
from csjm_opt.design.sweep.spec import SweepSpec
from csjm_opt.errors import DesignError
from csjm_opt.model.hole_pattern import expand_pattern
from csjm_opt.model.numeric import Model
from csjm_opt.model.rig import Rig

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("m", [4, 8, 12])
def test_hole_pairs_are_the_rig_files_pair_pattern(m):
    # the design's m/2 pairs (radius, gamma, theta0, heights) against the rig file's [geometry.pattern]
    # expansion (csjm_opt.model.hole_pattern, written separately)
    params = {"n_cables": m, "platform_radius_m": 0.05, "platform_gamma_deg": 11.0, "base_radius_m": 0.07,
              "base_gamma_deg": 0.8 * 720 / m, "platform_theta0_deg": 17.0, "base_theta0_deg": 17.0,
              "oo_a_m": 0.07, "oo_b_m": 0.09}
    A, B = design_holes(params)
    A_ref, B_ref = expand_pattern({"count": m, "platform_radius": 0.05, "base_radius": 0.07,
                                   "platform_height": 0.07, "base_height": -0.09, "platform_pair_angle_deg": 11.0,
                                   "base_pair_angle_deg": 0.8 * 720 / m, "phase_deg": 17.0})
    assert A.shape == B.shape == (m, 3)
    np.testing.assert_allclose(A, A_ref, atol=1e-15)
    np.testing.assert_allclose(B, B_ref, atol=1e-15)


@pytest.mark.parametrize("m", [4, 5, 7, 8, 11])
def test_chords_give_the_circle_whose_pair_chords_they_are(m):
    A, _ = design_holes({"n_cables": m, "platform_d12_m": 0.01, "platform_d23_m": 0.05})
    chords = np.linalg.norm(A - np.roll(A, -1, axis=0), axis=1)
    pairs = 2 * (m // 2)                                          # odd m: the last hole is single
    np.testing.assert_allclose(chords[0:pairs:2], 0.01, atol=1e-12)   # within a pair
    np.testing.assert_allclose(chords[1:pairs - 1:2], 0.05, atol=1e-12)   # between pairs
    if m % 2:
        # the single hole: d23 after the last pair, 360/m deg before hole 1 on the same circle
        radius = np.linalg.norm(A[0, :2])
        assert np.allclose(np.linalg.norm(A[:, :2], axis=1), radius, rtol=1e-12)
        assert chords[-1] == pytest.approx(2 * radius * np.sin(np.pi / m), rel=1e-12)
        np.testing.assert_allclose(chords[pairs - 1], 0.05, atol=1e-12)


@pytest.mark.parametrize("m", [5, 7, 9, 11])
def test_an_odd_count_continues_the_pairs_with_a_single_hole(m):
    """Odd m: the design's layout, the rig file's pair-angle pattern, and the pair rule written out here agree."""
    gamma, theta0 = 0.3 * 720 / m, 17.0
    A, _ = design_holes({"n_cables": m, "platform_radius_m": 0.05, "platform_gamma_deg": gamma,
                         "platform_theta0_deg": theta0, "oo_a_m": 0.07})
    angles = np.degrees(np.arctan2(A[:, 1], A[:, 0]))
    centres = theta0 + np.arange(m) // 2 * 720.0 / m          # pair j = i // 2 centred at theta0 + j 720/m
    want = centres + np.where(np.arange(m) % 2 == 0, -gamma / 2, gamma / 2)
    np.testing.assert_allclose(np.angle(np.exp(1j * np.radians(angles - want))), 0.0, atol=1e-12)
    np.testing.assert_allclose(A[:, 2], 0.07)
    A_file, _ = expand_pattern({"count": m, "platform_radius": 0.05, "base_radius": 0.07, "platform_height": 0.07,
                                "base_height": -0.09, "platform_pair_angle_deg": gamma, "phase_deg": theta0})
    np.testing.assert_allclose(A, A_file, atol=1e-15)


def test_bad_cable_counts_name_the_key():
    for params, key in (({"n_cables": 3}, "n_cables"), ({"n_cables": 6.5}, "n_cables"),
                        ({"n_cables": 4, "A5_dx_m": 0.001}, "A5_dx_m"),
                        ({"n_cables": 8, "platform_radius_m": 0.05, "platform_gamma_deg": 95.0},
                         "platform_radius_m")):
        with pytest.raises(DesignError) as exc:
            design_rig(params)
        assert exc.value.key == key


def _sweep(text: str) -> SweepSpec:
    return SweepSpec.from_dict(tomllib.loads(text))


SWEEP = """
[sweep]
method = "grid"
[base]
platform_radius_m = 0.06
base_radius_m = 0.075
platform_gamma_deg = 10.0
base_gamma_deg = 80.0
platform_mass_kg = 0.55
oo_a_m = 0.08
oo_b_m = 0.08
[parameters.n_cables]
values = [4, 6, 8]
[sampling]
orientations = 120
max_tilt_deg = 30.0
max_torsion_deg = 20.0
[loads]
tau_ext = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]
[metrics]
shaping_poses = 4
"""


def test_a_sweep_over_the_cable_count_scores_the_rig_files_of_each_count():
    # the 8-cable design of the sweep is the shipped rigs/eight_cable.toml (pattern form): the sweep's record
    # equals the metrics of the rig file read by the rig loader, and the six-cable record the hexagon's
    spec = _sweep(SWEEP)
    recs = {int(d["n_cables"]): evaluate_design(d, spec.settings) for d in spec.designs()}
    assert sorted(recs) == [4, 6, 8] and all(r["status"] == "ok" for r in recs.values())
    s = spec.settings
    rig8 = Rig.from_toml(ROOT / "rigs" / "eight_cable.toml")
    ref = evaluate(rig8, s.sampling, s.loads, s.options).as_dict()
    for key in ("workspace_fraction", "min_stiffness_Nm_per_rad", "tilt_cone_deg", "min_cable_distance_m"):
        assert recs[8]["metrics"][key] == pytest.approx(ref[key], rel=1e-12, abs=1e-12), key
    six = evaluate_design({}, spec.settings)                        # no n_cables: the paper's hexagon layout
    untimed = lambda rec: {k: v for k, v in rec["metrics"].items() if k != "seconds"}  # noqa: E731
    assert untimed(six) == untimed(recs[6])
    # more cables through the same circles widen the moment zonotope: the workspace does not shrink
    assert recs[4]["workspace_fraction"] <= recs[8]["workspace_fraction"]


def test_integer_axis_draws_integers_and_bad_values_name_the_key():
    text = SWEEP.replace('method = "grid"', 'method = "lhs"\ndesigns = 600').replace(
        "values = [4, 6, 8]", "min = 4\nmax = 8")
    counts = [d["n_cables"] for d in _sweep(text).designs()]
    assert set(counts) == {4.0, 5.0, 6.0, 7.0, 8.0}
    assert all(abs(np.mean(np.array(counts) == m) - 0.2) < 0.02 for m in range(4, 9))   # Latin hypercube: even
    grid = _sweep(SWEEP.replace("values = [4, 6, 8]", "min = 4\nmax = 12\nnum = 5")).designs()
    assert [d["n_cables"] for d in grid] == [4.0, 6.0, 8.0, 10.0, 12.0]
    for old, new, key in (("values = [4, 6, 8]", "values = [4, 6.5]", "parameters.n_cables.values"),
                          ("values = [4, 6, 8]", "values = [3, 6]", "parameters.n_cables.values"),
                          ("values = [4, 6, 8]", "min = 4\nmax = 8\nnum = 4", "parameters.n_cables.num"),
                          ("values = [4, 6, 8]", "min = 4\nmax = 13\nnum = 10", "parameters.n_cables.max")):
        with pytest.raises(DesignError) as exc:
            _sweep(SWEEP.replace(old, new))
        assert exc.value.key == key, (new, exc.value.key)


@pytest.mark.parametrize("m", [4, 5, 8, 12])
def test_zonotope_margin_sign_is_the_lp_verdict(m):
    rng = np.random.default_rng(m)
    t_min, t_max = 5.0, 150.0
    agree = 0
    for _ in range(40):
        J = rng.normal(size=(m, 3))
        load = -J.T @ (t_min + rng.uniform(-0.3, 1.3, m) * (t_max - t_min))
        margin = wrench_margin_Nm(J[None], load[None], t_min, t_max)[0]
        if abs(margin) < 1e-6:
            continue
        res = linprog(np.zeros(m), A_eq=J.T, b_eq=-load, bounds=[(t_min, t_max)] * m, method="highs")
        assert (margin > 0) == (res.status == 0)
        agree += 1
    assert agree >= 35


@pytest.mark.parametrize("m", [4, 8, 12])
def test_shaping_range_of_m_cables_solves_the_lps(m):
    rig = design_rig({"n_cables": m, "platform_radius_m": 0.06, "platform_gamma_deg": 10.0,
                      "base_radius_m": 0.075, "base_gamma_deg": 0.6 * 720 / m})
    model = Model(rig)
    Rs = OrientationSampling(n=4, max_tilt_deg=20.0, seed=4).rotations()
    K0, Ki = stiffness_affine_parts(model, Rs)
    J = model.jacobian(Rs)
    tau = np.array([0.5, 0.0, 0.0]) + model.weight_moment(Rs)
    U = np.eye(3)
    lo, hi = directional_stiffness_range(J, tau, K0, Ki, rig.t_min_N, rig.t_max_N, U)
    held = 0
    for p in range(len(Rs)):
        for d, u in enumerate(U):
            c = np.einsum("j,ijk,k->i", u, Ki[p], u)
            kw = dict(A_eq=J[p].T, b_eq=-tau[p], bounds=[(rig.t_min_N, rig.t_max_N)] * m, method="highs")
            lp_lo, lp_hi = linprog(c, **kw), linprog(-c, **kw)
            if lp_lo.status == 2:                          # no tensions in the box hold the load: NaN
                assert lp_hi.status == 2 and np.isnan(lo[p, d]) and np.isnan(hi[p, d])
                continue
            held += 1
            assert lp_lo.status == 0 and lp_hi.status == 0
            assert lo[p, d] == pytest.approx(u @ K0[p] @ u + lp_lo.fun, abs=1e-7)
            assert hi[p, d] == pytest.approx(u @ K0[p] @ u - lp_hi.fun, abs=1e-7)
    assert held >= 3


@pytest.mark.parametrize("m", [4, 8, 12])
def test_cable_interference_of_m_cables_matches_brute_force(m):
    rig = design_rig({"n_cables": m, "platform_radius_m": 0.05, "platform_gamma_deg": 8.0,
                      "base_radius_m": 0.075, "base_gamma_deg": 0.7 * 720 / m})
    Rs = tilt_torsion_rotations(np.array([0.0, 0.4]), np.array([0.0, 2.0]), np.array([0.0, 0.3]))
    p = pose_interference(rig, Rs)
    pairs = cable_pairs(m)
    assert p.cable_distance_m.shape == (2, m * (m - 1) // 2) and p.link_clearance_m.shape == (2, m)
    assert [tuple(q) for q in pairs] == list(itertools.combinations(range(m), 2))
    s = np.linspace(0.0, 1.0, 401)
    for n, R in enumerate(Rs):
        top, bot = (R @ rig.platform_holes_A_m.T).T, rig.base_holes_B_m
        pts = top[:, None] + s[None, :, None] * (bot - top)[:, None]          # (m, 401, 3)
        for k, (i, j) in enumerate(pairs):
            brute = np.linalg.norm(pts[i][:, None] - pts[j][None], axis=-1).min()
            # the sampled minimum lies above the exact one by at most the sample spacing
            spacing = (np.linalg.norm((bot - top)[i]) + np.linalg.norm((bot - top)[j])) / 400
            assert p.cable_distance_m[n, k] <= brute + 1e-12
            assert brute - p.cable_distance_m[n, k] < spacing


def test_an_odd_count_sweeps_by_free_coordinates():
    # five cables (no pairs): holes as free coordinates from a rig file pattern (platform evenly spaced, base
    # holes turned +-35 deg alternately); each record of the stiffness axis is the rig file's
    platform = np.arange(5) * 72.0
    A, B = expand_pattern({"count": 5, "platform_radius": 0.06, "base_radius": 0.08, "platform_height": 0.08,
                           "base_height": -0.08, "platform_angles_deg": platform.tolist(),
                           "base_angles_deg": (platform + 35.0 * np.array([1, -1, 1, -1, 1])).tolist()})
    text = SWEEP.replace("[parameters.n_cables]\nvalues = [4, 6, 8]",
                         "[parameters.cable_stiffness_N_per_m]\nvalues = [3000.0, 4600.0]").replace(
        "platform_radius_m = 0.06\nbase_radius_m = 0.075\nplatform_gamma_deg = 10.0\nbase_gamma_deg = 80.0\n",
        f"platform_holes = {A.tolist()}\nbase_holes = {B.tolist()}\n")
    spec = _sweep(text)
    s = spec.settings
    for d in spec.designs():
        rec = evaluate_design(d, s)
        assert rec["status"] == "ok"
        rig = Rig.from_dict({"geometry": {"platform_holes": A.tolist(), "base_holes": B.tolist()},
                             "cables": {"stiffness": [d["cable_stiffness_N_per_m"]] * 5, "t_min": 5.0, "t_max": 150.0},
                             "platform": {"mass": 0.55, "com": [0.0, 0.0, 0.081], "gravity": [0.0, 0.0, -9.81]}})
        ref = evaluate(rig, s.sampling, s.loads, s.options).as_dict()
        assert rec["metrics"]["workspace_fraction"] == ref["workspace_fraction"] > 0
        assert rec["metrics"]["min_stiffness_Nm_per_rad"] == pytest.approx(ref["min_stiffness_Nm_per_rad"], rel=1e-12)


@pytest.mark.parametrize("m", [5, 7, 9])
def test_dual_feasible_bases_give_the_exhaustive_range(m):
    # above six cables the range takes one dual-feasible candidate per basis, direction and sense: against the
    # numpy enumeration of every basic solution (C(m, 3) 2^(m - 3) per pose), held poses and empty ones alike
    from csjm_opt.design.shaping_range import (
        _range_kernel_dual,
        _tables,
        directional_stiffness_range_reference,
    )

    rng = np.random.default_rng(m)
    J = rng.normal(size=(60, m, 3)) * 0.05
    tau = rng.normal(size=(60, 3)) * 2.0
    K0 = rng.normal(size=(60, 3, 3))
    Ki = rng.normal(size=(60, m, 3, 3)) * 1e-2
    U = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.6, 0.0, 0.8]])
    lo, hi = directional_stiffness_range_reference(J, tau, K0, Ki, 5.0, 150.0, U)
    c0 = np.einsum("dj,njk,dk->nd", U, K0, U)
    ci = np.ascontiguousarray(np.einsum("dj,nijk,dk->nid", U, Ki, U))
    lo2, hi2 = np.empty(c0.shape), np.empty(c0.shape)
    _range_kernel_dual(J, -tau, 5.0, 150.0, 1e-9, _tables(m)[0], c0, ci, lo2, hi2)
    assert np.array_equal(np.isnan(lo), np.isnan(lo2)) and 5 < np.sum(~np.isnan(lo)) < lo.size
    np.testing.assert_allclose(lo2, lo, atol=1e-9)
    np.testing.assert_allclose(hi2, hi, atol=1e-9)
