"""Reachable stiffness set (csjm_opt/reachable.py) against brute force and another team's LP."""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from csjm_opt import so3
from csjm_opt._plotting import save
from csjm_opt.design import shaping_range
from csjm_opt.shaping.figures import plot_reachable_set
from csjm_opt.shaping.reachable import (
    directional_range,
    directional_stiffness_range,
    feasible_vertices,
    reachable_set,
)

R_POSE = so3.exp(np.array([-0.08, 0.12, 0.05]))
TAU = np.array([-0.2, 0.35, 0.05])


def _polytope_samples(rig, model, n, rng):
    """Random feasible tensions: rejection sampling in the null space (independent of the vertices)."""
    J = model.jacobian(R_POSE)
    tau_load = TAU + model.weight_moment(R_POSE)
    T0 = np.linalg.lstsq(J.T, -tau_load, rcond=None)[0]
    N = np.linalg.svd(J.T)[2][3:].T
    out = []
    while len(out) < n:
        T = T0 + N @ rng.uniform(-200, 200, 3)
        if np.all(T >= rig.t_min_N) and np.all(T <= rig.t_max_N):
            out.append(T)
    return np.array(out)


def test_vertices_are_feasible_and_bound_samples(rig, model):
    J = model.jacobian(R_POSE)
    tau_load = TAU + model.weight_moment(R_POSE)
    V = feasible_vertices(J, tau_load, rig.t_min_N, rig.t_max_N)
    assert len(V) >= 4
    assert np.allclose(J.T @ V.T + tau_load[:, None], 0, atol=1e-9)
    Vb, ok = shaping_range.vertices(J[None], tau_load[None], rig.t_min_N, rig.t_max_N)
    assert len(np.unique(np.round(Vb[0][ok[0]], 6), axis=0)) == len(V)


def test_directional_range_exact(rig, model):
    rs = reachable_set(rig, R_POSE, TAU, n_samples=200)
    U = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [1.0, 1.0, 0.5]])
    got = directional_range(rs.basis, rs.tau_load_A_Nm, U, rig.t_min_N, rig.t_max_N)
    Un = U / np.linalg.norm(U, axis=1, keepdims=True)
    # brute force: the linear function's extremes over the vertices, K from the CasADi model
    Ks = model.stiffness(np.repeat(R_POSE[None], len(rs.vertices_N), 0), rs.vertices_N)
    vals = np.einsum("ui,nij,uj->un", Un, Ks, Un)
    assert np.allclose(got[:, 0], vals.min(axis=1), atol=1e-8)
    assert np.allclose(got[:, 1], vals.max(axis=1), atol=1e-8)
    # another implementation (design sweep's batched vertex LP)
    lo, hi = shaping_range.directional_stiffness_range(
        model.jacobian(R_POSE)[None], rs.tau_load_A_Nm[None], rs.basis.K0[None], rs.basis.G[None],
        rig.t_min_N, rig.t_max_N, Un[:3])
    assert np.allclose(lo[0], got[:3, 0], atol=1e-8) and np.allclose(hi[0], got[:3, 1], atol=1e-8)
    assert np.allclose(directional_stiffness_range(rig, R_POSE, TAU, U), got, atol=1e-12)


def test_directional_range_errors(rig):
    import pytest

    import csjm_opt as co

    with pytest.raises(co.InfeasibleLoad):
        directional_stiffness_range(rig, R_POSE, np.array([30.0, 0, 0]), np.eye(3))
    with pytest.raises(co.InvalidInput):
        directional_stiffness_range(rig, R_POSE, TAU, np.zeros((1, 3)))


def test_eigenvalue_ranges_bound_samples(rig, model):
    rs = reachable_set(rig, R_POSE, TAU, n_samples=500)
    T = _polytope_samples(rig, model, 400, np.random.default_rng(5))
    lam = np.linalg.eigvalsh(model.stiffness(np.repeat(R_POSE[None], len(T), 0), T))
    tol = 1e-6
    assert np.all(lam[:, 0] >= rs.eigen_ranges[0, 0] - tol) and np.all(lam[:, 0] <= rs.eigen_ranges[0, 1] + tol)
    assert np.all(lam[:, 2] >= rs.eigen_ranges[2, 0] - tol) and np.all(lam[:, 2] <= rs.eigen_ranges[2, 1] + tol)
    assert rs.cutting_plane_gap <= 1e-5
    # max lambda_1 (convex problem): SLSQP from the samples' best cannot beat the cutting planes
    J = model.jacobian(R_POSE)
    tau_load = TAU + model.weight_moment(R_POSE)
    best = T[np.argmax(lam[:, 0])]
    res = minimize(lambda t: -np.linalg.eigvalsh(model.stiffness(R_POSE, t))[0], best, method="SLSQP",
                   bounds=[(rig.t_min_N, rig.t_max_N)] * 6,
                   constraints=[{"type": "eq", "fun": lambda t: J.T @ t + tau_load}])
    assert -res.fun <= rs.eigen_ranges[0, 1] + 1e-5
    assert -res.fun >= rs.eigen_ranges[0, 1] - 1e-2       # and they agree closely
    # trace range is exact (linear): samples inside
    tr = np.trace(model.stiffness(np.repeat(R_POSE[None], len(T), 0), T), axis1=1, axis2=2)
    assert rs.trace_range[0] - 1e-9 <= tr.min() and tr.max() <= rs.trace_range[1] + 1e-9


def test_figure_written(rig, tmp_path):
    rs = reachable_set(rig, R_POSE, TAU, n_samples=100)
    ax_eig, ax_dir = plot_reachable_set(rs, rig.t_min_N, rig.t_max_N,
                                        {"target": np.diag([20.0, 25.0, 30.0])}, n_directions=24)
    assert ax_eig.figure is ax_dir.figure and ax_dir.name == "polar"
    assert [t.get_text() for t in ax_eig.get_legend().get_texts()] == ["target"]
    path = save(ax_eig.figure, tmp_path / "reach.png")
    assert path.exists() and path.stat().st_size > 10_000
    assert not list(tmp_path.glob("*.tmp.*"))
