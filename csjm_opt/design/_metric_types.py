"""The inputs and results of :mod:`csjm_opt.design.metrics`: load set, options, per-pose and scalar metrics.

The metrics themselves are defined in the docstring of :mod:`csjm_opt.design.metrics`,
which computes them and re-exports these classes.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ..errors import DesignError


@dataclasses.dataclass(frozen=True, eq=False)
class LoadSet:
    """External moments (N m, in {A}, weight excluded) a feasible pose must hold; row 0 is the stiffness load."""

    taus_ext_A_Nm: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((1, 3)))

    def __post_init__(self) -> None:
        arr = np.array(self.taus_ext_A_Nm, dtype=float, ndmin=2)
        if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] < 1:
            raise DesignError(f"expected rows of [tx, ty, tz], got shape {arr.shape}", "loads.tau_ext")
        if not np.all(np.isfinite(arr)):
            raise DesignError("expected finite numbers", "loads.tau_ext")
        arr.setflags(write=False)
        object.__setattr__(self, "taus_ext_A_Nm", arr)


@dataclasses.dataclass(frozen=True)
class MetricOptions:
    """Tolerances and effort of :func:`evaluate`."""

    shaping_poses: int = 16
    feasibility_tol_Nm: float = 1e-9

    def __post_init__(self) -> None:
        if isinstance(self.shaping_poses, bool) or not isinstance(self.shaping_poses, int) \
                or self.shaping_poses < 0:
            raise DesignError(f"expected an integer >= 0, got {self.shaping_poses!r}", "shaping_poses")
        if not self.feasibility_tol_Nm >= 0:
            raise DesignError(f"expected >= 0, got {self.feasibility_tol_Nm}", "feasibility_tol_Nm")


@dataclasses.dataclass(frozen=True, eq=False)
class PoseMetrics:
    """Per-orientation arrays behind :class:`DesignMetrics` (n = number of samples)."""

    R: np.ndarray                   # (n, 3, 3)
    tilt_rad: np.ndarray            # (n,)
    feasible: np.ndarray            # (n,) bool, all loads held
    wrench_margin_Nm: np.ndarray    # (n, m) per load
    tensions_N: np.ndarray          # (n, m) planned for the stiffness load (valid where feasible)
    K: np.ndarray                   # (n, 3, 3) at those tensions
    eig_Nm_per_rad: np.ndarray      # (n, 3) ascending
    fallbacks: int                  # feasible rows the active-set method did not settle


@dataclasses.dataclass(frozen=True)
class DesignMetrics:
    """Scalar metrics of one design (defined in :mod:`csjm_opt.design.metrics`); NaN when undefined."""

    n_orientations: int
    workspace_fraction: float
    tilt_cone_deg: float
    min_stiffness_Nm_per_rad: float
    median_min_stiffness_Nm_per_rad: float
    max_condition: float
    median_condition: float
    min_torsion_stiffness_Nm_per_rad: float
    median_torsion_stiffness_Nm_per_rad: float
    min_bending_stiffness_Nm_per_rad: float
    median_bending_stiffness_Nm_per_rad: float
    stable_fraction: float
    min_tension_margin_N: float
    median_tension_margin_N: float
    median_wrench_margin_Nm: float
    home_feasible: bool
    home_min_stiffness_Nm_per_rad: float
    home_tension_margin_N: float
    home_wrench_margin_Nm: float
    shaping_range_Nm_per_rad: dict[str, tuple[float, float]]
    planner_fallbacks: int
    seconds: float
    #: Interference over the feasible orientations (csjm_opt.design.interference); NaN without any.
    min_cable_distance_m: float = math.nan
    min_link_clearance_m: float = math.nan
    max_exit_angle_deg: float = math.nan

    def as_dict(self) -> dict[str, Any]:
        """The metrics as a JSON-able dict (the ``metrics`` of a sweep record).

        Returns
        -------
        dict
        """
        return {k: _json_safe(v) for k, v in dataclasses.asdict(self).items()}


def _json_safe(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value
