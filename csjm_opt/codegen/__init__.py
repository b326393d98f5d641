"""Generated C for a real-time controller: the tension planner and K of one rig, and its bindings."""

from .generate import GeneratedCode, generate_c, rig_fingerprint, sample_trajectory_csv

__all__ = ["GeneratedCode", "generate_c", "rig_fingerprint", "sample_trajectory_csv"]
