"""Run an identification protocol (:mod:`csjm_opt.measurement.protocol`) on a simulated plant.

Each row commands its rest lengths and hangs its dead weight: a force fixed in {B} at a point
of the platform, whose moment about O in {A}, ``p x (R^T f)``, depends on the pose the
platform settles in. The plant (:class:`~csjm_opt.testbed.plant.TestbedPlant`) takes moments fixed in
{A}, so the pose is found by a fixed-point iteration on the load (the dead weight's stiffness
``|p| |f|`` is small against K; the iteration stops at 1e-12 rad). The F/T sensor then reads
that moment (plus the plant's bias and drift) with noise, the tracker the pose with noise.
Rows are independent for plants without path-dependent effects and are solved together;
friction or drum slip step through each cycle in order.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .. import so3
from ..errors import NoEquilibrium
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..measurement.protocol import Protocol
from ..model.rig import Rig
from .mujoco.plant import MujocoTestbedPlant
from .plant import TestbedPlant

#: Fixed-point iterations on the dead-weight moment before giving up.
MAX_LOAD_ITERATIONS = 60


def dead_weight_moments(R: np.ndarray, force_B_N: np.ndarray, point_A_m: np.ndarray) -> np.ndarray:
    """Moments about O in {A} (n, 3) of forces fixed in {B} at platform points: ``p x (R^T f)``.

    Parameters
    ----------
    R : array (n, 3, 3)
    force_B_N : array (n, 3)
    point_A_m : array (n, 3)

    Returns
    -------
    ndarray (n, 3)
    """
    return np.cross(point_A_m, np.einsum("nji,nj->ni", R, force_B_N))


def settle_protocol(plant: TestbedPlant | MujocoTestbedPlant, protocol: Protocol,
                    R_start: np.ndarray | None = None,
                    progress: Callable[[int], object] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """True poses (n, 3, 3) and true external moments in {A} (n, 3) of every protocol row.

    Parameters
    ----------
    plant : TestbedPlant
    protocol : Protocol
    R_start : array (3, 3), optional
        Where the platform starts (identity by default).
    progress : callable, optional
        Called with the number of rows settled, in every pass over the rows (the dead weights' moments
        are iterated: a pass per iteration, typically a few).

    Returns
    -------
    R : ndarray (n, 3, 3)
    tau_ext_A_Nm : ndarray (n, 3)

    Raises
    ------
    NoEquilibrium
        The plant cannot hold a row's load, or the load iteration does not settle.
    """
    n = len(protocol)
    base = plant.plant if isinstance(plant, MujocoTestbedPlant) else plant   # it wraps its TestbedPlant
    path = base.has_friction or bool(np.isfinite(base.drum_slip_threshold_N))
    cycle = protocol.cycle if path else np.arange(n)
    f, p, l = protocol.force_B_N, protocol.point_A_m, protocol.rest_lengths_m
    R = np.repeat((np.eye(3) if R_start is None else np.asarray(R_start, float))[None], n, 0)
    # the unloaded poses first (a good start for the loaded rows of each cycle)
    R = plant.respond(l, np.zeros((n, 3)), cycle, R, progress=progress)
    for _ in range(MAX_LOAD_ITERATIONS):
        tau = dead_weight_moments(R, f, p)
        R_new = plant.respond(l, tau, cycle, R, progress=progress)
        step = float(np.max(np.linalg.norm(so3.log(np.swapaxes(R, 1, 2) @ R_new), axis=1)))
        R = R_new
        if step < 1e-12:
            return R, dead_weight_moments(R, f, p)
    raise NoEquilibrium(f"dead-weight loads did not settle in {MAX_LOAD_ITERATIONS} iterations "
                        f"(last change {step:.3g} rad)", "diverged", step)


def run_protocol(plant: TestbedPlant | MujocoTestbedPlant | Rig, protocol: Protocol, rng: np.random.Generator,
                 noise: InstrumentNoise | None = None,
                 progress: Callable[[int], object] | None = None) -> MeasurementLog:
    """The measurement log a lab would record running ``protocol`` on ``plant``.

    Parameters
    ----------
    plant : TestbedPlant or Rig
        The simulated rig (a :class:`Rig` is its nominal plant).
    protocol : Protocol
    rng : numpy.random.Generator
        Instrument noise.
    noise : InstrumentNoise, optional
        The paper's instruments by default.
    progress : callable, optional
        As in :func:`settle_protocol`.

    Returns
    -------
    MeasurementLog
        With the protocol's load columns kept as extra columns.

    Raises
    ------
    NoEquilibrium
        As :func:`settle_protocol`.
    """
    plant = plant if isinstance(plant, (TestbedPlant, MujocoTestbedPlant)) else TestbedPlant(plant)
    noise = InstrumentNoise.paper() if noise is None else noise
    R_true, tau = settle_protocol(plant, protocol, progress=progress)
    tau_meas, R_meas = noise.sample(plant.measured_moment(tau), plant.measured_pose(R_true), rng)
    return MeasurementLog.from_arrays(protocol.cycle, protocol.rest_lengths_m, tau_meas, R_meas,
                                      extra=protocol.extra_columns())
