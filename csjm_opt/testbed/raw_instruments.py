"""Raw instrument files (tracker points, F/T readings) that preprocess back to a given log.

The inverse of :mod:`csjm_opt.measurement.preprocess`, written independently of
it, so that tests and benchmarks can check the preprocessing end to end.
"""

from __future__ import annotations

import numpy as np

from .. import so3
from ..measurement.preprocess import raw_columns


def raw_text_from_log(log, rig, R_LB, p_LB, R_AS, p_AS, base_points_B, rng, point_sigma_m=0.0,
                      tau_sigma_Nm=0.0, platform_points_A=None, ft_includes_weight=False,
                      force_A_N=None):
    """Text of a raw instrument CSV (the preprocessing format) that preprocesses back to ``log``.

    Inverse of preprocessing, written independently of it: tracker points map
    B -> L (``p_L = R_LB p_B + p_LB``), F/T reading ``f_S = R_AS^T f_A``,
    ``tau_S = R_AS^T (tau_A - p_AS x f_A)``.

    Parameters
    ----------
    log : MeasurementLog
        The log the raw file stands for.
    rig : Rig
        Its rig (mass and COM, when the F/T reading includes the weight).
    R_LB, p_LB : array
        Tracker frame {L} from {B}: rotation (3, 3) and origin (3,) (m).
    R_AS, p_AS : array
        Sensor frame {S} in {A}: rotation (3, 3) and origin (3,) (m).
    base_points_B : (k, 3) array
        Base points measured by the tracker (m, in {B}).
    rng : numpy.random.Generator
        Source of the point and moment noise.
    point_sigma_m, tau_sigma_Nm : float
        Noise on tracked points (m) and on the F/T moment (N m).
    platform_points_A : (p, 3) array, optional
        Tracked platform points (m, in {A}); without them the tracker reports a pose.
    ft_includes_weight : bool
        The F/T reading includes the platform's weight moment.
    force_A_N : (n, 3) array, optional
        Force on the sensor per row (N, in {A}).

    Returns
    -------
    str
        The file's text.
    """

    def cell(v):
        if isinstance(v, str):
            return v
        return str(int(v)) if isinstance(v, (int, np.integer)) else repr(float(v))

    m = log.rest_lengths_m.shape[1]
    columns = raw_columns(m)

    def row(**cells):
        return ",".join(cell(cells.get(c, "")) for c in columns)

    lines = [",".join(columns)]
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
                     **{f"l{k + 1}": float(log.rest_lengths_m[i, k]) for k in range(m)})
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
