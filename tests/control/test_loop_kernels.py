"""Compiled loop kernels (csjm_opt/loop_kernels.py) against the numpy references and the CasADi model."""

from __future__ import annotations

import numpy as np

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.control import loop_kernels as loop_kernels
from csjm_opt.model.cable_terms import CableTerms
from csjm_opt.model.statics import EquilibriumSolver, rest_lengths_for
from csjm_opt.planning import dense_qp as dense_qp
from csjm_opt.shaping.shaper import Shaper, make_objective, qp_matrices


def test_basis_and_exp_match(rig, model):
    terms = CableTerms.from_rig(rig)
    rng = np.random.default_rng(21)
    for R in so3.random_rotations(4, rng, max_angle=0.5):
        J, K0, G = loop_kernels.stiffness_basis(terms.A, terms.B, terms.k, np.ascontiguousarray(R))
        T = rng.uniform(5, 150, 6)
        assert np.allclose(K0 + np.einsum("i,ijk->jk", T, G), model.stiffness(R, T), atol=1e-9)
        assert np.allclose(J, model.jacobian(R), atol=1e-14)
    for w in (np.zeros(3), np.array([1e-9, 0, 0]), np.array([0.3, -1.2, 2.0])):
        assert np.allclose(loop_kernels.exp_so3(w), so3.exp(w), atol=1e-14)


def test_newton_matches_numpy_reference(rig, model):
    rng = np.random.default_rng(22)
    compiled, reference = EquilibriumSolver(rig), EquilibriumSolver(rig, compiled=False)
    for R in so3.random_rotations(4, rng, max_angle=0.25):
        tau = rng.uniform(-0.4, 0.4, 3)
        l = rest_lengths_for(rig, R, co.plan_tensions(rig, R, tau, model=model).tensions_N, model)
        a = compiled.solve(l, tau, np.eye(3))
        b = reference.solve(l, tau, np.eye(3))
        assert so3.angle_between(a.R, b.R) < 1e-12 and so3.angle_between(a.R, R) < 1e-9
        assert np.allclose(a.K_tangent, b.K_tangent, atol=1e-9) and a.iterations == b.iterations


def test_shaper_compiled_matches_reference(rig):
    rng = np.random.default_rng(23)
    R = so3.exp(np.array([0.05, 0.1, -0.02]))
    for K in (np.diag([40.0, 10.0, 25.0]), 80 * np.eye(3), 2 * np.eye(3), np.diag([18.0, 22.0, 30.0])):
        obj = make_objective(K)
        tau = rng.uniform(-0.3, 0.3, 3)
        xa, _, _ = Shaper(rig).solve(R, tau, obj)
        xb, _, rb = Shaper(rig, compiled=False).solve(R, tau, obj)
        assert np.allclose(xa, xb, atol=1e-8)
    # settled PDAS results satisfy the KKT conditions of the numpy QP
    shaper = Shaper(rig)
    x, basis, res = shaper.solve(R, np.array([0.1, 0.2, 0.0]), make_objective(np.diag([40.0, 10.0, 25.0])))
    P, q, A, b = qp_matrices(basis, np.array([0.1, 0.2, 0.0]), make_objective(np.diag([40.0, 10.0, 25.0])),
                             rig.t_mid_N)
    assert res.kkt_error(P, q, A, b, np.full(6, rig.t_min_N), np.full(6, rig.t_max_N)) <= 1e-7
    ref = dense_qp.solve(P, q, A, b, np.full(6, rig.t_min_N), np.full(6, rig.t_max_N))
    assert np.allclose(x, ref.x, atol=1e-8)
