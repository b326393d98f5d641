"""The result of stiffness shaping: tensions, achieved K, and the checks it carries."""

from __future__ import annotations

import dataclasses

import numpy as np

from .objectives import StiffnessObjective


@dataclasses.dataclass(frozen=True, eq=False)
class ShapingResult:
    """Shaped tensions for one pose and load; checks itself."""

    tensions_N: np.ndarray       # (m,)
    K: np.ndarray                # (3, 3) achieved stiffness, N m/rad (CasADi model)
    K_target: np.ndarray         # (3, 3)
    objective: StiffnessObjective
    R: np.ndarray
    tau_ext_A_Nm: np.ndarray
    tau_weight_A_Nm: np.ndarray
    J: np.ndarray
    t_min_N: float
    t_max_N: float
    solver: str
    exact_tol: float             # residual (N m/rad) below which the target counts as reached
    kkt_error: float             # of the QP solution (exact active-set check)

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (docs/conventions.md name)."""
        return self.tensions_N

    @property
    def residual(self) -> float:
        """Weighted residual of the objective (weighted Frobenius by default), N m/rad."""
        return self.objective.residual(self.K)

    @property
    def frobenius_error(self) -> float:
        """Unweighted ``||K - K_target||_F`` (N m/rad)."""
        return float(np.linalg.norm(self.K - self.K_target))

    @property
    def exact(self) -> bool:
        """The target is reached (residual below ``exact_tol``)."""
        return self.residual <= self.exact_tol

    @property
    def equilibrium_residual_Nm(self) -> float:
        """``||J^T T + tau_load||`` (N m)."""
        return float(np.linalg.norm(self.J.T @ self.tensions_N + self.tau_ext_A_Nm + self.tau_weight_A_Nm))

    @property
    def bound_violation_N(self) -> float:
        """Largest violation of the tension bounds ``[t_min, t_max]`` (N; 0 when inside)."""
        return float(max(0.0, np.max(self.t_min_N - self.tensions_N), np.max(self.tensions_N - self.t_max_N)))

    @property
    def active_bounds(self) -> list[str]:
        """Cables at a bound, e.g. ``["t3=t_min", "t5=t_max"]``."""
        tol = 1e-7 * max(1.0, self.t_max_N)
        return ([f"t{i + 1}=t_min" for i in np.flatnonzero(self.tensions_N <= self.t_min_N + tol)]
                + [f"t{i + 1}=t_max" for i in np.flatnonzero(self.tensions_N >= self.t_max_N - tol)])

    def is_valid(self, eq_tol_Nm: float = 1e-8, bound_tol_N: float = 1e-9) -> bool:
        """Whether the tensions hold the load and respect the bounds.

        Parameters
        ----------
        eq_tol_Nm : float, optional
            Largest accepted equilibrium residual ``||J^T T + tau_load||`` (N m).
        bound_tol_N : float, optional
            Largest accepted bound violation (N).

        Returns
        -------
        bool
        """
        return self.equilibrium_residual_Nm <= eq_tol_Nm and self.bound_violation_N <= bound_tol_N

    def as_dict(self) -> dict:
        """The result as a JSON-able dict (the output of ``csjm shape --json``).

        Returns
        -------
        dict
        """
        return {"tensions_N": self.tensions_N.tolist(), "K": self.K.tolist(), "K_target": self.K_target.tolist(),
                "objective": self.objective.name, "residual": self.residual, "exact": self.exact,
                "frobenius_error": self.frobenius_error, "active_bounds": self.active_bounds,
                "equilibrium_residual_Nm": self.equilibrium_residual_Nm, "solver": self.solver}
