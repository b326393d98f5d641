"""Identification experiments planned to make the Cramér-Rao bound of K small.

For each reference pose and each candidate pretension (reference tensions of the planner,
realised through rest lengths), every load of the load set (weight x attachment point x
direction) is settled on the rig model (:class:`~csjm_opt.model.statics.EquilibriumSolver`,
dead weight fixed in {B}); a load is *admissible* when the platform settles stably with every
tension in ``[t_min, t_max]`` and turns at most ``max_rotation_rad`` from the reference (the
tracker's range). Each admissible load adds its row information ``A^T V^-1 A``
(:mod:`csjm_opt.identification.cramer_rao`) at its predicted displacement. The budget is then spent
greedily on the unit that lowers the criterion most (A: trace of the six entries' bound;
D: log det), followed by exchange passes (a chosen unit swapped for a better one until none
improves). With ``pairs=True`` (default) a unit is a ``+-`` pair of the same weight and point
in opposite directions: the pair takes the even (second-order) part of the curvature of the
moment-rotation relation out of the slope, which makes the estimate less dependent on the rig
model's curvature (the odd, third-order part remains; docs/guide/identification.md). A pose
whose share of the budget is below six loads (three pairs, three axes) gets single loads. A
selection whose information does not determine K (singular, or numerically so) scores ``inf``.
The best pretension is kept per pose (a grid, then three rounds of bisection around the best
level); several poses (a K field) share the budget equally.

The paper's protocol and the bound of a given protocol are in
:mod:`csjm_opt.identification.experiment_plan`.
"""

from __future__ import annotations

import numpy as np

from .. import so3
from ..errors import DesignError
from ..measurement.instruments import InstrumentNoise
from ..measurement.protocol import Protocol
from ..model.numeric import Model
from ..model.rig import Rig
from .candidate_loads import Cycle, cycle_for
from .cramer_rao import bound
from .experiment_loads import ExperimentLoads
from .experiment_plan import ExperimentPlan, paper_protocol, predict_bound

CRITERIA = ("A", "D")
#: Exchange passes after the greedy selection.
EXCHANGE_PASSES = 3
#: Bisection rounds on the pretension around the best level of the grid.
REFINE_ROUNDS = 3
#: Fewest loads of a pose spent in +- pairs: a pair turns the platform along one axis (both ways),
#: so K needs three pairs; a smaller share is spent on single loads.
MIN_PAIRED_SHARE = 6


#: Smallest eigenvalue, relative to the largest, of an information matrix scaled to unit diagonal
#: that still determines K: below it the selection is (numerically) singular and its criterion inf.
RCOND = 1e-10


def _criterion(M: np.ndarray, kind: str) -> np.ndarray:
    """Criterion of information matrices (..., 9, 9): A = trace, D = log det of the entries' bound.

    ``inf`` for a selection that does not determine K (information singular or numerically so:
    the inverse would be round-off, and its trace can be any sign).
    """
    s = np.sqrt(np.maximum(np.einsum("...ii->...i", M), 1e-300))
    ss = s[..., :, None] * s[..., None, :]
    C = M / ss
    w = np.linalg.eigvalsh(C)
    ok = w[..., 0] > RCOND * w[..., -1]
    inv = np.linalg.inv(np.where(ok[..., None, None], C, np.eye(9))) / ss
    B = inv[..., 3:, 3:]
    if kind == "A":
        return np.where(ok, np.einsum("...ii->...", B), np.inf)
    sign, logdet = np.linalg.slogdet(B)
    return np.where(ok & (sign > 0), logdet, np.inf)


def _select(base: np.ndarray, units: np.ndarray, costs: np.ndarray, budget: int, kind: str,
            pairs: bool) -> list[int]:
    """Greedy then exchange selection of units (with repetition) spending exactly ``budget``."""
    ridge = 1e-9 * np.trace(units.sum(0)) / 9 * np.eye(9)
    chosen: list[int] = []
    M = base.copy()
    left = budget
    while left > 0:
        ok = costs <= left
        if pairs and left >= 2 and np.any(ok & (costs == 2)):
            ok &= costs == 2                     # singles only for an odd remainder
        if not np.any(ok):
            break
        crit = _criterion(M[None] + ridge + units, kind)
        crit[~ok] = np.inf
        j = int(np.argmin(crit))
        chosen.append(j)
        M = M + units[j]
        left -= int(costs[j])
    for _ in range(EXCHANGE_PASSES):
        improved = False
        for k in range(len(chosen)):
            rest = M - units[chosen[k]]
            crit = _criterion(rest[None] + units, kind)
            crit[costs != costs[chosen[k]]] = np.inf
            j = int(np.argmin(crit))
            if crit[j] < _criterion(M, kind) * (1 - 1e-9):
                chosen[k], M, improved = j, rest + units[j], True
        if not improved:
            break
    return chosen


def plan_experiment(rig: Rig, budget: int, loads: ExperimentLoads | None = None, poses: np.ndarray | None = None,
                    noise: InstrumentNoise | None = None, criterion: str = "A", pairs: bool = True,
                    model: Model | None = None) -> ExperimentPlan:
    """Plan an identification experiment of ``budget`` loads minimising the A- or D-criterion of K.

    Parameters
    ----------
    rig : Rig
    budget : int
        Number of loaded rows (the unloaded reference row of each pose comes on top).
    loads : ExperimentLoads, optional
        Weights, points, directions, pretensions and tracker range (default :meth:`ExperimentLoads.default`).
    poses : array (p, 3), optional
        Reference poses as rotation vectors (rad); one cycle each, budget split equally
        (a K field). Default: the home pose (identity).
    noise : InstrumentNoise, optional
        Instrument noise of the bound (the paper's by default).
    criterion : {"A", "D"}
    pairs : bool
        Spend the budget on +- pairs of loads (the second-order curvature leaves the slope);
        a pose with fewer than six loads gets single loads.
    model : Model, optional

    Returns
    -------
    ExperimentPlan

    Raises
    ------
    DesignError
        Bad budget or criterion, or the rig cannot hold enough of the load set to identify K.
    """
    if criterion not in CRITERIA:
        raise DesignError(f"criterion: expected 'A' or 'D', got {criterion!r}", "criterion")
    poses_arr = np.zeros((1, 3)) if poses is None else np.asarray(poses, float).reshape(-1, 3)
    if isinstance(budget, bool) or not isinstance(budget, (int, np.integer)) or budget < 3 * len(poses_arr):
        raise DesignError(f"budget: need at least 3 loads per pose ({3 * len(poses_arr)}), got {budget!r}",
                          "budget")
    loads = loads or ExperimentLoads.default(rig)
    noise = noise or InstrumentNoise.paper()
    model = model or Model(rig)
    shares = np.full(len(poses_arr), budget // len(poses_arr))
    shares[: budget % len(poses_arr)] += 1
    rows: list[Protocol] = []
    out: dict[str, list] = {"crlb6": [], "K_model": [], "pretension_N": [], "rotvec_ref": []}
    for c, (rv, share) in enumerate(zip(poses_arr, shares)):
        try:
            cyc, picked, t, crlb6 = _plan_pose(rig, model, rv, int(share), loads, noise, criterion, pairs)
        except np.linalg.LinAlgError as exc:      # a selection whose information matrix is singular
            raise DesignError(f"the loads admissible at pose {np.round(rv, 4).tolist()} cannot determine K with "
                              f"{budget} loads ({exc}); raise the budget or change the poses or loads",
                              "budget") from exc
        rows.append(_cycle_protocol(c, cyc, picked))
        out["crlb6"].append(crlb6)
        out["K_model"].append(cyc.K)
        out["pretension_N"].append(t)
        out["rotvec_ref"].append(so3.log(cyc.R_ref))
    return ExperimentPlan(_concat(rows), budget=int(budget), **out)


def _plan_pose(rig: Rig, model: Model, rv: np.ndarray, share: int, loads: ExperimentLoads, noise: InstrumentNoise,
               criterion: str, pairs: bool) -> tuple:
    """The best selection of ``share`` loads at pose ``rv``: ``(cycle, picked rows, pretension, its bound)``.

    Raises ``numpy.linalg.LinAlgError`` where the selection's information matrix is singular
    (:func:`plan_experiment` turns it into a :class:`DesignError`).
    """
    tried: dict[float, tuple | None] = {}

    def design_at(t: float) -> tuple | None:
        if t not in tried:
            tried[t] = _design_at(rig, model, so3.exp(rv), t, loads, noise, share, criterion, pairs)
        return tried[t]

    for t in loads.pretensions_N:
        design_at(float(t))
    for _ in range(REFINE_ROUNDS):   # bisect the pretension around the best so far
        levels = sorted(tried)
        scored = [(v[0], t) for t in levels if (v := tried[t]) is not None]
        if not scored:
            break
        i = levels.index(min(scored)[1])
        for j in (i - 1, i + 1):
            if 0 <= j < len(levels):
                design_at(0.5 * (levels[i] + levels[j]))
    found = [v for v in tried.values() if v is not None]
    best = min(found, key=lambda v: v[0]) if found else None
    if best is None:
        raise DesignError(f"the rig cannot identify K at pose {np.round(rv, 4).tolist()} with this load set: "
                          "fewer than three admissible loads at every pretension (lighter weights, "
                          "other points or a larger max_rotation_rad)", "loads")
    _, cyc, picked, t, M = best
    return cyc, picked, t, bound(M)


def _design_at(rig: Rig, model: Model, R: np.ndarray, t: float, loads: ExperimentLoads, noise: InstrumentNoise,
               share: int, criterion: str, pairs: bool) -> tuple | None:
    """(criterion, cycle, picked rows, pretension, information) of the best selection at pretension ``t``."""
    cyc = cycle_for(rig, model, R, t, loads, noise)
    if cyc is None or len(cyc.info) < 3:
        return None
    pairs = pairs and share >= MIN_PAIRED_SHARE
    units, costs, members = _units(cyc, pairs)
    if len(units) == 0:
        return None
    chosen = _select(cyc.ref_info, units, costs, share, criterion, pairs)
    M = cyc.ref_info + sum(units[j] for j in chosen)
    value = float(_criterion(M, criterion))
    return (value, cyc, [i for j in chosen for i in members[j]], t, M) if np.isfinite(value) else None


def _units(cyc: Cycle, pairs: bool) -> tuple[np.ndarray, np.ndarray, list[tuple[int, ...]]]:
    """Selectable units: +- pairs (cost 2, when ``pairs``) and single loads (cost 1)."""
    members: list[tuple[int, ...]] = []
    if pairs:
        members += [(i, int(j)) for i, j in enumerate(cyc.partner) if j > i]
    members += [(i,) for i in range(len(cyc.info))]
    units = np.array([sum(cyc.info[i] for i in m) for m in members]) if members else np.zeros((0, 9, 9))
    return units, np.array([len(m) for m in members]), members


def _cycle_protocol(c: int, cyc: Cycle, picked: list[int]) -> Protocol:
    n = len(picked) + 1
    w = np.r_[0.0, cyc.weight[picked]]
    d = np.vstack([np.zeros(3), cyc.direction[picked]])
    p = np.vstack([np.zeros(3), cyc.point[picked]])
    return Protocol(np.full(n, c), np.repeat(cyc.rest_lengths_m[None], n, 0), w, d, p)


def _concat(parts: list[Protocol]) -> Protocol:
    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(p, name) for p in parts])

    return Protocol(cat("cycle"), cat("rest_lengths_m"), cat("load_N"), cat("direction_B"), cat("point_A_m"))


__all__ = ["CRITERIA", "ExperimentPlan", "paper_protocol", "plan_experiment", "predict_bound"]
