"""Candidate load cycles a rig can hold: poses, pretensions and the lab's dead weights (for ``--suggest``).

A candidate cycle: a reference pose (tilt up to ``MAX_TILT_RAD``, any azimuth, twist up to
``MAX_TWIST_RAD``), rest lengths planned for reference tensions at a share
``PRETENSION_SHARE`` of the tension range (pretension changes go through the rest
lengths), and one load point of the load set with its masses hung in increasing, then
decreasing order. A row is kept only where the nominal rig holds it with every tension in
``[t_min, t_max]``.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ... import so3
from ...errors import CsjmError, InvalidInput
from ...model.numeric import Model
from ...model.rig import Rig
from ...model.statics import rest_lengths_for, solve_equilibrium
from ...planning.planner import plan_tensions
from .dead_weights import DeadWeight

MAX_TILT_RAD = 0.5
MAX_TWIST_RAD = 0.3
#: Reference tensions of a candidate cycle: this share range of [t_min, t_max].
PRETENSION_SHARE = (0.1, 0.9)
N_CANDIDATES = 40


def candidate_cycles(rig: Rig, loads: Sequence[DeadWeight], rng: np.random.Generator, n: int = N_CANDIDATES,
                     max_tries: int | None = None) -> list[dict]:
    """Feasible candidate cycles (nominal model): rest lengths, loads per row, planned poses.

    Parameters
    ----------
    rig : Rig
    loads : sequence of DeadWeight
    rng : numpy.random.Generator
    n : int, optional
        Number of cycles wanted.
    max_tries : int, optional
        Draws before giving up (default ``20 n``).

    Returns
    -------
    list of dict
        Each with ``rest_lengths_m`` (m,), ``loads`` (list), ``R`` (m, 3, 3), ``tau`` (m, 3).

    Raises
    ------
    InvalidInput
        No load of the set can be held at any pose tried (the load set does not fit the rig).
    """
    model = Model(rig)
    g = np.asarray(rig.gravity_B_m_per_s2, float)
    points = sorted({ld.point_A_m for ld in loads})
    by_point = {p: sorted([ld for ld in loads if ld.point_A_m == p], key=lambda ld: ld.mass_kg) for p in points}
    out: list[dict] = []
    held_any = False
    tries = max_tries or 20 * n
    for _ in range(tries):
        if len(out) >= n:
            break
        tilt, az = rng.uniform(0.0, MAX_TILT_RAD), rng.uniform(0, 2 * np.pi)
        R_ref = so3.exp(tilt * np.array([np.cos(az), np.sin(az), 0.0])) @ so3.exp(
            [0, 0, rng.uniform(-MAX_TWIST_RAD, MAX_TWIST_RAD)])
        share = rng.uniform(*PRETENSION_SHARE)
        t_ref = np.full(rig.n_cables, rig.t_min_N + share * (rig.t_max_N - rig.t_min_N))
        seq = by_point[points[rng.integers(len(points))]]
        try:
            plan = plan_tensions(rig, R_ref, np.zeros(3), t_ref_N=t_ref, model=model)
            l = rest_lengths_for(rig, R_ref, plan.tensions_N, model=model)
            eq0 = solve_equilibrium(rig, l, R_init=R_ref, model=model)
        except CsjmError:
            continue
        if not _within(rig, eq0.tensions_N):
            continue
        kept: list[tuple[DeadWeight, np.ndarray]] = []
        R = eq0.R
        for ld in seq:
            try:
                eq = solve_equilibrium(rig, l, point_forces=[(ld.mass_kg * g, np.asarray(ld.point_A_m))],
                                       R_init=R, model=model)
            except CsjmError:
                break
            if not _within(rig, eq.tensions_N):
                break
            kept.append((ld, eq.R))
            R = eq.R
        if not kept:
            continue
        held_any = True
        order = kept + kept[-2::-1]
        rows_R = [eq0.R] + [r for _, r in order] + [eq0.R]
        rows_load: list[DeadWeight | None] = [None] + [ld for ld, _ in order] + [None]
        tau = np.array([np.zeros(3) if ld is None else ld.moment_A_Nm(r, g) for ld, r in zip(rows_load, rows_R)])
        out.append({"rest_lengths_m": l, "loads": rows_load, "R": np.array(rows_R), "tau": tau})
    if not held_any:
        raise InvalidInput(f"the rig cannot hold any load of the load set ({', '.join(ld.name for ld in loads)}) "
                           f"with tensions in [{rig.t_min_N:g}, {rig.t_max_N:g}] N at any of {tries} poses tried",
                           "loads")
    return out


def _within(rig: Rig, T: np.ndarray) -> bool:
    return bool(np.all(T >= rig.t_min_N - 1e-9) and np.all(T <= rig.t_max_N + 1e-9))
