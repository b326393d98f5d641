"""Design studies: parametric hole geometry, orientation sampling, metrics and sweeps (issue 7)."""

from .geometry import (PAPER_DESIGN, PARAMETERS, GeometryLimits, check_holes, design_holes,
                       design_rig)
from .metrics import DesignMetrics, LoadSet, MetricOptions, PoseMetrics, evaluate, evaluate_poses
from .sampling import OrientationSampling, tilt_torsion_angles, tilt_torsion_rotations

__all__ = sorted([
    "DesignMetrics", "GeometryLimits", "LoadSet", "MetricOptions", "OrientationSampling",
    "PAPER_DESIGN", "PARAMETERS", "PoseMetrics", "check_holes", "design_holes", "design_rig",
    "evaluate", "evaluate_poses", "tilt_torsion_angles", "tilt_torsion_rotations",
])
