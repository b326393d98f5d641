"""The shaping range as an optimiser objective: an epigraph over a fixed pose set, certified by the exact LP.

The shaping range of a design at an orientation R and along a unit direction u
in {A} is ``max u^T K(T) u - min u^T K(T) u`` over the tensions T that hold
the stiffness load (row 0 of the loads, plus the weight) within
``[t_min + margin, t_max - margin]``: two linear programmes, since K is affine
in T (:mod:`csjm_opt.design.shaping_range`). The optimiser maximises its
smallest value over the required orientations and the axes x, y, z with an
epigraph: decision variables ``s`` and, per orientation and axis, two tension
vectors ``T_hi`` and ``T_lo``, each in the margin box and holding the load,
and the smooth constraints ``u^T K(T_hi) u - u^T K(T_lo) u >= s``. At the
optimum ``T_hi`` and ``T_lo`` of the binding orientation and axis are the LPs'
optimisers, so maximising over the design and the tensions together is
maximising the smallest LP range (exact, no soft minimum).

The certified number is the batched LP itself on the dense certification set
(plus a pattern search from its worst orientations): :func:`shaping_check`.
It is not the sweep's ``shaping_range_Nm_per_rad``, which is the median over
16 held poses of the LP's smallest and largest values per axis (six numbers,
over whichever poses the sweep held first): the objective here is the worst
range over the whole required set, one number.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import casadi as ca
import numpy as np

from ...model.casadi_model import build_functions
from ...model.numeric import Model
from ...model.rig import Rig
from ..sampling import OrientationSampling, tilt_torsion_rotations
from ..shaping_range import AXES, directional_stiffness_range
from .dense_check import TOLERANCES, Check
from .symbols import (
    MARGIN_SCALE_N,
    MOMENT_SCALE_NM,
    STIFFNESS_SCALE_NM_PER_RAD,
    rotation_sym,
    start_tensions,
)


def n_tensions(n_cables: int) -> int:
    """Tension variables per orientation: (T_hi, T_lo) for each axis, m cables each (36 for m = 6).

    Parameters
    ----------
    n_cables : int
        m.

    Returns
    -------
    int
    """
    return 2 * len(AXES) * n_cables


def shaping_rows(n_cables: int) -> int:
    """Constraint rows per orientation: 2 m bounds and 3 equilibrium rows per tension vector, one epigraph row per axis.

    Parameters
    ----------
    n_cables : int
        m.

    Returns
    -------
    int
        93 for m = 6.
    """
    return 2 * len(AXES) * (2 * n_cables + 3) + len(AXES)

#: Worst dense orientations refined by the certification's pattern search, its rounds and first steps (deg).
LOCAL_SEEDS = 4
LOCAL_ROUNDS = 10
LOCAL_STEPS_DEG = (2.0, 10.0, 2.0)


@functools.lru_cache(maxsize=4)
def shaping_pose_constraints(n_cables: int = 6) -> Any:
    """The shaping constraints at one orientation, as a CasADi function (mapped over orientations).

    Inputs as :func:`csjm_opt.design.optimisation.symbols.pose_constraints` (``A``, ``B``, ``rig``,
    ``q`` = [margin, lambda, s, cos(exit limit)], ``ang``), then ``load`` (3, the stiffness load),
    ``T`` (6 m: per axis x, y, z the tensions T_hi then T_lo, scaled by t_max) and ``s_shape``
    (N m/rad). Output ``g``: per tension vector 2 m box rows (>= 0) and 3 equilibrium rows (== 0),
    then 3 epigraph rows ``(u^T K(T_hi) u - u^T K(T_lo) u - s_shape) / scale >= 0``.

    Parameters
    ----------
    n_cables : int
        m.

    Returns
    -------
    casadi.Function
    """
    c = n_cables
    A, B = ca.SX.sym("A", 3, c), ca.SX.sym("B", 3, c)
    rig, q, ang = ca.SX.sym("rig", 8), ca.SX.sym("q", 4), ca.SX.sym("ang", 3)
    load, tv, s_shape = ca.SX.sym("load", 3), ca.SX.sym("T", n_tensions(c)), ca.SX.sym("s_shape")
    f = build_functions(c)
    k, t_min, t_max, mass, com_z = rig[0], rig[1], rig[2], rig[3], rig[4]
    mu = q[0]
    R = rotation_sym(q[2] * ang[0], ang[1], q[2] * ang[2])
    J = f["jacobian"](R, A, B)
    tau_w = f["weight_moment"](R, mass, ca.vertcat(0, 0, com_z), rig[5:8])[0]
    out, directional = [], []
    for v in range(2 * len(AXES)):
        T = tv[c * v:c * v + c] * t_max
        out += [(T - t_min - mu) / MARGIN_SCALE_N, (t_max - mu - T) / MARGIN_SCALE_N,
                (J.T @ T + load + tau_w) / MOMENT_SCALE_NM]
        u = ca.DM(list(AXES.values())[v // 2])
        directional.append(u.T @ f["stiffness"](R, T, k * ca.DM.ones(c), A, B) @ u)
    for d in range(len(AXES)):
        out.append((directional[2 * d] - directional[2 * d + 1] - s_shape) / STIFFNESS_SCALE_NM_PER_RAD)
    return ca.Function("shaping_constraints", [A, B, rig, q, ang, load, tv, s_shape], [ca.vertcat(*out)],
                       ["A", "B", "rig", "q", "ang", "load", "T", "s_shape"], ["g"])


def shaping_bounds(n_cables: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of :func:`shaping_pose_constraints`'s ``g``.

    Parameters
    ----------
    n_cables : int
        m.

    Returns
    -------
    lower, upper : ndarray
    """
    per_lo = np.concatenate([np.zeros(2 * n_cables), np.zeros(3)])
    per_hi = np.concatenate([np.full(2 * n_cables, np.inf), np.zeros(3)])
    n_v = 2 * len(AXES)
    return (np.concatenate([np.tile(per_lo, n_v), np.zeros(len(AXES))]),
            np.concatenate([np.tile(per_hi, n_v), np.full(len(AXES), np.inf)]))


def shaping_block(A: Any, B: Any, rig: Any, q: Any, ang: Any, load: np.ndarray, T: Any, s_shape: Any,
                  n_slots: int) -> tuple[Any, np.ndarray, np.ndarray]:
    """The shaping constraints of every orientation slot of an NLP, with their bounds.

    Parameters
    ----------
    A, B, rig, q : casadi.MX
        The design's holes, rig vector and held values (as for the pose constraints).
    ang : casadi.MX, shape (3, n_slots)
        Orientations at range scale 1.
    load : ndarray, shape (3,)
        The stiffness load (N m, {A}, weight excluded).
    T : casadi.MX, shape (6 m n_slots,)
        The tension vectors (scaled by t_max), slot by slot.
    s_shape : casadi.MX
        The range every slot and axis must reach (N m/rad).
    n_slots : int
        Orientation slots.

    Returns
    -------
    g : casadi.MX
    lbg, ubg : ndarray
    """
    c = A.size2()
    F = shaping_pose_constraints(c).map(n_slots, "serial")
    g = F(A, B, rig, q, ang, ca.DM(np.asarray(load, float)), ca.reshape(T, n_tensions(c), n_slots), s_shape)
    lo, hi = shaping_bounds(c)
    return ca.vec(g), np.tile(lo, n_slots), np.tile(hi, n_slots)


def initial_tensions(design: Any, u0: np.ndarray, q0: float, pq: np.ndarray, angles: np.ndarray,
                     loads: np.ndarray) -> np.ndarray:
    """Start values of the tension vectors: the stiffness load's least-squares tensions, clipped, for all six vectors.

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
    ndarray, shape (6 m n_slots,)
        Scaled by t_max, slot by slot.
    """
    T = start_tensions(design, u0, q0, pq, angles, loads[0])
    return np.tile(T, (2 * len(AXES), 1)).T.reshape(-1)


def lp_shaping_range(rig: Rig, angles: np.ndarray, load_A_Nm: np.ndarray, margin_N: float,
                     model: Model | None = None) -> np.ndarray:
    """The exact shaping range (LP max minus LP min of ``u^T K u``) per orientation and axis.

    Parameters
    ----------
    rig : Rig
        The design.
    angles : ndarray, shape (n, 3)
        Tilt, azimuth, torsion (rad).
    load_A_Nm : ndarray, shape (3,)
        The stiffness load (N m in {A}, weight excluded: it is added per orientation).
    margin_N : float
        Tension margin: tensions in ``[t_min + margin, t_max - margin]``.
    model : Model, optional
        Numeric model of ``rig`` to reuse.

    Returns
    -------
    ndarray, shape (n, 3)
        N m/rad per axis x, y, z of :data:`~csjm_opt.design.shaping_range.AXES`; NaN where no tensions
        in the box hold the stiffness load.
    """
    model = model or Model(rig)
    angles = np.asarray(angles, float).reshape(-1, 3)
    Rs = tilt_torsion_rotations(angles[:, 0], angles[:, 1], angles[:, 2])
    K0, Ki = model.stiffness_basis(Rs)
    tau = np.asarray(load_A_Nm, float)[None, :] + model.weight_moment(Rs)
    lo, hi = directional_stiffness_range(model.jacobian(Rs), tau, K0, Ki, rig.t_min_N + margin_N,
                                         rig.t_max_N - margin_N, np.array(list(AXES.values())))
    return hi - lo


def _worst(rig: Rig, model: Model, angles: np.ndarray, load: np.ndarray, margin_N: float) -> np.ndarray:
    """Smallest range over the axes per orientation (-inf where the load cannot be held)."""
    r = lp_shaping_range(rig, angles, load, margin_N, model).min(axis=1)
    return np.where(np.isnan(r), -np.inf, r)


def shaping_check(rig: Rig, angles: np.ndarray, load_A_Nm: np.ndarray, margin_N: float, max_tilt: float,
                  max_torsion: float) -> tuple[float, np.ndarray, np.ndarray, np.ndarray, int]:
    """The certified shaping range: the LP on ``angles`` and a pattern search from its worst orientations.

    Parameters
    ----------
    rig : Rig
        The design.
    angles : ndarray, shape (n, 3)
        The dense set (rad).
    load_A_Nm : ndarray, shape (3,)
        Stiffness load (weight excluded).
    margin_N : float
        Tension margin.
    max_tilt, max_torsion : float
        The range the search stays in (rad).

    Returns
    -------
    worst : float
        Smallest range over orientations and axes (N m/rad; -inf where the load cannot be held).
    where : ndarray, shape (3,)
        Orientation of the smallest range (rad).
    ranked : ndarray, shape (k, 3)
        The dense set's worst orientations and the search's end points, worst first (rad).
    ranked_values : ndarray, shape (k,)
        Their smallest ranges (N m/rad).
    count : int
        Orientations evaluated.
    """
    model = Model(rig)
    v = _worst(rig, model, angles, load_A_Nm, margin_N)
    idx = np.argsort(v)[:LOCAL_SEEDS]
    x, f = angles[idx].copy(), v[idx].copy()
    count = angles.shape[0]
    step = np.radians(np.array(LOCAL_STEPS_DEG))
    lo, hi = np.array([0.0, -np.inf, -max_torsion]), np.array([max_tilt, np.inf, max_torsion])
    moves = np.vstack([np.eye(3), -np.eye(3)])
    for _ in range(LOCAL_ROUNDS):
        cand = np.clip(x[:, None, :] + moves[None] * step, lo, hi)
        fc = _worst(rig, model, cand.reshape(-1, 3), load_A_Nm, margin_N).reshape(-1, 6)
        count += fc.size
        best = np.argmin(fc, axis=1)
        better = fc[np.arange(len(x)), best] < f
        x = np.where(better[:, None], cand[np.arange(len(x)), best], x)
        f = np.where(better, fc[np.arange(len(x)), best], f)
        step = step * 0.5
    every = np.vstack([angles[idx], x])
    values = np.concatenate([v[idx], f])
    order = np.argsort(values, kind="stable")
    return float(values[order[0]]), every[order[0]], every[order], values[order], count


def dense_angles(n: int, max_tilt_deg: float, max_torsion_deg: float, seed: int) -> np.ndarray:
    """The certification's dense set: R = I and ``n`` Halton orientations (as :func:`~.certify.certify`).

    Parameters
    ----------
    n : int
    max_tilt_deg, max_torsion_deg : float
    seed : int

    Returns
    -------
    ndarray, shape (n + 1, 3)
        Tilt, azimuth, torsion (rad).
    """
    s = OrientationSampling(n, max_tilt_deg, max_torsion_deg, seed=seed)
    return np.vstack([np.zeros((1, 3)), np.column_stack(s.angles())])


def with_shaping(check: Check, settings: Any, rig: Rig, values: dict[str, float]) -> Check:
    """A certification with the shaping range added: its slack against the held value, its failing orientations.

    Parameters
    ----------
    check : Check
        The dense certification (:func:`~.certify.certify`) of the design.
    settings : OptimiseSettings
        Requirements (stiffness load, margin, range), dense set size and seed (as ``certify`` used them).
    rig : Rig
        The design.
    values : dict of str to float
        The values the solve held (``range``, ``tension_margin``, ``shaping``).

    Returns
    -------
    Check
        ``worst["shaping"]``: certified smallest range minus the held value (N m/rad) and where.
    """
    req, scale = settings.requirements, values["range"]
    tilt, tors = req.max_tilt_deg * scale, req.max_torsion_deg * scale
    angles = dense_angles(settings.certify_orientations, tilt, tors, settings.seed + 7919)
    worst, where, ranked, ranked_values, count = shaping_check(
        rig, angles, np.asarray(req.loads, float)[0], values["tension_margin"], math.radians(tilt), math.radians(tors))
    slack = worst - values["shaping"]
    bad = ranked[ranked_values - values["shaping"] < -TOLERANCES["shaping"]]
    failing = np.unique(np.vstack([check.failing, bad]), axis=0) if bad.size else check.failing
    where_deg = (math.degrees(where[0]), math.degrees(where[1]), math.degrees(where[2]))
    return dataclasses.replace(check, worst={**check.worst, "shaping": (slack, where_deg)}, failing=failing,
                               orientations=check.orientations + count)


def objective_shortfall_only(settings: Any, check: Check) -> bool:
    """Whether the only shortfall of a certification is the shaping range as the objective (not a requirement).

    The rounds add the orientations where the dense LP falls short of the value the solve claimed;
    when they run out with the shaping range the objective, the design still holds every requirement
    and its certified objective is the dense LP's value (:func:`~.result.objectives_of`),
    so it is a certified design. A held shaping range (a front's epsilon) is a requirement and must hold.

    Parameters
    ----------
    settings : OptimiseSettings
    check : Check
        The last certification.

    Returns
    -------
    bool
    """
    failing = [k for k, (v, _) in check.worst.items() if v < -TOLERANCES[k if not k.startswith("load ") else "load"]]
    return settings.objective == "shaping" and failing == ["shaping"] and math.isfinite(check.worst["shaping"][0])


__all__ = ["dense_angles", "initial_tensions", "lp_shaping_range", "n_tensions", "objective_shortfall_only",
           "shaping_block", "shaping_bounds", "shaping_rows", "shaping_check", "shaping_pose_constraints",
           "with_shaping"]
