"""Simulated load cycles from the project's own forward statics (no noise).

A cycle: tensions planned at a reference pose under a pre-load, rest lengths
fixed from them (``rest_lengths_for``), then load increments applied and the
equilibrium solved (``solve_equilibrium``). The first row is the reference.
The true stiffness is ``Equilibrium.K`` at the reference equilibrium.
"""

from __future__ import annotations

import numpy as np

from csjm_opt import so3
from csjm_opt.logfile import MeasurementLog
from csjm_opt.model import Model
from csjm_opt.planner import plan_tensions
from csjm_opt.statics import rest_lengths_for, solve_equilibrium


def load_directions(n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` load directions: +-e_x, +-e_y, +-e_z first, then random unit vectors."""
    base = np.vstack([np.eye(3), -np.eye(3)])
    extra = rng.normal(size=(max(0, n - 6), 3))
    extra /= np.linalg.norm(extra, axis=1, keepdims=True)
    return np.vstack([base, extra])[:n]


def simulate_cycle(rig, rotvec_ref, tau_pre_A_Nm, increments_A_Nm, model=None):
    """Rows (R, tau_ext, rest_lengths) of one cycle and the reference equilibrium."""
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


def simulate_log(rig, cycles, model=None):
    """A MeasurementLog of several cycles; ``cycles`` is a list of (rotvec_ref, tau_pre, increments).

    Returns the log and the list of reference equilibria (true K: ``ref.K``).
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


def add_noise(log: MeasurementLog, noise, rng: np.random.Generator) -> MeasurementLog:
    """Instrument noise: Gaussian moment noise per axis, isotropic body-frame angle noise."""
    tau = log.tau_ext_A_Nm + rng.normal(size=log.tau_ext_A_Nm.shape) * np.asarray(noise.tau_sigma_Nm)
    R = log.R @ so3.exp(rng.normal(size=(len(log), 3)) * noise.angle_sigma_rad)
    return MeasurementLog.from_arrays(log.cycle, log.rest_lengths_m, tau, R, sample=log.sample)
