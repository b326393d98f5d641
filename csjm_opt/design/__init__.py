"""Design studies: parametric hole geometry, orientation sampling, metrics, sweeps and optimisation (issue 7).

The core: :mod:`.geometry` (design parameters -> validated Rig), :mod:`.sampling` (uniform SO(3)
samples in a tilt/torsion range), :mod:`.feasibility` (exact zonotope wrench-feasibility test and
margin), :mod:`.shaping_range` (batched exact LPs for the reachable directional stiffness),
:mod:`.clearance` (cable-cable and cable-link distances, exit angles), :mod:`.metrics` (per design,
with its load set and options), :mod:`.design_evaluation` (one design's record) and its settings
(:mod:`.evaluation_settings`). The families: :mod:`.sweep` (the sweep file, the parallel resumable
runner, the result store) and :mod:`.optimisation` (IPOPT on the sweep's vocabulary, its dense
check, the front in the sweep's own metrics).
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
