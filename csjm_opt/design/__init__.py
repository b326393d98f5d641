"""Design studies: parametric hole geometry, orientation sampling, metrics and sweeps (issue 7).

Modules: :mod:`.geometry` (design parameters -> validated Rig), :mod:`.sampling`
(uniform SO(3) samples in a tilt/torsion range), :mod:`.feasibility` (exact
zonotope wrench-feasibility test and margin), :mod:`.shaping_range` (batched
exact LPs for the reachable directional stiffness), :mod:`.metrics` (per
design), :mod:`.sweep_file` (TOML description; its axes in :mod:`.sweep_axes`, its
settings in :mod:`.evaluation_settings`), :mod:`.store` (crash-safe JSON Lines results),
:mod:`.design_evaluation` (one design's record), :mod:`.sweep` (parallel, resumable runner;
processes or Dask, result in :mod:`.sweep_result`), :mod:`.interference` (cable-cable and
cable-link distances, exit angles), :mod:`.optimisation` (IPOPT on the sweep's vocabulary, problem in
:mod:`.optimise_problem`, settings in :mod:`.optimise_settings`, results in :mod:`.optimise_result`, starts
in :mod:`.optimise_starts`, dense check in :mod:`.certify`, evaluation bound in :mod:`.optimise_budget`,
the shaping-range objective and its exact LP check in :mod:`.optimise_shaping`),
:mod:`.optimise_sweep_front` (the front in the sweep's own metrics, on the smooth twins of
:mod:`.optimise_sweep_surrogate` and their quadratic models in :mod:`.optimise_front_model`).
"""

from .clearance import Interference, interference, pose_interference, segment_distance
from .geometry import (
    PAPER_DESIGN,
    PARAMETERS,
    GeometryLimits,
    check_holes,
    design_holes,
    design_rig,
)
from .metrics import DesignLoads, DesignMetrics, MetricOptions, PoseMetrics, evaluate, evaluate_poses
from .optimisation.dense_check import Check, certify
from .optimisation.front import SweepFrontResult, sweep_front
from .optimisation.runner import OptimisationResult, OptimisedDesign, design_rig_of, optimise
from .optimisation.settings import OptimiseSettings, Requirements, read_optimise_file
from .optimisation.shaping import lp_shaping_range
from .sampling import OrientationSampling, tilt_torsion_angles, tilt_torsion_rotations
from .sweep.runner import SweepResult, evaluate_design, run_sweep
from .sweep.spec import EvaluationSettings, SweepSpec

__all__ = ["Check", "DesignLoads", "DesignMetrics", "EvaluationSettings", "GeometryLimits", "Interference",
           "MetricOptions", "OptimisationResult", "OptimiseSettings", "OptimisedDesign",
           "OrientationSampling", "PAPER_DESIGN", "PARAMETERS", "PoseMetrics", "Requirements",
           "SweepFrontResult", "SweepResult", "SweepSpec", "certify", "check_holes", "design_holes",
           "design_rig", "design_rig_of", "evaluate", "evaluate_design", "evaluate_poses", "interference",
           "lp_shaping_range", "optimise", "pose_interference", "read_optimise_file", "run_sweep",
           "segment_distance", "sweep_front", "tilt_torsion_angles", "tilt_torsion_rotations"]
