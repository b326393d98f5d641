"""A static equilibrium of the platform, as found by forward statics (checks itself)."""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True, eq=False)
class Equilibrium:
    """A static equilibrium found by :func:`solve_equilibrium` (checks itself)."""

    R: np.ndarray                   # (3, 3) orientation of {A} in {B}
    rest_lengths_m: np.ndarray      # (m,)
    tensions_N: np.ndarray          # (m,)
    tau_ext_A_Nm: np.ndarray        # (3,) external moment fixed in {A}
    tau_cable_A_Nm: np.ndarray      # (3,) J^T T
    tau_points_A_Nm: np.ndarray     # (3,) weight plus dead-weight forces
    K: np.ndarray                   # (3, 3) cable stiffness (convention of docs/conventions.md) at R
    K_tangent: np.ndarray           # (3, 3) tangent stiffness of the whole loaded system
    iterations: int

    @property
    def tensions(self) -> np.ndarray:
        """Alias of ``tensions_N`` (docs/conventions.md name)."""
        return self.tensions_N

    @property
    def tau_load_A_Nm(self) -> np.ndarray:
        """Total load on the platform (external plus weight/point forces), {A}."""
        return self.tau_ext_A_Nm + self.tau_points_A_Nm

    @property
    def residual_Nm(self) -> float:
        """``||J^T T + tau_load||`` (N m)."""
        return float(np.linalg.norm(self.tau_cable_A_Nm + self.tau_load_A_Nm))

    @property
    def slack(self) -> np.ndarray:
        """Mask of slack cables (zero tension)."""
        return self.tensions_N <= 0.0

    @property
    def stable(self) -> bool:
        """All eigenvalues of the tangent stiffness have positive real part."""
        return bool(np.all(np.linalg.eigvals(self.K_tangent).real > 0))

    def is_valid(self, tol_Nm: float = 1e-9) -> bool:
        """Residual within ``tol_Nm`` and stable."""
        return self.residual_Nm <= tol_Nm and self.stable
