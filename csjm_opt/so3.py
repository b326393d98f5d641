"""SO(3) helpers: hat, vee, exp, log, on numpy arrays and CasADi symbols.

Conventions (docs/conventions.md): ``R`` is the orientation of {A} in {B}; body-frame
canonical coordinates ``zeta`` with ``R = R_ref @ exp(hat(zeta))``, paper (1)-(3).
Numpy versions broadcast over leading axes: ``exp`` takes (..., 3) and returns
(..., 3, 3). Small-angle branches keep everything finite at zero, and ``log``
is accurate near pi.
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from .errors import InvalidInput

_SMALL = 1e-6
_EYE3 = np.eye(3)
_EYE3.setflags(write=False)


def _vectors(w: Any, name: str) -> np.ndarray:
    """float64 array of shape (..., 3), else :class:`InvalidInput` ("expected ..., got ...")."""
    try:
        arr = np.asarray(w, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: expected numbers of shape (..., 3), got {w!r:.60}", name) from None
    if arr.ndim == 0 or arr.shape[-1] != 3:
        raise InvalidInput(f"{name}: expected shape (..., 3), got {arr.shape}", name)
    return arr


def _matrices(M: Any, name: str) -> np.ndarray:
    """float64 array of shape (..., 3, 3), else :class:`InvalidInput`."""
    try:
        arr = np.asarray(M, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: expected numbers of shape (..., 3, 3), got {M!r:.60}", name) from None
    if arr.ndim < 2 or arr.shape[-2:] != (3, 3):
        raise InvalidInput(f"{name}: expected shape (..., 3, 3), got {arr.shape}", name)
    return arr


def _symbolic(x: Any) -> bool:
    """True for CasADi SX/MX/DM (a plain bool: static types stay ``Any``).

    CasADi is not imported here: an object can only be a CasADi symbol if the caller imported CasADi.
    """
    ca = sys.modules.get("casadi")
    return ca is not None and isinstance(x, (ca.SX, ca.MX, ca.DM))


def hat(w: Any) -> Any:
    """Skew matrix of paper (2): ``hat(w) @ v == cross(w, v)``.

    Parameters
    ----------
    w : array_like, shape (..., 3), or CasADi SX/MX/DM (3, 1)
        Vector(s).

    Returns
    -------
    ndarray, shape (..., 3, 3), or CasADi (3, 3)
        The skew-symmetric matrices.

    Raises
    ------
    InvalidInput
        If a numpy input does not have shape (..., 3).
    """
    if _symbolic(w):
        import casadi as ca
        return ca.vertcat(ca.horzcat(0, -w[2], w[1]),
                          ca.horzcat(w[2], 0, -w[0]),
                          ca.horzcat(-w[1], w[0], 0))
    return _hat(_vectors(w, "w"))


def _hat(w: np.ndarray) -> np.ndarray:
    """:func:`hat` of a checked float array (..., 3)."""
    out = np.zeros(w.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def vee(W: Any) -> Any:
    """Inverse of :func:`hat` (uses the antisymmetric part of ``W``).

    Parameters
    ----------
    W : array_like, shape (..., 3, 3), or CasADi (3, 3)
        Matrices.

    Returns
    -------
    ndarray, shape (..., 3), or CasADi (3, 1)
        ``w`` with ``hat(w) == (W - W^T) / 2``.

    Raises
    ------
    InvalidInput
        If a numpy input does not have shape (..., 3, 3).
    """
    if _symbolic(W):
        import casadi as ca
        return 0.5 * ca.vertcat(W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1])
    W = _matrices(W, "W")
    return 0.5 * np.stack([W[..., 2, 1] - W[..., 1, 2],
                           W[..., 0, 2] - W[..., 2, 0],
                           W[..., 1, 0] - W[..., 0, 1]], axis=-1)


def exp(w: Any) -> Any:
    """Rotation matrix ``exp(hat(w))`` by Rodrigues' formula, with a Taylor branch near zero.

    Parameters
    ----------
    w : array_like, shape (..., 3), or CasADi (3, 1)
        Rotation vector(s) (rad): axis times angle.

    Returns
    -------
    ndarray, shape (..., 3, 3), or CasADi (3, 3)
        The rotation matrices; finite (and exact to round-off) at ``w = 0``.

    Raises
    ------
    InvalidInput
        If a numpy input does not have shape (..., 3).
    """
    if _symbolic(w):
        import casadi as ca
        th2 = ca.dot(w, w)
        th = ca.sqrt(th2 + 1e-300)
        a = ca.if_else(th2 < _SMALL**2, 1 - th2 / 6, ca.sin(th) / th)
        b = ca.if_else(th2 < _SMALL**2, 0.5 - th2 / 24, (1 - ca.cos(th)) / (th2 + 1e-300))
        W = hat(w)
        return ca.DM.eye(3) + a * W + b * (W @ W)
    w = _vectors(w, "w")
    th2 = np.sum(w * w, axis=-1)
    th = np.sqrt(th2)
    small = th < _SMALL
    if np.any(small):
        ths = np.where(small, 1.0, th)
        a = np.where(small, 1 - th2 / 6, np.sin(ths) / ths)
        b = np.where(small, 0.5 - th2 / 24, (1 - np.cos(ths)) / ths**2)
    else:                           # the same numbers without the Taylor branch's arrays
        a, b = np.sin(th) / th, (1 - np.cos(th)) / th**2
    W = _hat(w)
    return _EYE3 + a[..., None, None] * W + b[..., None, None] * (W @ W)


def log(R: Any) -> Any:
    """Rotation vector ``w`` with ``exp(w) == R`` and ``|w| <= pi``.

    Parameters
    ----------
    R : array_like, shape (..., 3, 3), or CasADi (3, 3)
        Rotation matrices (not checked to be rotations: validate inputs from users with
        ``csjm_opt._validate.as_rotation``).

    Returns
    -------
    ndarray, shape (..., 3), or CasADi (3, 1)
        Rotation vectors (rad); accurate near 0 and near pi.

    Raises
    ------
    InvalidInput
        If a numpy input does not have shape (..., 3, 3).
    """
    if _symbolic(R):
        return _log_casadi(R)
    R = _matrices(R, "R")
    cos = np.clip((np.trace(R, axis1=-2, axis2=-1) - 1) / 2, -1.0, 1.0)
    v = vee(R)  # = sin(th) * axis
    sin = np.linalg.norm(v, axis=-1)
    th = np.arctan2(sin, cos)
    small = th < _SMALL
    near_pi = th > np.pi - 1e-3
    scale = np.where(small, 1 + th**2 / 6, th / np.where(small | near_pi, 1.0, sin))
    out = scale[..., None] * v
    if np.any(near_pi):
        S = 0.5 * (R + np.swapaxes(R, -1, -2))
        B = (S - cos[..., None, None] * np.eye(3)) / np.maximum(1 - cos, 1e-12)[..., None, None]
        # B = n n^T: take its largest column for a well-conditioned axis.
        diag = np.diagonal(B, axis1=-2, axis2=-1)
        j = np.argmax(diag, axis=-1)
        col = np.take_along_axis(B, j[..., None, None].repeat(3, axis=-2), axis=-1)[..., 0]
        n = col / np.sqrt(np.maximum(np.take_along_axis(diag, j[..., None], -1), 1e-300))
        sign = np.where(np.sum(n * v, axis=-1) < 0, -1.0, 1.0)
        out = np.where(near_pi[..., None], (sign * th)[..., None] * n, out)
    return out


def _log_casadi(R: Any) -> Any:
    """Symbolic log with the same three branches as the numpy version."""
    import casadi as ca

    v = vee(R)
    sin = ca.sqrt(ca.dot(v, v))
    cos = (R[0, 0] + R[1, 1] + R[2, 2] - 1) / 2
    th = ca.atan2(sin, cos)
    generic = th / ca.fmax(sin, 1e-300) * v
    small = (1 + th**2 / 6) * v
    # near pi: axis from the largest diagonal entry of (R + R^T)/2 - cos I = (1 - cos) n n^T
    S = 0.5 * (R + R.T) - cos * ca.DM.eye(3)
    cols = [S[:, j] / ca.sqrt(ca.fmax(S[j, j] * (1 - cos), 1e-300)) * ca.sqrt(1 - cos) for j in range(3)]
    n = ca.if_else(ca.logic_and(S[0, 0] >= S[1, 1], S[0, 0] >= S[2, 2]), cols[0],
                   ca.if_else(S[1, 1] >= S[2, 2], cols[1], cols[2]))
    n = n / ca.sqrt(ca.fmax(ca.dot(n, n), 1e-300))
    n = ca.if_else(ca.dot(n, v) < 0, -n, n)
    return ca.if_else(th < _SMALL, small, ca.if_else(th > np.pi - 1e-3, th * n, generic))


def random_rotations(n: int, rng: np.random.Generator, max_angle: float = np.pi) -> np.ndarray:
    """Random rotations: axes uniform on the sphere, angles uniform in ``[0, max_angle]``.

    Parameters
    ----------
    n : int
        Number of rotations (>= 0).
    rng : numpy.random.Generator
        Random generator.
    max_angle : float, optional
        Largest rotation angle (rad).

    Returns
    -------
    ndarray, shape (n, 3, 3)
        The rotations.

    Raises
    ------
    InvalidInput
        If ``n`` is negative or not an integer, or ``max_angle`` is negative or not finite.
    """
    if not (isinstance(n, (int, np.integer)) and n >= 0):
        raise InvalidInput(f"n: expected an integer >= 0, got {n!r}", "n")
    if not (np.isfinite(max_angle) and max_angle >= 0):
        raise InvalidInput(f"max_angle: expected a finite angle >= 0 (rad), got {max_angle!r}", "max_angle")
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    return exp(axis * rng.uniform(0, max_angle, size=(n, 1)))


def angle_between(R1: Any, R2: Any) -> np.ndarray:
    """Geodesic distance ``||log(R1^T R2)||`` (rad), paper (63)-(65).

    Parameters
    ----------
    R1, R2 : array_like, shape (..., 3, 3)
        Rotations (broadcast against each other).

    Returns
    -------
    ndarray, shape (...)
        Angles in ``[0, pi]`` (rad).

    Raises
    ------
    InvalidInput
        If an input does not have shape (..., 3, 3) or the shapes do not broadcast.
    """
    R1 = _matrices(R1, "R1")
    R2 = _matrices(R2, "R2")
    try:
        product = np.swapaxes(R1, -1, -2) @ R2
    except ValueError:
        raise InvalidInput(f"R1 {R1.shape} and R2 {R2.shape} do not broadcast", "R2") from None
    return np.linalg.norm(log(product), axis=-1)
