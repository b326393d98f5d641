"""Closed-loop simulation: controllers, load profiles and plants."""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from . import controllers, load_profiles, plants
    from .closed_loop import ClosedLoopLog, plot_closed_loop, plot_closed_loop_stiffness, simulate

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'controllers': ('.controllers', None),
    'load_profiles': ('.load_profiles', None),
    'plants': ('.plants', None),
    'ClosedLoopLog': ('.closed_loop', 'ClosedLoopLog'),
    'plot_closed_loop': ('.closed_loop', 'plot_closed_loop'),
    'plot_closed_loop_stiffness': ('.closed_loop', 'plot_closed_loop_stiffness'),
    'simulate': ('.closed_loop', 'simulate'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ClosedLoopLog", "controllers", "load_profiles", "plants", "plot_closed_loop",
           "plot_closed_loop_stiffness", "simulate"]
