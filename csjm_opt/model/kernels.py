"""Compiled (numba) cable physics: geometry, J (38), weight moment, K, one pose or many.

The same closed forms as the numpy reference :mod:`csjm_opt.model.cable_terms`
(read its docstring for the formulas), written as loops that allocate
nothing: ``*_into`` functions write into arrays the caller owns, so a
controller can call them every step at a cost of ~1 us. The ``*_many``
functions loop over poses; their ``*_many_par`` twins do the same in
parallel (``prange``, ``NUMBA_NUM_THREADS`` threads), for large batches
called from the main thread (the workqueue threading layer must not be
entered from two threads at once; see :func:`csjm_opt.model.numeric.parallel_ok`).
``tests/model/test_stiffness_kernel.py`` checks every kernel against the numpy reference,
the CasADi model and a finite-difference energy Hessian.
Compiled on first use and cached on disk (``cache=True``).

The kernels live in :mod:`csjm_opt.model._pose_kernels` (one pose) and
:mod:`csjm_opt.model._batch_kernels` (stacks, serial and parallel); this module
re-exports the same function objects.

Argument names: ``A`` (m, 3) platform holes in {A}, ``B`` (m, 3) base holes
in {B}, ``k`` (m,) cable stiffness (m cables, from the arrays), ``m r`` the first moment of the platform's
mass (kg m) in {A} and ``g`` gravity in {B}; ``R`` (3, 3) or ``Rs`` (n, 3, 3).
"""

from __future__ import annotations

from ._batch_kernels import (
    _CHUNKS,  # noqa: F401
    geometry_many,
    geometry_many_par,
    rest_terms_many,
    rest_terms_many_par,
    stiffness_basis_many,
    stiffness_basis_many_par,
    stiffness_many,
    stiffness_many_par,
    weight_moment_many,
    weight_moment_many_par,
)
from ._pose_kernels import (
    NON_FINITE,
    NOT_A_ROTATION,
    OK,
    all_exact_rotations,
    checked_stiffness_into,
    det3,
    geometry_into,
    pose_terms_into,
    rest_terms_into,
    rotation_error,
    stiffness_from_geometry_into,
    stiffness_into,
    weight_moment_into,
)

__all__ = [
    "NON_FINITE", "NOT_A_ROTATION", "OK", "all_exact_rotations", "checked_stiffness_into", "det3",
    "geometry_into", "geometry_many", "geometry_many_par", "pose_terms_into", "rest_terms_into",
    "rest_terms_many", "rest_terms_many_par", "rotation_error", "stiffness_basis_many",
    "stiffness_basis_many_par", "stiffness_from_geometry_into", "stiffness_into", "stiffness_many",
    "stiffness_many_par", "weight_moment_into", "weight_moment_many", "weight_moment_many_par",
]
