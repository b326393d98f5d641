"""Batched cable kinematics and a batched forward-statics solver (numpy).

The diagnosis and the testbed evaluate the moment balance of many rows at once, for many
parameter vectors, so it does not go through CasADi row by row. Conventions
are those of docs/conventions.md and :mod:`csjm_opt.model.casadi_model`: cable ``i`` runs from
the platform hole ``a_i`` (in {A}) to the base hole ``b_i`` (in {B}); in {A}
its unit vector is ``u_i = (R^T b_i - a_i) / c_i``; ``J`` has rows
``a_i x u_i`` (38), and ``J^T T`` is the cables' moment on the platform.

:func:`solve_poses` finds, for every row, the orientation ``R`` with
``g(R) = 0`` for any batched residual ``g`` (N m) by Newton's method on SO(3)
(right perturbation ``R exp(hat(zeta))``) with a finite-difference Jacobian
and a backtracking line search per row.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Callable

import numpy as np

from .. import so3
from . import cable_terms as _reference

Residual = Callable[[np.ndarray], np.ndarray]   # (n, 3, 3) -> (n, 3)


def cable_terms(R: np.ndarray, A_m: np.ndarray, B_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cable lengths (n, m) and Jacobian J (n, m, 3) for poses R (n, 3, 3).

    ``A_m``, ``B_m`` are (m, 3) or per-row (n, m, 3) hole positions in {A}, {B}.
    The physics is :func:`csjm_opt.model.cable_terms.geometry` (the numpy reference).
    """
    c, _, J = _reference.geometry(R, A_m, B_m)
    return c, J


def weight_moment(R: np.ndarray, first_moment_A_kgm: np.ndarray, gravity_B: np.ndarray) -> np.ndarray:
    """Moment of the weight about O in {A}: ``(m r) x (R^T g)`` (N m), (n, 3).

    See :func:`csjm_opt.model.cable_terms.weight_moment` (the numpy reference).
    """
    return _reference.weight_moment(R, first_moment_A_kgm, gravity_B)


@functools.lru_cache(maxsize=16)
def basis_rotations(h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``exp(h e_j)`` for the three axes (read-only): the tangent's steps, computed once per ``h``."""
    out = []
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        E = so3.exp(step)
        E.setflags(write=False)
        out.append(E)
    return out[0], out[1], out[2]


def tangent(g: Residual, R: np.ndarray, g0: np.ndarray | None = None, h: float = 1e-7) -> np.ndarray:
    """Finite-difference ``dg/dzeta`` (n, 3, 3) under ``R exp(hat(zeta))``."""
    g0 = g(R) if g0 is None else g0
    G = np.empty(g0.shape + (3,))
    for j, E in enumerate(basis_rotations(float(h))):
        G[..., j] = (g(R @ E) - g0) / h
    return G


@dataclasses.dataclass(frozen=True, eq=False)
class PoseSolution:
    """Equilibrium orientations for a batch of rows."""

    R: np.ndarray              # (n, 3, 3)
    residual_Nm: np.ndarray    # (n,) ||g|| at R
    iterations: int

    def converged(self, tol_Nm: float = 1e-6) -> np.ndarray:
        """Which rows converged.

        Parameters
        ----------
        tol_Nm : float
            Largest accepted residual ``||g||`` (N m).

        Returns
        -------
        (n,) bool array
            ``residual_Nm <= tol_Nm`` per row.
        """
        return self.residual_Nm <= tol_Nm


def solve_poses(g: Residual, R_init: np.ndarray, tol_Nm: float = 1e-10, max_iter: int = 60,
                max_step_rad: float = 0.2, tangent_step_rad: float = 1e-7,
                tangent_fn: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None) -> PoseSolution:
    """Solve ``g(R) = 0`` row-wise by damped Newton on SO(3) (batched).

    ``tangent_step_rad`` is the finite-difference step of the tangent (:func:`tangent`); a
    residual that changes steeply over a narrower range of rotation (a stiff, regularised
    stick-slip law) needs a step below that range. ``tangent_fn(R, g0)``, when given, returns that
    tangent (the same numbers, computed by the caller's faster route).
    """
    R = np.array(R_init, dtype=float)
    g0 = g(R)
    norm = np.linalg.norm(g0, axis=1)
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 (the count is reported after the loop)
        active = norm > tol_Nm
        if not np.any(active):
            break
        G = tangent(g, R, g0, tangent_step_rad) if tangent_fn is None else tangent_fn(R, g0)
        try:
            step = -np.linalg.solve(G, g0[..., None])[..., 0]
        except np.linalg.LinAlgError:
            step = -np.einsum("nij,nj->ni", np.linalg.pinv(G), g0)
        bad = ~np.all(np.isfinite(step), axis=1)
        step[bad] = 0.0
        length = np.linalg.norm(step, axis=1, keepdims=True)
        step *= np.minimum(1.0, max_step_rad / np.maximum(length, 1e-300))
        step[~active] = 0.0
        alpha = np.ones(len(R))
        pending = active.copy()
        for _ in range(25):
            R_try = R @ so3.exp(alpha[:, None] * step)
            g_try = g(R_try)
            n_try = np.linalg.norm(g_try, axis=1)
            ok = pending & np.isfinite(n_try) & (n_try < norm)
            R[ok], g0[ok], norm[ok] = R_try[ok], g_try[ok], n_try[ok]
            pending &= ~ok
            if not np.any(pending):
                break
            alpha[pending] *= 0.5
        if np.all(~active | pending):      # no row improved: stalled
            break
    return PoseSolution(R, norm, it)
