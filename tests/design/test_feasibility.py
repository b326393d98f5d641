"""Laws of the exact zonotope feasibility test (any Jacobian, any load)."""

from __future__ import annotations

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.optimize import linprog

import csjm_opt as co
from csjm_opt.design.feasibility import feasible, wrench_margin_Nm
from csjm_opt.design.shaping_range import vertices

finite = st.floats(-1.0, 1.0, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(J=arrays(float, (6, 3), elements=finite), s=arrays(float, (6,), elements=st.floats(-0.6, 1.6)),
       t_min=st.floats(0.0, 20.0), span=st.floats(1.0, 200.0))
def test_margin_sign_is_the_lp_verdict_and_vertices_exist_iff_feasible(J, s, t_min, span):
    t_max = t_min + span
    load = -J.T @ (t_min + s * span)      # the moment of tensions partly outside the box: both verdicts occur
    margin = wrench_margin_Nm(J[None], load[None], t_min, t_max)[0]
    assume(np.linalg.svd(J, compute_uv=False)[-1] > 1e-3 and abs(margin) > 1e-6)
    res = linprog(np.zeros(6), A_eq=J.T, b_eq=-load, bounds=[(t_min, t_max)] * 6, method="highs")
    assert res.status in (0, 2)
    assert (margin > 0) == (res.status == 0)
    _, ok = vertices(J[None], load[None], t_min, t_max)
    assert ok.any() == (margin > 0)


@settings(max_examples=40, deadline=None)
@given(J=arrays(float, (6, 3), elements=finite), T=arrays(float, (6,), elements=st.floats(0.0, 1.0)))
def test_moments_of_admissible_tensions_are_inside(J, T):
    t_min, t_max = 5.0, 150.0
    T = t_min + T * (t_max - t_min)
    tau_load = -(J.T @ T)                               # held exactly by T
    assume(np.linalg.svd(J, compute_uv=False)[-1] > 1e-3)
    assert wrench_margin_Nm(J[None], tau_load[None], t_min, t_max)[0] >= -1e-9
    # scaling the load far out always leaves the set
    assert not feasible(J[None], (1e6 * (tau_load + 1.0))[None], t_min, t_max)[0]


def test_rank_deficient_jacobian_is_infeasible():
    J = np.zeros((6, 3))
    J[:, :2] = np.random.default_rng(0).normal(size=(6, 2))   # all moments in the x-y plane
    assert wrench_margin_Nm(J[None], np.zeros((1, 3)), 5.0, 150.0)[0] == -np.inf


def test_compiled_margin_equals_numpy_reference():
    from csjm_opt.design.feasibility import wrench_margin_reference

    rig = co.paper_rig()
    rng = np.random.default_rng(8)
    Rs = co.so3.random_rotations(300, rng, max_angle=0.9)
    J = co.Model(rig).jacobian(Rs)
    J[0] = np.outer(np.arange(6.0), [1.0, 0.0, 0.0])        # rank 1: -inf in both
    tau = rng.normal(size=(300, 7, 3)) * 2.0
    a = wrench_margin_Nm(J, tau, rig.t_min_N, rig.t_max_N)
    b = wrench_margin_reference(J, tau, rig.t_min_N, rig.t_max_N)
    assert np.array_equal(np.isinf(a), np.isinf(b)) and np.all(a[0] == -np.inf)
    assert np.abs(a[1:] - b[1:]).max() <= 1e-12 * np.abs(b[1:]).max()
    assert np.allclose(wrench_margin_Nm(J, tau[:, 0], 5.0, 150.0), a[:, 0])


def test_compiled_shaping_range_equals_numpy_reference():
    from csjm_opt.design import shaping_range

    rig = co.paper_rig()
    model = co.Model(rig)
    rng = np.random.default_rng(9)
    Rs = co.so3.random_rotations(100, rng, max_angle=0.8)
    J = model.jacobian(Rs)
    tau = model.weight_moment(Rs) + rng.normal(size=(100, 3)) * 2.0      # some poses infeasible
    K0, G = model.stiffness_basis(Rs)
    D = np.array(list(shaping_range.AXES.values()) + [[0.6, 0.8, 0.0]])
    lo, hi = shaping_range.directional_stiffness_range(J, tau, K0, G, rig.t_min_N, rig.t_max_N, D)
    lo_r, hi_r = shaping_range.directional_stiffness_range_reference(J, tau, K0, G, rig.t_min_N, rig.t_max_N, D)
    empty = np.isnan(lo_r[:, 0])
    assert 0 < empty.sum() < 100 and np.array_equal(np.isnan(lo), np.isnan(lo_r))
    np.testing.assert_allclose(lo[~empty], lo_r[~empty], rtol=1e-12)
    np.testing.assert_allclose(hi[~empty], hi_r[~empty], rtol=1e-12)
