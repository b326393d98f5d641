"""File input and output at the package boundary: safe reads, checked and atomic writes.

Input (:func:`read_text`): only regular files are opened (a FIFO, device or
folder is refused from ``os.stat`` before anything blocks, and the file is
opened with ``O_NONBLOCK`` in case it is swapped in between), the size is
bounded before reading (:data:`MAX_INPUT_BYTES`), and the bytes are decoded
as UTF-8 (a UTF-8 byte-order mark is allowed) with an error that says what
the bytes look like instead (UTF-16/32, binary, another 8-bit encoding).

Output (:func:`check_output`, :func:`check_output_dir`, :func:`atomic_write_text`):
every output path is checked *before* a command starts its work (not a folder,
not a special file, in a writable folder, not one of the command's inputs), and
written to a temporary file in the target folder that is renamed into place,
so a reader never sees a half-written file. Files get the usual permissions
(``0o666 & ~umask``), not ``mkstemp``'s private ``0o600``.
"""

from __future__ import annotations

import codecs
import json
import os
import stat
import tempfile
from pathlib import Path
from typing import Any, Callable

from .errors import InvalidInput

__all__ = ["MAX_INPUT_BYTES", "atomic_write_json", "atomic_write_text", "check_output", "check_output_dir",
           "decode_text", "file_kind", "read_bytes", "read_text", "refuse_input_overwrite"]

# ------------ input: regular files only, bounded size, UTF-8 with a clear error otherwise
#: Largest input file read (bytes): 1 GiB, about 7 million log rows. Bounded so a
#: mistaken path (a disk image, /dev/zero) fails at once instead of filling memory.
MAX_INPUT_BYTES = 1 << 30

_BOMS = ((codecs.BOM_UTF32_LE, "UTF-32"), (codecs.BOM_UTF32_BE, "UTF-32"),
         (codecs.BOM_UTF16_LE, "UTF-16"), (codecs.BOM_UTF16_BE, "UTF-16"))


def file_kind(mode: int) -> str:
    """A readable name of a non-regular file type (``"folder"``, ``"FIFO (named pipe)"``...)."""
    for test, name in ((stat.S_ISDIR, "folder"), (stat.S_ISFIFO, "FIFO (named pipe)"),
                       (stat.S_ISCHR, "character device"), (stat.S_ISBLK, "block device"),
                       (stat.S_ISSOCK, "socket")):
        if test(mode):
            return name
    return "special file"


def read_bytes(path: str | Path, error: Callable[[str], Exception], what: str = "file",
               max_bytes: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of a regular file, without ever blocking on a FIFO or device.

    Parameters
    ----------
    path : str or Path
        File to read.
    error : callable
        Builds the exception raised on failure from a message, e.g.
        ``lambda msg: RigFileError(msg, path)``.
    what : str
        Name of the file in messages (``"rig file"``).
    max_bytes : int
        Largest accepted size.

    Returns
    -------
    bytes

    Raises
    ------
    Exception
        ``error(message)`` when the path is missing, not a regular file,
        larger than ``max_bytes`` or unreadable (chained to the ``OSError``).
    """
    try:
        st = os.stat(path)
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror}") from exc
    except ValueError as exc:  # embedded NUL in the name
        raise error(f"cannot read {what}: {exc}") from exc
    if not stat.S_ISREG(st.st_mode):
        raise error(f"cannot read {what}: it is a {file_kind(st.st_mode)}, not a regular file")
    if st.st_size > max_bytes:
        raise error(f"{what} is {st.st_size / 2**20:.0f} MiB, more than the {max_bytes / 2**20:.0f} MiB "
                    "accepted (MAX_INPUT_BYTES)")
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
        try:
            if not stat.S_ISREG(os.fstat(fd).st_mode):  # swapped in after the stat
                raise error(f"cannot read {what}: not a regular file")
            chunks, total = [], 0
            while True:
                chunk = os.read(fd, 1 << 24)
                if not chunk:
                    break
                total += len(chunk)
                if total > max_bytes:
                    raise error(f"{what} grew beyond the {max_bytes / 2**20:.0f} MiB accepted while reading")
                chunks.append(chunk)
        finally:
            os.close(fd)
    except OSError as exc:
        raise error(f"cannot read {what}: {exc.strerror}") from exc
    return b"".join(chunks)


def decode_text(data: bytes, error: Callable[[str], Exception], what: str = "file") -> str:
    """UTF-8 text of ``data`` (a leading UTF-8 BOM dropped); a clear error for anything else."""
    for bom, name in _BOMS:
        if data.startswith(bom):
            raise error(f"{what} is encoded as {name}; save it as UTF-8")
    if data.startswith(codecs.BOM_UTF8):
        data = data[len(codecs.BOM_UTF8):]
    if b"\x00" in data[:4096]:
        raise error(f"{what} holds NUL bytes: binary data or UTF-16 without a byte-order mark; "
                    "expected UTF-8 text")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise error(f"{what} is not UTF-8 text: byte 0x{data[exc.start]:02x} on line {line} "
                    "(re-save it as UTF-8)") from None


def read_text(path: str | Path, error: Callable[[str], Exception], what: str = "file",
              encoding: str = "utf-8", max_bytes: int = MAX_INPUT_BYTES) -> str:
    """A file's UTF-8 text: :func:`read_bytes` then :func:`decode_text`.

    Parameters
    ----------
    path : str or Path
        File to read.
    error : callable
        Builds the exception raised on failure from a message.
    what : str
        Name of the file in messages.
    encoding : str
        Kept for compatibility; only ``"utf-8"`` and ``"utf-8-sig"`` are
        accepted (both allow a byte-order mark).
    max_bytes : int
        Largest accepted size.

    Returns
    -------
    str

    Raises
    ------
    Exception
        ``error(message)`` on any of the failures above.
    """
    if encoding.lower().replace("_", "-") not in ("utf-8", "utf-8-sig", "utf8"):
        raise ValueError(f"only UTF-8 input is supported, got encoding={encoding!r}")
    return decode_text(read_bytes(path, error, what, max_bytes), error, what)


# ------------ output paths, checked before a command starts its work
def _same_file(a: Path, b: Path) -> bool:
    try:
        if os.path.samefile(a, b):
            return True
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_output(path: str | Path | None, *inputs: str | Path | None, name: str = "--json",
                 overwrite: bool = True) -> None:
    """Refuse an output file path before any work is done.

    ``"-"`` (stdout) and ``None`` (no output) pass. Otherwise the path must
    not be a folder or special file, must not name any of ``inputs`` (same
    resolved path or same inode), must not exist unless ``overwrite``, and its
    folder (or the nearest existing ancestor, which will be created) must be
    writable.

    Parameters
    ----------
    path : str, Path or None
        The output file.
    *inputs : str, Path or None
        Files the same command reads (``None`` entries are ignored).
    name : str
        Option name used in messages and as the error's ``name``.
    overwrite : bool
        Whether an existing regular file may be replaced.

    Raises
    ------
    InvalidInput
        Naming ``name`` and the reason.
    """
    if path is None or str(path) == "-":
        return
    if str(path) == "":
        raise InvalidInput(f"{name}: expected a file path, got an empty string", name)
    out = Path(path)
    for item in inputs:
        if item is not None and str(item) not in ("-", "paper") and _same_file(out, Path(item)):
            raise InvalidInput(f"{name} {path} is an input file of this command ({item}); refusing to "
                               "overwrite it", name)
    try:
        st = os.stat(out)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise InvalidInput(f"{name} {path}: {exc.strerror}", name) from exc
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            raise InvalidInput(f"{name} {path} is a {file_kind(st.st_mode)}; expected a file path", name)
        if not overwrite:
            raise InvalidInput(f"{name} {path} exists; refusing to overwrite it (--force replaces it)", name)
    _check_writable_parent(out.parent, f"{name} {path}", name)


def check_output_dir(path: str | Path | None, *inputs: str | Path | None, name: str = "--out") -> None:
    """Refuse an output folder path before any work is done.

    The path must be an existing writable folder or creatable (nearest
    existing ancestor a writable folder), and no input of the command may be
    the folder itself.

    Raises
    ------
    InvalidInput
        Naming ``name`` and the reason.
    """
    if path is None:
        return
    if str(path) == "":
        raise InvalidInput(f"{name}: expected a folder path, got an empty string", name)
    out = Path(path)
    for item in inputs:
        if item is not None and str(item) not in ("-", "paper") and _same_file(out, Path(item)):
            raise InvalidInput(f"{name} {path} is an input of this command; refusing to write into it", name)
    if out.exists():
        if not out.is_dir():
            raise InvalidInput(f"{name} {path} exists and is not a folder", name)
        if not os.access(out, os.W_OK | os.X_OK):
            raise InvalidInput(f"{name} {path}: folder is not writable", name)
        return
    _check_writable_parent(out.parent, f"{name} {path}", name)


def _check_writable_parent(parent: Path, what: str, name: str) -> None:
    folder = parent if str(parent) else Path(".")
    while not folder.exists():
        if folder.is_symlink() or folder == folder.parent:
            raise InvalidInput(f"{what}: folder {folder} cannot be created", name)
        folder = folder.parent
    if not folder.is_dir():
        raise InvalidInput(f"{what}: {folder} is not a folder", name)
    if not os.access(folder, os.W_OK | os.X_OK):
        raise InvalidInput(f"{what}: folder {folder} is not writable", name)


def refuse_input_overwrite(output: str | Path, *inputs: str | Path | None) -> None:
    """Raise :class:`InvalidInput` if ``output`` names the same file as one of ``inputs``."""
    if output is None or str(output) == "-":
        return
    for item in inputs:
        if item is not None and str(item) not in ("-", "paper") and _same_file(Path(output), Path(item)):
            raise InvalidInput(f"output {output} is an input file; refusing to overwrite it", "output")


# ------------ atomic writes: a temporary file in the target folder renamed into place
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
