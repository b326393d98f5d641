"""The raw instrument CSV file: its columns and record kinds, read strictly.

The format is described in :mod:`csjm_opt.measurement.preprocess`.
"""

from __future__ import annotations

import csv
import io
import math
import re
from typing import Any

import numpy as np

from .._limits import LIMITS, ROTVEC_MAX_NORM_RAD
from ..errors import DataFileError
from ._log_checks import parse_number

#: The columns of every raw file before the rest lengths ``l1..lm`` (m: the rig's cable count).
FIXED_COLUMNS = ("record", "sample", "cycle", "name", "x", "y", "z", "rx", "ry", "rz", "px", "py", "pz",
                 "fx", "fy", "fz", "mx", "my", "mz")
_POSE = ("x", "y", "z", "rx", "ry", "rz")
_OPTIONAL = {"sample": _POSE}
_REST = re.compile(r"l[0-9]+")


def raw_columns(n_cables: int = 6) -> tuple[str, ...]:
    """The raw header of a rig of ``n_cables`` cables: :data:`FIXED_COLUMNS` then ``l1..lm``."""
    return FIXED_COLUMNS + tuple(f"l{i}" for i in range(1, n_cables + 1))


#: The raw header of a six-cable rig (the paper's).
RAW_COLUMNS = raw_columns(6)


def _required(n_cables: int) -> dict[str, tuple[str, ...]]:
    return {"base_point": ("name", "x", "y", "z", "px", "py", "pz"),
            "sensor": _POSE,
            "sample": ("sample", "cycle", "fx", "fy", "fz", "mx", "my", "mz")
            + raw_columns(n_cables)[len(FIXED_COLUMNS):],
            "platform_point": ("sample", "name", "x", "y", "z", "px", "py", "pz")}


def _quantity(col: str) -> str:
    if col in ("x", "y", "z", "px", "py", "pz"):
        return "position_m"
    if col in ("fx", "fy", "fz"):
        return "force_N"
    if col in ("mx", "my", "mz"):
        return "moment_Nm"
    return "rest_length_m" if _REST.fullmatch(col) else ""


def parse_raw(text: str, source: str | None = None,
              n_cables: int = 6) -> dict[str, list[tuple[int, dict[str, Any]]]]:
    """Records of a raw instrument CSV by kind, parsed strictly; errors name the line.

    Parameters
    ----------
    text : str
        The file's contents (header first).
    source : str, optional
        File name for error messages.
    n_cables : int, optional
        The rig's cable count m: the header's rest-length columns must be ``l1..lm``.

    Returns
    -------
    dict
        Record kind (``"base_point"``, ``"sensor"``, ``"sample"``, ``"platform_point"``) -> list of
        ``(line, {column: value})``, numbers parsed and checked against their limits (m, N, N m).

    Raises
    ------
    DataFileError
        Empty file, bad header (rest-length columns other than ``l1..lm``: named with the count
        the rig needs), unknown record kind, a missing, misplaced, non-numeric or
        out-of-limit value, a rotation vector of norm above pi, or a partial sample pose
        (naming the line and column).
    """
    columns = raw_columns(n_cables)
    required = _required(n_cables)
    reader = csv.reader(io.StringIO(text))
    try:
        header = [h.strip() for h in next(reader)]
    except StopIteration:
        raise DataFileError("empty file: expected the raw header " + ",".join(columns), source, 1) from None
    rest = [h for h in header if _REST.fullmatch(h)]
    expected = columns[len(FIXED_COLUMNS):]
    if rest and set(rest) != set(expected):
        odd = [h for h in rest if h not in expected] or [c for c in expected if c not in rest]
        raise DataFileError(f"{len(rest)} rest-length columns ({', '.join(rest)}) for a rig of {n_cables} cables: "
                            f"expected l1..l{n_cables} (the raw file and the rig file do not belong together?)",
                            source, 1, odd[0])
    unknown = [h for h in header if h not in columns and h != "note"]
    missing = [c for c in columns if c not in header]
    if unknown or missing or len(set(header)) != len(header):
        raise DataFileError(f"raw header must hold the columns {','.join(columns)} (any order, "
                            f"plus 'note'); missing {missing}, unknown {unknown}", source, 1)
    records: dict[str, list] = {k: [] for k in required}
    for row in reader:
        line = reader.line_num
        if not row or all(not c.strip() for c in row):
            continue
        if len(row) != len(header):
            raise DataFileError(f"expected {len(header)} values, got {len(row)}", source, line)
        cells = {h: c.strip() for h, c in zip(header, row)}
        kind = cells["record"]
        if kind not in required:
            raise DataFileError(f"unknown record {kind!r} (expected one of {sorted(required)})",
                                source, line, "record")
        allowed = set(required[kind]) | set(_OPTIONAL.get(kind, ())) | {"record", "note"}
        values: dict[str, Any] = {}
        for col in columns[1:]:
            cell = cells[col]
            if col not in allowed:
                if cell:
                    raise DataFileError(f"a {kind} record has no {col!r} value (got {cell!r})", source, line, col)
                continue
            if not cell:
                if col in required[kind]:
                    raise DataFileError(f"missing value for a {kind} record", source, line, col)
                continue
            values[col] = cell if col == "name" else parse_number(cell, col, source, line,
                                                                     integer=col in ("sample", "cycle"))
            lim = LIMITS.get(_quantity(col))
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
