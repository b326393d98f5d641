"""The raw instrument CSV file: its columns and record kinds, read strictly.

The format is described in :mod:`csjm_opt.measurement.preprocess`.
"""

from __future__ import annotations

import csv
import io
import math
from typing import Any

import numpy as np

from .._limits import LIMITS, ROTVEC_MAX_NORM_RAD
from ..errors import DataFileError
from ._log_checks import parse_number

RAW_COLUMNS = ("record", "sample", "cycle", "name", "x", "y", "z", "rx", "ry", "rz", "px", "py", "pz",
               "fx", "fy", "fz", "mx", "my", "mz", "l1", "l2", "l3", "l4", "l5", "l6")
_NUMERIC = RAW_COLUMNS[4:]
_POSE = ("x", "y", "z", "rx", "ry", "rz")
_REQUIRED = {
    "base_point": ("name", "x", "y", "z", "px", "py", "pz"),
    "sensor": _POSE,
    "sample": ("sample", "cycle", "fx", "fy", "fz", "mx", "my", "mz", "l1", "l2", "l3", "l4", "l5", "l6"),
    "platform_point": ("sample", "name", "x", "y", "z", "px", "py", "pz"),
}
_OPTIONAL = {"sample": _POSE}


_QUANTITY = {**{c: "position_m" for c in ("x", "y", "z", "px", "py", "pz")},
             **{c: "force_N" for c in ("fx", "fy", "fz")}, **{c: "moment_Nm" for c in ("mx", "my", "mz")},
             **{f"l{i}": "rest_length_m" for i in range(1, 7)}}


def parse_raw(text: str, source: str | None = None) -> dict[str, list[tuple[int, dict[str, Any]]]]:
    """Records of a raw instrument CSV by kind, parsed strictly; errors name the line.

    Parameters
    ----------
    text : str
        The file's contents (header first).
    source : str, optional
        File name for error messages.

    Returns
    -------
    dict
        Record kind (``"base_point"``, ``"sensor"``, ``"sample"``, ``"platform_point"``) -> list of
        ``(line, {column: value})``, numbers parsed and checked against their limits (m, N, N m).

    Raises
    ------
    DataFileError
        Empty file, bad header, unknown record kind, a missing, misplaced, non-numeric or
        out-of-limit value, a rotation vector of norm above pi, or a partial sample pose
        (naming the line and column).
    """
    reader = csv.reader(io.StringIO(text))
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise DataFileError("empty file: expected the raw header " + ",".join(RAW_COLUMNS), source, 1) from None
    unknown = [h for h in header if h not in RAW_COLUMNS and h != "note"]
    missing = [c for c in RAW_COLUMNS if c not in header]
    if unknown or missing or len(set(header)) != len(header):
        raise DataFileError(f"raw header must hold the columns {','.join(RAW_COLUMNS)} (any order, "
                            f"plus 'note'); missing {missing}, unknown {unknown}", source, 1)
    records: dict[str, list] = {k: [] for k in _REQUIRED}
    for row in reader:
        line = reader.line_num
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise DataFileError(f"expected {len(header)} values, got {len(row)}", source, line)
        cells = {h: c.strip() for h, c in zip(header, row)}
        kind = cells["record"]
        if kind not in _REQUIRED:
            raise DataFileError(f"unknown record {kind!r} (expected one of {sorted(_REQUIRED)})",
                                source, line, "record")
        allowed = set(_REQUIRED[kind]) | set(_OPTIONAL.get(kind, ())) | {"record", "note"}
        values: dict[str, Any] = {}
        for col in RAW_COLUMNS[1:]:
            cell = cells[col]
            if col not in allowed:
                if cell:
                    raise DataFileError(f"a {kind} record has no {col!r} value (got {cell!r})", source, line, col)
                continue
            if not cell:
                if col in _REQUIRED[kind]:
                    raise DataFileError(f"missing value for a {kind} record", source, line, col)
                continue
            values[col] = cell if col == "name" else parse_number(cell, col, source, line,
                                                                     integer=col in ("sample", "cycle"))
            lim = LIMITS.get(_QUANTITY.get(col, ""))
            if lim is not None and not lim.contains(np.array(values[col])):
                raise DataFileError(f"{values[col]:.6g} outside {lim.describe()} ({lim.why.split(';')[0]})",
                                    source, line, col)
        if "rx" in values and "ry" in values and "rz" in values:
            norm = math.hypot(values["rx"], values["ry"], values["rz"])  # no overflow warning
            if not norm <= ROTVEC_MAX_NORM_RAD:
                raise DataFileError(f"rotation vector of norm {norm:.6g} rad; expected a principal rotation "
                                    "vector (norm <= pi; degrees written as radians?)", source, line, "rx..rz")
        if kind == "sample":
            given = [c for c in _POSE if c in values]
            if given and len(given) != 6:
                raise DataFileError("a sample's pose needs all of x,y,z,rx,ry,rz or none", source, line,
                                    [c for c in _POSE if c not in values][0])
        records[kind].append((line, values))
    return records
