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


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
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

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'Interference': ('.clearance', 'Interference'),
    'interference': ('.clearance', 'interference'),
    'pose_interference': ('.clearance', 'pose_interference'),
    'segment_distance': ('.clearance', 'segment_distance'),
    'PAPER_DESIGN': ('.geometry', 'PAPER_DESIGN'),
    'PARAMETERS': ('.geometry', 'PARAMETERS'),
    'GeometryLimits': ('.geometry', 'GeometryLimits'),
    'check_holes': ('.geometry', 'check_holes'),
    'design_holes': ('.geometry', 'design_holes'),
    'design_rig': ('.geometry', 'design_rig'),
    'DesignLoads': ('.metrics', 'DesignLoads'),
    'DesignMetrics': ('.metrics', 'DesignMetrics'),
    'MetricOptions': ('.metrics', 'MetricOptions'),
    'PoseMetrics': ('.metrics', 'PoseMetrics'),
    'evaluate': ('.metrics', 'evaluate'),
    'evaluate_poses': ('.metrics', 'evaluate_poses'),
    'Check': ('.optimisation.dense_check', 'Check'),
    'certify': ('.optimisation.dense_check', 'certify'),
    'SweepFrontResult': ('.optimisation.front', 'SweepFrontResult'),
    'sweep_front': ('.optimisation.front', 'sweep_front'),
    'OptimisationResult': ('.optimisation.runner', 'OptimisationResult'),
    'OptimisedDesign': ('.optimisation.runner', 'OptimisedDesign'),
    'design_rig_of': ('.optimisation.runner', 'design_rig_of'),
    'optimise': ('.optimisation.runner', 'optimise'),
    'OptimiseSettings': ('.optimisation.settings', 'OptimiseSettings'),
    'Requirements': ('.optimisation.settings', 'Requirements'),
    'read_optimise_file': ('.optimisation.settings', 'read_optimise_file'),
    'lp_shaping_range': ('.optimisation.shaping', 'lp_shaping_range'),
    'OrientationSampling': ('.sampling', 'OrientationSampling'),
    'tilt_torsion_angles': ('.sampling', 'tilt_torsion_angles'),
    'tilt_torsion_rotations': ('.sampling', 'tilt_torsion_rotations'),
    'SweepResult': ('.sweep.runner', 'SweepResult'),
    'evaluate_design': ('.sweep.runner', 'evaluate_design'),
    'run_sweep': ('.sweep.runner', 'run_sweep'),
    'EvaluationSettings': ('.sweep.spec', 'EvaluationSettings'),
    'SweepSpec': ('.sweep.spec', 'SweepSpec'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["Check", "DesignLoads", "DesignMetrics", "EvaluationSettings", "GeometryLimits", "Interference",
           "MetricOptions", "OptimisationResult", "OptimiseSettings", "OptimisedDesign",
           "OrientationSampling", "PAPER_DESIGN", "PARAMETERS", "PoseMetrics", "Requirements",
           "SweepFrontResult", "SweepResult", "SweepSpec", "certify", "check_holes", "design_holes",
           "design_rig", "design_rig_of", "evaluate", "evaluate_design", "evaluate_poses", "interference",
           "lp_shaping_range", "optimise", "pose_interference", "read_optimise_file", "run_sweep",
           "segment_distance", "sweep_front", "tilt_torsion_angles", "tilt_torsion_rotations"]
