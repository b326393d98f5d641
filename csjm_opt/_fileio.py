"""Atomic, non-clobbering file output.

Outputs are written to a temporary file in the target folder and renamed into
place, so a reader never sees a half-written file. An existing file is never
replaced unless the caller asks for it, and a caller's *input* is protected
with :func:`refuse_input_overwrite`.
"""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable

from .errors import InvalidInput


def read_text(path: str | Path, error: Callable[[str], Exception], what: str = "file",
              encoding: str = "utf-8") -> str:
    """A file's text; an unreadable file raises ``error("cannot read <what>: <reason>")`` (chained)."""
    try:
        return Path(path).read_text(encoding=encoding)
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror}") from exc


def atomic_write_text(path: str | Path, text: str, overwrite: bool = True) -> Path:
    """Write ``text`` to ``path`` atomically (temp file + ``os.replace``)."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise InvalidInput(f"{path} exists; refusing to overwrite it", "path")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def atomic_write_json(path: str | Path, data: Any, overwrite: bool = True) -> Path:
    """Write JSON atomically; ``path == "-"`` prints to stdout instead."""
    text = json.dumps(data, indent=2, default=_jsonable) + "\n"
    if str(path) == "-":
        print(text, end="")
        return Path("-")
    return atomic_write_text(path, text, overwrite=overwrite)


def refuse_input_overwrite(output: str | Path, *inputs: str | Path | None) -> None:
    """Raise if ``output`` names the same file as one of ``inputs``."""
    if str(output) == "-":
        return
    out = Path(output).resolve()
    for item in inputs:
        if item is not None and str(item) != "-" and Path(item).resolve() == out:
            raise InvalidInput(f"output {output} is an input file; refusing to overwrite it", "output")


def _jsonable(value: Any) -> Any:
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
