"""Synthetic experiments: load-cycle design, random rigs, a plant with injected effects, noisy logs."""

from __future__ import annotations

from .cycles import CycleDesign, design_cycles, up_down
from .injection import inject, make_plant
from .plant import EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES, Plant
from .rigs import RigRanges, random_rig
from .simulate import simulate_experiment

__all__ = ["CycleDesign", "EFFECT_NAMES", "OUTSIDE_NAMES", "Plant", "RigRanges", "VARIANT_NAMES",
           "design_cycles", "inject", "make_plant", "random_rig", "simulate_experiment", "up_down"]
