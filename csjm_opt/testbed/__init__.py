"""Synthetic experiments: load-cycle design, random rigs, a plant with injected effects, noisy logs."""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .cycles import CycleDesign, design_cycles, up_down
    from .injection import inject, make_plant
    from .log_protocol import LogProtocol, check_protocol, read_protocol, simulate_protocol
    from .mujoco.plant import MUJOCO_UNSUPPORTED, PLANTS, MujocoRow, MujocoTestbedPlant, as_mujoco
    from .plant import EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES, TestbedPlant
    from .protocol_runner import run_protocol, settle_protocol
    from .rigs import RigRanges, random_rig
    from .simulate import simulate_experiment, with_persistence
    from .static_certificate import FrictionCertificate, certify_static

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'CycleDesign': ('.cycles', 'CycleDesign'),
    'design_cycles': ('.cycles', 'design_cycles'),
    'up_down': ('.cycles', 'up_down'),
    'inject': ('.injection', 'inject'),
    'make_plant': ('.injection', 'make_plant'),
    'LogProtocol': ('.log_protocol', 'LogProtocol'),
    'check_protocol': ('.log_protocol', 'check_protocol'),
    'read_protocol': ('.log_protocol', 'read_protocol'),
    'simulate_protocol': ('.log_protocol', 'simulate_protocol'),
    'MUJOCO_UNSUPPORTED': ('.mujoco.plant', 'MUJOCO_UNSUPPORTED'),
    'PLANTS': ('.mujoco.plant', 'PLANTS'),
    'MujocoRow': ('.mujoco.plant', 'MujocoRow'),
    'MujocoTestbedPlant': ('.mujoco.plant', 'MujocoTestbedPlant'),
    'as_mujoco': ('.mujoco.plant', 'as_mujoco'),
    'EFFECT_NAMES': ('.plant', 'EFFECT_NAMES'),
    'OUTSIDE_NAMES': ('.plant', 'OUTSIDE_NAMES'),
    'VARIANT_NAMES': ('.plant', 'VARIANT_NAMES'),
    'TestbedPlant': ('.plant', 'TestbedPlant'),
    'run_protocol': ('.protocol_runner', 'run_protocol'),
    'settle_protocol': ('.protocol_runner', 'settle_protocol'),
    'RigRanges': ('.rigs', 'RigRanges'),
    'random_rig': ('.rigs', 'random_rig'),
    'simulate_experiment': ('.simulate', 'simulate_experiment'),
    'with_persistence': ('.simulate', 'with_persistence'),
    'FrictionCertificate': ('.static_certificate', 'FrictionCertificate'),
    'certify_static': ('.static_certificate', 'certify_static'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["CycleDesign", "EFFECT_NAMES", "FrictionCertificate", "LogProtocol", "MUJOCO_UNSUPPORTED",
           "MujocoRow", "MujocoTestbedPlant", "OUTSIDE_NAMES", "PLANTS", "RigRanges", "TestbedPlant",
           "VARIANT_NAMES", "as_mujoco", "certify_static", "check_protocol", "design_cycles", "inject",
           "make_plant", "random_rig", "read_protocol", "run_protocol", "settle_protocol",
           "simulate_experiment", "simulate_protocol", "up_down", "with_persistence"]
