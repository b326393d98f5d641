"""The bounded least squares of the stick condition: the loop kernel against array operations and scipy.

The kernel (:func:`csjm_opt.diagnose.fitting.friction_stick._bounded_lsq`) is written out in loops for speed; the
same iteration in numpy array operations (as it was first written) and scipy's bounded least squares
(an independent solver) must give the same forces and distances.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy.optimize import lsq_linear

from csjm_opt.diagnose.fitting.friction_stick import MAX_ITER, STEP_TOL, _bounded_lsq


@njit
def _reference(a: np.ndarray, B: np.ndarray, F: np.ndarray, f0: np.ndarray,
                           max_iter: int, tol: float) -> np.ndarray:   # pragma: no cover (compiled)
    """:func:`_bounded_lsq` in array operations (as first written; the tests compare the two)."""
    n, _, m = B.shape
    out = np.empty((n, m))
    for i in range(n):
        H = B[i].T @ B[i]
        q = B[i].T @ a[i]
        v = np.ones(m)
        L = 0.0
        for _ in range(30):                      # largest eigenvalue of H (power iteration)
            w = H @ v
            nw = np.sqrt(np.dot(w, w))
            if nw <= 0.0:
                break
            L = nw / np.sqrt(np.dot(v, v))
            v = w / nw
        L *= 1.05
        f = np.minimum(np.maximum(f0[i], -F), F)
        if L <= 0.0:
            out[i] = f
            continue
        y = f.copy()
        t = 1.0
        for _ in range(max_iter):
            grad = H @ y + q
            fn = np.minimum(np.maximum(y - grad / L, -F), F)
            step = fn - f
            if np.dot(step, H @ step) > 0 and np.dot(H @ fn + q, step) > 0:   # restart on a rise
                t = 1.0
                y = f.copy()
                continue
            tn = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
            y = fn + ((t - 1.0) / tn) * step
            f, t = fn, tn
            if np.dot(step, step) <= tol * (1.0 + np.dot(F, F)):
                break
        out[i] = f
    return out



@pytest.mark.parametrize("m", [6, 4, 8])
def test_loop_kernel_equals_array_operations_and_scipy(m):
    rng = np.random.default_rng(m)
    n = 60
    B = rng.normal(size=(n, 3, m))
    a = 3.0 * rng.normal(size=(n, 3))
    F = rng.uniform(0.1, 1.0, m)
    f0 = np.zeros((n, m))
    f = _bounded_lsq(a, B, F, f0, MAX_ITER, STEP_TOL)
    ref = _reference(a, B, F, f0, MAX_ITER, STEP_TOL)
    np.testing.assert_allclose(f, ref, rtol=0, atol=1e-11)        # the same iteration, to round-off
    assert np.all(np.abs(f) <= F + 1e-15)
    for i in range(n):     # scipy's minimum distance (an independent solver); FISTA stops at its step tolerance
        sol = lsq_linear(B[i], -a[i], bounds=(-F, F), tol=1e-14, method="bvls")
        d, d_min = np.linalg.norm(a[i] + B[i] @ f[i]), np.linalg.norm(a[i] + B[i] @ sol.x)
        assert d_min - 1e-12 <= d <= d_min + 1e-3
