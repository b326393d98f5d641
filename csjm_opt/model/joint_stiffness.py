"""Validated stiffness functions of the public API: K at one pose or many.

K is the load-convention (docs/conventions.md) stiffness ``K = dtau_load/dzeta - 1/2
hat(tau_load)``, the Levi-Civita Hessian of the cable energy
``sum 1/2 k_i (c_i - l_i)^2`` (minus the paper's (45) with corrected
structure constants (31)), computed in closed form by the compiled kernels
of :mod:`csjm_opt.model.kernels`::

    K = sum_{i taut} k_i j_i j_i^T + sum_i t_i Hess(c_i)

**Slack cables.** K needs to know which cables are taut. Given tensions,
a cable with ``t_i <= 0`` is slack and contributes nothing (neither
``k_i j_i j_i^T`` nor a tension term); given rest lengths
(``rest_lengths_m=``), a cable with ``c_i <= l_i`` is slack and the
tensions are ``t_i = k_i (c_i - l_i)`` for the others.

**Checks.** Tensions from a planner lie in ``[t_min, t_max]`` and hold the
pose's load; :func:`stiffness` checks the bounds of the taut cables (within
``bound_tol_N``; ``t_i <= 0`` is slack, not a violation) unless
``check_bounds=False``, and checks equilibrium when the load
``tau_ext_A_Nm`` is given. K is returned whatever its eigenvalues: a K
that is not positive definite means an unstable pose (see :func:`is_stable`).
"""

from __future__ import annotations

import numpy as np

from .._validate import ROTATION_TOL, as_array, as_rotation, as_vector3
from ..errors import InconsistentTensions, InvalidInput
from . import kernels as kernels
from .numeric import Model, as_rotations_fast, model_for
from .rig import Rig

#: Default tolerances of the tension checks.
BOUND_TOL_N = 1e-6
EQUILIBRIUM_TOL_NM = 1e-6

_NO_LOAD = np.zeros(3)


def stiffness(rig: Rig, R: np.ndarray, tensions_N: np.ndarray | None = None, model: Model | None = None, *,
              tau_ext_A_Nm: np.ndarray | None = None, rest_lengths_m: np.ndarray | None = None,
              check_bounds: bool = True, bound_tol_N: float = BOUND_TOL_N,
              equilibrium_tol_Nm: float = EQUILIBRIUM_TOL_NM) -> np.ndarray:
    """K (3, 3) in N m/rad at ``R`` for cable tensions (or rest lengths).

    Parameters
    ----------
    rig : the rig.
    R : (3, 3) orientation of {A} in {B}.
    tensions_N : (m,) cable tensions; ``t_i <= 0`` marks cable i slack.
    model : a :class:`Model` of ``rig`` to reuse (optional).
    tau_ext_A_Nm : (3,) external load in {A} (weight excluded); when given, the
        tensions must hold it: ``||J^T T + tau_ext + tau_weight|| <= equilibrium_tol_Nm``.
    rest_lengths_m : (m,) rest lengths instead of tensions: tensions follow from
        ``t = k (c - l)``, slack cables are found, the bounds are not checked.
    check_bounds : check ``t_min - bound_tol_N <= t_i <= t_max + bound_tol_N`` for every
        taut cable (``t_i > 0``); set False for states outside the planner's box.
    bound_tol_N, equilibrium_tol_Nm : tolerances of the checks.

    Returns
    -------
    K : (3, 3) symmetric; positive definite at a stable pose.

    Raises
    ------
    InvalidInput, NotARotation : bad shapes, non-finite numbers, not a rotation.
    InconsistentTensions : tensions outside the bounds or out of equilibrium.
    """
    if (tensions_N is None) == (rest_lengths_m is None):
        raise InvalidInput("give exactly one of tensions_N and rest_lengths_m", "tensions")
    model = model_for(rig, model)
    if rest_lengths_m is not None:
        K, T, _, _ = model.stiffness_rest(as_rotation(R), as_array(rest_lengths_m, (rig.n_cables,), "rest_lengths_m"))
        if tau_ext_A_Nm is not None:
            _check_equilibrium(model, as_rotation(R), T, as_vector3(tau_ext_A_Nm, "tau_ext"), equilibrium_tol_Nm)
        return K
    R_arr = R if isinstance(R, np.ndarray) and R.dtype == np.float64 and R.shape == (3, 3) \
        else np.asarray(as_array(R, (3, 3), "R"))
    T = tensions_N if isinstance(tensions_N, np.ndarray) and tensions_N.dtype == np.float64 \
        and tensions_N.shape == (rig.n_cables,) else as_array(tensions_N, (rig.n_cables,), "tensions")
    check_eq = tau_ext_A_Nm is not None
    tau = as_vector3(tau_ext_A_Nm, "tau_ext") if check_eq else _NO_LOAD
    lo, hi = (rig.t_min_N, rig.t_max_N) if check_bounds else (1.0, -1.0)
    K, info = np.empty((3, 3)), np.empty(2)
    status = kernels.checked_stiffness_into(model.A, model.B, model.k, model.first_moment_A_kgm, model.g,
                                            R_arr, T, lo, hi, tau, check_eq, 1e-12, K, info)
    if status != kernels.OK:  # the slow path says what is wrong, or re-orthonormalises R
        R_arr = as_rotation(R_arr)
        as_array(T, (rig.n_cables,), "tensions")
        status = kernels.checked_stiffness_into(model.A, model.B, model.k, model.first_moment_A_kgm,
                                                model.g, R_arr, T, lo, hi, tau, check_eq, ROTATION_TOL, K, info)
    if check_bounds and info[0] > bound_tol_N:
        raise InconsistentTensions(
            f"tensions {np.round(T, 4).tolist()} N leave [{rig.t_min_N:g}, {rig.t_max_N:g}] N by "
            f"{info[0]:.3g} N (pass check_bounds=False for a state outside the planner's bounds)",
            "bounds", info[0])
    if check_eq and info[1] > equilibrium_tol_Nm:
        raise _not_in_equilibrium(info[1], equilibrium_tol_Nm)
    return K


def stiffness_batch(rig: Rig, Rs: np.ndarray, tensions_N: np.ndarray, model: Model | None = None, *,
                    check_bounds: bool = True, bound_tol_N: float = BOUND_TOL_N) -> np.ndarray:
    """K for ``n`` poses (n, 3, 3) and tensions (n, m), compiled and parallel.

    Parameters
    ----------
    rig : the rig.
    Rs : (n, 3, 3) orientations.
    tensions_N : (n, m) tensions; ``t_i <= 0`` marks a slack cable.
    model : a :class:`Model` of ``rig`` to reuse (optional).
    check_bounds, bound_tol_N : as in :func:`stiffness`.

    Returns
    -------
    K : (n, 3, 3).

    Raises
    ------
    InvalidInput, NotARotation : bad shapes, non-finite numbers, not rotations.
    InconsistentTensions : a row of tensions outside the bounds.
    """
    model = model_for(rig, model)
    Rs = as_rotations_fast(Rs)
    T = as_array(tensions_N, (Rs.shape[0], rig.n_cables), "tensions")
    if check_bounds and T.size:
        viol = np.where(T > 0, np.maximum(rig.t_min_N - T, T - rig.t_max_N), -np.inf).max(axis=1)
        if viol.max() > bound_tol_N:
            i = int(np.argmax(viol))
            raise InconsistentTensions(
                f"tensions[{i}] {np.round(T[i], 4).tolist()} N leave [{rig.t_min_N:g}, {rig.t_max_N:g}] N "
                f"by {viol[i]:.3g} N (pass check_bounds=False for states outside the planner's bounds)",
                "bounds", viol[i])
    return model.stiffness(Rs, T)


def is_stable(K: np.ndarray, tol_Nm_per_rad: float = 0.0) -> bool | np.ndarray:
    """Whether K (3, 3) or (n, 3, 3) is positive definite (smallest eigenvalue > tol): a stable pose."""
    return np.linalg.eigvalsh(0.5 * (K + np.swapaxes(K, -1, -2)))[..., 0] > tol_Nm_per_rad


def _check_equilibrium(model: Model, R: np.ndarray, T: np.ndarray, tau_ext: np.ndarray, tol: float) -> None:
    _, J, tau_w = model.pose_terms(R)
    res = float(np.linalg.norm(J.T @ T + tau_ext + tau_w))
    if res > tol:
        raise _not_in_equilibrium(res, tol)


def _not_in_equilibrium(residual: float, tol: float) -> InconsistentTensions:
    return InconsistentTensions(
        f"the tensions do not hold the load at this pose: ||J^T T + tau_ext + tau_weight|| = "
        f"{residual:.3g} N m > {tol:g} N m", "equilibrium", residual)
