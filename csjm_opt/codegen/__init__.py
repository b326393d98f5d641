"""Generated C for a real-time controller: the tension planner and K of one rig, and its bindings.

``generate_c(rig, DIR)`` writes self-contained C99 (no dynamic memory, libm only) with the rig
baked in; ``load(DIR)`` compiles it and returns a drop-in for :func:`csjm_opt.plan_tensions` and
:func:`csjm_opt.stiffness`; :class:`CTensionPlanningController` runs it in the closed loop.
"""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .bindings import (
        BAD_INPUT,
        INFEASIBLE,
        ITERATION_CAP,
        NO_FALLBACK,
        SOLVED,
        CPlanBatch,
        CPlanner,
        load,
    )
    from .build import CFLAGS, build_shared, find_compiler
    from .controller import CTensionPlanningController
    from .generate import GeneratedCode, generate_c, rig_fingerprint, sample_trajectory_csv

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'BAD_INPUT': ('.bindings', 'BAD_INPUT'),
    'INFEASIBLE': ('.bindings', 'INFEASIBLE'),
    'ITERATION_CAP': ('.bindings', 'ITERATION_CAP'),
    'NO_FALLBACK': ('.bindings', 'NO_FALLBACK'),
    'SOLVED': ('.bindings', 'SOLVED'),
    'CPlanBatch': ('.bindings', 'CPlanBatch'),
    'CPlanner': ('.bindings', 'CPlanner'),
    'load': ('.bindings', 'load'),
    'CFLAGS': ('.build', 'CFLAGS'),
    'build_shared': ('.build', 'build_shared'),
    'find_compiler': ('.build', 'find_compiler'),
    'CTensionPlanningController': ('.controller', 'CTensionPlanningController'),
    'GeneratedCode': ('.generate', 'GeneratedCode'),
    'generate_c': ('.generate', 'generate_c'),
    'rig_fingerprint': ('.generate', 'rig_fingerprint'),
    'sample_trajectory_csv': ('.generate', 'sample_trajectory_csv'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["BAD_INPUT", "CFLAGS", "CPlanBatch", "CPlanner", "CTensionPlanningController", "GeneratedCode",
           "INFEASIBLE", "ITERATION_CAP", "NO_FALLBACK", "SOLVED", "build_shared", "find_compiler",
           "generate_c", "load", "rig_fingerprint", "sample_trajectory_csv"]
