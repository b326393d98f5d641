"""Identification experiments: many load directions around each reference pose.

The diagnosis cycles of :mod:`csjm_opt.testbed.cycles` load along one
direction each, which is right for hysteresis but cannot identify a 3x3 K
per cycle (the displacements span one direction). An identification cycle,
like the paper's 85 measurements at R0 (Section IV-B), holds rest lengths
planned at a reference pose under a pre-load and applies load increments in
many directions and magnitudes: ``+-x, +-y, +-z`` first, then random ones.
The first row of each cycle is the reference (pre-load only).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from .. import so3
from ..errors import CsjmError, InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.numeric import Model
from ..model.rig import Rig
from ..model.statics import rest_lengths_for, solve_equilibrium
from ..planning.planner import plan_tensions
from .injection import make_plant
from .plant import TestbedPlant


def load_increments(n: int, rng: np.random.Generator, magnitude_Nm: tuple[float, float]) -> np.ndarray:
    """``n`` increments (N m): the six axis directions first, then random directions."""
    dirs = np.vstack([np.eye(3), -np.eye(3), rng.normal(size=(max(0, n - 6), 3))])[:n]
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    return dirs * rng.uniform(*magnitude_Nm, size=(n, 1))


def simulate_identification_experiment(
        rig: Rig, n_cycles: int, rng: np.random.Generator, loads_per_cycle: int = 12,
        load_Nm: tuple[float, float] = (0.3, 1.5), max_tilt_rad: float = 0.3,
        preload_Nm: float = 1.0, effect: str | Iterable[str] | TestbedPlant | None = None,
        severity: float = 1.0, noise: InstrumentNoise | None = None, first_cycle: int = 0,
        max_tries: int = 50) -> MeasurementLog:
    """A log of ``n_cycles`` identification cycles (``loads_per_cycle + 1`` rows each).

    Rest lengths are planned with the nominal rig; the plant (nominal or with
    ``effect`` injected) responds; instrument noise (``InstrumentNoise.paper()``
    by default) is added to the F/T moment and the tracked orientation.
    """
    if int(n_cycles) < 1 or int(loads_per_cycle) < 1:
        raise InvalidInput(f"need n_cycles >= 1 and loads_per_cycle >= 1 (got {n_cycles}, {loads_per_cycle})",
                           "n_cycles")
    noise = InstrumentNoise.paper() if noise is None else noise
    plant = effect if isinstance(effect, TestbedPlant) else make_plant(rig, effect, severity, rng)
    model = Model(rig)
    rows_cycle, rows_l, rows_tau, rows_R = [], [], [], []
    for c in range(n_cycles):
        for _ in range(max_tries):
            drawn = _draw_cycle(rig, model, rng, loads_per_cycle, load_Nm, max_tilt_rad, preload_Nm)
            if drawn is not None:
                break
        else:
            raise CsjmError(f"could not design a feasible identification cycle in {max_tries} tries")
        R_ref, l, taus = drawn
        rows_cycle.append(np.full(len(taus), first_cycle + c))
        rows_l.append(np.repeat(l[None], len(taus), 0))
        rows_tau.append(taus)
        rows_R.append(np.repeat(R_ref[None], len(taus), 0))
    cycle, l, tau, R_init = map(np.concatenate, (rows_cycle, rows_l, rows_tau, rows_R))
    R_true = plant.respond(l, tau, cycle, R_init)
    tau_meas, R_meas = noise.sample(plant.measured_moment(tau), plant.measured_pose(R_true), rng)
    return MeasurementLog.from_arrays(cycle, l, tau_meas, R_meas)


def _draw_cycle(rig, model, rng, n_loads, load_Nm, max_tilt, preload_Nm):
    tilt, az = rng.uniform(0.0, max_tilt), rng.uniform(0, 2 * np.pi)
    R_ref = so3.exp(tilt * np.array([np.cos(az), np.sin(az), 0.0]))
    pre = rng.normal(size=3)
    tau0 = preload_Nm * pre / np.linalg.norm(pre)
    increments = load_increments(n_loads, rng, load_Nm)
    try:
        plan = plan_tensions(rig, R_ref, tau0, model=model)
        l = rest_lengths_for(rig, R_ref, plan.tensions_N, model=model)
        ref = solve_equilibrium(rig, l, tau0, R_init=R_ref, model=model)
        for d in increments:  # nominal response must keep every cable taut and within bounds
            eq = solve_equilibrium(rig, l, tau0 + d, R_init=ref.R, model=model)
            if eq.tensions_N.min() < 0.5 * rig.t_min_N or eq.tensions_N.max() > rig.t_max_N:
                return None
    except CsjmError:
        return None
    return ref.R, l, np.vstack([tau0, tau0 + increments])
