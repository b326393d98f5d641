"""Globalised forward statics: energy descent on SO(3) (pseudo-transient continuation).

Used by :mod:`csjm_opt.model.statics` only when plain Newton from the start
fails or lands on an unstable equilibrium. It follows the overdamped motion
of the platform, ``dzeta/dt = g(R)`` (``g = J^T T + tau_points + tau_ext``,
the net moment in {A}), with implicit-Euler steps of growing length::

    (K_t + I / h) s = g,     R <- R exp(hat(alpha s))

(``K_t = -dg/dzeta``), so it ends where a heavily damped platform settles,
and becomes Newton's method (``h -> inf``) near the answer. Each step must
decrease the merit ``E_cable + E_points - W_ext`` along its geodesic
(Armijo backtracking): ``E_cable = sum 1/2 k_i max(0, c_i - l_i)^2`` (slack
cables carry nothing), ``E_points = -sum f . (R p)`` (weight and dead
weights fixed in {B}), and ``W_ext = alpha tau_ext . s`` the work of the
moment fixed in {A} along the step (a moment fixed in the body has no global
potential, but its work along a body-frame geodesic is exact). At the answer
the tangent stiffness is checked: a saddle (an eigenvalue with non-positive
real part) is left along its unstable direction and the descent resumed.
"""

from __future__ import annotations

import numpy as np

from .. import so3

#: Largest rotation (rad) from the start of the descent before the platform is said to fall over.
FALL_ANGLE_RAD = 0.5 * np.pi


def merit_terms(terms, F: np.ndarray, P: np.ndarray, R: np.ndarray, l: np.ndarray) -> float:
    """``E_cable + E_points`` (J) at ``R`` for rest lengths ``l``."""
    c = terms.geometry(R)[0]
    stretch = np.maximum(c - l, 0.0)
    energy = 0.5 * float(np.sum(terms.k * stretch * stretch))
    if len(F):
        energy -= float(np.sum(F * (P @ R.T)))
    return energy


def descend(evaluate, terms, F: np.ndarray, P: np.ndarray, l: np.ndarray, R0: np.ndarray,
            tau_ext: np.ndarray, tol_Nm: float, max_iter: int = 400, max_step_rad: float = 0.25,
            fall_angle_rad: float = FALL_ANGLE_RAD, escapes: int = 3):
    """Descent from ``R0``; returns ``((R, terms_at_R, iterations), status)``.

    ``status`` is ``"ok"`` (stable equilibrium, residual <= ``tol_Nm``),
    ``"fell"`` (left the ``fall_angle_rad`` ball around ``R0``), ``"unstable"``
    (only saddles found) or ``"stalled"``.
    """
    R = R0
    out = evaluate(R, l, tau_ext)
    E = merit_terms(terms, F, P, R, l)
    K_scale = max(1.0, float(np.linalg.norm(out[2], 2)))
    inv_h = K_scale
    it = 0
    stalled = False
    while it < max_iter:
        it += 1
        g, K_t = out[0], out[2]
        norm_g = float(np.linalg.norm(g))
        floor = max(tol_Nm, 1e-12 * (1.0 + float(np.sum(out[3]))))   # round-off level of the residual
        if norm_g <= tol_Nm or (stalled and norm_g <= floor):
            stalled = False
            lam, vecs = np.linalg.eig(K_t)
            if np.all(lam.real > 0):
                return (R, out, it), "ok"
            if escapes <= 0:
                return (R, out, it), "unstable"
            escapes -= 1
            v = np.real(vecs[:, int(np.argmin(lam.real))])
            v = 0.05 * v / np.linalg.norm(v)
            cand = [R @ so3.exp(sgn * v) for sgn in (1.0, -1.0)]
            R = min(cand, key=lambda Rc: merit_terms(terms, F, P, Rc, l))
            out, E, inv_h = evaluate(R, l, tau_ext), merit_terms(terms, F, P, R, l), K_scale
            continue
        if not (np.all(np.isfinite(g)) and np.all(np.isfinite(K_t))):
            return (R, out, it), "stalled"
        s = _regularised_step(K_t, g, inv_h)
        n = float(np.linalg.norm(s))
        if n > max_step_rad:
            s *= max_step_rad / n
        slope = float(s @ g)                      # -d(merit)/d(alpha) at alpha = 0
        alpha, accepted = 1.0, False
        for _ in range(30):
            R_try = R @ so3.exp(alpha * s)
            E_try = merit_terms(terms, F, P, R_try, l)
            if E_try - alpha * float(tau_ext @ s) - E <= -1e-4 * alpha * slope:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            # near round-off the merit cannot resolve progress: a plain Newton step that lowers |g|
            try:
                s_newton = np.linalg.solve(K_t, g)
            except np.linalg.LinAlgError:
                s_newton = s
            R_try = R @ so3.exp(s_newton)
            out_try = evaluate(R_try, l, tau_ext)
            if np.linalg.norm(out_try[0]) < norm_g:
                R, out, E = R_try, out_try, merit_terms(terms, F, P, R_try, l)
            elif norm_g <= floor:
                stalled = True               # converged to round-off: check stability above
            else:
                return (R, out, it), "stalled"
            continue
        out_new = evaluate(R_try, l, tau_ext)
        norm_new = float(np.linalg.norm(out_new[0]))
        # switched evolution relaxation: longer pseudo-time steps as the residual falls
        inv_h = inv_h * min(4.0, max(0.1, norm_new / max(norm_g, 1e-300))) if alpha == 1.0 else inv_h * 4.0
        inv_h = min(max(inv_h, 1e-12 * K_scale), 1e6 * K_scale)
        R, out, E = R_try, out_new, E_try
        if rotation_angle(R0, R) > fall_angle_rad:
            return (R, out, it), "fell"
    return (R, out, it), "stalled"


def _regularised_step(K_t: np.ndarray, g: np.ndarray, inv_h: float) -> np.ndarray:
    """``(K_t + I/h)^{-1} g``, more regularised until it is a descent direction."""
    for _ in range(60):
        try:
            s = np.linalg.solve(K_t + inv_h * np.eye(3), g)
        except np.linalg.LinAlgError:
            s = None
        if s is not None and np.all(np.isfinite(s)) and s @ g > 0:
            return s
        inv_h = max(4.0 * inv_h, 1e-6)
    return g / max(inv_h, 1e-6)


def rotation_angle(R0: np.ndarray, R: np.ndarray) -> float:
    """Rotation angle of ``R0^T R`` (rad), from the trace."""
    return float(np.arccos(np.clip(0.5 * (np.sum(R0 * R) - 1.0), -1.0, 1.0)))
