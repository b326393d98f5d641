"""Unmodelled effects, one class per file; :data:`EFFECTS` maps SPEC names to classes."""

from __future__ import annotations

from .base import Effect
from .cable_hardening import CableHardening
from .friction import Friction
from .hole_offsets import HoleOffsets
from .link_compliance import LinkCompliance
from .mass_com import MassCom
from .sensor_bias import SensorBias

#: docs/conventions.md vocabulary (besides ``none``) -> effect class, in report order.
EFFECTS: dict[str, type[Effect]] = {
    "hole_offsets": HoleOffsets,
    "friction": Friction,
    "cable_hardening": CableHardening,
    "link_compliance": LinkCompliance,
    "sensor_bias": SensorBias,
    "mass_com": MassCom,
}


def make_effect(name: str, rig=None) -> Effect:
    """An effect instance by SPEC name (``rig`` supplies the nominal mass)."""
    cls = EFFECTS[name]
    if cls is MassCom and rig is not None:
        return MassCom(rig.platform_mass_kg)
    return cls()


__all__ = ["EFFECTS", "CableHardening", "Effect", "Friction", "HoleOffsets", "LinkCompliance",
           "MassCom", "SensorBias", "make_effect"]
