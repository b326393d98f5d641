"""Measurement logs: the CSV format of docs/conventions.md, read strictly and written atomically.

One row per static equilibrium, in time order. Header (exactly these columns
first, extra columns allowed after them)::

    sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz

for the paper's six cables; an m-cable rig (4 <= m <= 12) has ``l1..lm``
(same order as the rig's holes), and a log's count must match the rig it is
used with (:meth:`MeasurementLog.check_cables`). ``l1..lm`` rest lengths (m);
``tau_*`` the external moment about O in {A} (N m, platform weight excluded);
``r*`` the measured orientation of {A} in {B}
as a rotation vector (rad). Rows of one ``cycle`` are consecutive. Malformed
input raises :class:`DataFileError` naming the file and line; nothing is
silently dropped. Every number is checked against the bounds of
:mod:`csjm_opt._limits` (ids integers below 2^53, rest lengths in (0, 10] m,
moments within 1e4 N m, rotation vectors of norm <= pi).
"""

from __future__ import annotations

import csv
import dataclasses
import io
from pathlib import Path

import numpy as np

from .. import so3
from .._fileio import atomic_write_text, decode_text, read_bytes
from .._limits import MAX_EXACT_INT
from ..errors import DataFileError, InvalidInput
from ._log_checks import _check_rows, _rows, parse_number
from ._log_reader import COLUMNS, LogRows, columns_for, header_cables, read_log_bytes, read_log_strict

__all__ = ["COLUMNS", "MeasurementLog", "columns_for", "header_cables", "parse_number"]


@dataclasses.dataclass(frozen=True, eq=False)
class MeasurementLog:
    """A measurement log; arrays share a leading axis ``n`` (rows in time order)."""

    sample: np.ndarray              # (n,) int
    cycle: np.ndarray               # (n,) int
    rest_lengths_m: np.ndarray      # (n, m), columns l1..lm
    tau_ext_A_Nm: np.ndarray        # (n, 3)
    rotvec_rad: np.ndarray          # (n, 3)
    extra: dict = dataclasses.field(default_factory=dict)  # column name -> (n,) str array
    source: str | None = None

    def __len__(self) -> int:
        return int(self.sample.shape[0])

    @property
    def n_cables(self) -> int:
        """m, the number of rest-length columns ``l1..lm``."""
        return int(self.rest_lengths_m.shape[1])

    def check_cables(self, n_cables: int, rig_name: str | None = None) -> "MeasurementLog":
        """Check that the rest-length columns match an ``n_cables``-cable rig; returns the log.

        Parameters
        ----------
        n_cables : int
            The rig's cable count (``rig.n_cables``).
        rig_name : str, optional
            The rig (file) named in the error.

        Returns
        -------
        MeasurementLog
            ``self``.

        Raises
        ------
        DataFileError
            Naming the log's header line and its last rest-length column when the counts differ.
        """
        if self.n_cables != n_cables:
            rig = f"the rig {rig_name}" if rig_name else "the rig"
            raise DataFileError(f"{self.n_cables} rest-length columns l1..l{self.n_cables}, but {rig} has "
                                f"{n_cables} cables (expected l1..l{n_cables})", self.source, 1,
                                f"l{self.n_cables}")
        return self

    @property
    def R(self) -> np.ndarray:
        """Measured orientations (n, 3, 3)."""
        return so3.exp(self.rotvec_rad)

    @property
    def cycle_ids(self) -> list[int]:
        """Cycle ids in order of first appearance."""
        _, first = np.unique(self.cycle, return_index=True)
        return [int(self.cycle[i]) for i in sorted(first)]

    def cycle_rows(self, cycle: int) -> np.ndarray:
        """Row indices of one load cycle, in time order.

        Parameters
        ----------
        cycle : int
            A cycle id of this log.

        Returns
        -------
        ndarray of int
            Indices of the cycle's rows; the first is the cycle's reference.

        Raises
        ------
        DataFileError
            If the log has no such cycle.
        """
        rows = np.flatnonzero(self.cycle == cycle)
        if rows.size == 0:
            raise DataFileError(f"no cycle {cycle} (cycles: {self.cycle_ids})", self.source)
        return rows

    def subset(self, rows: np.ndarray) -> MeasurementLog:
        """The log restricted to ``rows`` (kept in the given order).

        Parameters
        ----------
        rows : array_like of int
            Row indices (0-based, in the order wanted).

        Returns
        -------
        MeasurementLog
            A new log with those rows.

        Raises
        ------
        InvalidInput
            If an index is not an integer or is out of range.
        """
        rows = np.asarray(rows)
        if rows.size and (rows.dtype.kind not in "iu" or rows.min() < -len(self) or rows.max() >= len(self)):
            raise InvalidInput(f"rows: expected integer indices in [0, {len(self)}), got {rows.tolist()[:8]}",
                               "rows")
        return MeasurementLog(self.sample[rows], self.cycle[rows], self.rest_lengths_m[rows],
                              self.tau_ext_A_Nm[rows], self.rotvec_rad[rows],
                              {k: v[rows] for k, v in self.extra.items()}, self.source)

    # ------------------------------------------------------------ construction
    @classmethod
    def from_arrays(cls, cycle, rest_lengths_m, tau_ext_A_Nm, R_or_rotvec, sample=None,
                    extra: dict | None = None) -> MeasurementLog:
        """Build a log from arrays (one row per static equilibrium, in time order).

        Parameters
        ----------
        cycle : array_like of int, shape (n,)
            Load-cycle id of each row.
        rest_lengths_m : array_like, shape (n, m)
            Commanded rest lengths (m), one column per cable (4 <= m <= 12).
        tau_ext_A_Nm : array_like, shape (n, 3)
            Measured external moments in {A} (N m), platform weight excluded.
        R_or_rotvec : array_like, shape (n, 3, 3) or (n, 3)
            Measured orientations of {A} in {B}, as rotations or rotation vectors (rad).
        sample : array_like of int, shape (n,), optional
            Unique row ids (default ``0 .. n-1``).
        extra : dict of str to array_like (n,), optional
            Extra columns, kept and written after the standard ones.

        Returns
        -------
        MeasurementLog
            The log, checked like a file (finite values, unique sample ids).

        Raises
        ------
        InvalidInput
            If the arrays do not share ``n`` rows or have the wrong shapes.
        DataFileError
            If a value is not finite or sample ids repeat.
        """
        X = _rows(R_or_rotvec, None, "R_or_rotvec")
        if X.ndim not in (2, 3) or X.shape[1:] not in ((3,), (3, 3)):
            raise InvalidInput(f"R_or_rotvec: expected (n, 3, 3) or (n, 3), got {X.shape}", "R_or_rotvec")
        rotvec = so3.log(X) if X.ndim == 3 else X
        n = rotvec.shape[0]
        sample = np.arange(n) if sample is None else _rows(sample, (n,), "sample")
        cycle = _rows(cycle, (n,), "cycle")
        if np.any(np.abs(sample) > MAX_EXACT_INT):
            raise DataFileError("sample id outside +-(2^53 - 1)", None, None, "sample")
        if np.any(np.abs(cycle) > MAX_EXACT_INT):
            raise DataFileError("cycle id outside +-(2^53 - 1)", None, None, "cycle")
        l_m = _rows(rest_lengths_m, None, "rest_lengths_m")
        m = l_m.shape[1] if l_m.ndim == 2 else 6
        log = cls(sample.astype(int), cycle.astype(int), _rows(rest_lengths_m, (n, m), "rest_lengths_m"),
                  _rows(tau_ext_A_Nm, (n, 3), "tau_ext_A_Nm"), rotvec,
                  {k: _rows(v, (n,), k, float_=False) for k, v in (extra or {}).items()})
        _check_rows(log, None, lines=np.arange(2, n + 2))
        return log

    @classmethod
    def from_csv(cls, path: str | Path) -> MeasurementLog:
        """Read and validate a measurement log file (format in docs/conventions.md).

        Parameters
        ----------
        path : str or Path
            The CSV file (UTF-8, a byte-order mark is accepted).

        Returns
        -------
        MeasurementLog
            The log, rows in file order.

        Raises
        ------
        DataFileError
            If the file cannot be read, the header is wrong, or a row is malformed (missing,
            non-numeric or non-finite value, duplicate sample id), naming the line.
        """
        path = Path(path)

        def error(msg: str) -> DataFileError:
            return DataFileError(msg, str(path))

        data = read_bytes(path, error, "log file")
        if not data.isascii() or b"\x00" in data[:4096]:   # what decode_text checks or changes
            data = decode_text(data, error, "log file").encode("utf-8")
        return cls._from_rows(read_log_bytes(data, str(path)), str(path))

    @classmethod
    def from_text(cls, text: str, source: str | None = None) -> MeasurementLog:
        """Parse and validate log text; ``source`` names it in errors.

        Plain rows (numbers only in the 8 + m standard columns, no quotes) are read
        by a compiled pass over the bytes; any other line is read by the strict
        row-by-row parser, which raises the :class:`DataFileError` naming the
        line and column of a fault. Both accept the same rows with the same
        values (see :mod:`csjm_opt.measurement._log_reader`).

        Parameters
        ----------
        text : str
            The log's text (a leading byte-order mark is dropped).
        source : str, optional
            Name of the log in errors (a file name).

        Returns
        -------
        MeasurementLog
            The log, rows in text order.

        Raises
        ------
        DataFileError
            If the header is wrong or a row is malformed, naming the line.
        """
        try:
            data = text.encode("utf-8")
        except UnicodeEncodeError:        # lone surrogates: text no file holds; the strict parser reads it
            return cls._from_rows(read_log_strict(text, source), source)
        return cls._from_rows(read_log_bytes(data, source), source)

    @classmethod
    def _from_rows(cls, rows: LogRows, source: str | None) -> MeasurementLog:
        V, m = rows.values, rows.n_cables
        log = cls(V[:, 0].astype(np.int64), V[:, 1].astype(np.int64), V[:, 2:2 + m], V[:, 2 + m:5 + m],
                  V[:, 5 + m:8 + m], rows.extra, source)
        _check_rows(log, source, rows.lines)
        return log

    def to_csv(self, path: str | Path, overwrite: bool = False) -> Path:
        """Write the log as CSV, atomically.

        Parameters
        ----------
        path : str or Path
            Output file.
        overwrite : bool, optional
            Replace an existing file (by default an existing file is kept and an error raised).

        Returns
        -------
        Path
            The file written.

        Raises
        ------
        InvalidInput
            If the file exists and ``overwrite`` is false, or it cannot be written.
        """
        return atomic_write_text(path, self.to_text(), overwrite=overwrite)

    def to_text(self) -> str:
        """The log as CSV text (standard columns, then the extra ones).

        Returns
        -------
        str
            CSV text that :meth:`from_text` reads back to the same log.
        """
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(columns_for(self.n_cables) + tuple(self.extra))
        for i in range(len(self)):
            w.writerow([int(self.sample[i]), int(self.cycle[i])]
                       + [repr(float(x)) for x in self.rest_lengths_m[i]]
                       + [repr(float(x)) for x in self.tau_ext_A_Nm[i]]
                       + [repr(float(x)) for x in self.rotvec_rad[i]]
                       + [str(v[i]) for v in self.extra.values()])
        return buf.getvalue()

