"""Numeric model of a rig: the compiled kernels, with the CasADi model as reference.

:class:`Model` binds a :class:`~csjm_opt.model.rig.Rig` to the compiled cable
physics of :mod:`csjm_opt.model.kernels` (numba; same closed forms as the
numpy reference :mod:`csjm_opt.model.cable_terms`). Every method takes one
pose ``R`` (3, 3) or a stack ``Rs`` (n, 3, 3); stacks run in parallel.
Inputs are trusted here (float64 rotations of the right shape); the public
functions in :mod:`csjm_opt.model.joint_stiffness` validate them.

The named CasADi functions of :mod:`csjm_opt.model.casadi_model` stay
available as :attr:`Model.functions` and through :meth:`Model.casadi`, the
symbolic reference the kernels are tested against (evaluated by a CasADi
``map`` for stacks; ``compiled=True`` JIT-compiles them to C first).
"""

from __future__ import annotations

import functools
import os
import threading
import weakref
from typing import Any

import numpy as np

from .._validate import as_rotations
from . import kernels as kernels
from ._casadi_eval import CasadiReference, _jit, _mapped, _squeeze, _stack_h, _unstack_h  # noqa: F401
from .rig import Rig


def _f64(X: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(X, dtype=np.float64)


#: Batches at least this large run on all numba threads (smaller ones are not worth the start-up).
PARALLEL_MIN_POSES = 4096


def parallel_ok(n: int) -> bool:
    """Whether ``n`` poses go to the parallel kernels: large batches, from the main thread only.

    numba's workqueue threading layer (chosen because it survives ``fork()``)
    must not be entered from two threads at once, so calls from other threads
    (a threaded Dask worker, a GUI) run the serial kernels. The layer is chosen
    here, before the first parallel call, not at import (see
    :func:`_choose_threading_layer`).

    Parameters
    ----------
    n : int
        Number of poses of the batch.

    Returns
    -------
    bool
        True when the batch goes to the ``*_par`` kernels.
    """
    ok = n >= PARALLEL_MIN_POSES and threading.current_thread() is threading.main_thread()
    if ok:
        _choose_threading_layer()
    return ok


@functools.cache
def _choose_threading_layer() -> None:
    """Pick numba's ``workqueue`` layer before the first parallel kernel runs, unless the user chose one.

    GNU OpenMP aborts a process that forks after using it (a sweep's process pool
    did); workqueue does not. A layer set through ``NUMBA_THREADING_LAYER`` or
    ``numba.config.THREADING_LAYER`` is left alone. Nothing is changed by
    importing the package: only a process that runs a parallel kernel gets here.
    """
    import numba

    if "NUMBA_THREADING_LAYER" not in os.environ and numba.config.THREADING_LAYER == "default":  # type: ignore[attr-defined]
        numba.config.THREADING_LAYER = "workqueue"  # type: ignore[attr-defined]


def as_rotations_fast(Rs: Any, name: str = "Rs") -> np.ndarray:
    """:func:`csjm_opt._validate.as_rotations` with a compiled check for the common case.

    A float64 stack of exact rotations (to 1e-12) is returned as is (no copy);
    anything else goes through the validator (which explains or re-orthonormalises).
    """
    if isinstance(Rs, np.ndarray) and Rs.dtype == np.float64 and Rs.ndim == 3 and Rs.shape[1:] == (3, 3) \
            and Rs.flags.c_contiguous and kernels.all_exact_rotations(Rs):
        return Rs
    return as_rotations(Rs, name)


def _many(name: str, n: int):
    return getattr(kernels, name + "_par" if parallel_ok(n) else name)


class Model(CasadiReference):
    """Cable geometry, Jacobian, moments and stiffness of one rig (compiled kernels).

    Parameters
    ----------
    rig : the rig.
    compiled : JIT-compile the CasADi reference functions to C for
        :meth:`casadi` (needs a C compiler; falls back to the CasADi VM).
    """

    def __init__(self, rig: Rig, compiled: bool = False):
        self.rig = rig
        self.compiled = compiled
        self.A = _f64(rig.platform_holes_A_m).copy()
        self.B = _f64(rig.base_holes_B_m).copy()
        self.k = _f64(rig.cable_stiffness_N_per_m).copy()
        self.first_moment_A_kgm = rig.platform_mass_kg * _f64(rig.com_A_m)
        self.g = _f64(rig.gravity_B_m_per_s2).copy()
        self.n_cables = int(self.A.shape[0])
        self.t_mid = np.full(self.n_cables, 0.5 * (rig.t_min_N + rig.t_max_N))
        self.t_mid.setflags(write=False)

    # ------------------------------------------------------- single-pose fast path
    def pose_terms(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Cable lengths, J and weight moment at one pose, in one kernel call (~1 us).

        The per-step call of a controller: no validation.

        Parameters
        ----------
        R : (3, 3) float64 rotation of {A} in {B} (trusted).

        Returns
        -------
        c : (m,) cable lengths (m); J : (m, 3) Jacobian (38); tau_weight : (3,) weight moment in {A} (N m).
        """
        m = self.n_cables
        c, J, tau_w = np.empty(m), np.empty((m, 3)), np.empty(3)
        kernels.pose_terms_into(self.A, self.B, self.first_moment_A_kgm, self.g, R, c, J, tau_w)
        return c, J, tau_w

    # ----------------------------------------------------------------- kernels
    def geometry(self, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cable lengths (m) and J: ``(m,), (m, 3)`` or ``(n, m), (n, m, 3)``."""
        if R.ndim == 2:
            m = self.n_cables
            c, U, J = np.empty(m), np.empty((m, 3)), np.empty((m, 3))
            kernels.geometry_into(self.A, self.B, R, c, U, J)
            return c, J
        n = R.shape[0]
        c, J = np.empty((n, self.n_cables)), np.empty((n, self.n_cables, 3))
        _many("geometry_many", R.shape[0])(self.A, self.B, _f64(R), c, J)
        return c, J

    def cable_vectors_B(self, R: np.ndarray) -> np.ndarray:
        """Cable vectors ``c_i = b_i - R a_i`` in {B}: (m, 3) or (n, m, 3), m."""
        return self.B - self.A @ np.swapaxes(R, -1, -2)

    def cable_lengths(self, R: np.ndarray) -> np.ndarray:
        """Cable lengths ``c_i = ||b_i - R a_i||``.

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).

        Returns
        -------
        ndarray, shape (m,) or (n, m)
            Lengths (m).
        """
        return self.geometry(R)[0]

    def jacobian(self, R: np.ndarray) -> np.ndarray:
        """The Jacobian ``J`` of (38): row i is ``a_i x (R^T u_i)`` in {A}; ``dc = -J dzeta`` (40).

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).

        Returns
        -------
        ndarray, shape (m, 3) or (n, m, 3)
            ``J`` per pose (m).
        """
        return self.geometry(R)[1]

    def cable_moment(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """The cables' moment ``J^T T`` on the platform about O, in {A}.

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).
        T : ndarray, shape (m,) or (n, m)
            Cable tensions (N).

        Returns
        -------
        ndarray, shape (3,) or (n, 3)
            Moment (N m).
        """
        J = self.jacobian(R)
        return np.einsum("...ij,...i->...j", J, T)

    def stiffness(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """The stiffness K (load convention of docs/conventions.md) for given tensions.

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).
        T : ndarray, shape (m,) or (n, m)
            Cable tensions (N); ``T_i <= 0`` is a slack cable.

        Returns
        -------
        ndarray, shape (3, 3) or (n, 3, 3)
            K (N m/rad), symmetric.
        """
        if R.ndim == 2:
            K = np.empty((3, 3))
            kernels.stiffness_into(self.A, self.B, self.k, R, _f64(T), K)
            return K
        K = np.empty((R.shape[0], 3, 3))
        _many("stiffness_many", R.shape[0])(self.A, self.B, self.k, _f64(R), _f64(T), K)
        return K

    def stiffness_rest(self, R: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, Any]:
        """K, tensions, cable moment and cable energy for rest lengths, slack cables found.

        Parameters
        ----------
        R : (3, 3) or (n, 3, 3) rotations (trusted).
        l : (m,) or (n, m) rest lengths (m).

        Returns
        -------
        K : (..., 3, 3); T : (..., m) tensions ``k (c - l)``, 0 when ``c <= l``;
        tau : (..., 3) cables' moment ``J^T T`` in {A}; energy : float or (n,) cable energy (J).
        """
        if R.ndim == 2:
            K, T, tau = np.empty((3, 3)), np.empty(self.n_cables), np.empty(3)
            kernels.rest_terms_into(self.A, self.B, self.k, R, _f64(l), K, T, tau)
        else:
            n = R.shape[0]
            K, T, tau = np.empty((n, 3, 3)), np.empty((n, self.n_cables)), np.empty((n, 3))
            _many("rest_terms_many", R.shape[0])(self.A, self.B, self.k, _f64(R), _f64(l), K, T, tau)
        energy = 0.5 * np.sum(T * T / self.k, axis=-1)       # 1/2 k s^2 = 1/2 t^2 / k
        return K, T, tau, (float(energy) if R.ndim == 2 else energy)

    def tensions_from_rest(self, R: np.ndarray, l: np.ndarray) -> np.ndarray:
        """Tensions ``t = k (c - l)`` for taut cables, 0 for slack ones.

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).
        l : ndarray, shape (m,) or (n, m)
            Rest lengths (m).

        Returns
        -------
        ndarray, shape (m,) or (n, m)
            Tensions (N).
        """
        return np.maximum(self.k * (self.cable_lengths(R) - l), 0.0)

    def rest_lengths(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """Rest lengths that produce tensions ``T`` at ``R``: ``l = c - T / k``.

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).
        T : ndarray, shape (m,) or (n, m)
            Cable tensions (N).

        Returns
        -------
        ndarray, shape (m,) or (n, m)
            Rest lengths (m).
        """
        return self.cable_lengths(R) - np.asarray(T) / self.k

    def weight_moment(self, R: np.ndarray) -> np.ndarray:
        """Moment of the platform's weight about O, in {A}: ``m r_G x (R^T g)``, (56).

        Parameters
        ----------
        R : ndarray, shape (3, 3) or (n, 3, 3)
            Orientation(s) of {A} in {B} (not validated: the fast path trusts its caller; use the
            top-level functions for user input).

        Returns
        -------
        ndarray, shape (3,) or (n, 3)
            Moment (N m).
        """
        if R.ndim == 2:
            out = np.empty(3)
            kernels.weight_moment_into(self.first_moment_A_kgm, self.g, R, out)
            return out
        out = np.empty((R.shape[0], 3))
        _many("weight_moment_many", R.shape[0])(self.first_moment_A_kgm, self.g, _f64(R), out)
        return out

    def stiffness_basis(self, Rs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``K(T) = K0 + sum_i T_i G_i`` (all cables taut): K0 (n, 3, 3), G (n, m, 3, 3)."""
        n = Rs.shape[0]
        K0, G = np.empty((n, 3, 3)), np.empty((n, self.n_cables, 3, 3))
        _many("stiffness_basis_many", Rs.shape[0])(self.A, self.B, self.k, _f64(Rs), K0, G)
        return K0, G



_MODELS: weakref.WeakKeyDictionary[Rig, Model] = weakref.WeakKeyDictionary()


def model_for(rig: Rig, model: Model | None = None) -> Model:
    """``model`` if it belongs to ``rig``, else a cached :class:`Model` of ``rig`` (one per rig object)."""
    if model is not None and model.rig is rig:
        return model
    cached = _MODELS.get(rig)
    if cached is None:
        cached = _MODELS[rig] = Model(rig)
    return cached
