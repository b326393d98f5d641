"""Synthetic experiments: load-cycle design, a plant with injected effects, noisy logs."""

from __future__ import annotations

from .cycles import CycleDesign, design_cycles, up_down
from .injection import inject, make_plant
from .plant import EFFECT_NAMES, Plant
from .simulate import simulate_experiment

__all__ = ["EFFECT_NAMES", "CycleDesign", "Plant", "design_cycles", "inject", "make_plant",
           "simulate_experiment", "up_down"]
