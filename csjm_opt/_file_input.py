"""Safe reads of input files: regular files only, bounded size, UTF-8 with a clear error otherwise."""

from __future__ import annotations

import codecs
import os
import stat
from pathlib import Path
from typing import Callable

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
