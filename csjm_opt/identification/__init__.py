"""Identification: K from measured poses and loads ((49)-(50) and better).

Also parameter fits, verification (Section IV-C), experiment design for a small
Cramér-Rao bound, and the paper's tables.
"""

from .cramer_rao import SYM_NAMES, crlb
from .experiment_design import ExperimentPlan, paper_protocol, plan_experiment, predict_bound
from .experiment_loads import ExperimentLoads
from .figures import ConvergenceCurve, convergence_curve, plot_convergence, plot_verification
from .identify import StiffnessEstimate, identify_log, identify_stiffness
from .ml_estimator import MLFit, fit_ml
from .paper_tables import paper_report
from .param_fit import ParameterFit, check_fit, fit_parameters
from .verify import (
    Verification,
    estimation_error,
    predict_pose,
    predict_pose_external,
    verify_increments,
    verify_log,
)

__all__ = ["ConvergenceCurve", "ExperimentLoads", "ExperimentPlan", "MLFit", "ParameterFit", "SYM_NAMES",
           "StiffnessEstimate", "Verification", "check_fit", "convergence_curve", "crlb",
           "estimation_error", "fit_ml", "fit_parameters", "identify_log", "identify_stiffness",
           "paper_protocol", "paper_report", "plan_experiment", "plot_convergence", "plot_verification",
           "predict_bound", "predict_pose", "predict_pose_external", "verify_increments", "verify_log"]
