"""Design studies: parametric hole geometry, orientation sampling, metrics and sweeps (issue 7).

Modules: :mod:`.geometry` (design parameters -> validated Rig), :mod:`.sampling`
(uniform SO(3) samples in a tilt/torsion range), :mod:`.feasibility` (exact
zonotope wrench-feasibility test and margin), :mod:`.shaping_range` (batched
exact LPs for the reachable directional stiffness), :mod:`.metrics` (per
design), :mod:`.sweep_file` (TOML description; its axes in :mod:`.sweep_axes`, its
settings in :mod:`.evaluation_settings`), :mod:`.store` (crash-safe JSON Lines results),
:mod:`.design_evaluation` (one design's record), :mod:`.sweep` (parallel, resumable runner;
processes or Dask, result in :mod:`.sweep_result`).
"""

from .geometry import (
    PAPER_DESIGN,
    PARAMETERS,
    GeometryLimits,
    check_holes,
    design_holes,
    design_rig,
)
from .metrics import DesignMetrics, LoadSet, MetricOptions, PoseMetrics, evaluate, evaluate_poses
from .sampling import OrientationSampling, tilt_torsion_angles, tilt_torsion_rotations
from .sweep import SweepResult, evaluate_design, run_sweep
from .sweep_file import EvaluationSettings, SweepSpec

__all__ = [
    "DesignMetrics", "EvaluationSettings", "GeometryLimits", "LoadSet", "MetricOptions",
    "OrientationSampling", "PAPER_DESIGN", "PARAMETERS", "PoseMetrics", "SweepResult", "SweepSpec",
    "check_holes", "design_holes", "design_rig", "evaluate", "evaluate_design", "evaluate_poses",
    "run_sweep", "tilt_torsion_angles", "tilt_torsion_rotations",
]
