"""Append-only, crash-safe result file of a sweep (JSON Lines, one design per line).

Each finished design is appended as one complete line with a single
``write`` followed by ``flush`` and ``fsync``, so an interrupted run leaves
at most one partial *last* line. Opening the store repairs that: the partial
line is cut off (that design is simply computed again) and every complete
line is kept. A line in the middle that is not valid JSON means the file was
edited or is not a result file: an error names the line. An exclusive lock
(``fcntl.flock``) keeps two runs from appending to the same file at once.
Records carry the digest of the evaluation settings; a file holding another
sweep's settings is refused rather than mixed.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from ..errors import DesignError

try:  # POSIX only; elsewhere the lock is skipped
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]


def read_records(path: str | Path) -> tuple[list[dict[str, Any]], int]:
    """Complete records of a result file and the byte length they occupy (partial tail excluded)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return [], 0
    except OSError as exc:
        raise DesignError(f"cannot read results: {exc.strerror}", "--out", str(path)) from exc
    end = data.rfind(b"\n") + 1          # complete lines end with a newline
    records = []
    for number, line in enumerate(data[:end].splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError as exc:
            raise DesignError(f"line {number} is not a JSON record ({exc.msg}); not a csjm sweep "
                              "result file, or edited by hand", "--out", str(path)) from exc
        if not isinstance(record, dict) or "id" not in record:
            raise DesignError(f"line {number} is not a design record", "--out", str(path))
        records.append(record)
    return records, end


class ResultStore:
    """Open (and repair) a result file for appending; use as a context manager."""

    def __init__(self, path: str | Path, settings_digest: str):
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            raise DesignError(f"cannot open results file: {exc.strerror}", "--out", str(self.path)) from exc
        try:
            if fcntl is not None:
                try:
                    fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError as exc:
                    raise DesignError("results file is in use by another running sweep", "--out",
                                      str(self.path)) from exc
            records, end = read_records(self.path)
            if os.fstat(self._fd).st_size != end:  # cut a partial last line (interrupted write)
                os.ftruncate(self._fd, end)
                os.fsync(self._fd)
            other = [r for r in records if r.get("settings") != settings_digest]
            if other:
                raise DesignError("results file holds designs evaluated with other settings "
                                  "(sampling, loads, base design or metrics differ); give a new --out",
                                  "--out", str(self.path))
            self.records: dict[str, dict[str, Any]] = {r["id"]: r for r in records}
            os.lseek(self._fd, 0, os.SEEK_END)
        except BaseException:
            os.close(self._fd)
            raise

    def append(self, record: dict[str, Any]) -> None:
        """Write one record as one line, durably (flush + fsync)."""
        line = (json.dumps(record, sort_keys=True, allow_nan=False) + "\n").encode()
        view = memoryview(line)
        while view:
            written = os.write(self._fd, view)
            view = view[written:]
        os.fsync(self._fd)
        self.records[record["id"]] = record

    def close(self) -> None:
        if self._fd >= 0:
            os.close(self._fd)  # also releases the lock
            self._fd = -1

    def __enter__(self) -> "ResultStore":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
