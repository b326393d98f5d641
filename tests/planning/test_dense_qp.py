"""Exact dense QP (csjm_opt/dense_qp.py) against SLSQP and the KKT conditions."""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from csjm_opt.planning import dense_qp as dense_qp


def _random_qp(rng, n=6, m=3):
    M = rng.normal(size=(9, n))
    P = M.T @ M + 1e-3 * np.eye(n)
    q = rng.normal(size=n) * 100
    A = rng.normal(size=(m, n))
    b = A @ rng.uniform(5, 150, n)
    return P, q, A, b, np.full(n, 5.0), np.full(n, 150.0)


def test_matches_slsqp_and_kkt():
    rng = np.random.default_rng(11)
    methods = set()
    for _ in range(40):
        P, q, A, b, lo, hi = _random_qp(rng)
        res = dense_qp.solve(P, q, A, b, lo, hi)
        methods.add(res.method)
        assert res.converged and res.kkt_error(P, q, A, b, lo, hi) <= 1e-7
        ref = minimize(lambda x: 0.5 * x @ P @ x + q @ x, np.full(6, 77.5), jac=lambda x: P @ x + q,
                       method="SLSQP", bounds=list(zip(lo, hi)),
                       constraints=[{"type": "eq", "fun": lambda x: A @ x - b, "jac": lambda x: A}],
                       options={"ftol": 1e-14, "maxiter": 500})
        f = 0.5 * res.x @ P @ res.x + q @ res.x
        assert f <= ref.fun + 1e-8 * max(1.0, abs(ref.fun))
    assert methods == {"pdas", "primal"}          # both paths exercised


def test_warm_start_and_primal_agree():
    rng = np.random.default_rng(12)
    P, q, A, b, lo, hi = _random_qp(rng)
    cold = dense_qp.solve(P, q, A, b, lo, hi)
    warm = dense_qp.solve(P, q, A, b, lo, hi, cold.lower, cold.upper)
    primal = dense_qp._primal_active_set(P, q, A, b, lo, hi, 60, 1e-10)
    assert warm.iterations == 1 and np.allclose(warm.x, cold.x, atol=1e-9)
    assert np.allclose(primal.x, cold.x, atol=1e-7)


def test_infeasible_reports_not_converged():
    P, q, A, b, lo, hi = _random_qp(np.random.default_rng(13))
    res = dense_qp.solve(P, q, A, 1e6 * np.abs(b) + 1e6, lo, hi)
    assert not res.converged
