"""Tension planning: the bounded QP that holds a pose under a load, one pose or many."""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .mjcf_export import export_mjcf
    from .planner import (
        TensionPlan,
        TensionPlanBatch,
        build_tension_qp,
        build_tension_qp_for,
        feasibility_distance_Nm,
        plan_tensions,
        plan_tensions_batch,
    )

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'export_mjcf': ('.mjcf_export', 'export_mjcf'),
    'TensionPlan': ('.planner', 'TensionPlan'),
    'TensionPlanBatch': ('.planner', 'TensionPlanBatch'),
    'build_tension_qp': ('.planner', 'build_tension_qp'),
    'build_tension_qp_for': ('.planner', 'build_tension_qp_for'),
    'feasibility_distance_Nm': ('.planner', 'feasibility_distance_Nm'),
    'plan_tensions': ('.planner', 'plan_tensions'),
    'plan_tensions_batch': ('.planner', 'plan_tensions_batch'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["TensionPlan", "TensionPlanBatch", "build_tension_qp", "build_tension_qp_for",
           "export_mjcf", "feasibility_distance_Nm", "plan_tensions", "plan_tensions_batch"]
