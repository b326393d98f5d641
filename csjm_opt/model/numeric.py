"""Numeric model of a rig: fast wrappers around the CasADi functions.

:class:`Model` binds a :class:`~csjm_opt.model.rig.Rig` to the named CasADi
functions of :mod:`csjm_opt.model.casadi_model`. Every method takes one pose
``R`` (3, 3) or a stack ``Rs`` (n, 3, 3); stacks are evaluated by a CasADi
``map`` (one call for all poses). Inputs are trusted here; the public
functions in :mod:`csjm_opt.model.stiffness` validate them.
"""

from __future__ import annotations

import functools
from typing import Any

import casadi as ca
import numpy as np

from .casadi_model import build_functions
from .rig import Rig


def _stack_h(X: np.ndarray) -> np.ndarray:
    """(n, r, c) -> (r, n*c), CasADi's horizontal stacking for ``map``."""
    n, r, c = X.shape
    return np.ascontiguousarray(X.transpose(1, 0, 2).reshape(r, n * c))


def _unstack_h(M: np.ndarray, n: int) -> np.ndarray:
    """(r, n*c) -> (n, r, c)."""
    r = M.shape[0]
    return M.reshape(r, n, -1).transpose(1, 0, 2)


class Model:
    """Cable geometry, Jacobian, moments and stiffness of one rig.

    ``compiled=True`` evaluates stacks of poses with C code generated from the
    CasADi functions and compiled by the system C compiler on first use
    (about 2x faster than ``map`` for 10,000 poses, after a one-time compile of
    ~1-2 s; see benchmarks/bench_model.py). Without a compiler it falls back to
    the CasADi virtual machine.
    """

    def __init__(self, rig: Rig, compiled: bool = False):
        self.rig = rig
        self.compiled = compiled
        self._A = np.ascontiguousarray(rig.platform_holes_A_m.T)   # (3, 6)
        self._B = np.ascontiguousarray(rig.base_holes_B_m.T)       # (3, 6)
        self._k = np.asarray(rig.cable_stiffness_N_per_m, float).reshape(6, 1)
        self.functions = build_functions()

    # ---------------------------------------------------------------- calls
    def _call(self, name: str, R: np.ndarray, *per_pose: np.ndarray, consts: tuple = ()) -> list[np.ndarray]:
        f = self.functions[name]
        if R.ndim == 2:
            args = [R] + [np.reshape(p, (-1, 1)) for p in per_pose] + list(consts)
            return [np.array(o) for o in f.call(args)]
        n = R.shape[0]
        fm = _mapped(name, n, self.compiled)
        args = [_stack_h(R)] + [np.asarray(p, float).T for p in per_pose] + list(consts)
        return [np.array(o) for o in fm.call(args)]

    def cable_vectors_B(self, R: np.ndarray) -> np.ndarray:
        """Cable vectors ``c_i = b_i - R a_i`` in {B}: (6, 3) or (n, 6, 3), m."""
        (C,) = self._call("cable_vectors", R, consts=(self._A, self._B))
        return C.T if R.ndim == 2 else _unstack_h(C, R.shape[0]).transpose(0, 2, 1)

    def cable_lengths(self, R: np.ndarray) -> np.ndarray:
        """Cable lengths ``c_i`` (m): (6,) or (n, 6)."""
        (c,) = self._call("cable_lengths", R, consts=(self._A, self._B))
        return c.ravel() if R.ndim == 2 else c.T

    def jacobian(self, R: np.ndarray) -> np.ndarray:
        """J of (38): (6, 3) or (n, 6, 3); rows ``a_i x (R^T u_i)`` in {A}."""
        (J,) = self._call("jacobian", R, consts=(self._A, self._B))
        return J if R.ndim == 2 else _unstack_h(J, R.shape[0])

    def cable_moment(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """Cables' moment ``J^T T`` on the platform about O, in {A} (N m)."""
        (tau,) = self._call("cable_moment", R, T, consts=(self._A, self._B))
        return tau.ravel() if R.ndim == 2 else tau.T

    def stiffness(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """K (load convention of docs/conventions.md, N m/rad) for given tensions: (3, 3) or (n, 3, 3)."""
        (K,) = self._call("stiffness", R, T, consts=(self._k, self._A, self._B))
        return K if R.ndim == 2 else _unstack_h(K, R.shape[0])

    def stiffness_rest(self, R: np.ndarray, l: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """K, tensions T, cable moment and cable energy for rest lengths ``l`` (m)."""
        K, T, tau, energy = self._call("stiffness_rest", R, l, consts=(self._k, self._A, self._B))
        if R.ndim == 2:
            return K, T.ravel(), tau.ravel(), energy.ravel()[0]
        n = R.shape[0]
        return _unstack_h(K, n), T.T, tau.T, energy.ravel()

    def tensions_from_rest(self, R: np.ndarray, l: np.ndarray) -> np.ndarray:
        """``t = k (c - l)`` for taut cables, 0 for slack ones (N)."""
        (T,) = self._call("tensions_from_rest", R, l, consts=(self._k, self._A, self._B))
        return T.ravel() if R.ndim == 2 else T.T

    def rest_lengths(self, R: np.ndarray, T: np.ndarray) -> np.ndarray:
        """Rest lengths that produce tensions ``T`` at ``R``: ``l = c - T / k`` (m)."""
        return self.cable_lengths(R) - np.asarray(T) / self._k.ravel()

    def weight_moment(self, R: np.ndarray) -> np.ndarray:
        """Moment of the platform's weight about O in {A} (N m)."""
        return self.point_force_moment(R, self.rig.platform_mass_kg * self.rig.gravity_B_m_per_s2,
                                       self.rig.com_A_m)[0]

    def point_force_moment(self, R: np.ndarray, force_B_N: np.ndarray,
                           point_A_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Moment (in {A}) and Levi-Civita energy Hessian of a force fixed in {B} at a platform point."""
        f = self.functions["weight_moment"]
        consts = (1.0, np.reshape(point_A_m, (3, 1)), np.reshape(force_B_N, (3, 1)))
        if R.ndim == 2:
            tau, H = f.call([R, *consts])
            return np.array(tau).ravel(), np.array(H)
        n = R.shape[0]
        tau, H = _mapped("weight_moment", n).call([_stack_h(R), *consts])
        return np.array(tau).T, _unstack_h(np.array(H), n)


@functools.lru_cache(maxsize=32)
def _mapped(name: str, n: int, compiled: bool = False) -> Any:
    """``build_functions()[name].map(n)``, cached by size (JIT-compiled C if asked)."""
    f = _jit(name) if compiled else build_functions()[name]
    return f.map(n, "serial")


@functools.cache
def _jit(name: str) -> ca.Function:
    f = build_functions()[name]
    mx = f.mx_in()
    try:
        return ca.Function(f"{name}_jit", mx, f.call(mx), f.name_in(), f.name_out(),
                           {"jit": True, "compiler": "shell",
                            "jit_options": {"flags": ["-O2"], "verbose": False}})
    except RuntimeError:  # no C compiler here: the CasADi VM gives the same numbers
        return f
