"""Tension planning: the bounded QP that holds a pose under a load, one pose or many."""

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

__all__ = ["TensionPlan", "TensionPlanBatch", "build_tension_qp", "build_tension_qp_for",
           "export_mjcf", "feasibility_distance_Nm", "plan_tensions", "plan_tensions_batch"]
