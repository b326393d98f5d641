"""The curvature of the moment-rotation relation from the rig model (second order and beyond).

At fixed rest lengths ``l`` the load moment that holds the platform at ``R_ref exp(zeta)`` is
``g(zeta) = -tau_cable(R_ref exp(zeta); l)`` (the cable moment balances the total load). Its
linear part ``g(0) + G0 zeta`` is what the identification estimates (``G0 = K + 1/2 hat(g(0))``,
load convention); the rest::

    c(zeta) = g(zeta) - g(0) - G0 zeta

is taken from the rig model with the log's rest lengths and subtracted from the measured
moments before the fit. It is a difference of model moments, so a wrong rig model enters
only through its *curvature*: a cable stiffness 20 % off leaves about 20 % of the curvature
bias (which itself is a few per cent of K for 0.07 rad loads), not 20 % of K
(docs/guide/identification.md quantifies this).
"""

from __future__ import annotations

import numpy as np

from .. import so3
from ..model.numeric import Model


def right_jacobian(zeta: np.ndarray) -> np.ndarray:
    """Right Jacobian of SO(3), (n, 3, 3): ``exp(z + dz) = exp(z) exp(J_r(z) dz)`` to first order.

    Parameters
    ----------
    zeta : array (n, 3)
        Rotation vectors (rad).

    Returns
    -------
    ndarray (n, 3, 3)
    """
    z = np.asarray(zeta, float)
    th2 = np.sum(z * z, axis=-1)
    th = np.sqrt(th2)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    a = np.where(small, 0.5 - th2 / 24, (1 - np.cos(ths)) / ths ** 2)
    b = np.where(small, 1 / 6 - th2 / 120, (ths - np.sin(ths)) / ths ** 3)
    Z = so3.hat(z)
    return np.eye(3) - a[..., None, None] * Z + b[..., None, None] * (Z @ Z)


def model_curvature(model: Model, R_ref: np.ndarray, rest_lengths_m: np.ndarray,
                    zeta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Curvature ``c(zeta_i)`` (n, 3) and its slope ``dc/dzeta`` (n, 3, 3) from the rig model.

    Parameters
    ----------
    model : Model
        Numeric model of the rig.
    R_ref : array (3, 3)
        Reference orientation (the linearisation point).
    rest_lengths_m : array (m,)
        Rest lengths of the cycle (m).
    zeta : array (n, 3)
        Displacements from the reference (rad, body frame).

    Returns
    -------
    c : ndarray (n, 3)
        Load moment beyond its linear part (N m, {A}).
    dc : ndarray (n, 3, 3)
        Its derivative by ``zeta`` (N m/rad).
    """
    zeta = np.asarray(zeta, float)
    n = len(zeta)
    Rs = np.concatenate([np.asarray(R_ref, float)[None], R_ref @ so3.exp(zeta)])
    ls = np.repeat(np.asarray(rest_lengths_m, float)[None], n + 1, 0)
    K, _, tau_c, _ = model.stiffness_rest(Rs, ls)
    g = -tau_c
    G = K + 0.5 * so3.hat(g)                     # body-frame slope of the load moment at each pose
    c = g[1:] - g[0] - zeta @ G[0].T
    dc = G[1:] @ right_jacobian(zeta) - G[0]
    return c, dc


def weight_slopes(model: Model, R: np.ndarray, zeta: np.ndarray) -> np.ndarray:
    """Slope (n, 3, 3) of the platform weight moment by the displacement ``zeta`` at poses ``R``.

    ``tau_w = m r x (R^T g)``, so a body-frame turn ``delta`` changes it by
    ``hat(m r) hat(R^T g) delta``; times the right Jacobian for ``zeta`` coordinates.

    Parameters
    ----------
    model : Model
    R : array (n, 3, 3)
        Poses.
    zeta : array (n, 3)
        Their displacements from the reference.

    Returns
    -------
    ndarray (n, 3, 3)
    """
    gA = np.einsum("nji,j->ni", np.asarray(R, float), model.g)
    return so3.hat(model.first_moment_A_kgm)[None] @ so3.hat(gA) @ right_jacobian(zeta)
