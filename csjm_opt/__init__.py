"""csjm_opt: modelling and control of cable-driven spherical joint modules (CSJM).

Modelling, tension planning, identification, stiffness shaping, diagnosis and
design of cable-driven spherical joint modules.

Conventions (docs/conventions.md): ``R`` is the orientation of {A} in {B};
``zeta`` are body-frame canonical coordinates, ``R = R_ref @ exp(hat(zeta))``;
SI units; moments in {A}; ``K`` is the load-convention stiffness
``dtau_load/dzeta - 1/2 hat(tau_load)``, the Levi-Civita Hessian of the cable
energy (symmetric, positive definite at a stable pose).

The top level holds the names a newcomer needs first; everything else lives
in its layer: :mod:`csjm_opt.model`, :mod:`csjm_opt.planning`,
:mod:`csjm_opt.measurement`, :mod:`csjm_opt.identification`,
:mod:`csjm_opt.shaping`, :mod:`csjm_opt.control`, :mod:`csjm_opt.diagnose`,
:mod:`csjm_opt.testbed`, :mod:`csjm_opt.design`, :mod:`csjm_opt.report`.
"""

from typing import TYPE_CHECKING, Any

from . import so3
from .errors import (
    CsjmError,
    DataFileError,
    DesignError,
    IllConditionedData,
    InconsistentTensions,
    InfeasibleLoad,
    InvalidInput,
    NoEquilibrium,
    NotARotation,
    RigFileError,
    SolverError,
    UsageError,
)

if TYPE_CHECKING:
    from .diagnose import Diagnosis
    from .diagnose import diagnose as diagnose_log
    from .identification.estimate import StiffnessEstimate
    from .identification.identify_pose import identify_stiffness
    from .identification.log_identification import identify_log
    from .measurement.logfile import MeasurementLog
    from .model.joint_stiffness import stiffness, stiffness_batch
    from .model.numeric import Model
    from .model.rig import Rig, load_rig, paper_rig
    from .model.statics import Equilibrium, rest_lengths_for, solve_equilibrium
    from .planning.planner import TensionPlan, TensionPlanBatch, plan_tensions, plan_tensions_batch
    from .shaping.shaper import ShapingResult, shape_stiffness

__version__ = "0.1.0"

#: Top-level name -> (module, attribute): imported on first use (PEP 562), so ``import csjm_opt``
#: loads neither CasADi, numba, SciPy, qpsolvers, MuJoCo, matplotlib nor Dask.
_LAZY: dict[str, tuple[str, str]] = {
    "Diagnosis": (".diagnose", "Diagnosis"),
    "diagnose_log": (".diagnose", "diagnose"),
    "StiffnessEstimate": (".identification.estimate", "StiffnessEstimate"),
    "identify_log": (".identification.log_identification", "identify_log"),
    "identify_stiffness": (".identification.identify_pose", "identify_stiffness"),
    "MeasurementLog": (".measurement.logfile", "MeasurementLog"),
    "Model": (".model.numeric", "Model"),
    "Rig": (".model.rig", "Rig"),
    "load_rig": (".model.rig", "load_rig"),
    "paper_rig": (".model.rig", "paper_rig"),
    "Equilibrium": (".model.statics", "Equilibrium"),
    "rest_lengths_for": (".model.statics", "rest_lengths_for"),
    "solve_equilibrium": (".model.statics", "solve_equilibrium"),
    "stiffness": (".model.joint_stiffness", "stiffness"),
    "stiffness_batch": (".model.joint_stiffness", "stiffness_batch"),
    "TensionPlan": (".planning.planner", "TensionPlan"),
    "TensionPlanBatch": (".planning.planner", "TensionPlanBatch"),
    "plan_tensions": (".planning.planner", "plan_tensions"),
    "plan_tensions_batch": (".planning.planner", "plan_tensions_batch"),
    "ShapingResult": (".shaping.shaper", "ShapingResult"),
    "shape_stiffness": (".shaping.shaper", "shape_stiffness"),
}


def __getattr__(name: str) -> Any:
    """Import a top-level name's module on first use and cache the name here."""
    if name in _LAZY:
        import importlib

        module, attr = _LAZY[name]
        value = getattr(importlib.import_module(module, __name__), attr)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    """Every public name, the lazy ones included."""
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "CsjmError", "DataFileError", "DesignError", "Diagnosis", "Equilibrium", "IllConditionedData",
    "InconsistentTensions", "InfeasibleLoad", "InvalidInput", "MeasurementLog", "Model",
    "NoEquilibrium", "NotARotation", "Rig", "RigFileError", "ShapingResult", "SolverError",
    "StiffnessEstimate", "TensionPlan", "TensionPlanBatch", "UsageError", "__version__",
    "diagnose_log", "identify_log", "identify_stiffness", "load_rig", "paper_rig", "plan_tensions",
    "plan_tensions_batch", "rest_lengths_for", "shape_stiffness", "so3", "solve_equilibrium",
    "stiffness", "stiffness_batch",
]
