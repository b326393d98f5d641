"""Reading the rows of a measurement log: a compiled pass over plain rows, the strict parser for the rest.

:func:`read_log_bytes` reads plain rows with
:func:`csjm_opt.measurement._fast_csv.scan_rows` and hands every other line
(one record at a time) to :func:`strict_records`, the row-by-row parser built
on the ``csv`` module, then resumes the compiled pass after it (unless most
rows so far needed the strict parser: then it reads the rest). Both accept
exactly the same rows with the same values, so the result, and the first
error with its line and column, are those of :func:`read_log_strict`, the
row-by-row reading of the whole text (the reference, and the path used where
the compiled pass is unavailable).

To accept a new kind of cell (say, empty measured columns in a protocol
file), change :func:`strict_row`, the reference: the compiled pass already
hands every line it does not accept to it, so the result stays right (only
slower on those lines) until the pass learns the same rule.
"""

from __future__ import annotations

import codecs
import csv
import dataclasses
import io
from collections.abc import Iterator

import numpy as np

from ..errors import DataFileError
from . import _fast_csv
from ._log_checks import parse_number

_IDS = ("sample", "cycle")        # the leading integer columns
_MEASURED = ("tau_x", "tau_y", "tau_z", "rx", "ry", "rz")
#: Fewest and most rest-length columns (cables) a log may have.
MIN_CABLES, MAX_CABLES = 4, 12


def columns_for(n_cables: int) -> tuple[str, ...]:
    """The standard columns of a log of an ``n_cables``-cable rig: ``sample,cycle,l1..lm,tau_*,r*``."""
    return _IDS + tuple(f"l{i}" for i in range(1, n_cables + 1)) + _MEASURED


#: The standard columns of a six-cable log (the paper's rig).
COLUMNS = columns_for(6)


@dataclasses.dataclass
class LogRows:
    """The rows of a log as read: numbers, line numbers, extra (text) columns."""

    values: np.ndarray      # (n, 8 + m) float, in columns_for(m) order
    lines: np.ndarray       # (n,) 1-based line of each row
    extra: dict             # column name -> (n,) str array
    n_cables: int = 6       # m, the number of rest-length columns l1..lm


def header_cables(header: list[str]) -> int:
    """m, the number of consecutive rest-length columns ``l1, l2, ...`` after ``sample,cycle``."""
    m = 0
    while len(header) > 2 + m and header[2 + m] == f"l{m + 1}":
        m += 1
    return m


def check_header(row: list[str] | None, source: str | None) -> list[str]:
    """The header's cell names (stripped) from the file's first record (``None``: empty file).

    Raises :class:`DataFileError` naming line 1 if the names do not start with
    ``sample,cycle,l1..lm,tau_x,tau_y,tau_z,rx,ry,rz`` for some 4 <= m <= 12.
    """
    template = "sample,cycle,l1,...,lm,tau_x,tau_y,tau_z,rx,ry,rz (m rest lengths, one per cable)"
    if row is None:
        raise DataFileError("empty file: expected a header " + template, source, 1)
    header = [h.strip() for h in row]
    m = header_cables(header)
    columns = columns_for(m)
    if tuple(header[:len(columns)]) != columns:
        missing = [c for c in columns if c not in header]
        detail = f"missing {missing}" if missing else f"got {header[:len(columns)]}"
        raise DataFileError(f"header must start with {template}; {detail}", source, 1)
    if not MIN_CABLES <= m <= MAX_CABLES:
        raise DataFileError(f"expected {MIN_CABLES} to {MAX_CABLES} rest-length columns l1..lm, got {m}", source, 1,
                            f"l{m}" if m else "l1")
    return header


def strict_row(row: list[str], n_header: int, source: str | None, line: int,
               columns: tuple[str, ...] = COLUMNS) -> tuple[list, list] | None:
    """Numbers and extra cells of one CSV record, ``None`` for a blank one; faults name the line and column."""
    if not row or all(not c.strip() for c in row):
        return None
    if len(row) < len(columns) or len(row) > n_header:
        raise DataFileError(f"expected {n_header} values, got {len(row)}", source, line)
    nums = []
    for name, cell in zip(columns, row, strict=False):
        cell = cell.strip()
        if cell == "":
            raise DataFileError("missing value", source, line, name)
        nums.append(parse_number(cell, name, source, line, integer=name in _IDS))
    return nums, row[len(columns):] + [""] * (n_header - len(row))


def read_log_strict(text: str, source: str | None) -> LogRows:
    """Read a whole log row by row (the reference reading).

    Parameters
    ----------
    text : str
        The log's text (a leading byte-order mark is dropped).
    source : str or None
        Names the log in errors.

    Returns
    -------
    LogRows

    Raises
    ------
    DataFileError
        On the first fault in file order, naming its line (and column).
    """
    reader = csv.reader(io.StringIO(text.removeprefix("\ufeff")))
    try:
        header = check_header(next(reader, None), source)
        columns = columns_for(header_cables(header))
        values, extras, lines = [], [], []
        for row in reader:
            parsed = strict_row(row, len(header), source, reader.line_num, columns)
            if parsed is not None:
                values.append(parsed[0])
                extras.append(parsed[1])
                lines.append(reader.line_num)
    except csv.Error as exc:
        raise DataFileError(f"not readable as CSV: {exc}", source, reader.line_num) from None
    names = header[len(columns):]
    V = np.asarray(values, dtype=float).reshape(len(values), len(columns))
    E = np.asarray(extras, dtype=str).reshape(len(values), len(names))
    return _finish(V, np.asarray(lines, dtype=np.int64), {name: E[:, j] for j, name in enumerate(names)},
                   source)


def _finish(V: np.ndarray, lines: np.ndarray, extra: dict, source: str | None) -> LogRows:
    if V.shape[0] == 0:
        raise DataFileError("no data rows", source, 2)
    return LogRows(V, lines, extra, V.shape[1] - len(_IDS) - len(_MEASURED))


def strict_records(data: bytes, pos: int, line: int, n_header: int, source: str | None,
                   columns: tuple[str, ...] = COLUMNS) -> Iterator[tuple[int, int, tuple[list, list] | None]]:
    """Records read by the strict parser from ``data[pos:]`` (``line`` is its first line), one at a time.

    Parameters
    ----------
    data : bytes
        The log's UTF-8 bytes.
    pos : int
        Offset of the first record's first line.
    line : int
        That line's number.
    n_header : int
        Number of header cells.
    source : str or None
        Names the log in errors.

    Yields
    ------
    tuple
        ``(pos, line, parsed)``: the offset and number of the line after the
        record, and :func:`strict_row`'s result (the record's line is ``line - 1``).

    Raises
    ------
    DataFileError
        If a record is malformed, naming its line and column.
    """
    after = [pos]

    def physical_lines() -> Iterator[str]:
        p = pos
        while p < len(data):
            end = data.find(b"\n", p)
            end = len(data) if end < 0 else end + 1
            after[0] = end
            yield data[p:end].decode("utf-8")
            p = end

    reader = csv.reader(physical_lines())
    while True:
        try:
            row = next(reader, None)
        except csv.Error as exc:
            raise DataFileError(f"not readable as CSV: {exc}", source, line + reader.line_num - 1) from None
        if row is None:
            return
        last = line + reader.line_num - 1
        yield after[0], last + 1, strict_row(row, n_header, source, last, columns)


#: After this many lines for the strict parser, if they are most of the rows so far, it reads the rest.
_STRICT_RUN = 1000


def read_log_bytes(data: bytes, source: str | None) -> LogRows:
    """Read a log from its UTF-8 bytes: compiled pass over plain rows, strict parser for the others.

    Parameters
    ----------
    data : bytes
        The log (UTF-8, a leading byte-order mark is skipped).
    source : str or None
        Names the log in errors.

    Returns
    -------
    LogRows
        The same rows, values and line numbers as :func:`read_log_strict`.

    Raises
    ------
    DataFileError
        The same error as :func:`read_log_strict` (first fault in file order).
    """
    start = len(codecs.BOM_UTF8) if data.startswith(codecs.BOM_UTF8) else 0
    eol = data.find(b"\n", start)
    pos = len(data) if eol < 0 else eol + 1
    first = data[start:pos]
    if not _fast_csv.AVAILABLE or b'"' in first:
        return read_log_strict(data[start:].decode("utf-8"), source)
    try:
        header = check_header(next(csv.reader(io.StringIO(first.decode("utf-8"))), None), source)
    except csv.Error as exc:
        raise DataFileError(f"not readable as CSV: {exc}", source, 1) from None
    columns = columns_for(header_cables(header))
    n_header, n_num = len(header), len(columns)
    n_max = data.count(b"\n", pos) + 1
    values = np.empty((n_max, n_num))
    lines = np.empty(n_max, np.int64)
    lo = np.empty((n_max, n_header - n_num), np.int64)
    hi = np.empty_like(lo)
    buf = np.frombuffer(data, np.uint8)
    strict_extras: dict[int, list[str]] = {}
    row, line = 0, 2
    while True:
        pos, line, row, status = _fast_csv.scan_rows(buf, pos, line, row, len(_IDS), n_header, values, lines,
                                                     lo, hi)
        if status == _fast_csv.END:
            break
        for after, next_line, parsed in strict_records(data, pos, line, n_header, source, columns):
            pos, line = after, next_line
            if parsed is not None:
                values[row] = parsed[0]
                lines[row] = line - 1
                lo[row] = hi[row] = 0
                strict_extras[row] = parsed[1]
                row += 1
            if len(strict_extras) < _STRICT_RUN or 2 * len(strict_extras) < row:
                break                      # back to the compiled pass
        else:
            break                          # the strict parser read to the end
    extra = {}
    for j, name in enumerate(header[n_num:]):
        column = _fast_csv.text_column(buf, lo[:row, j], hi[:row, j])
        if strict_extras:
            cells = {i: cells[j] for i, cells in strict_extras.items()}
            width = max([column.dtype.itemsize // 4] + [len(c) for c in cells.values()])
            column = column.astype(f"U{width}")
            column[list(cells)] = list(cells.values())
        extra[name] = column
    return _finish(values[:row], lines[:row], extra, source)
