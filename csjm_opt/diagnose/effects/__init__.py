"""Unmodelled effects, one class per file; :data:`EFFECTS` maps vocabulary names to classes."""

from __future__ import annotations

from typing import Mapping

from ...errors import InvalidInput
from .base import Effect
from .cable_hardening import CableHardening
from .drive_offsets import DriveOffsets
from .friction import Friction
from .guide_radius import GuideRadius, guide_axis
from .hole_offsets import HoleOffsets
from .joint_friction import JointFriction
from .link_compliance import LinkCompliance
from .mass_com import MassCom
from .sensor_bias import SensorBias
from .sensor_gain import SensorGain
from .stiffness_scale import StiffnessScale
from .tracker_registration import TrackerRegistration

#: Vocabulary of ``selected`` (besides ``none`` and ``unexplained``) -> effect class, in report order.
EFFECTS: dict[str, type[Effect]] = {
    "hole_offsets": HoleOffsets,
    "friction": Friction,
    "cable_hardening": CableHardening,
    "link_compliance": LinkCompliance,
    "sensor_bias": SensorBias,
    "mass_com": MassCom,
    "tracker_registration": TrackerRegistration,
    "stiffness_scale": StiffnessScale,
    "guide_radius": GuideRadius,
    "drive_offsets": DriveOffsets,
    "sensor_gain": SensorGain,
    "joint_friction": JointFriction,
}


def n_cables_of(rig) -> int:
    """The rig's cable count ``m`` (``rig.n_cables``, else the length of its stiffness list)."""
    m = getattr(rig, "n_cables", None)
    return int(m) if m is not None else len(rig.cable_stiffness_N_per_m)


def make_effect(name: str, rig=None, ranges: Mapping[str, tuple[float, float]] | None = None,
                **options) -> Effect:
    """An effect instance by vocabulary name.

    Parameters
    ----------
    name : str
        One of :data:`EFFECTS`.
    rig : Rig, optional
        Supplies the cable count ``m`` that sizes the per-cable parameters (``hole_offsets``,
        ``friction``, ``drive_offsets``; 6 without a rig), the nominal mass (``mass_com``), gravity
        (``tracker_registration``) and base plane (``guide_radius``).
    ranges : mapping, optional
        Prior-range overrides, parameter name or fnmatch pattern -> ``(lo, hi)``.
    **options
        Variant of the effect (``friction``: ``law``, ``memory``; ``joint_friction``: ``memory``;
        ``sensor_gain``: ``axes``).

    Returns
    -------
    Effect

    Raises
    ------
    InvalidInput
        ``name`` is not in the vocabulary.
    """
    if name not in EFFECTS:
        raise InvalidInput(f"unknown effect {name!r}; expected one of {', '.join(EFFECTS)}", "effect")
    cls = EFFECTS[name]
    m = n_cables_of(rig) if rig is not None else 6
    effect: Effect
    if cls is MassCom and rig is not None:
        effect = MassCom(rig.platform_mass_kg, n_cables=m)
    elif cls is TrackerRegistration and rig is not None:
        effect = TrackerRegistration(rig.gravity_B_m_per_s2, n_cables=m)
    elif cls is GuideRadius and rig is not None:
        effect = GuideRadius(guide_axis(rig.base_holes_B_m), n_cables=m)
    elif cls is Friction:
        effect = Friction(t_max_N=rig.t_max_N if rig is not None else 100.0, n_cables=m, **options)
    elif cls is SensorGain:
        effect = SensorGain(n_cables=m, **options)
    elif cls is JointFriction:
        effect = JointFriction(n_cables=m, **options)
    else:
        effect = cls(n_cables=m)
    return effect.with_ranges(ranges)


__all__ = ["EFFECTS", "CableHardening", "DriveOffsets", "Effect", "Friction", "GuideRadius", "HoleOffsets",
           "JointFriction", "LinkCompliance", "MassCom", "SensorBias", "SensorGain", "StiffnessScale",
           "TrackerRegistration", "make_effect", "n_cables_of"]
