"""Validated top-level functions of docs/conventions.md that are not planners."""

from __future__ import annotations

import numpy as np

from .numeric import Model
from .rig import Rig
from .._validate import as_array, as_rotation, as_rotations


def stiffness(rig: Rig, R: np.ndarray, tensions_N: np.ndarray, model: Model | None = None) -> np.ndarray:
    """K (3, 3) in N m/rad at ``R`` for cable tensions ``tensions_N`` (6,).

    load convention of docs/conventions.md: ``K = dtau_load/dzeta - 1/2 hat(tau_load)``, the
    Levi-Civita Hessian of the cable energy; symmetric, positive definite at a
    stable pose. Equals minus the paper's (45) with corrected (31).
    """
    model = model or Model(rig)
    return model.stiffness(as_rotation(R), as_array(tensions_N, (6,), "tensions"))


def stiffness_batch(rig: Rig, Rs: np.ndarray, tensions_N: np.ndarray, model: Model | None = None) -> np.ndarray:
    """K for ``n`` poses (n, 3, 3) and tensions (n, 6), in one CasADi ``map`` call."""
    model = model or Model(rig)
    Rs = as_rotations(Rs)
    return model.stiffness(Rs, as_array(tensions_N, (Rs.shape[0], 6), "tensions"))
