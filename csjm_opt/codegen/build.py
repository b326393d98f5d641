"""Compile a generated folder with the system C compiler (for the Python bindings and the tests).

``build_shared(DIR)`` compiles the core sources of :func:`csjm_opt.codegen.generate_c` plus
``csjm_host.c`` (batch loops and timing) into one shared library in ``DIR``, with
``-std=c99 -Wall -Wextra -Werror -O2``, named for the hash of its sources and flags.
The compiler is ``$CC`` or ``cc``.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path

from .._fileio import _file_mode
from ..errors import InvalidInput, SolverError

__all__ = ["CFLAGS", "CORE_SOURCES", "HEADERS", "build_shared", "find_compiler"]

#: The flags every build uses (warnings are errors).
CFLAGS = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-O2")
#: The sources a target needs (``csjm_host.c`` is only for the host bindings).
CORE_SOURCES = ("csjm_api.c", "csjm_qp.c", "csjm_model.c")
HEADERS = ("csjm.h", "csjm_qp.h", "csjm_rig.h", "csjm_model.h")


def find_compiler() -> str | None:
    """The C compiler to use (``$CC`` or ``cc``), or ``None`` when there is none.

    Returns
    -------
    str or None
        Full path of the compiler executable.
    """
    cc = os.environ.get("CC", "cc")
    return shutil.which(cc)


def build_shared(out_dir: str | Path, extra_cflags: Sequence[str] = (), force: bool = False) -> Path:
    """Compile ``out_dir``'s C into a shared library named for its content (reused if it exists).

    The name ``libcsjm_py-<hash>.so`` hashes the sources, headers and flags, so a regenerated
    folder gets a new file (a process that loaded the old one keeps it, and ``ctypes`` does not
    hand back a stale library for the same path); older builds in the folder are removed.

    Parameters
    ----------
    out_dir : str or Path
        A folder written by :func:`csjm_opt.codegen.generate_c`.
    extra_cflags : sequence of str, optional
        More compiler flags (e.g. ``-fsanitize=address,undefined``).
    force : bool, optional
        Compile even when the library exists.

    Returns
    -------
    Path
        The library.

    Raises
    ------
    InvalidInput
        ``out_dir`` lacks a generated file.
    SolverError
        No C compiler, or the compiler failed (its first error line is quoted).
    """
    d = Path(out_dir)
    sources = [d / s for s in CORE_SOURCES + ("csjm_host.c",)]
    inputs = sources + [d / h for h in HEADERS]
    missing = [p.name for p in inputs if not p.is_file()]
    if missing:
        raise InvalidInput(f"{d}: not a generated folder (missing {', '.join(missing)}); "
                           "run `csjm codegen -o DIR` first", "out_dir")
    digest = hashlib.sha256(" ".join(CFLAGS + tuple(extra_cflags)).encode())
    for p in inputs:
        digest.update(p.name.encode() + b"\0" + p.read_bytes())
    lib = d / f"libcsjm_py-{digest.hexdigest()[:16]}.so"
    if lib.is_file() and not force:
        return lib
    cc = find_compiler()
    if cc is None:
        raise SolverError("no C compiler found (set CC or install cc)", "cc")
    fd, tmp = tempfile.mkstemp(prefix=".build-", suffix=".so", dir=d)
    os.close(fd)
    cmd = [cc, *CFLAGS, *extra_cflags, "-fPIC", "-shared", *map(str, sources), "-o", tmp, "-lm"]
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            first = next((ln for ln in proc.stderr.splitlines() if "error" in ln), proc.stderr.strip()[:300])
            raise SolverError(f"{cc} failed on {d}: {first}", "cc")
        os.chmod(tmp, _file_mode(executable=True))     # not mkstemp's private 0600
        os.replace(tmp, lib)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    for old in d.glob("libcsjm_py-*.so"):
        if old != lib:
            old.unlink(missing_ok=True)
    return lib
