"""Scripted load cycles on the nominal statics: the caller chooses every pose and load; no randomness.

A cycle: tensions planned at a reference pose under a pre-load, rest lengths
fixed from them (``rest_lengths_for``), then load increments applied and the
equilibrium solved (``solve_equilibrium``). The first row is the reference.
The true stiffness is ``Equilibrium.K`` at the reference equilibrium. Noise
is added separately (:func:`add_noise`), so tests can compare a noise-free
log with its noisy twin. For random cycles with injected effects see
:mod:`csjm_opt.testbed.identification`.
"""

from __future__ import annotations

import numpy as np

from .. import so3
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.equilibrium import Equilibrium
from ..model.numeric import Model
from ..model.rig import Rig
from ..model.statics import rest_lengths_for, solve_equilibrium
from ..planning.planner import plan_tensions


def load_directions(n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` unit load directions: +-e_x, +-e_y, +-e_z first, then random unit vectors.

    Parameters
    ----------
    n : int
        Number of directions.
    rng : numpy.random.Generator
        Source of the random directions after the first six.

    Returns
    -------
    (n, 3) array
        Unit vectors.
    """
    base = np.vstack([np.eye(3), -np.eye(3)])
    extra = rng.normal(size=(max(0, n - 6), 3))
    extra /= np.linalg.norm(extra, axis=1, keepdims=True)
    return np.vstack([base, extra])[:n]


def simulate_cycle(rig: Rig, rotvec_ref, tau_pre_A_Nm, increments_A_Nm, model: Model | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Equilibrium]:
    """One noise-free cycle on the nominal statics.

    Parameters
    ----------
    rig : Rig
        The rig (nominal: no effect).
    rotvec_ref : (3,) array
        Reference pose as a rotation vector (rad).
    tau_pre_A_Nm : (3,) array
        Pre-load (N m, in {A}) under which the tensions are planned.
    increments_A_Nm : (m, 3) array
        Load increments added to the pre-load, one row each.
    model : Model, optional
        Compiled model of ``rig`` (built when ``None``).

    Returns
    -------
    R : (m + 1, 3, 3) array
        Equilibrium poses, reference first.
    tau : (m + 1, 3) array
        External moments of the rows (N m, in {A}).
    rest_lengths : (m,) array
        Rest lengths held through the cycle (m).
    reference : Equilibrium
        The reference equilibrium (its ``K`` is the true stiffness).
    """
    model = model or Model(rig)
    R_ref = so3.exp(np.asarray(rotvec_ref, float))
    plan = plan_tensions(rig, R_ref, tau_pre_A_Nm, model=model)
    l = rest_lengths_for(rig, R_ref, plan.tensions_N, model=model)
    ref = solve_equilibrium(rig, l, tau_pre_A_Nm, R_init=R_ref, model=model)
    Rs, taus = [ref.R], [np.asarray(tau_pre_A_Nm, float)]
    for d in increments_A_Nm:
        tau = np.asarray(tau_pre_A_Nm, float) + d
        eq = solve_equilibrium(rig, l, tau, R_init=ref.R, model=model)
        Rs.append(eq.R)
        taus.append(tau)
    return np.array(Rs), np.array(taus), l, ref


def simulate_log(rig: Rig, cycles, model: Model | None = None) -> tuple[MeasurementLog, list[Equilibrium]]:
    """A noise-free log of several scripted cycles.

    Parameters
    ----------
    rig : Rig
        The rig (nominal: no effect).
    cycles : list of (rotvec_ref, tau_pre, increments)
        One entry per cycle, as the arguments of :func:`simulate_cycle`.
    model : Model, optional
        Compiled model of ``rig`` (built when ``None``).

    Returns
    -------
    log : MeasurementLog
        The rows of all cycles in order (cycle ids 0, 1, ...).
    references : list of Equilibrium
        The reference equilibrium of each cycle (true K: ``ref.K``).
    """
    model = model or Model(rig)
    cyc, ls, taus, Rs, refs = [], [], [], [], []
    for c, (rv, pre, inc) in enumerate(cycles):
        R, tau, l, ref = simulate_cycle(rig, rv, pre, inc, model)
        cyc += [c] * len(R)
        ls += [l] * len(R)
        taus.append(tau)
        Rs.append(R)
        refs.append(ref)
    log = MeasurementLog.from_arrays(cyc, np.array(ls), np.vstack(taus), np.vstack(Rs))
    return log, refs


def add_noise(log: MeasurementLog, noise: InstrumentNoise, rng: np.random.Generator) -> MeasurementLog:
    """Instrument noise: Gaussian moment noise per axis, isotropic body-frame angle noise.

    Parameters
    ----------
    log : MeasurementLog
        Noise-free log.
    noise : InstrumentNoise
        Standard deviations (``tau_sigma_Nm`` per axis, ``angle_sigma_rad``).
    rng : numpy.random.Generator
        Source of the noise.

    Returns
    -------
    MeasurementLog
        A new log with the same samples, cycles and rest lengths.
    """
    tau, R = noise.sample(log.tau_ext_A_Nm, log.R, rng)
    return MeasurementLog.from_arrays(log.cycle, log.rest_lengths_m, tau, R, sample=log.sample)
