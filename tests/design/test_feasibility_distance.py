"""The exact infeasibility distance (zonotope facets + two-variable faces) against SLSQP/BVLS."""

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from csjm_opt import paper_rig
from csjm_opt.errors import InfeasibleLoad
from csjm_opt.model import Model
from csjm_opt.planning import feasibility_distance_Nm, kernels, plan_tensions
from csjm_opt.so3 import exp


def _bvls_distance(J, tau_load, lo, hi):
    res = lsq_linear(J.T, -tau_load, bounds=(lo, hi), method="bvls", tol=1e-15)
    return np.linalg.norm(J.T @ res.x + tau_load)


@pytest.mark.parametrize("seed", range(4))
def test_distance_matches_bounded_least_squares(seed):
    rng = np.random.default_rng(seed)
    for _ in range(50):
        J = rng.normal(size=(6, 3)) * 0.05
        tau = rng.normal(size=3) * rng.choice([0.5, 5.0, 50.0])
        ref = _bvls_distance(J, tau, 5.0, 150.0)
        margin = kernels.outside_margin(J, -tau, 5.0, 150.0)
        assert (margin > 0.0) == (ref > 1e-9), (margin, ref)    # the facet test decides feasibility
        d = feasibility_distance_Nm(J, tau, 5.0, 150.0)
        assert d == pytest.approx(ref, rel=1e-9, abs=1e-12)
        if ref > 1e-9:
            assert margin <= d + 1e-12                            # a facet plane is never farther than the set


def test_minimiser_is_in_the_box_and_attains_the_distance():
    rng = np.random.default_rng(7)
    J = rng.normal(size=(6, 3)) * 0.05
    b = np.array([40.0, -30.0, 10.0])
    t = np.empty(6)
    d = kernels.boundary_distance(J, b, 5.0, 150.0, t)
    assert np.all(t >= 5.0) and np.all(t <= 150.0)
    assert np.linalg.norm(J.T @ t - b) == pytest.approx(d, rel=1e-12)


def test_planner_reports_the_same_distance_on_the_paper_rig():
    rig = paper_rig()
    R = exp(np.array([0.2, -0.1, 0.05]))
    model = Model(rig)
    J = model.jacobian(R)
    big = np.array([30.0, 0.0, 0.0])
    with pytest.raises(InfeasibleLoad) as info:
        plan_tensions(rig, R, big)
    ref = _bvls_distance(J, big + model.weight_moment(R), rig.t_min_N, rig.t_max_N)
    assert info.value.distance_Nm == pytest.approx(ref, rel=1e-9)
