"""Append-only, crash-safe result file of a sweep (JSON Lines, one design per line).

Each finished design is appended as one complete line with a single
``write``, so an interrupted run leaves at most one partial *last* line. A
killed process loses nothing it has written (the data is in the kernel's page
cache); ``fsync`` guards against a machine crash and is grouped: at most once
every :data:`FSYNC_INTERVAL_S` and on close, so a crash of the machine costs
at most that much recomputation, and the sweep is not paced by the disk
(one ``fsync`` a design took ~4 ms, more than evaluating the design). Opening the store repairs that: the partial
line is cut off (that design is simply computed again) and every complete
line is kept. A line in the middle that is not valid JSON means the file was
edited or is not a result file: an error names the line. An exclusive lock
(``fcntl.flock``) keeps two runs from appending to the same file at once.
Records carry the digest of the evaluation settings; a file holding another
sweep's settings is refused rather than mixed. Lines repeating a design id
(a file concatenated or edited by hand) are counted in ``duplicates`` and
ignored: the first record of each id is kept.

The lock is taken with ``flock``, which the kernel drops when the holding
process dies, so a sweep killed by any signal leaves no stale lock (worker
processes never inherit the descriptor, see :mod:`csjm_opt.design.sweep.runner`).
Opening retries for up to :data:`LOCK_WAIT_S` seconds, so a sweep that is
still exiting does not make a resumed one fail, before naming the holders.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path
from typing import Any

from ..._fileio import read_bytes
from ...errors import DesignError

try:  # POSIX only; elsewhere the lock is skipped
    import fcntl
except ImportError:  # pragma: no cover
    fcntl = None  # type: ignore[assignment]

#: How long opening a locked result file waits for the holder to exit (s).
LOCK_WAIT_S = 5.0


def read_records(path: str | Path) -> tuple[list[dict[str, Any]], int]:
    """Complete records of a result file and the byte length they occupy (partial tail excluded).

    Every complete line is returned, duplicates included (see :func:`unique_records`).
    """
    path = Path(path)
    if not os.path.lexists(path):
        return [], 0
    data = read_bytes(path, lambda msg: DesignError(msg, "--out", str(path)), "results file")
    end = data.rfind(b"\n") + 1          # complete lines end with a newline
    records = []
    for number, line in enumerate(data[:end].splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError as exc:  # JSONDecodeError, or bytes that are not UTF-8
            msg = exc.msg if isinstance(exc, json.JSONDecodeError) else "not UTF-8"
            raise DesignError(f"line {number} is not a JSON record ({msg}); not a csjm sweep "
                              "result file, or edited by hand", "--out", str(path)) from exc
        if not isinstance(record, dict) or "id" not in record:
            raise DesignError(f"line {number} is not a design record", "--out", str(path))
        records.append(record)
    return records, end


def unique_records(records: list[dict[str, Any]]) -> tuple[dict[str, dict[str, Any]], int]:
    """Records by design id (first occurrence kept) and the number of repeated lines dropped."""
    out: dict[str, dict[str, Any]] = {}
    for r in records:
        out.setdefault(r["id"], r)
    return out, len(records) - len(out)


def lock_holders(fd: int) -> list[int]:
    """Process ids holding a lock on the file of ``fd`` (from ``/proc/locks``; empty if unknown)."""
    try:
        st = os.fstat(fd)
        text = Path("/proc/locks").read_text()
    except OSError:
        return []
    key = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    pids = []
    for line in text.splitlines():
        parts = line.split()
        if len(parts) > 5 and parts[5] == key and parts[4].isdigit():
            pids.append(int(parts[4]))
    return sorted(set(pids))


def _lock(fd: int, path: Path) -> None:
    deadline = time.monotonic() + LOCK_WAIT_S
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError as exc:
            if time.monotonic() >= deadline:
                pids = lock_holders(fd)
                who = f" (pid {', '.join(map(str, pids))})" if pids else ""
                raise DesignError(f"results file is in use by another running sweep{who}", "--out",
                                  str(path)) from exc
            time.sleep(0.05)


#: Longest time (s) a written record may wait for its ``fsync``.
FSYNC_INTERVAL_S = 1.0


class ResultStore:
    """Open (and repair) a result file for appending; use as a context manager."""

    def __init__(self, path: str | Path, settings_digest: str):
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            if self.path.exists() and not self.path.is_file():
                raise DesignError("results path exists and is not a regular file", "--out", str(self.path))
            self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NONBLOCK", 0), 0o644)
        except OSError as exc:
            raise DesignError(f"cannot open results file: {exc.strerror}", "--out", str(self.path)) from exc
        try:
            if fcntl is not None:
                _lock(self._fd, self.path)
            records, end = read_records(self.path)
            if os.fstat(self._fd).st_size != end:  # cut a partial last line (interrupted write)
                os.ftruncate(self._fd, end)
                os.fsync(self._fd)
            other = [r for r in records if r.get("settings") != settings_digest]
            if other:
                raise DesignError("results file holds designs evaluated with other settings "
                                  "(sampling, loads, base design or metrics differ); give a new --out",
                                  "--out", str(self.path))
            self.records, self.duplicates = unique_records(records)
            os.lseek(self._fd, 0, os.SEEK_END)
            self._synced_at = time.monotonic()
        except BaseException:
            os.close(self._fd)
            raise

    def append(self, record: dict[str, Any]) -> None:
        """Write one record as one line (``fsync`` at most every :data:`FSYNC_INTERVAL_S`)."""
        line = (json.dumps(record, sort_keys=True, allow_nan=False) + "\n").encode()
        view = memoryview(line)
        while view:
            written = os.write(self._fd, view)
            view = view[written:]
        if time.monotonic() - self._synced_at >= FSYNC_INTERVAL_S:
            os.fsync(self._fd)
            self._synced_at = time.monotonic()
        self.records[record["id"]] = record

    @property
    def fileno(self) -> int:
        """The locked descriptor (worker processes close their inherited copy)."""
        return self._fd

    def close(self) -> None:
        """Flush the file to disk and close it, releasing the lock (a second call does nothing)."""
        if self._fd >= 0:
            os.fsync(self._fd)
            os.close(self._fd)  # also releases the lock
            self._fd = -1

    def __enter__(self) -> "ResultStore":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
