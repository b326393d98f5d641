"""Generated C for a real-time controller: the tension planner and K of one rig, and its bindings.

``generate_c(rig, DIR)`` writes self-contained C99 (no dynamic memory, libm only) with the rig
baked in; ``load(DIR)`` compiles it and returns a drop-in for :func:`csjm_opt.plan_tensions` and
:func:`csjm_opt.stiffness`; :class:`CTensionPlanningController` runs it in the closed loop.
"""

from .bindings import BAD_INPUT, INFEASIBLE, ITERATION_CAP, NO_FALLBACK, SOLVED, CPlanBatch, CPlanner, load
from .build import CFLAGS, build_shared, find_compiler
from .controller import CTensionPlanningController
from .generate import GeneratedCode, generate_c, rig_fingerprint, sample_trajectory_csv

__all__ = ["BAD_INPUT", "CFLAGS", "CPlanBatch", "CPlanner", "CTensionPlanningController", "GeneratedCode",
           "INFEASIBLE", "ITERATION_CAP", "NO_FALLBACK", "SOLVED", "build_shared", "find_compiler",
           "generate_c", "load", "rig_fingerprint", "sample_trajectory_csv"]
