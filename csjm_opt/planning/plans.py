"""Results of the tension planner: one pose (:class:`TensionPlan`) or many (:class:`TensionPlanBatch`).

Both check themselves (qpsolvers ``Solution`` style): equilibrium residual,
bound violation, active bounds. Both carry the cable lengths ``c(R)`` and the
rest lengths ``l = c - T / k`` that realise the tensions (``t = k (c - l)``),
computed by the planning kernel at no extra solve.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True, eq=False, init=False)
class TensionPlan:
    """Tensions for one pose and load; checks itself (qpsolvers ``Solution`` style)."""

    tensions_N: np.ndarray          # (m,)
    R: np.ndarray                   # (3, 3) orientation of {A} in {B}
    tau_ext_A_Nm: np.ndarray        # (3,) external moment, {A}
    tau_weight_A_Nm: np.ndarray     # (3,) platform weight moment, {A}
    J: np.ndarray                   # (m, 3) Jacobian (38) at R
    t_min_N: float
    t_max_N: float
    t_ref_N: np.ndarray             # (m,) reference tensions of the objective
    solver: str
    cable_lengths_m: np.ndarray     # (m,) c_i = |b_i - R a_i| at R
    rest_lengths_m: np.ndarray      # (m,) l_i = c_i - t_i / k_i: rest lengths that realise the plan

    def __init__(self, tensions_N: np.ndarray, R: np.ndarray, tau_ext_A_Nm: np.ndarray,
                 tau_weight_A_Nm: np.ndarray, J: np.ndarray, t_min_N: float, t_max_N: float,
                 t_ref_N: np.ndarray, solver: str, cable_lengths_m: np.ndarray,
                 rest_lengths_m: np.ndarray) -> None:
        # One dict update instead of the frozen dataclass's eleven object.__setattr__
        # calls: 2 us of the one-pose plan's 7 us (benchmarks/bench_cables.py).
        vars(self).update(tensions_N=tensions_N, R=R, tau_ext_A_Nm=tau_ext_A_Nm, tau_weight_A_Nm=tau_weight_A_Nm,
                          J=J, t_min_N=t_min_N, t_max_N=t_max_N, t_ref_N=t_ref_N, solver=solver,
                          cable_lengths_m=cable_lengths_m, rest_lengths_m=rest_lengths_m)

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (the documented API name)."""
        return self.tensions_N

    @property
    def tau_load_A_Nm(self) -> np.ndarray:
        """Total load moment ``tau_ext + tau_weight`` in {A} (the paper's W)."""
        return self.tau_ext_A_Nm + self.tau_weight_A_Nm

    @property
    def equilibrium_residual_Nm(self) -> float:
        """``||J^T T + tau_load||`` (N m)."""
        return float(np.linalg.norm(self.J.T @ self.tensions_N + self.tau_load_A_Nm))

    @property
    def bound_margins_N(self) -> np.ndarray:
        """Per cable ``min(T - t_min, t_max - T)`` (N); negative means violated."""
        return np.minimum(self.tensions_N - self.t_min_N, self.t_max_N - self.tensions_N)

    @property
    def bound_violation_N(self) -> float:
        """Largest bound violation (N), 0 when within bounds."""
        return float(max(0.0, -np.min(self.bound_margins_N)))

    @property
    def active_bounds(self) -> list[str]:
        """Cables at a bound, e.g. ``["t3=t_min", "t5=t_max"]``."""
        tol = 1e-7 * max(1.0, self.t_max_N)
        out = []
        for i, t in enumerate(self.tensions_N):
            if abs(t - self.t_min_N) <= tol:
                out.append(f"t{i + 1}=t_min")
            elif abs(t - self.t_max_N) <= tol:
                out.append(f"t{i + 1}=t_max")
        return out

    def is_valid(self, eq_tol_Nm: float = 1e-8, bound_tol_N: float = 1e-9) -> bool:
        """Equilibrium and bounds hold within the given tolerances."""
        return self.equilibrium_residual_Nm <= eq_tol_Nm and self.bound_violation_N <= bound_tol_N


@dataclasses.dataclass(frozen=True, eq=False)
class TensionPlanBatch:
    """Tensions for many poses: arrays with a leading axis ``n``."""

    tensions_N: np.ndarray          # (n, m)
    R: np.ndarray                   # (n, 3, 3) the input poses (exact rotations are not copied)
    tau_ext_A_Nm: np.ndarray        # (n, 3)
    tau_weight_A_Nm: np.ndarray     # (n, 3)
    J: np.ndarray                   # (n, m, 3)
    t_min_N: float
    t_max_N: float
    solver: str
    fallbacks: int                  # rows solved by the general QP solver instead
    cable_lengths_m: np.ndarray     # (n, m)
    rest_lengths_m: np.ndarray      # (n, m) l = c - T / k

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (the documented API name)."""
        return self.tensions_N

    def __len__(self) -> int:
        return self.tensions_N.shape[0]

    @property
    def equilibrium_residual_Nm(self) -> np.ndarray:
        """Per pose ``||J^T T + tau_load||`` (N m), shape (n,)."""
        tau = np.einsum("nij,ni->nj", self.J, self.tensions_N)
        return np.linalg.norm(tau + self.tau_ext_A_Nm + self.tau_weight_A_Nm, axis=1)

    @property
    def bound_violation_N(self) -> np.ndarray:
        """Per pose largest bound violation (N), shape (n,)."""
        margin = np.minimum(self.tensions_N - self.t_min_N, self.t_max_N - self.tensions_N)
        return np.maximum(0.0, -margin.min(axis=1))

    def __getitem__(self, i: int) -> TensionPlan:
        return TensionPlan(self.tensions_N[i], self.R[i], self.tau_ext_A_Nm[i],
                           self.tau_weight_A_Nm[i], self.J[i], self.t_min_N, self.t_max_N,
                           np.full(self.tensions_N.shape[1], np.nan), self.solver, self.cable_lengths_m[i],
                           self.rest_lengths_m[i])
