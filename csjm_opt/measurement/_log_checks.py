"""Checks of measurement-log values: shapes, numbers in CSV cells, bounds, ids and cycles."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._limits import LIMITS, MAX_EXACT_INT, ROTVEC_MAX_NORM_RAD
from ..errors import DataFileError, InvalidInput

if TYPE_CHECKING:
    from .logfile import MeasurementLog


def _rows(value, shape: tuple[int, ...] | None, name: str, float_: bool = True) -> np.ndarray:
    """An array of ``shape`` (``None``: any), else :class:`InvalidInput` naming ``name``."""
    try:
        arr = np.asarray(value, float) if float_ else np.asarray(value)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name}: expected numbers, got {value!r:.60}", name) from None
    if shape is not None and arr.shape != shape:
        raise InvalidInput(f"{name}: expected shape {shape}, got {arr.shape}", name)
    return arr


def parse_number(cell: str, column: str, source: str | None, line: int, integer: bool = False) -> float | int:
    """A finite number (an ``int`` if ``integer``) from a CSV cell, or a :class:`DataFileError`.

    Integers (ids) must be whole and within ``+-(2^53 - 1)`` (exact in float64
    and int64); range checks of other quantities are left to the caller.
    """
    try:
        x = float(cell)
    except ValueError:
        raise DataFileError(f"not a number: {cell[:40]!r}", source, line, column) from None
    if not np.isfinite(x):
        raise DataFileError(f"not finite: {cell[:40]!r}", source, line, column)
    if integer:
        if x != int(x):
            raise DataFileError(f"expected an integer, got {cell[:40]!r}", source, line, column)
        if abs(x) > MAX_EXACT_INT:
            raise DataFileError(f"id {cell[:40]!r} outside +-(2^53 - 1)", source, line, column)
        return int(x)
    return x


#: Columns of the log checked against each bound of :data:`csjm_opt._limits.LIMITS`.
_COLUMN_LIMITS = (("rest_lengths_m", "rest_length_m", tuple(f"l{i}" for i in range(1, 13))),
                  ("tau_ext_A_Nm", "moment_Nm", ("tau_x", "tau_y", "tau_z")))


def _check_bounds(log: MeasurementLog, source: str | None, lines: np.ndarray) -> None:
    for ids, name in ((log.sample, "sample"), (log.cycle, "cycle")):
        bad = np.abs(np.asarray(ids, dtype=float)) > MAX_EXACT_INT
        if bad.any():
            i = int(np.argmax(bad))
            raise DataFileError("id outside +-(2^53 - 1)", source, int(lines[i]), name)
    for attr, quantity, columns in _COLUMN_LIMITS:
        lim = LIMITS[quantity]
        ok = lim.contains(getattr(log, attr))
        if not ok.all():
            i, j = (int(x) for x in np.unravel_index(int(np.argmin(ok.ravel())), ok.shape))
            value = float(getattr(log, attr)[i, j])
            raise DataFileError(f"{value:.6g} outside {lim.describe()} ({lim.why.split(';')[0]})",
                                source, int(lines[i]), columns[j])
    rv = log.rotvec_rad
    with np.errstate(over="ignore", invalid="ignore"):
        norm = np.sqrt(np.sum(rv * rv, axis=1))
    bad = ~(norm <= ROTVEC_MAX_NORM_RAD)
    if bad.any():
        i = int(np.argmax(bad))
        raise DataFileError(f"rotation vector of norm {norm[i]:.6g} rad; expected a principal rotation "
                            "vector (norm <= pi; degrees written as radians?)", source, int(lines[i]), "rx..rz")


def _check_rows(log: MeasurementLog, source: str | None, lines: np.ndarray) -> None:
    if not (np.all(np.isfinite(log.rest_lengths_m)) and np.all(np.isfinite(log.tau_ext_A_Nm))
            and np.all(np.isfinite(log.rotvec_rad))):
        i = int(np.argmin(np.all(np.isfinite(np.hstack([log.rest_lengths_m, log.tau_ext_A_Nm, log.rotvec_rad])),
                                 axis=1)))
        raise DataFileError("not a finite number", source, int(lines[i]))
    _check_bounds(log, source, lines)
    sample = np.asarray(log.sample)
    order = np.argsort(sample, kind="stable")
    dup = np.flatnonzero(sample[order][1:] == sample[order][:-1])
    if dup.size:  # report the earliest second occurrence
        second = order[dup + 1]
        i = int(second.min())
        first = int(order[dup[np.argmin(second)]])
        raise DataFileError(f"duplicate sample id {int(sample[i])} (first on line {int(lines[first])})",
                            source, int(lines[i]), "sample")
    cycle = np.asarray(log.cycle)
    starts = np.flatnonzero(np.r_[True, cycle[1:] != cycle[:-1]])   # first row of each run
    run_ids = cycle[starts]
    order = np.argsort(run_ids, kind="stable")
    rep = np.flatnonzero(run_ids[order][1:] == run_ids[order][:-1])
    if rep.size:
        i = int(starts[order[rep + 1]].min())
        raise DataFileError(f"rows of cycle {int(cycle[i])} are not consecutive", source, int(lines[i]), "cycle")
    if np.any(log.rest_lengths_m <= 0):
        i = int(np.argmax(np.any(log.rest_lengths_m <= 0, axis=1)))
        raise DataFileError("rest lengths must be positive", source, int(lines[i]),
                            f"l{int(np.argmax(log.rest_lengths_m[i] <= 0)) + 1}")
