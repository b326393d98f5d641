"""Identify K for every load cycle of a measurement log."""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import so3
from ..errors import IllConditionedData
from ..measurement.logfile import MeasurementLog
from ..measurement.rig_fit import check_log_rig
from ..model.numeric import Model
from ..model.rig import Rig
from .estimate import StiffnessEstimate
from .identify_pose import identify_stiffness


def identify_log(log: MeasurementLog, rig: Rig, cycle: int | None = None, model: Model | None = None,
                 progress: Any = None, check_rig: bool = True, **options: Any) -> list[StiffnessEstimate]:
    """One :class:`StiffnessEstimate` per cycle of ``log`` (or only ``cycle``).

    Parameters
    ----------
    log : MeasurementLog
    rig : Rig
    cycle : int, optional
        Only this cycle.
    model : Model, optional
        Reused numeric model of ``rig``.
    progress : callable, optional
        Wraps the iterable of cycles (e.g. ``functools.partial(tqdm, ...)``).
    check_rig : bool, optional
        Refuse a log that ``rig`` cannot have produced (:func:`csjm_opt.measurement.rig_fit.check_log_rig`).
    **options
        Passed to :func:`identify_stiffness`.

    Returns
    -------
    list of StiffnessEstimate

    Raises
    ------
    IllConditionedData
        For the first cycle that cannot be identified (message starts with its id).
    LogRigMismatch
        The log's first rows are out of equilibrium with the rig's cables (``check_rig``).
    """
    if check_rig:
        check_log_rig(rig, log)
    model = model or Model(rig)
    cycles = log.cycle_ids if cycle is None else [cycle]
    out = []
    pairs = _cycle_rows(log, cycles)
    R, W = _poses_and_weight(log, np.concatenate([rows for _, rows in pairs]), model)
    for c, rows in (progress(pairs) if progress is not None else pairs):
        try:
            out.append(identify_stiffness(R[rows], log.tau_ext_A_Nm[rows], model, W[rows], cycle=c,
                                          **_rest(log, rows, options)))
        except IllConditionedData as exc:
            raise IllConditionedData(f"cycle {c}: {exc}", exc.condition, exc.rank, exc.direction) from exc
    return out


def identify_cycles(log: MeasurementLog, rig: Rig, model: Model | None = None, progress: Any = None,
                    **options: Any) -> tuple[list[StiffnessEstimate], list[dict[str, Any]]]:
    """Every cycle that can be identified, and the others with the reason.

    A log may mix identification cycles with cycles that load along one
    direction (hysteresis or diagnosis cycles), which cannot determine K; those
    are returned as ``{"cycle", "reason", "condition", "weakest_load_direction_A"}``
    instead of stopping the whole log. Time is linear in the log length
    (orientations are computed once per cycle's rows).

    Parameters
    ----------
    log : MeasurementLog
    rig : Rig
    model : Model, optional
        Reused numeric model of ``rig``.
    progress : callable, optional
        Wraps the iterable of cycles (e.g. ``functools.partial(tqdm, ...)``).
    **options
        Passed to :func:`identify_stiffness`.

    Returns
    -------
    estimates : list of StiffnessEstimate
        One per identified cycle, in the log's cycle order.
    skipped : list of dict
        One per refused cycle: ``{"cycle", "reason", "condition", "weakest_load_direction_A"}``.

    Raises
    ------
    IllConditionedData
        The first cycle's error, when no cycle can be identified.
    """
    model = model or Model(rig)
    estimates, skipped, first_error = [], [], None
    pairs = _cycle_rows(log, log.cycle_ids)
    R, W = _poses_and_weight(log, np.arange(len(log)), model)
    for c, rows in (progress(pairs) if progress is not None else pairs):
        try:
            estimates.append(identify_stiffness(R[rows], log.tau_ext_A_Nm[rows], model, W[rows], cycle=c,
                                                **_rest(log, rows, options)))
        except IllConditionedData as exc:
            err = IllConditionedData(f"cycle {c}: {exc}", exc.condition, exc.rank, exc.direction)
            first_error = first_error or err
            skipped.append({"cycle": c, "reason": str(exc), "condition": exc.condition,
                            "weakest_load_direction_A": None if exc.direction is None else exc.direction.tolist()})
    if not estimates and first_error is not None:
        raise first_error
    return estimates, skipped


def _rest(log: MeasurementLog, rows: np.ndarray, options: dict[str, Any]) -> dict[str, Any]:
    """Options plus the cycle's rest lengths (for K_ml's model curvature) when they are constant."""
    l = log.rest_lengths_m[rows]
    if "rest_lengths_m" in options or not np.allclose(l, l[0], rtol=0, atol=1e-9):
        return options
    return options | {"rest_lengths_m": l[0]}


def _cycle_rows(log: MeasurementLog, cycles: list[int]) -> list[tuple[int, np.ndarray]]:
    """(cycle id, row indices) pairs; rows found once for the whole log (no per-cycle scan)."""
    cyc = np.asarray(log.cycle)
    starts = np.flatnonzero(np.r_[True, cyc[1:] != cyc[:-1]])
    ends = np.r_[starts[1:], len(cyc)]
    where = {int(cyc[a]): np.arange(a, b) for a, b in zip(starts, ends)}
    pairs = []
    for c in cycles:
        if c not in where:
            log.cycle_rows(c)  # raises DataFileError naming the cycles
        pairs.append((c, where[c]))
    return pairs


def _poses_and_weight(log: MeasurementLog, rows: np.ndarray, model: Model) -> tuple[np.ndarray, np.ndarray]:
    """Orientations (n, 3, 3) and weight moments (n, 3, N m in {A}) of the log's rows.

    Computed once for ``rows`` (other rows are left zero): one batched call instead of one per cycle.
    """
    R = np.zeros((len(log), 3, 3))
    W = np.zeros((len(log), 3))
    if len(rows):
        R[rows] = so3.exp(log.rotvec_rad[rows])
        W[rows] = model.weight_moment(R[rows])
    return R, W
