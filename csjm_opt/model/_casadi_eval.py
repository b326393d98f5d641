"""The CasADi reference of :class:`~csjm_opt.model.numeric.Model`: its named functions, evaluated.

:class:`CasadiReference` gives :class:`~csjm_opt.model.numeric.Model` its
:attr:`functions`, :meth:`casadi` and :meth:`point_force_moment`; stacks of
poses are evaluated by a CasADi ``map`` (cached by size; ``compiled=True``
JIT-compiles the function to C first).
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import casadi as ca


def build_functions(n_cables: int = 6) -> dict[str, Any]:
    """The named CasADi functions for ``n_cables`` cables (:func:`csjm_opt.model.casadi_model.build_functions`).

    CasADi is imported on first use: a :class:`~csjm_opt.model.numeric.Model` that only runs its
    compiled kernels never loads it.
    """
    from .casadi_model import build_functions as build

    return build(n_cables)


def _stack_h(X: np.ndarray) -> np.ndarray:
    """(n, r, c) -> (r, n*c), CasADi's horizontal stacking for ``map``."""
    n, r, c = X.shape
    return np.ascontiguousarray(X.transpose(1, 0, 2).reshape(r, n * c))


def _unstack_h(M: np.ndarray, n: int) -> np.ndarray:
    """(r, n*c) -> (n, r, c)."""
    r = M.shape[0]
    return M.reshape(r, n, -1).transpose(1, 0, 2)


class CasadiReference:
    """The CasADi reference methods of :class:`~csjm_opt.model.numeric.Model` (a mixin)."""

    A: np.ndarray
    B: np.ndarray
    k: np.ndarray
    compiled: bool

    @property
    def functions(self) -> dict[str, ca.Function]:
        """The named CasADi functions (symbolic reference, code generation)."""
        return build_functions(self.A.shape[0])

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

    def casadi(self, name: str, R: np.ndarray, *per_pose: np.ndarray) -> list[np.ndarray]:
        """Evaluate the CasADi function ``name`` (e.g. ``"stiffness"``) at one pose or a stack.

        Per-pose inputs (tensions, rest lengths) are (m,) or (n, m); rig
        constants are filled in. Outputs come back per pose, e.g. K (3, 3)
        or (n, 3, 3), vectors (k,) or (n, k).
        """
        f = self.functions[name]
        names = f.name_in()
        consts = {"k": self.k.reshape(-1, 1), "A": self.A.T, "B": self.B.T}
        if R.ndim == 2:
            args = [R] + [np.reshape(p, (-1, 1)) for p in per_pose] + [consts[s] for s in names[1 + len(per_pose):]]
            return [_squeeze(np.array(o)) for o in f.call(args)]
        n = R.shape[0]
        fm = _mapped(name, n, self.compiled, self.A.shape[0])
        args = [_stack_h(R)] + [np.asarray(p, float).T for p in per_pose] \
            + [consts[s] for s in names[1 + len(per_pose):]]
        outs = [np.array(o) for o in fm.call(args)]
        return [o.T if o.shape[1] == n else _unstack_h(o, n) for o in outs]


def _squeeze(M: np.ndarray) -> np.ndarray:
    return M.ravel() if M.shape[1] == 1 else M


@functools.lru_cache(maxsize=32)
def _mapped(name: str, n: int, compiled: bool = False, n_cables: int = 6) -> ca.Function:
    """``build_functions(n_cables)[name].map(n)``, cached by size (JIT-compiled C if asked)."""
    f = _jit(name, n_cables) if compiled else build_functions(n_cables)[name]
    return f.map(n, "serial")


@functools.cache
def _jit(name: str, n_cables: int = 6) -> ca.Function:
    f = build_functions(n_cables)[name]
    mx = f.mx_in()
    import casadi as ca

    try:
        return ca.Function(f"{name}_{n_cables}_jit", mx, f.call(mx), f.name_in(), f.name_out(),
                           {"jit": True, "compiler": "shell",
                            "jit_options": {"flags": ["-O2"], "verbose": False}})
    except RuntimeError:  # no C compiler here: the CasADi VM gives the same numbers
        return f
