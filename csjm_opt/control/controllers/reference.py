"""Angular velocity and acceleration of a pose reference ``R_ref(t)``, in the body frame {A}.

With ``xi_+ = log(R(t)^T R(t + h))`` and ``xi_- = log(R(t)^T R(t - h))``::

    omega(t)     = (xi_+ - xi_-) / (2 h) + O(h^2)
    omega_dot(t) = (xi_+ + xi_-) / h^2   + O(h^2)

(``R^T dR/dt = hat(omega)``; the second-order BCH term vanishes because
``omega x omega = 0``). ``h = 1e-3`` s keeps round-off near 1e-10 rad/s^2.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..loop_kernels import log_so3


def reference_rates(R_ref: Callable[[float], np.ndarray] | np.ndarray, t_s: float,
                    h_s: float = 1e-3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(R, omega_A, omega_dot_A)`` of the reference at ``t_s`` (rad/s, rad/s^2; zero for a fixed pose)."""
    if not callable(R_ref):
        return np.asarray(R_ref, float), np.zeros(3), np.zeros(3)
    R = R_ref(t_s)
    xi_p = log_so3(np.ascontiguousarray(R.T @ R_ref(t_s + h_s)))
    xi_m = log_so3(np.ascontiguousarray(R.T @ R_ref(t_s - h_s)))
    return R, (xi_p - xi_m) / (2 * h_s), (xi_p + xi_m) / (h_s * h_s)


class MemoReference:
    """A pose reference that remembers its last values (a loop asks for the same times repeatedly)."""

    def __init__(self, R_ref: Callable[[float], np.ndarray], size: int = 16):
        self._R_ref, self._size = R_ref, size
        self._memo: dict[int, np.ndarray] = {}

    def __call__(self, t_s: float) -> np.ndarray:
        """The reference pose at ``t_s`` (remembered to the nanosecond).

        Parameters
        ----------
        t_s : float
            Time (s).

        Returns
        -------
        (3, 3) array
            Reference orientation of {A} in {B}.
        """
        key = round(t_s * 1e9)                          # ns: t_k + dt and t_{k+1} are the same instant
        R = self._memo.get(key)
        if R is None:
            if len(self._memo) >= self._size:
                self._memo.pop(next(iter(self._memo)))
            R = self._memo[key] = np.asarray(self._R_ref(t_s), float)
        return R
