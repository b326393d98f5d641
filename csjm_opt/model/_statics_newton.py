"""Damped Newton on SO(3) for forward statics, numpy reference: closed-form terms, step, stability test.

The compiled twin is :func:`csjm_opt.model.statics_kernels.newton`; the method is described in
:mod:`csjm_opt.model.statics`.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .. import so3
from ._descent import rotation_angle as _angle
from .cable_terms import CableTerms, point_force_terms
from .rig import Rig

PointForce = tuple[np.ndarray, np.ndarray]  # (force in {B}, N; point in {A}, m)

#: Largest rotation (rad) away from the start before a Newton run is called diverged.
MAX_EXCURSION_RAD = 2.5


# ------------------------------------------------------------------ terms
@functools.lru_cache(maxsize=64)
def cable_terms_for(rig: Rig) -> CableTerms:
    """Closed-form cable terms of ``rig`` (cached per rig object)."""
    return CableTerms.from_rig(rig)


class _Evaluator:
    """All Newton terms at a pose, closed form (checked against the CasADi model in the tests)."""

    def __init__(self, rig: Rig, forces: list[PointForce]):
        self._terms = cable_terms_for(rig)
        self._F = np.array([f for f, _ in forces], float).reshape(-1, 3)
        self._P = np.array([p for _, p in forces], float).reshape(-1, 3)

    def __call__(self, R: np.ndarray, l: np.ndarray, tau_ext: np.ndarray):
        T, tau_c, K = self._terms.rest_terms(R, l)
        tau_p, H_p = point_force_terms(R, self._F, self._P)
        g = tau_c + tau_p + tau_ext
        K_t = K + H_p - 0.5 * so3.hat(tau_c + tau_p)
        return g, K, K_t, T, tau_c, tau_p


def _stable(K_t: np.ndarray) -> bool:
    """All eigenvalues of the 3x3 ``K_t`` have positive real part (Routh-Hurwitz on ``det(s I + K_t)``).

    Plain float arithmetic on the nine entries (one call per equilibrium, on the 1 kHz loop's path).
    """
    (a, b, c), (d, e, f), (g, h, i) = K_t.tolist()
    if not all(math.isfinite(x) for x in (a, b, c, d, e, f, g, h, i)):
        return False
    tr = a + e + i
    m2 = a * e - b * d + a * i - c * g + e * i - f * h
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return tr > 0 and det > 0 and tr * m2 > det


def _newton(evaluate: _Evaluator, l: np.ndarray, R0: np.ndarray, tau_ext: np.ndarray, tol_Nm: float,
            max_iter: int, max_step_rad: float):
    """Damped Newton from ``R0``; returns ``((R, terms, iterations), converged)``."""
    R = R0
    terms = evaluate(R, l, tau_ext)
    best = float(np.linalg.norm(terms[0]))
    it = 0
    for it in range(1, max_iter + 1):
        if best <= tol_Nm:
            it -= 1
            break
        g, _, K_t = terms[0], terms[1], terms[2]
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(K_t))):
            return (R, terms, it), False
        step = _newton_step(K_t, g, max_step_rad)
        alpha, improved = 1.0, False
        for _ in range(30):
            R_try = R @ so3.exp(alpha * step)
            out = evaluate(R_try, l, tau_ext)
            norm = float(np.linalg.norm(out[0]))
            if norm < best or norm <= tol_Nm:
                R, terms, best, improved = R_try, out, norm, True
                break
            alpha *= 0.5
        if not improved or _angle(R0, R) > MAX_EXCURSION_RAD:
            return (R, terms, it), False
    return (R, terms, it), best <= tol_Nm


def _newton_step(K_t: np.ndarray, g: np.ndarray, max_step_rad: float) -> np.ndarray:
    """Solve ``K_t step = g`` (g + dg/dzeta step = 0, dg/dzeta = -K_t), regularised and capped."""
    try:
        step = np.linalg.solve(K_t, g)
        if not np.all(np.isfinite(step)) or (np.dot(step, g) <= 0 and np.linalg.cond(K_t) > 1e10):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        S = 0.5 * (K_t + K_t.T)
        mu = max(0.0, -np.min(np.linalg.eigvalsh(S))) + 1e-3 * max(1.0, np.abs(S).max())
        step = np.linalg.solve(S + mu * np.eye(3), g)
    norm = np.linalg.norm(step)
    return step if norm <= max_step_rad else step * (max_step_rad / norm)
