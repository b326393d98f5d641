"""Atomic writes: a temporary file in the target folder renamed into place, usual permissions."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any

from ._file_input import file_kind
from .errors import InvalidInput


def _file_mode(executable: bool = False) -> int:
    """The mode ``open()`` would give a new file under the current umask (``0o644`` under ``022``).

    ``mkstemp`` creates its files ``0o600``: a file renamed into place keeps that unless it is
    changed, so every atomic writer sets this mode first (``executable``: ``0o777 & ~umask``).
    """
    mask = os.umask(0)
    os.umask(mask)
    return (0o777 if executable else 0o666) & ~mask


def atomic_write_text(path: str | Path, text: str, overwrite: bool = True) -> Path:
    """Write ``text`` to ``path`` atomically (temporary file + ``os.replace``).

    Parameters
    ----------
    path : str or Path
        Target file; its folder is created if missing.
    text : str
        Content, written as UTF-8.
    overwrite : bool
        Whether an existing file may be replaced.

    Returns
    -------
    Path

    Raises
    ------
    InvalidInput
        When ``path`` exists and ``overwrite`` is false, or is a folder or
        special file, or cannot be written (the ``OSError`` is chained).
    """
    path = Path(path)
    if path.is_dir():
        raise InvalidInput(f"{path} is a folder; expected a file path", "path")
    if path.exists() and not overwrite:
        raise InvalidInput(f"{path} exists; refusing to overwrite it", "path")
    if path.exists() and not path.is_file():
        raise InvalidInput(f"{path} is a {file_kind(path.stat().st_mode)}; expected a file path", "path")
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
            fh.flush()
            os.fchmod(fh.fileno(), _file_mode())
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        raise InvalidInput(f"cannot write {path}: {exc.strerror}", "path") from exc
    except BaseException:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def atomic_write_json(path: str | Path, data: Any, overwrite: bool = True, indent: int | None = 2) -> Path:
    """Write JSON atomically (see :func:`atomic_write_text`); ``path == "-"`` prints to stdout instead.

    ``indent=None`` writes compact JSON with the C encoder (several times
    faster: for large documents).
    """
    text = json.dumps(data, indent=indent, default=_jsonable) + "\n"
    if str(path) == "-":
        print(text, end="")
        return Path("-")
    return atomic_write_text(path, text, overwrite=overwrite)


def _jsonable(value: Any) -> Any:
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
