"""Compiled (numba) matrices of the shaping QP (see :func:`csjm_opt.shaping.shaper.qp_matrices`).

Solved by the dense active-set QP :func:`csjm_opt.planning.kernels.pdas`.
Compiled on first use and cached on disk (``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def shaping_qp(G, K0, L, s, w, J, tau_load, t_mid, rho_rel):
    """Dense P, q, A, b of the shaping QP (see :func:`csjm_opt.shaping.shaper.qp_matrices`)."""
    m = G.shape[0]
    M = L @ G.reshape(m, 9).T
    d = s - L @ K0.reshape(9)
    MW = M.T * w
    H = MW @ M
    curvature = np.trace(H) / m
    rho = rho_rel * (curvature if curvature > 1e-300 else 1.0)
    P = 2.0 * (H + rho * np.eye(m))
    q = -2.0 * (MW @ d + rho * t_mid)
    return P, q, J.T.copy(), -tau_load
