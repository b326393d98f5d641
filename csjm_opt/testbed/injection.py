"""Injecting one effect (or several) of a given severity into the nominal rig.

``severity = 1`` is a typical magnitude, chosen so that the effect is a few
times the instrument noise floor (about 2-3 mrad) on the paper rig's loads:

================  ===========================================================
hole_offsets      each hole coordinate ~ N(0, (1.0 mm * severity)^2)
friction          mu_beta_i = 0.03 * severity * U(0.7, 1.3), rho = 0.1
cable_hardening   h = 15 /m * severity
link_compliance   C = 0.004 rad/(N m) * severity * SPD with eigenvalues U(0.5, 1.5)
sensor_bias       |b| = 0.12 N m * severity, random direction
mass_com          mass * (1 +- 0.2 severity), com + 15 mm * severity random direction
================  ===========================================================
"""

from __future__ import annotations

import dataclasses
from typing import Any, Iterable

import numpy as np

from .. import so3
from ..model.rig import Rig
from .plant import EFFECT_NAMES, Plant


def _unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def inject(plant: Plant, effect: str, severity: float, rng: np.random.Generator) -> Plant:
    """``plant`` with one more effect of ``severity`` (1 = typical)."""
    s = float(severity)
    rig = plant.rig
    if effect == "hole_offsets":
        rig = rig.replace(platform_holes_A_m=rig.platform_holes_A_m + rng.normal(0, 1e-3 * s, (6, 3)),
                          base_holes_B_m=rig.base_holes_B_m + rng.normal(0, 1e-3 * s, (6, 3)))
        changes: dict[str, Any] = {"rig": rig}
    elif effect == "friction":
        changes = {"friction_mu_beta": 0.03 * s * rng.uniform(0.7, 1.3, 6)}
    elif effect == "cable_hardening":
        changes = {"hardening_per_m": 15.0 * s}
    elif effect == "link_compliance":
        Q = so3.exp(rng.normal(size=3))
        changes = {"link_compliance_rad_per_Nm": 0.004 * s * (Q * rng.uniform(0.5, 1.5, 3)) @ Q.T}
    elif effect == "sensor_bias":
        changes = {"sensor_bias_A_Nm": 0.12 * s * _unit(rng)}
    elif effect == "mass_com":
        rig = rig.replace(platform_mass_kg=rig.platform_mass_kg * (1 + 0.2 * s * rng.choice([-1.0, 1.0])),
                          com_A_m=np.asarray(rig.com_A_m) + 15e-3 * s * _unit(rng))
        changes = {"rig": rig}
    else:
        raise ValueError(f"unknown effect {effect!r}; expected one of {EFFECT_NAMES}")
    return dataclasses.replace(plant, effects=plant.effects + (effect,), **changes)


def make_plant(rig: Rig, effects: str | Iterable[str] | None, severity: float,
               rng: np.random.Generator) -> Plant:
    """The nominal ``rig`` with the named effect(s) injected (``None`` or ``"none"``: nominal)."""
    plant = Plant.nominal(rig)
    if effects is None or effects == "none":
        return plant
    for name in ([effects] if isinstance(effects, str) else list(effects)):
        plant = inject(plant, name, severity, rng)
    return plant
