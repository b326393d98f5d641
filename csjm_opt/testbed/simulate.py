"""Simulate a measurement log (format in docs/conventions.md) on a plant, with instrument noise."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

import numpy as np

from ..errors import InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.rig import Rig
from .cycles import design_cycles
from .injection import make_plant
from .mujoco.plant import MujocoTestbedPlant
from .plant import TestbedPlant


def simulate_experiment(rig: Rig, n_cycles: int, rng: np.random.Generator,
                        effect: str | Iterable[str] | TestbedPlant | MujocoTestbedPlant | None = None,
                        severity: float = 1.0,
                        noise: InstrumentNoise | None = None, steps: int = 4,
                        first_cycle: int = 0, persistent: bool | None = None) -> MeasurementLog:
    """A log of ``n_cycles`` load cycles (``2 * steps + 1`` rows each) on ``rig``.

    ``effect``: ``None``/``"none"`` (nominal plant), an effect name from the
    documented vocabulary, several names, or a ready :class:`TestbedPlant` or
    :class:`~csjm_opt.testbed.mujoco.plant.MujocoTestbedPlant`. Rest lengths are
    commanded with the *nominal* rig (as an experimenter would); the plant
    responds; the F/T reading (plus any bias) and the tracked pose get the
    instrument noise (``InstrumentNoise.paper()`` by default). ``persistent``
    (default: the plant's own setting, ``True`` unless changed) makes each cycle
    start where the previous one settled, friction state included; ``False``
    starts every cycle relaxed.
    """
    if int(n_cycles) < 1 or int(steps) < 1:
        raise InvalidInput(f"need n_cycles >= 1 and steps >= 1 (got {n_cycles}, {steps})", "n_cycles")
    noise = InstrumentNoise.paper() if noise is None else noise
    plant = effect if isinstance(effect, (TestbedPlant, MujocoTestbedPlant)) else make_plant(rig, effect, severity, rng)
    if persistent is not None:
        plant = with_persistence(plant, bool(persistent))
    cycles = design_cycles(rig, n_cycles, rng, steps=steps)
    cycle = np.concatenate([np.full(len(c.alphas), first_cycle + i) for i, c in enumerate(cycles)])
    l = np.concatenate([np.repeat(c.rest_lengths_m[None], len(c.alphas), 0) for c in cycles])
    tau = np.concatenate([c.tau_ext_A_Nm for c in cycles])
    R_init = np.concatenate([np.repeat(c.R_ref[None], len(c.alphas), 0) for c in cycles])
    R_true = plant.respond(l, tau, cycle, R_init)
    tau_meas, R_meas = noise.sample(plant.measured_moment(tau), plant.measured_pose(R_true), rng)
    return MeasurementLog.from_arrays(cycle, l, tau_meas, R_meas)


def with_persistence(plant, persistent: bool):
    """``plant`` (a :class:`TestbedPlant` or a MuJoCo plant) with its ``persistent`` setting changed.

    Parameters
    ----------
    plant : TestbedPlant or MujocoTestbedPlant
    persistent : bool

    Returns
    -------
    TestbedPlant or MujocoTestbedPlant
    """
    if isinstance(plant, TestbedPlant):
        return dataclasses.replace(plant, persistent=persistent)
    return dataclasses.replace(plant, plant=dataclasses.replace(plant.plant, persistent=persistent))
