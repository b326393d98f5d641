"""csjm_opt: modelling, planning, identification and shaping of cable-driven spherical joints.

Conventions (SPEC.md): ``R`` is the orientation of {A} in {B}; ``zeta`` are
body-frame canonical coordinates, ``R = R_ref @ exp(hat(zeta))``; SI units;
moments in {A}; ``K`` is the load-convention stiffness (Levi-Civita Hessian of
the cable energy).
"""

from . import so3
from .api import stiffness, stiffness_batch
from .errors import (CsjmError, DataFileError, IllConditionedData, InfeasibleLoad, InvalidInput,
                     NoEquilibrium, NotARotation, RigFileError, SolverError)
from .model import Model
from .planner import (TensionPlan, TensionPlanBatch, build_tension_qp, build_tension_qp_for,
                      plan_tensions, plan_tensions_batch)
from .rig import Rig, load_rig, paper_rig

__version__ = "0.1.0"

__all__ = sorted([
    "CsjmError", "DataFileError", "IllConditionedData", "InfeasibleLoad", "InvalidInput", "Model",
    "NoEquilibrium", "NotARotation", "Rig", "RigFileError", "SolverError", "TensionPlan",
    "TensionPlanBatch", "__version__", "build_tension_qp", "build_tension_qp_for", "load_rig",
    "paper_rig", "plan_tensions", "plan_tensions_batch", "so3", "stiffness", "stiffness_batch",
])
