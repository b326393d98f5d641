"""Synthetic experiments: load-cycle design, random rigs, a plant with injected effects, noisy logs."""

from __future__ import annotations

from .cycles import CycleDesign, design_cycles, up_down
from .injection import inject, make_plant
from .log_protocol import LogProtocol, check_protocol, read_protocol, simulate_protocol
from .mujoco.plant import MUJOCO_UNSUPPORTED, PLANTS, MujocoRow, MujocoTestbedPlant, as_mujoco
from .plant import EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES, TestbedPlant
from .protocol_runner import run_protocol, settle_protocol
from .rigs import RigRanges, random_rig
from .simulate import simulate_experiment, with_persistence
from .static_certificate import FrictionCertificate, certify_static

__all__ = ["CycleDesign", "EFFECT_NAMES", "FrictionCertificate", "LogProtocol", "MUJOCO_UNSUPPORTED",
           "MujocoRow", "MujocoTestbedPlant", "OUTSIDE_NAMES", "PLANTS", "RigRanges", "TestbedPlant",
           "VARIANT_NAMES", "as_mujoco", "certify_static", "check_protocol", "design_cycles", "inject",
           "make_plant", "random_rig", "read_protocol", "run_protocol", "settle_protocol",
           "simulate_experiment", "simulate_protocol", "up_down", "with_persistence"]
