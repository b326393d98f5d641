"""Checks of output paths before a command starts its work (not a folder, writable, not an input)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ._file_input import file_kind
from .errors import InvalidInput


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
