"""csjm_opt: modelling, planning, identification, shaping, diagnosis and design of
cable-driven spherical joint modules (CSJM).

Conventions (SPEC.md): ``R`` is the orientation of {A} in {B}; ``zeta`` are
body-frame canonical coordinates, ``R = R_ref @ exp(hat(zeta))``; SI units;
moments in {A}; ``K`` is the load-convention stiffness
``dtau_load/dzeta - 1/2 hat(tau_load)``, the Levi-Civita Hessian of the cable
energy (symmetric, positive definite at a stable pose).
"""

from . import controllers, design, diagnose, load_profiles, paper_data, so3, testbed
from .api import stiffness, stiffness_batch
from .closed_loop import ClosedLoopLog, plot_closed_loop
from .closed_loop import simulate as simulate_closed_loop
from .design import (DesignMetrics, LoadSet, OrientationSampling, SweepResult, SweepSpec,
                     evaluate_design, run_sweep)
from .diagnose import Diagnosis
from .diagnose import diagnose as diagnose_log
from .errors import (CsjmError, DataFileError, DesignError, IllConditionedData, InfeasibleLoad,
                     InvalidInput, NoEquilibrium, NotARotation, RigFileError, SolverError)
from .identify import StiffnessEstimate, identify_log, identify_stiffness
from .identify_figures import ConvergenceCurve, convergence_curve, plot_convergence
from .instruments import InstrumentNoise
from .logfile import MeasurementLog
from .model import Model
from .paper_tables import paper_report
from .param_fit import ParameterFit, check_fit, fit_parameters
from .planner import (TensionPlan, TensionPlanBatch, build_tension_qp, build_tension_qp_for,
                      plan_tensions, plan_tensions_batch)
from .preprocess import fit_rigid_transform, preprocess_file, preprocess_text
from .reachable import ReachableSet, directional_stiffness_range, plot_reachable_set, reachable_set
from .rig import Rig, load_rig, paper_rig
from .shaping import Shaper, ShapingResult, build_shaping_qp, shape_stiffness
from .statics import Equilibrium, EquilibriumSolver, rest_lengths_for, solve_equilibrium
from .testbed import Plant, make_plant, simulate_experiment
from .testbed.identification import simulate_identification_experiment
from .verify import (Verification, estimation_error, plot_verification, predict_pose,
                     predict_pose_external, verify_increments, verify_log)

__version__ = "0.1.0"

__all__ = sorted([
    "ClosedLoopLog", "ConvergenceCurve", "CsjmError", "DataFileError", "DesignError",
    "DesignMetrics", "Diagnosis", "Equilibrium", "EquilibriumSolver", "IllConditionedData",
    "InfeasibleLoad", "InstrumentNoise", "InvalidInput", "LoadSet", "MeasurementLog", "Model",
    "NoEquilibrium", "NotARotation", "OrientationSampling", "ParameterFit", "Plant", "ReachableSet", "Rig",
    "RigFileError", "Shaper", "ShapingResult", "SolverError", "StiffnessEstimate", "SweepResult",
    "SweepSpec", "TensionPlan", "TensionPlanBatch", "Verification", "__version__",
    "build_shaping_qp", "build_tension_qp", "build_tension_qp_for", "check_fit", "controllers",
    "convergence_curve", "design", "diagnose", "diagnose_log", "directional_stiffness_range",
    "estimation_error", "evaluate_design", "fit_parameters", "fit_rigid_transform",
    "identify_log", "identify_stiffness", "load_profiles", "load_rig", "make_plant", "paper_data",
    "paper_report", "paper_rig", "plan_tensions", "plan_tensions_batch", "plot_closed_loop",
    "plot_convergence", "plot_reachable_set", "plot_verification", "predict_pose",
    "predict_pose_external", "preprocess_file", "preprocess_text", "reachable_set",
    "rest_lengths_for", "run_sweep", "shape_stiffness", "simulate_closed_loop",
    "simulate_experiment", "simulate_identification_experiment", "so3", "solve_equilibrium",
    "stiffness", "stiffness_batch", "testbed", "verify_increments", "verify_log",
])
