"""Stiffness shaping: tensions in the redundant directions that reach a target K, and the reachable set."""

from .figures import plot_reachable_set
from .reachable import ReachableSet, directional_stiffness_range, reachable_set
from .shaper import Shaper, ShapingResult, build_shaping_qp, shape_stiffness

__all__ = ["ReachableSet", "Shaper", "ShapingResult", "build_shaping_qp",
           "directional_stiffness_range", "plot_reachable_set", "reachable_set", "shape_stiffness"]
