"""Identification protocols: the measurement-log format with the measured columns empty.

A protocol is what a lab runs (and the testbed simulates): per row, the rest lengths to
command and the dead weight to hang. Header::

    sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz,load_N,dir_x,dir_y,dir_z,point_x,point_y,point_z

for six cables; an m-cable rig has ``l1..lm`` (as in the log, :func:`~csjm_opt.measurement.logfile.columns_for`).

``tau_*`` and ``r*`` are empty (the F/T moment and the tracked orientation are filled in by the
measurement); ``load_N`` the weight (N, 0 for the unloaded reference row, first of each
cycle), ``dir_*`` the unit direction of its force in the base frame {B} (a cable over a
pulley; straight down is ``0,0,-1``), ``point_*`` where it is attached on the platform, in
{A} (m). Once the measured columns are filled the file is a measurement log
(:class:`~csjm_opt.measurement.logfile.MeasurementLog`) whose load columns are kept as extra
columns.

Not to be confused with :class:`csjm_opt.testbed.log_protocol.LogProtocol`, the protocol ``csjm diagnose --suggest``
writes (dead weights in kg at tool points, intended moments and planned poses); ``csjm simulate`` runs both.
"""

from __future__ import annotations

import csv
import dataclasses
import io
from pathlib import Path

import numpy as np

from .._fileio import atomic_write_text, read_text
from ..errors import DataFileError
from ._log_reader import header_cables
from .logfile import columns_for

#: Columns after the log's: weight, its direction in {B}, its attachment point in {A}.
LOAD_COLUMNS = ("load_N", "dir_x", "dir_y", "dir_z", "point_x", "point_y", "point_z")
_MEASURED = ("tau_x", "tau_y", "tau_z", "rx", "ry", "rz")


@dataclasses.dataclass(frozen=True, eq=False)
class Protocol:
    """An identification protocol; arrays share a leading axis ``n`` (rows in run order)."""

    cycle: np.ndarray            # (n,) int
    rest_lengths_m: np.ndarray   # (n, m), columns l1..lm
    load_N: np.ndarray           # (n,) weight, 0 for a reference row
    direction_B: np.ndarray      # (n, 3) unit direction of the force in {B}
    point_A_m: np.ndarray        # (n, 3) attachment point in {A}
    source: str | None = None    # the file, named in errors

    def __len__(self) -> int:
        return int(self.cycle.shape[0])

    @property
    def n_cables(self) -> int:
        """m, the number of rest-length columns."""
        return int(self.rest_lengths_m.shape[1])

    @property
    def force_B_N(self) -> np.ndarray:
        """(n, 3) force of each row's weight in {B} (N)."""
        return self.load_N[:, None] * self.direction_B

    def extra_columns(self) -> dict[str, np.ndarray]:
        """The load columns as the string columns of a measurement log.

        Returns
        -------
        dict of str to ndarray of str
        """
        vals = np.column_stack([self.load_N, self.direction_B, self.point_A_m])
        return {name: np.array([repr(float(x)) for x in vals[:, j]]) for j, name in enumerate(LOAD_COLUMNS)}

    def to_text(self) -> str:
        """The protocol as CSV text (measured columns empty).

        Returns
        -------
        str
        """
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(columns_for(self.n_cables) + LOAD_COLUMNS)
        for i in range(len(self)):
            w.writerow([i, int(self.cycle[i])] + [repr(float(x)) for x in self.rest_lengths_m[i]]
                       + [""] * len(_MEASURED)
                       + [repr(float(x)) for x in (self.load_N[i], *self.direction_B[i], *self.point_A_m[i])])
        return buf.getvalue()

    def to_csv(self, path: str | Path, overwrite: bool = False) -> Path:
        """Write the protocol atomically.

        Parameters
        ----------
        path : str or Path
        overwrite : bool, optional
            Replace an existing file.

        Returns
        -------
        Path

        Raises
        ------
        InvalidInput
            The file exists and ``overwrite`` is false, or it cannot be written.
        """
        return atomic_write_text(path, self.to_text(), overwrite=overwrite)

    @classmethod
    def from_csv(cls, path: str | Path) -> "Protocol":
        """Read a protocol (or a filled-in log with the load columns; measured values are ignored).

        Parameters
        ----------
        path : str or Path

        Returns
        -------
        Protocol

        Raises
        ------
        DataFileError
            Wrong header, a missing or non-numeric value, a non-unit direction, naming the line.
        """
        path = Path(path)
        text = read_text(path, lambda msg: DataFileError(msg, str(path)), "protocol", encoding="utf-8-sig")
        return cls.from_text(text, str(path))

    @classmethod
    def from_text(cls, text: str, source: str | None = None) -> "Protocol":
        """Parse protocol text; ``source`` names it in errors.

        Parameters
        ----------
        text : str
        source : str, optional

        Returns
        -------
        Protocol

        Raises
        ------
        DataFileError
            As :meth:`from_csv`.
        """
        reader = csv.reader(io.StringIO(text))
        header = [h.strip() for h in next(reader, [])]
        m = header_cables(header)
        want = columns_for(m) + LOAD_COLUMNS
        if tuple(header[:len(want)]) != want or not 4 <= m <= 12:
            raise DataFileError("protocol header must start with sample,cycle,l1,...,lm (4 <= m <= 12 cables),"
                                f"{','.join(want[2 + m:])}", source, 1)
        idx = {name: header.index(name) for name in want}
        rows, lines = [], []
        for row in reader:
            if not row or all(not c.strip() for c in row):
                continue
            line = reader.line_num
            if len(row) < len(want):
                raise DataFileError(f"expected {len(header)} values, got {len(row)}", source, line)
            vals = []
            for name in ("cycle",) + want[2:2 + m] + LOAD_COLUMNS:
                cell = row[idx[name]].strip()
                try:
                    v = float(cell)
                except ValueError:
                    raise DataFileError(f"not a number: {cell!r}", source, line, name) from None
                if not np.isfinite(v):
                    raise DataFileError(f"not finite: {cell!r}", source, line, name)
                vals.append(v)
            rows.append(vals)
            lines.append(line)
        if not rows:
            raise DataFileError("no protocol rows", source, 2)
        V = np.asarray(rows)
        proto = cls(V[:, 0].astype(int), V[:, 1:1 + m], V[:, 1 + m], V[:, 2 + m:5 + m], V[:, 5 + m:8 + m], source)
        norm = np.linalg.norm(proto.direction_B, axis=1)
        bad = np.flatnonzero((proto.load_N > 0) & (np.abs(norm - 1) > 1e-6))
        if len(bad):
            raise DataFileError(f"direction is not a unit vector (norm {norm[bad[0]]:.6g})", source,
                                lines[bad[0]], "dir_x")
        neg = np.flatnonzero((proto.load_N < 0) | np.any(proto.rest_lengths_m <= 0, axis=1))
        if len(neg):
            raise DataFileError("negative load or non-positive rest length", source, lines[neg[0]], "load_N")
        return proto
