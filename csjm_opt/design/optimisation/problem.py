"""The hole-geometry optimisation problem as a CasADi NLP, solved by IPOPT with exact derivatives.

Decision variables: the optimised design parameters (scaled to [0, 1] on their
bounds), the objective's variable, and for every sampled orientation and every
load but the first the m cable tensions. Constraints at every sampled
orientation R_j of the required set (tilt <= s max_tilt, |torsion| <= s
max_torsion; R = I always included):

* load 0 (the stiffness load) is held by the planner's tensions, those closest
  to mid-range. Where they lie inside the tension box they are the
  least-squares tensions ``T0 = t_mid + J (J^T J)^-1 (w - J^T t_mid)``, a
  smooth function of the design, and the constraint
  ``t_min + margin <= T0 <= t_max - margin`` keeps them there, so the
  optimiser's tensions are the planner's (and the sweep's) exactly;
* ``K(T0) - lambda I`` positive semidefinite, written as its seven principal
  minors >= 0 (smooth, exact for a 3 x 3 matrix): the smallest eigenvalue of K
  is at least ``lambda``;
* every other load k is held by some tensions ``T_jk`` in the margin box
  (``J^T T_jk + tau_ext_k + tau_weight = 0``): the existence test the sweep's
  exact zonotope check decides;
* the angle of every cable at its holes at most the exit-angle limit;
* the cable-cable and cable-link distances at least the required clearance at
  the closest points found for the current design (the points are updated
  between rounds of :mod:`csjm_opt.design.optimisation.dense_check`, which checks the exact
  distance);
* holes of a body at least the hole spacing apart;
* with the shaping range in play (objective or front), per orientation and axis
  two more tension vectors and the epigraph rows of
  :mod:`csjm_opt.design.optimisation.shaping`.

The objective is one of :data:`OBJECTIVES`; the others are constraints at
their required values, or at an epsilon value for a Pareto front. The model
(J, K, weight moment) is :mod:`csjm_opt.model.casadi_model`, called
symbolically so IPOPT gets exact first and second derivatives.
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import casadi as ca
import numpy as np

from ..clearance import cable_pairs
from .budget import BOUNDED_OPTIONS, IterationStop
from .settings import OptimiseSettings
from .shaping import initial_tensions, n_tensions, shaping_block
from .symbols import (
    HESSIAN,
    LENGTH_SCALE_M,
    MARGIN_SCALE_N,
    MAX_ITER,
    SIZE_SCALE_M,
    STIFFNESS_SCALE_NM_PER_RAD,
    design_sym,
    initial_load_tensions,
    pose_bounds,
    pose_constraints,
    rotation_sym,
)


@dataclasses.dataclass(frozen=True)
class Contact:
    """A cable pair (or cable and link part) to keep apart at one orientation, at fixed closest points."""

    orientation: int      # index into the problem's orientation set
    kind: str             # "pair", "rod" or "ball"
    i: int                # cable (0-based)
    j: int                # other cable (pair) or -1
    s: float              # parameter of the closest point on cable i (0: platform hole, 1: base hole)
    t: float              # parameter on cable j or on the rod (0: bottom, 1: O)


@dataclasses.dataclass
class Problem:
    """A built NLP with its start, bounds and parameter values, and what is needed to read its solution."""

    solver: Any
    x0: np.ndarray
    p: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    n_design: int
    objective_index: int
    design_of: Any        # casadi Function: u -> design vector (natural units)
    constraints_of: Any   # casadi Function: x, p -> g
    n_slots: int = 0      # orientation slots (the pose constraints come first, slot by slot)
    stop: Any = None      # IterationStop of a bounded solver (budget.py), else None
    n_cables: int = 6     # m of the design (tension rows per load)


@dataclasses.dataclass
class _Built:
    solver: Any
    design: Any
    design_of: Any
    constraints_of: Any
    lbg: np.ndarray
    ubg: np.ndarray
    n_slots: int
    n_contacts: int
    stop: Any = None
    n_cables: int = 6


def _quantity_values(settings: OptimiseSettings, epsilon: dict[str, float]) -> dict[str, float]:
    req = settings.requirements
    values = {"stiffness": req.min_stiffness_Nm_per_rad, "tension_margin": req.tension_margin_N,
              "range": req.range_scale, "size": _NO_SIZE_LIMIT_M, "shaping": 0.0}
    values.update(epsilon)
    return values


def build_problem(settings: OptimiseSettings, angles: np.ndarray, start: dict[str, float],
                  contacts: list[Contact], epsilon: dict[str, float],
                  objective_start: float | None = None, bounded: bool = False) -> Problem:
    """The NLP on the orientation set ``angles`` from ``start`` (see the module docstring).

    The solver is built once per process for a number of orientation and contact slots
    (rounded up to :data:`SLOT_STEP`) and reused: orientations, contacts and held values are its
    parameters.

    Parameters
    ----------
    settings : OptimiseSettings
        Variables and bounds, fixed parameters, requirements, objective.
    angles : ndarray, shape (N, 3)
        Tilt, azimuth, torsion (rad) of the orientations at range scale 1.
    start : dict of str to float
        Initial values of the optimised parameters.
    contacts : list of Contact
        Cable distances to keep, at fixed closest points.
    epsilon : dict of str to float
        Quantities held at a value instead of their requirement (Pareto front).
    objective_start : float, optional
        Initial value of the objective's variable (natural units).
    bounded : bool
        A solver whose evaluations can be bounded (:mod:`csjm_opt.design.optimisation.budget`; ``Problem.stop``).

    Returns
    -------
    Problem
    """
    n_slots = -(-angles.shape[0] // SLOT_STEP) * SLOT_STEP
    n_contacts = max(-(-len(contacts) // SLOT_STEP) * SLOT_STEP, MIN_CONTACT_SLOTS)
    built = _built_for(settings, n_slots, n_contacts, bounded)
    padded = np.vstack([angles, np.zeros((n_slots - angles.shape[0], 3))])
    values = _quantity_values(settings, epsilon)
    p_q = [values["tension_margin"], values["stiffness"], values["range"], values["size"], values["shaping"]]
    m = built.n_cables
    p_c = np.zeros((n_contacts, contact_width(m)))
    p_c[:, -1] = -1.0                                   # unused slot: needs a negative distance
    link, req = settings.link, settings.requirements
    for row, c in zip(p_c, contacts):
        row[:3] = padded[c.orientation]
        row[3 + c.i] = 1.0
        row[3 + 2 * m], row[4 + 2 * m] = c.s, c.t
        if c.kind == "pair":
            row[3 + m + c.j] = 1.0
            row[6 + 2 * m] = req.min_cable_distance_m
        else:
            row[5 + 2 * m] = link.rod_length_m if c.kind == "rod" else 0.0
            row[6 + 2 * m] = req.min_link_clearance_m + (link.rod_radius_m if c.kind == "rod"
                                                         else link.ball_radius_m)
    p = np.concatenate([padded.ravel(), p_q, p_c.ravel()])
    names, lo, hi = settings.names, settings.lower, settings.upper
    obj = settings.objective
    u0 = np.array([(start[n] - lo[k]) / (hi[k] - lo[k]) for k, n in enumerate(names)])
    q_lo, q_hi = _objective_bounds(settings, _SCALE[obj])
    q0 = objective_start if objective_start is not None else {"stiffness": req.min_stiffness_Nm_per_rad,
                                                              "tension_margin": req.tension_margin_N,
                                                              "range": 0.5, "size": SIZE_SCALE_M,
                                                              "shaping": 0.0}[obj]
    q0 = min(max(q0 / _SCALE[obj], q_lo), q_hi)
    loads = np.asarray(req.loads, float)
    n_t = m * (loads.shape[0] - 1) * n_slots
    n_s = n_tensions(m) * n_slots if _shaping(settings) else 0
    x0 = np.concatenate([u0, [q0], initial_load_tensions(built.design, u0, q0, np.array(p_q), padded, loads),
                         initial_tensions(built.design, u0, q0, np.array(p_q), padded, loads) if n_s else []])
    lbx = np.concatenate([np.zeros(len(names)), [q_lo], np.zeros(n_t + n_s)])
    ubx = np.concatenate([np.ones(len(names)), [q_hi], np.full(n_t + n_s, np.inf)])
    return Problem(solver=built.solver, x0=x0, p=p, lbx=lbx, ubx=ubx, lbg=built.lbg, ubg=built.ubg,
                   n_design=len(names), objective_index=len(names), design_of=built.design_of,
                   constraints_of=built.constraints_of, n_slots=n_slots, stop=built.stop,
                   n_cables=m)


_SCALE = {"stiffness": STIFFNESS_SCALE_NM_PER_RAD, "tension_margin": MARGIN_SCALE_N, "range": 1.0,
          "size": SIZE_SCALE_M, "shaping": STIFFNESS_SCALE_NM_PER_RAD}


def _shaping(settings: OptimiseSettings) -> bool:
    """Whether the shaping range is the objective or the front's other quantity."""
    return "shaping" in (settings.objective, settings.pareto_with)


#: Orientation and contact slots come in multiples of this (a solver is reused for all sizes below).
SLOT_STEP = 16
#: Contact slots of every solver (a round with more builds a larger one).
MIN_CONTACT_SLOTS = 32


def contact_width(n_cables: int) -> int:
    """Parameters of one contact slot: angles (3), one-hot cable i (m), one-hot cable j (m), s, t, rod, need.

    Parameters
    ----------
    n_cables : int
        m.

    Returns
    -------
    int
        ``2 m + 7`` (19 for six cables).
    """
    return 2 * n_cables + 7


_NO_SIZE_LIMIT_M = 1e3


_CACHE: dict[tuple[str, int, int, bool], _Built] = {}
_CACHE_SIZE = 8


def _built_for(settings: OptimiseSettings, n_slots: int, n_contacts: int, bounded: bool = False) -> _Built:
    """The cached solver of settings with this content (a worker process reuses it across tasks)."""
    key = (json.dumps([settings.names, settings.lower, settings.upper, settings.base, settings.requirements.as_dict(),
                       settings.objective, settings.pareto_with, dataclasses.asdict(settings.link),
                       settings.gravity_B_m_per_s2], sort_keys=True, default=str), n_slots, n_contacts, bounded)
    if key not in _CACHE:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = _built(settings, n_slots, n_contacts, bounded)
    return _CACHE[key]


def clear_cache() -> None:
    """Forget the built solvers (benchmarks time fresh runs).

    Returns
    -------
    None
    """
    _CACHE.clear()


def _built(settings: OptimiseSettings, n_slots: int, n_contacts: int, bounded: bool) -> _Built:
    """The solver for ``n_slots`` orientations and ``n_contacts`` contacts."""
    names = settings.names
    n_d = len(names)
    req = settings.requirements
    loads = np.asarray(req.loads, float)
    n_l = loads.shape[0]
    exit_limit = req.max_exit_angle_deg < 180
    obj = settings.objective
    u, q_var = ca.SX.sym("u", n_d), ca.SX.sym("q")
    pq = ca.SX.sym("pq", 5)
    held = {"tension_margin": pq[0], "stiffness": pq[1], "range": pq[2], "size": pq[3], "shaping": pq[4]}
    q = {k: (q_var * _SCALE[k] if k == obj else v) for k, v in held.items()}
    p, A, B, rig = design_sym(settings, u)
    m = A.size2()
    cw = contact_width(m)
    qv = ca.vertcat(q["tension_margin"], q["stiffness"], q["range"], math.cos(math.radians(req.max_exit_angle_deg)))
    design = ca.Function("design", [u, q_var, pq], [A, B, rig, qv, q["shaping"]])
    pc = ca.SX.sym("pc", cw, n_contacts)
    fixed: list[Any] = []
    for c in range(n_contacts):
        row = pc[:, c]
        R = rotation_sym(q["range"] * row[0], row[1], q["range"] * row[2])
        top, bottom = R @ A, B
        s_i, t_j, rod, need = row[3 + 2 * m], row[4 + 2 * m], row[5 + 2 * m], row[6 + 2 * m]
        point = (top + s_i * (bottom - top)) @ row[3:3 + m]
        other = (top + t_j * (bottom - top)) @ row[3 + m:3 + 2 * m] \
            + ca.vertcat(0, 0, -rod * (1.0 - t_j))
        fixed.append((ca.sqrt(ca.sumsqr(point - other) + 1e-18) - need) / LENGTH_SCALE_M)
    for H in (A, B):
        for a, b in cable_pairs(m):
            fixed.append((ca.norm_2(H[:, a] - H[:, b]) - req.min_hole_spacing_m) / LENGTH_SCALE_M)
    if "size" in (obj, settings.pareto_with):
        for H in (A, B):
            fixed.append((q["size"] ** 2 - ca.sum1(H[:2, :] ** 2).T) / SIZE_SCALE_M ** 2)
    g_fixed = ca.Function("fixed", [u, q_var, pq, pc], [ca.vertcat(*fixed)])

    n_t = m * (n_l - 1) * n_slots
    n_s = n_tensions(m) * n_slots if _shaping(settings) else 0
    x = ca.MX.sym("x", n_d + 1 + n_t + n_s)
    par = ca.MX.sym("p", 3 * n_slots + 5 + cw * n_contacts)
    ux, qx = x[:n_d], x[n_d]
    ang = ca.reshape(par[:3 * n_slots], 3, n_slots)
    pq_m = par[3 * n_slots:3 * n_slots + 5]
    pc_m = ca.reshape(par[3 * n_slots + 5:], cw, n_contacts)
    A_m, B_m, rig_m, q_m, s_shape = design(ux, qx, pq_m)
    F = pose_constraints(n_l, exit_limit, m).map(n_slots, "serial")
    g_pose, _ = F(A_m, B_m, rig_m, q_m, ang, ca.DM(loads.T), ca.reshape(x[n_d + 1:n_d + 1 + n_t], m * (n_l - 1),
                                                                          n_slots))
    g = ca.vertcat(ca.vec(g_pose), g_fixed(ux, qx, pq_m, pc_m))
    lo_pose, hi_pose = pose_bounds(n_l, exit_limit, m)
    n_fixed = g_fixed.size1_out(0)
    lbg = np.concatenate([np.tile(lo_pose, n_slots), np.zeros(n_fixed)])
    ubg = np.concatenate([np.tile(hi_pose, n_slots), np.full(n_fixed, np.inf)])
    if n_s:                                             # the shaping epigraph (shaping.py)
        g_s, lo_s, hi_s = shaping_block(A_m, B_m, rig_m, q_m, ang, loads[0], x[n_d + 1 + n_t:], s_shape, n_slots)
        g, lbg, ubg = ca.vertcat(g, g_s), np.concatenate([lbg, lo_s]), np.concatenate([ubg, hi_s])
    sign = -1.0 if obj != "size" else 1.0
    opts: dict[str, Any] = {"ipopt": {"print_level": 0, "max_iter": MAX_ITER, "tol": 1e-9, "acceptable_tol": 1e-7,
                                      "constr_viol_tol": 1e-9, "mu_strategy": "adaptive", "sb": "yes",
                                      "hessian_approximation": HESSIAN}, "print_time": False, "expand": True}
    nlp: dict[str, Any] = {"x": x, "p": par, "f": sign * qx, "g": g}
    stop = IterationStop(x.numel(), g.numel(), par.numel()) if bounded else None
    if stop is not None:                                # evaluations bounded (budget.py)
        opts.update(iteration_callback=stop, ipopt={**opts["ipopt"], **BOUNDED_OPTIONS})
    solver = ca.nlpsol("csjm_optimise", "ipopt", nlp, opts)
    design_of = ca.Function("design_of", [u], [ca.vertcat(*[p[n] for n in names])])
    return _Built(solver=solver, design=design, design_of=design_of,
                  constraints_of=ca.Function("constraints_of", [x, par], [g]), lbg=lbg, ubg=ubg,
                  n_slots=n_slots, n_contacts=n_contacts, stop=stop, n_cables=m)


def _objective_bounds(settings: OptimiseSettings, scale: float) -> tuple[float, float]:
    req, obj = settings.requirements, settings.objective
    if obj == "stiffness":
        return req.min_stiffness_Nm_per_rad / scale, math.inf
    if obj == "tension_margin":
        return req.tension_margin_N / scale, math.inf
    if obj == "range":
        return 1e-3, 1.0
    return 0.0, math.inf            # size, shaping
