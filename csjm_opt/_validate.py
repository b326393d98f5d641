"""Validators used at the package boundary (pytransform3d ``check_matrix`` style).

Each converts to float64, checks shape and finiteness, and raises an
:class:`~csjm_opt.errors.InvalidInput` (or subclass) that says what was
expected and what was given. Inside the package, types are trusted.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .errors import InvalidInput, NotARotation

#: Default tolerance on ``||R^T R - I||_F`` for a matrix accepted as a rotation.
#: Loose enough for matrices printed to three decimals (the paper's R0 after
#: errata item 3 is orthogonal to 1e-3), tight enough to reject the printed R0
#: (0.81).
ROTATION_TOL = 1e-2


def as_array(value: Any, shape: tuple[int | None, ...], name: str) -> np.ndarray:
    """Return ``value`` as a finite float64 array of ``shape`` (``None`` = any)."""
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidInput(f"{name}: expected numbers of shape {_fmt(shape)}, got {value!r:.80}",
                           name) from exc
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape)):
        raise InvalidInput(f"{name}: expected shape {_fmt(shape)}, got {arr.shape}", name)
    if not np.all(np.isfinite(arr)):
        raise InvalidInput(f"{name}: expected finite numbers, got {arr.ravel()[~np.isfinite(arr.ravel())][:3]}",
                           name)
    return arr


def as_vector3(value: Any, name: str) -> np.ndarray:
    """A finite (3,) float64 vector."""
    return as_array(value, (3,), name)


def as_rotation(R: Any, name: str = "R", tol: float = ROTATION_TOL) -> np.ndarray:
    """Validate a rotation matrix and return its nearest exact rotation.

    Raises :class:`NotARotation` with the measured ``||R^T R - I||_F`` and
    ``det(R)`` when ``R`` is not a rotation within ``tol``.
    """
    arr = as_array(R, (3, 3), name)
    return as_rotations(arr[None], name, tol)[0]


def as_rotations(Rs: Any, name: str = "Rs", tol: float = ROTATION_TOL) -> np.ndarray:
    """Validate a stack (n, 3, 3) of rotations; return them re-orthonormalised."""
    arr = as_array(Rs, (None, 3, 3), name)
    err = np.linalg.norm(np.swapaxes(arr, -1, -2) @ arr - np.eye(3), axis=(-2, -1))
    det = np.linalg.det(arr)
    bad = (err > tol) | (det <= 0)
    if np.any(bad):
        i = int(np.argmax(bad))
        where = f"{name}[{i}]" if arr.shape[0] > 1 else name
        raise NotARotation(
            f"{where} is not a rotation: ||R^T R - I|| = {err[i]:.3g} (tolerance {tol:g}), "
            f"det = {det[i]:.4g}", err[i], det[i], name)
    out = np.array(arr)
    fix = err > 1e-12  # re-orthonormalise only what is not already a rotation to round-off
    if np.any(fix):
        U, _, Vt = np.linalg.svd(arr[fix])
        out[fix] = U @ Vt
    return out


def _fmt(shape: tuple[int | None, ...]) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
