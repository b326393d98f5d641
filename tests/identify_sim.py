"""Simulated load cycles from the project's own forward statics (no noise).

A cycle: tensions planned at a reference pose under a pre-load, rest lengths
fixed from them (``rest_lengths_for``), then load increments applied and the
equilibrium solved (``solve_equilibrium``). The first row is the reference.
The true stiffness is ``Equilibrium.K`` at the reference equilibrium.
"""

from __future__ import annotations

import numpy as np

from csjm_opt import so3
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.model.numeric import Model
from csjm_opt.planning.planner import plan_tensions
from csjm_opt.model.statics import rest_lengths_for, solve_equilibrium


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


def raw_text_from_log(log, rig, R_LB, p_LB, R_AS, p_AS, base_points_B, rng, point_sigma_m=0.0,
                      tau_sigma_Nm=0.0, platform_points_A=None, ft_includes_weight=False,
                      force_A_N=None):
    """Write a raw instrument CSV (csjm_opt.measurement.preprocess format) that preprocesses back to ``log``.

    Inverse of preprocessing, written independently: tracker points map B -> L
    (``p_L = R_LB p_B + p_LB``), F/T reading ``f_S = R_AS^T f_A``,
    ``tau_S = R_AS^T (tau_A - p_AS x f_A)``.
    """
    from csjm_opt.measurement.preprocess import RAW_COLUMNS

    def cell(v):
        if isinstance(v, str):
            return v
        return str(int(v)) if isinstance(v, (int, np.integer)) else repr(float(v))

    def row(**cells):
        return ",".join(cell(cells.get(c, "")) for c in RAW_COLUMNS)

    lines = [",".join(RAW_COLUMNS)]
    for j, pb in enumerate(base_points_B):
        pl = R_LB @ pb + p_LB + rng.normal(size=3) * point_sigma_m
        lines.append(row(record="base_point", name=f"H{j + 1}", x=float(pl[0]), y=float(pl[1]), z=float(pl[2]),
                         px=float(pb[0]), py=float(pb[1]), pz=float(pb[2])))
    rv = so3.log(R_AS)
    lines.append(row(record="sensor", x=p_AS[0], y=p_AS[1], z=p_AS[2], rx=rv[0], ry=rv[1], rz=rv[2]))
    n = len(log)
    f_A = np.zeros((n, 3)) if force_A_N is None else np.asarray(force_A_N, float)
    R_BA = log.R
    for i in range(n):
        tau_A = log.tau_ext_A_Nm[i].copy()
        if ft_includes_weight:
            tau_A += np.cross(rig.com_A_m, R_BA[i].T @ (rig.platform_mass_kg * rig.gravity_B_m_per_s2))
        f_S = R_AS.T @ f_A[i]
        tau_S = R_AS.T @ (tau_A - np.cross(p_AS, f_A[i])) + rng.normal(size=3) * tau_sigma_Nm
        R_LA = R_LB @ R_BA[i]
        cells = dict(record="sample", sample=int(log.sample[i]), cycle=int(log.cycle[i]),
                     fx=float(f_S[0]), fy=float(f_S[1]), fz=float(f_S[2]),
                     mx=float(tau_S[0]), my=float(tau_S[1]), mz=float(tau_S[2]),
                     **{f"l{k + 1}": float(log.rest_lengths_m[i, k]) for k in range(6)})
        if platform_points_A is None:
            rvl = so3.log(R_LA)
            cells.update(x=float(p_LB[0]), y=float(p_LB[1]), z=float(p_LB[2]),
                         rx=float(rvl[0]), ry=float(rvl[1]), rz=float(rvl[2]))
            lines.append(row(**cells))
        else:
            lines.append(row(**cells))
            for j, pa in enumerate(platform_points_A):
                pl = R_LA @ pa + p_LB + rng.normal(size=3) * point_sigma_m
                lines.append(row(record="platform_point", sample=int(log.sample[i]), name=f"P{j + 1}",
                                 x=float(pl[0]), y=float(pl[1]), z=float(pl[2]),
                                 px=float(pa[0]), py=float(pa[1]), pz=float(pa[2])))
    return "\n".join(lines) + "\n"
