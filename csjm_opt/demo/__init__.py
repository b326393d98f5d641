"""``csjm demo``: the whole chain on the paper rig, step by step, into one report folder.

The pipeline (:mod:`csjm_opt.demo.pipeline`) runs its steps in order; each
step module holds one part of the job and its report section. The document
model and renderer the steps write with are in :mod:`csjm_opt.report`.
"""

from .pipeline import STEPS
from .pipeline import run as run_demo

__all__ = ["STEPS", "run_demo"]
