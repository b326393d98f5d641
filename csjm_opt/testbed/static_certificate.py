"""Certified static settling under Coulomb friction: a small linear programme.

A pose is a static equilibrium of a plant with Coulomb friction when some
friction forces *within their bounds* balance the frictionless net force
there. With the engine's generalised net force ``q`` (frictionless: springs,
gravity, load, applied forces) and the friction directions ``A`` (columns:
each tendon's length Jacobian, each frictional joint axis), the LP

    minimise t   subject to   |A f + q| <= tol (row-wise),   |f_j| <= t b_j

(HiGHS through :func:`scipy.optimize.linprog`) gives the smallest fraction
``t`` of the friction bounds ``b`` that holds the pose. ``t <= 1`` certifies the
pose; ``t`` near 1 says a cable or the joint is about to slip. Rows of ``q``
without friction (e.g. a compliant link) must balance within ``tol`` on
their own.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.optimize import linprog


@dataclasses.dataclass(frozen=True)
class FrictionCertificate:
    """Result of :func:`certify_static`.

    Attributes
    ----------
    certified : bool
        Friction forces within their bounds hold the pose (``utilisation <= 1``).
    utilisation : float
        Smallest fraction of the friction bounds that holds the pose (``inf``: none does).
    friction_forces : ndarray
        One such set of friction forces (N for tendons, N m for joint axes; ``nan`` if none).
    residual_Nm : float
        Largest generalised force left unbalanced by those forces.
    """

    certified: bool
    utilisation: float
    friction_forces: np.ndarray
    residual_Nm: float


def certify_static(net: np.ndarray, directions: np.ndarray, bounds: np.ndarray,
                   tol_Nm: float = 1e-7) -> FrictionCertificate:
    """Whether friction forces within ``bounds`` balance the net force ``net`` (see the module doc).

    Parameters
    ----------
    net : (nv,) array
        Frictionless generalised net force at the pose (N m).
    directions : (nv, m) array
        Generalised force of a unit friction force in each friction element.
    bounds : (m,) array
        Friction bounds (>= 0; 0 = no friction in that element).
    tol_Nm : float, optional
        Allowed imbalance per generalised coordinate.

    Returns
    -------
    FrictionCertificate
    """
    q = np.asarray(net, float).ravel()
    A = np.asarray(directions, float).reshape(len(q), -1)
    b = np.asarray(bounds, float).ravel()
    m = A.shape[1]
    if m == 0 or not np.any(b > 0):
        res = float(np.abs(q).max(initial=0.0))
        ok = res <= tol_Nm
        return FrictionCertificate(ok, 0.0 if ok else np.inf, np.zeros(m), res)
    c = np.r_[np.zeros(m), 1.0]
    A_ub = np.block([[A, np.zeros((len(q), 1))], [-A, np.zeros((len(q), 1))],
                     [np.eye(m), -b[:, None]], [-np.eye(m), -b[:, None]]])
    b_ub = np.r_[tol_Nm - q, tol_Nm + q, np.zeros(2 * m)]
    var_bounds = [(0.0, 0.0) if bj <= 0 else (None, None) for bj in b] + [(0.0, None)]
    sol = linprog(c, A_ub=A_ub, b_ub=b_ub, bounds=var_bounds, method="highs")
    if sol.status != 0:
        return FrictionCertificate(False, np.inf, np.full(m, np.nan), float(np.abs(q).max()))
    f = sol.x[:m]
    t = float(sol.x[m])
    return FrictionCertificate(bool(t <= 1.0 + 1e-9), t, f, float(np.abs(A @ f + q).max()))
