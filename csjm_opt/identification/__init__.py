"""Identification: K from measured poses and loads ((49)-(50) and better).

Also parameter fits, verification (Section IV-C), experiment design for a small
Cramér-Rao bound, and the paper's tables.
"""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .cramer_rao import SYM_NAMES, crlb
    from .estimate import StiffnessEstimate
    from .experiment_design import ExperimentPlan, paper_protocol, plan_experiment, predict_bound
    from .experiment_loads import ExperimentLoads
    from .figures import ConvergenceCurve, convergence_curve, plot_convergence, plot_verification
    from .identify_pose import identify_stiffness
    from .log_identification import identify_log
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

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'SYM_NAMES': ('.cramer_rao', 'SYM_NAMES'),
    'crlb': ('.cramer_rao', 'crlb'),
    'ExperimentPlan': ('.experiment_design', 'ExperimentPlan'),
    'paper_protocol': ('.experiment_design', 'paper_protocol'),
    'plan_experiment': ('.experiment_design', 'plan_experiment'),
    'predict_bound': ('.experiment_design', 'predict_bound'),
    'ExperimentLoads': ('.experiment_loads', 'ExperimentLoads'),
    'ConvergenceCurve': ('.figures', 'ConvergenceCurve'),
    'convergence_curve': ('.figures', 'convergence_curve'),
    'plot_convergence': ('.figures', 'plot_convergence'),
    'plot_verification': ('.figures', 'plot_verification'),
    'StiffnessEstimate': ('.estimate', 'StiffnessEstimate'),
    'identify_log': ('.log_identification', 'identify_log'),
    'identify_stiffness': ('.identify_pose', 'identify_stiffness'),
    'MLFit': ('.ml_estimator', 'MLFit'),
    'fit_ml': ('.ml_estimator', 'fit_ml'),
    'paper_report': ('.paper_tables', 'paper_report'),
    'ParameterFit': ('.param_fit', 'ParameterFit'),
    'check_fit': ('.param_fit', 'check_fit'),
    'fit_parameters': ('.param_fit', 'fit_parameters'),
    'Verification': ('.verify', 'Verification'),
    'estimation_error': ('.verify', 'estimation_error'),
    'predict_pose': ('.verify', 'predict_pose'),
    'predict_pose_external': ('.verify', 'predict_pose_external'),
    'verify_increments': ('.verify', 'verify_increments'),
    'verify_log': ('.verify', 'verify_log'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["ConvergenceCurve", "ExperimentLoads", "ExperimentPlan", "MLFit", "ParameterFit", "SYM_NAMES",
           "StiffnessEstimate", "Verification", "check_fit", "convergence_curve", "crlb",
           "estimation_error", "fit_ml", "fit_parameters", "identify_log", "identify_stiffness",
           "paper_protocol", "paper_report", "plan_experiment", "plot_convergence", "plot_verification",
           "predict_bound", "predict_pose", "predict_pose_external", "verify_increments", "verify_log"]
