"""The optimisation's symbolic pieces: geometry of a design, orientations, the constraints at one orientation.

Written in CasADi so IPOPT gets exact derivatives; the numeric twins are
:func:`csjm_opt.design.geometry.design_holes` and
:func:`csjm_opt.design.sampling.tilt_torsion_rotations` (tested equal), and the
model is :mod:`csjm_opt.model.casadi_model`.
"""

from __future__ import annotations

import functools
import math
from typing import Any

import casadi as ca
import numpy as np

from ...errors import DesignError
from ...model import hexagon
from ...model.casadi_model import build_functions

#: Scales that make the objectives and constraints of order one.
STIFFNESS_SCALE_NM_PER_RAD = 10.0
MARGIN_SCALE_N = 10.0
SIZE_SCALE_M = 0.1
LENGTH_SCALE_M = 0.01
MOMENT_SCALE_NM = 1.0
#: IPOPT's Hessian: "limited-memory" (quasi-Newton on exact gradients) or "exact".
HESSIAN = "exact"
#: IPOPT iteration limit of one solve.
MAX_ITER = 300


def rotation_sym(tilt: Any, azimuth: Any, torsion: Any) -> Any:
    """``Rz(phi) Ry(theta) Rz(sigma - phi)`` in CasADi (same as :func:`~.sampling.tilt_torsion_rotations`).

    Parameters
    ----------
    tilt, azimuth, torsion : casadi.SX or float
        Angles (rad).

    Returns
    -------
    casadi.SX, shape (3, 3)
    """
    def rz(a: Any) -> Any:
        c, s = ca.cos(a), ca.sin(a)
        return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))

    c, s = ca.cos(tilt), ca.sin(tilt)
    ry = ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))
    return rz(azimuth) @ ry @ rz(torsion - azimuth)


def n_cables_sym(p: dict[str, Any]) -> int:
    """m, the number of cables of a design whose parameters may be symbolic (never m itself).

    ``n_cables`` when given (a number: the cable count cannot be optimised), else the rows of the
    free platform holes, else 6 (as :func:`csjm_opt.design.geometry.design_holes`).

    Parameters
    ----------
    p : dict
        Every parameter of the design.

    Returns
    -------
    int

    Raises
    ------
    DesignError
        If ``n_cables`` is symbolic or not an integer from 4 to 12.
    """
    if "n_cables" in p:
        value = p["n_cables"]
        if isinstance(value, (ca.SX, ca.MX)):
            raise DesignError("the cable count is an integer and cannot be optimised: fix it in [base] "
                              "(one optimisation per count)", "n_cables")
        if float(value) != int(value) or not 4 <= int(value) <= 12:
            raise DesignError(f"expected an integer from 4 to 12, got {value}", "n_cables")
        return int(value)
    if "platform_holes" in p:
        return int(np.shape(p["platform_holes"])[0])
    return 6


def holes_sym(p: dict[str, Any]) -> tuple[Any, Any]:
    """Platform and base holes (3 x m, columns) of a design whose parameters may be symbolic.

    Same parametrisation as :func:`csjm_opt.design.geometry.design_holes`: hole pairs on a
    circle of radius r, pair j centred at ``theta0 + j 720/m`` deg, its holes gamma apart (m = 6:
    the semi-regular hexagon; odd m: the last a single hole), at height +oo_a / -oo_b; per-hole
    offsets; or free hole coordinates.
    Chords ``*_d12_m`` / ``*_d23_m`` must be numbers here.

    Parameters
    ----------
    p : dict
        Every parameter of the design (paper values filled in), numbers or CasADi symbols.

    Returns
    -------
    A, B : casadi.SX, shape (3, m)
    """
    n_cab = n_cables_sym(p)
    out = []
    for body, letter, height in (("platform", "A", "oo_a_m"), ("base", "B", "oo_b_m")):
        if f"{body}_holes" in p:
            xyz = ca.SX(np.asarray(p[f"{body}_holes"], float).T)
        else:
            if f"{body}_radius_m" in p:
                r, gamma = p[f"{body}_radius_m"], p[f"{body}_gamma_deg"] * math.pi / 180
            else:
                d12, d23 = p[f"{body}_d12_m"], p[f"{body}_d23_m"]
                if isinstance(d12, ca.SX) or isinstance(d23, ca.SX):
                    raise DesignError("chords cannot be optimised: optimise the radius and gamma instead",
                                      f"{body}_d12_m")
                if n_cab == 6:
                    r, gamma = hexagon.circle_from_chords(float(d12), float(d23))
                else:
                    from ..geometry import pair_circle_from_chords

                    r, gamma = pair_circle_from_chords(float(d12), float(d23), n_cab)
            theta0 = p[f"{body}_theta0_deg"] * math.pi / 180
            z = p[height] if body == "platform" else -p[height]
            spacing = 2 * math.pi / 3 if n_cab == 6 else 4 * math.pi / n_cab   # between pair centres
            if n_cab % 2:      # odd m: the pairs continued, the last a single hole (hole_pattern.paired_angles_deg)
                step = 2 * math.pi / n_cab
                angles = [theta0 + (i - 0.5) * step + (-1 if i % 2 == 0 else 1) * (gamma - step) / 2
                          for i in range(n_cab)]
            else:
                angles = [theta0 + spacing * m + sign * gamma / 2 for m in range(n_cab // 2) for sign in (-1, 1)]
            cols = [ca.vertcat(r * ca.cos(a), r * ca.sin(a), z) for a in angles]
            xyz = ca.horzcat(*cols)
        offsets = ca.vertcat(*[ca.horzcat(*[p.get(f"{letter}{i + 1}_d{ax}_m", 0.0) for i in range(n_cab)])
                               for ax in "xyz"])
        out.append(xyz + offsets)
    return out[0], out[1]


def design_sym(settings: Any, u: Any) -> tuple[dict[str, Any], Any, Any, Any]:
    """A design's parameters, holes and rig vector as functions of the scaled variables ``u``.

    Parameters
    ----------
    settings : OptimiseSettings
        Names and bounds of the optimised parameters, the fixed ones (``base``) and gravity.
    u : casadi.SX or casadi.MX
        The optimised parameters scaled to their bounds (0 at the lower, 1 at the upper).

    Returns
    -------
    p : dict
        Every design parameter (paper values filled in), symbolic where optimised.
    A, B : casadi expression, shape (3, m)
        Platform and base holes (:func:`holes_sym`).
    rig : casadi expression
        ``(k, t_min, t_max, mass, com_z, g_B)``, the rig inputs of the model functions.
    """
    from ..geometry import PAPER_DESIGN

    p: dict[str, Any] = {**PAPER_DESIGN, **settings.base}
    lo, hi = settings.lower, settings.upper
    for k, name in enumerate(settings.names):
        p[name] = lo[k] + u[k] * (hi[k] - lo[k])
    A, B = holes_sym(p)
    rig = ca.vertcat(p["cable_stiffness_N_per_m"], p["t_min_N"], p["t_max_N"], p["platform_mass_kg"],
                     p["com_z_m"], *settings.gravity_B_m_per_s2)
    return p, A, B, rig


@functools.lru_cache(maxsize=16)
def pose_constraints(n_loads: int, exit_limit: bool, n_cables: int = 6) -> Any:
    """Constraints at one orientation, as a CasADi function (built once, mapped over orientations).

    Inputs: ``A``, ``B`` (3 x c for c cables), ``rig`` = [k, t_min, t_max, mass, com_z, g_x, g_y, g_z],
    ``q`` = [margin, lambda, s, cos(exit limit)], ``ang`` = [tilt, azimuth, torsion] at scale 1,
    ``load`` (3 x L), ``T`` (c (L - 1), scaled by t_max). Output ``g`` (all >= 0 but the
    equilibrium rows, == 0) and ``T0`` (the stiffness load's tensions).

    Parameters
    ----------
    n_loads : int
        Loads L of the set (row 0 the stiffness load).
    exit_limit : bool
        Include the exit-angle rows.
    n_cables : int
        Cables c of the design.

    Returns
    -------
    casadi.Function
    """
    c = n_cables
    A, B = ca.SX.sym("A", 3, c), ca.SX.sym("B", 3, c)
    rig, q, ang = ca.SX.sym("rig", 8), ca.SX.sym("q", 4), ca.SX.sym("ang", 3)
    loads = ca.SX.sym("load", 3, n_loads)
    tv = ca.SX.sym("T", c * (n_loads - 1))
    f = build_functions(c)
    k, t_min, t_max, mass, com_z = rig[0], rig[1], rig[2], rig[3], rig[4]
    mu, lam, s_range, cos_exit = q[0], q[1], q[2], q[3]
    R = rotation_sym(s_range * ang[0], ang[1], s_range * ang[2])
    J = f["jacobian"](R, A, B)
    tau_w = f["weight_moment"](R, mass, ca.vertcat(0, 0, com_z), rig[5:8])[0]
    t_mid = 0.5 * (t_min + t_max) * ca.DM.ones(c)
    T0 = t_mid + J @ ca.solve(J.T @ J, -(loads[:, 0] + tau_w) - J.T @ t_mid)
    out = [(T0 - t_min - mu) / MARGIN_SCALE_N, (t_max - mu - T0) / MARGIN_SCALE_N]
    M = (f["stiffness"](R, T0, k * ca.DM.ones(c), A, B) - lam * ca.DM.eye(3)) / STIFFNESS_SCALE_NM_PER_RAD
    out.append(ca.vertcat(M[0, 0], M[1, 1], M[2, 2], M[0, 0] * M[1, 1] - M[0, 1] ** 2,
                          M[0, 0] * M[2, 2] - M[0, 2] ** 2, M[1, 1] * M[2, 2] - M[1, 2] ** 2, ca.det(M)))
    for kk in range(1, n_loads):
        T = tv[c * (kk - 1):c * kk] * t_max
        out += [(T - t_min - mu) / MARGIN_SCALE_N, (t_max - mu - T) / MARGIN_SCALE_N,
                (J.T @ T + loads[:, kk] + tau_w) / MOMENT_SCALE_NM]
    if exit_limit:
        C = B - R @ A                                       # cables, platform to base, in {B}
        U = C / ca.repmat(ca.sqrt(ca.sum1(C * C)), 3, 1)
        out += [-(R[:, 2].T @ U).T - cos_exit, -U[2, :].T - cos_exit]
    return ca.Function("pose_constraints", [A, B, rig, q, ang, loads, tv], [ca.vertcat(*out), T0],
                       ["A", "B", "rig", "q", "ang", "load", "T"], ["g", "T0"])


def pose_bounds(n_loads: int, exit_limit: bool, n_cables: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of :func:`pose_constraints`'s ``g``.

    Parameters
    ----------
    n_loads : int
    exit_limit : bool
    n_cables : int

    Returns
    -------
    lower, upper : ndarray
    """
    box = 2 * n_cables                                  # lower and upper tension rows
    lo = [np.zeros(box + 7)]
    hi = [np.full(box + 7, np.inf)]
    for _ in range(1, n_loads):
        lo += [np.zeros(box), np.zeros(3)]
        hi += [np.full(box, np.inf), np.zeros(3)]
    if exit_limit:
        lo.append(np.zeros(box))
        hi.append(np.full(box, np.inf))
    return np.concatenate(lo), np.concatenate(hi)


def initial_load_tensions(design: Any, u0: np.ndarray, q0: float, pq: np.ndarray, angles: np.ndarray,
                          loads: np.ndarray) -> np.ndarray:
    """Least-squares tensions of every load k >= 1 at the start, clipped to the tension box, scaled.

    Parameters
    ----------
    design : casadi.Function
        ``(u, q, pq) -> (A, B, rig, q, s_shape)`` of the optimisation problem.
    u0 : ndarray
        Scaled design variables.
    q0 : float
        Objective variable (scaled).
    pq : ndarray
        Held values.
    angles : ndarray, shape (n_slots, 3)
        Orientations at range scale 1.
    loads : ndarray, shape (L, 3)
        Loads (row 0 the stiffness load).

    Returns
    -------
    ndarray
        ``T_jk / t_max``, slot by slot.
    """
    if loads.shape[0] == 1:
        return np.zeros(0)
    out = [start_tensions(design, u0, q0, pq, angles, load) for load in loads[1:]]
    return np.stack(out, axis=1).transpose(2, 1, 0).reshape(-1)


def start_tensions(design: Any, u0: np.ndarray, q0: float, pq: np.ndarray, angles: np.ndarray,
                   load: np.ndarray) -> np.ndarray:
    """Least-squares tensions holding one load at each orientation at the start, clipped, scaled.

    Parameters
    ----------
    design : casadi.Function
        ``(u, q, pq) -> (A, B, rig, q, s_shape)`` of the optimisation problem.
    u0 : ndarray
        Scaled design variables.
    q0 : float
        Objective variable (scaled).
    pq : ndarray
        Held values.
    angles : ndarray, shape (n_slots, 3)
        Orientations at range scale 1.
    load : ndarray, shape (3,)
        The load (N m in {A}).

    Returns
    -------
    ndarray, shape (m, n_slots)
        The tensions clipped to ``[t_min, t_max]``, divided by ``t_max``.
    """
    A, B, rig, q, _ = (np.array(v) for v in design(u0, q0, pq))
    n = angles.shape[0]
    _, T0 = pose_constraints(1, False, A.shape[1]).map(n, "serial")(A, B, rig, q, angles.T,
                                                        np.asarray(load, float).reshape(3, 1), np.zeros((0, n)))
    return np.clip(np.array(T0), rig[1, 0], rig[2, 0]) / rig[2, 0]
