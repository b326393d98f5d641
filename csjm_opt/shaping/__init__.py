"""Stiffness shaping: tensions in the redundant directions that reach a target K, and the reachable set."""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .figures import plot_reachable_set
    from .reachable import ReachableSet, directional_stiffness_range, reachable_set
    from .shaper import Shaper, ShapingResult, build_shaping_qp, shape_stiffness

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'plot_reachable_set': ('.figures', 'plot_reachable_set'),
    'ReachableSet': ('.reachable', 'ReachableSet'),
    'directional_stiffness_range': ('.reachable', 'directional_stiffness_range'),
    'reachable_set': ('.reachable', 'reachable_set'),
    'Shaper': ('.shaper', 'Shaper'),
    'ShapingResult': ('.shaper', 'ShapingResult'),
    'build_shaping_qp': ('.shaper', 'build_shaping_qp'),
    'shape_stiffness': ('.shaper', 'shape_stiffness'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ReachableSet", "Shaper", "ShapingResult", "build_shaping_qp",
           "directional_stiffness_range", "plot_reachable_set", "reachable_set", "shape_stiffness"]
