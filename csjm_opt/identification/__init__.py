"""Identification: K from measured poses and loads ((49)-(50) and better), parameter fits,
verification (Section IV-C) and the paper's tables."""

from .figures import ConvergenceCurve, convergence_curve, plot_convergence, plot_verification
from .identify import StiffnessEstimate, identify_log, identify_stiffness
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

__all__ = ["ConvergenceCurve", "ParameterFit", "StiffnessEstimate", "Verification", "check_fit",
           "convergence_curve", "estimation_error", "fit_parameters", "identify_log",
           "identify_stiffness", "paper_report", "plot_convergence", "plot_verification",
           "predict_pose", "predict_pose_external", "verify_increments", "verify_log"]
