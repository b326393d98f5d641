"""Injecting one effect (or several) of a given severity into the nominal rig.

``severity = 1`` is a typical magnitude, chosen so that the effect is a few
times the instrument noise floor (about 2-3 mrad) on the paper rig's loads:

================  ===========================================================
hole_offsets      each hole coordinate ~ N(0, (1.0 mm * severity)^2)
friction          mu_beta_i = 0.03 * severity * U(0.7, 1.3), rho = 0.1
cable_hardening   h = 15 /m * severity
link_compliance   C = 0.004 rad/(N m) * severity * SPD with eigenvalues U(0.5, 1.5)
sensor_bias       |b| = 0.12 N m * severity, random direction
mass_com          mass * (1 + 0.2 severity)^(+-1), com + 15 mm * severity random direction
tracker_          tracker frame rotated by 2.5 mrad * severity about a random
registration      axis (``marker=True`` in :func:`inject`: also the markers)
stiffness_scale   every stiffness times exp(+-0.03 severity)
drive_offsets     each drive's rest length off by N(0, (0.3 mm * severity)^2)
sensor_gain       the F/T moment reading times exp(+-0.05 severity) (common),
                  each axis's factor times exp(N(0, (0.01 severity)^2))
joint_friction    Coulomb friction at the ball joint, 0.03 N m * severity per
                  axis of {A} (MuJoCo's ball-joint ``frictionloss``)
================  ===========================================================

A further law of a vocabulary effect (:data:`~csjm_opt.testbed.plant.VARIANT_NAMES`
gives the vocabulary name a diagnosis should give it):

================  ===========================================================
coulomb_friction  a constant friction force at each guide hole,
                  F_i = 0.5 N * severity * U(0.7, 1.3) (MuJoCo's tendon
                  ``frictionloss``), rho = 0.1; named ``friction``
================  ===========================================================

:data:`PLAUSIBLE_SEVERITY` is the largest severity of each effect whose injected
magnitudes stay inside the diagnosis's default prior ranges
(:meth:`csjm_opt.diagnose.effects.base.Effect.default_ranges`): hole
coordinates within 4 mm (3.3 sd at 1.2), capstan factors within 0.3,
hardening within 300 /m, compliance entries within 0.05 rad/(N m), a bias
within 0.5 N m, ``|d(m r)|`` within 0.1 x mass per axis (com z up to
120 mm), registration within 0.05 rad, a stiffness factor within [0.5, 2], drive
offsets within 2 mm (3.3 sd at 2), a sensor gain within [0.5, 2], a joint
friction moment within 0.3 N m.
A study that wants an effect larger than that against the noise floor lowers
the noise instead (a better instrument), not the plausibility of the effect.

Outside the diagnosis's vocabulary (:data:`~csjm_opt.testbed.plant.OUTSIDE_NAMES`):

================  ===========================================================
guide_radius      guide eyelets of radius 3 mm * severity (``eyelet_radius``: the
                  old name, deprecated); the diagnosis has modelled it since the
                  eyelet round, the testbed keeps it among these
sensor_drift      F/T offset drifting by 0.5 mN m per row * severity, random
                  direction (0.1 N m over a 200-row log)
drum_slip         cables slip on their drums above 55 % of the tension range,
                  by 20 um per N over the threshold * severity
================  ===========================================================
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Iterable
from typing import Any

import numpy as np

from .. import so3
from ..errors import InvalidInput
from ..model.rig import Rig
from .plant import DEPRECATED_NAMES, EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES, TestbedPlant

#: Largest severity whose injected magnitudes stay within the diagnosis's default priors (see above).
PLAUSIBLE_SEVERITY = {"hole_offsets": 1.2, "friction": 7.0, "cable_hardening": 15.0, "link_compliance": 8.0,
                      "sensor_bias": 4.0, "mass_com": 2.5, "tracker_registration": 15.0,
                      "stiffness_scale": 15.0, "coulomb_friction": 15.0, "drive_offsets": 2.0,
                      "sensor_gain": 9.0, "joint_friction": 10.0}


def _unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def inject(plant, effect: str, severity: float, rng: np.random.Generator):
    """``plant`` with one more effect of ``severity`` (1 = typical).

    Parameters
    ----------
    plant : TestbedPlant or MujocoTestbedPlant
        A MuJoCo plant gets the effect in its :class:`TestbedPlant` description (same draws).
    effect : str
        A name of the module's tables.
    severity : float
    rng : numpy.random.Generator

    Returns
    -------
    TestbedPlant or MujocoTestbedPlant
        Of the same kind as ``plant``.

    Raises
    ------
    InvalidInput
        Unknown effect name (or one the MuJoCo plant cannot realise).
    """
    if effect in DEPRECATED_NAMES:
        warnings.warn(f"the effect {effect!r} is now called {DEPRECATED_NAMES[effect]!r}; the old name will go",
                      DeprecationWarning, stacklevel=2)
        effect = DEPRECATED_NAMES[effect]
    if not isinstance(plant, TestbedPlant):            # a MujocoTestbedPlant: inject into its description
        return dataclasses.replace(plant, plant=inject(plant.plant, effect, severity, rng))
    s = float(severity)
    rig = plant.rig
    m = rig.n_cables                            # per-cable effects get one draw per cable
    if effect == "hole_offsets":
        rig = rig.replace(platform_holes_A_m=rig.platform_holes_A_m + rng.normal(0, 1e-3 * s, (m, 3)),
                          base_holes_B_m=rig.base_holes_B_m + rng.normal(0, 1e-3 * s, (m, 3)))
        changes: dict[str, Any] = {"rig": rig}
    elif effect == "friction":
        changes = {"friction_mu_beta": 0.03 * s * rng.uniform(0.7, 1.3, m)}
    elif effect == "coulomb_friction":
        changes = {"friction_coulomb_N": 0.5 * s * rng.uniform(0.7, 1.3, m)}
    elif effect == "cable_hardening":
        changes = {"hardening_per_m": 15.0 * s}
    elif effect == "link_compliance":
        Q = so3.exp(rng.normal(size=3))
        changes = {"link_compliance_rad_per_Nm": 0.004 * s * (Q * rng.uniform(0.5, 1.5, 3)) @ Q.T}
    elif effect == "sensor_bias":
        changes = {"sensor_bias_A_Nm": 0.12 * s * _unit(rng)}
    elif effect == "mass_com":
        rig = rig.replace(platform_mass_kg=rig.platform_mass_kg * (1 + 0.2 * s) ** rng.choice([-1.0, 1.0]),
                          com_A_m=np.asarray(rig.com_A_m) + 15e-3 * s * _unit(rng))
        changes = {"rig": rig}
    elif effect == "tracker_registration":
        changes = {"tracker_rotation_B": so3.exp(2.5e-3 * s * _unit(rng))}
    elif effect == "stiffness_scale":
        factor = np.exp(0.03 * s * rng.choice([-1.0, 1.0]))
        changes = {"rig": rig.replace(cable_stiffness_N_per_m=factor * np.asarray(rig.cable_stiffness_N_per_m))}
    elif effect == "drive_offsets":
        m = len(np.asarray(rig.cable_stiffness_N_per_m))
        changes = {"drive_offsets_m": rng.normal(0.0, 3e-4 * s, m)}
    elif effect == "sensor_gain":
        common = np.exp(0.05 * s * rng.choice([-1.0, 1.0]))
        changes = {"sensor_gain_A": common * np.exp(rng.normal(0.0, 0.01 * s, 3))}
    elif effect == "joint_friction":
        changes = {"joint_friction_Nm": 0.03 * s}
    elif effect == "guide_radius":
        changes = {"guide_radius_m": 3e-3 * s}
    elif effect == "sensor_drift":
        changes = {"sensor_drift_A_Nm_per_row": 5e-4 * s * _unit(rng)}
    elif effect == "drum_slip":
        changes = {"drum_slip_threshold_N": rig.t_min_N + 0.55 * (rig.t_max_N - rig.t_min_N),
                   "drum_slip_compliance_m_per_N": 2e-5 * s}
    else:
        known = EFFECT_NAMES + tuple(VARIANT_NAMES) + OUTSIDE_NAMES
        raise InvalidInput(f"unknown effect {effect!r}; expected one of {known}", "effect")
    return dataclasses.replace(plant, effects=plant.effects + (effect,), **changes)


def make_plant(rig: Rig, effects: str | Iterable[str] | None, severity: float,
               rng: np.random.Generator, plant: str = "quasi-static", persistent: bool = True,
               loading: str = "ramp", static_friction_ratio: float = 1.0):
    """The nominal ``rig`` with the named effect(s) injected (``None`` or ``"none"``: nominal).

    Parameters
    ----------
    rig : Rig
        The nominal rig.
    effects : str, iterable of str or None
        Effect names (module tables).
    severity : float
        Common severity (1 = typical).
    rng : numpy.random.Generator
        Draws of the effects (the same for both plants).
    plant : {"quasi-static", "mujoco"}, optional
        The quasi-static :class:`TestbedPlant` or the :class:`~csjm_opt.testbed.mujoco.plant.MujocoTestbedPlant`.
    persistent : bool, optional
        Cycles start where the previous one settled (default) or relaxed.
    loading : {"ramp", "step"}, optional
        How each row's load reaches the rig (:attr:`TestbedPlant.loading`,
        :attr:`~csjm_opt.testbed.mujoco.plant.MujocoTestbedPlant.loading`): ramped (default) or hung at once.
    static_friction_ratio : float, optional
        Static over sliding friction (default 1; above 1 on the quasi-static plant with step loading only).

    Returns
    -------
    TestbedPlant or MujocoTestbedPlant

    Raises
    ------
    InvalidInput
        Unknown effect, plant or loading name; a static friction ratio below 1 or not finite (or above 1
        with ramped loads on the quasi-static plant).
    """
    if plant not in ("quasi-static", "mujoco"):
        raise InvalidInput(f"unknown plant {plant!r}; expected 'quasi-static' or 'mujoco'", "plant")
    made = dataclasses.replace(TestbedPlant.nominal(rig), persistent=bool(persistent))
    if not (effects is None or effects == "none"):
        for name in ([effects] if isinstance(effects, str) else list(effects)):
            made = inject(made, name, severity, rng)
    if plant == "mujoco":
        from .mujoco.plant import as_mujoco

        return as_mujoco(made, loading=loading, static_friction_ratio=_ratio(static_friction_ratio))
    return dataclasses.replace(made, loading=loading, static_friction_ratio=_ratio(static_friction_ratio))


def _ratio(value) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InvalidInput(f"static_friction_ratio must be a finite number >= 1 (got {value!r})",
                           "static_friction_ratio") from None
