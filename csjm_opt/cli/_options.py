"""Validated command-line options: argparse ``type=`` factories and output-path checks.

Every numeric option of ``csjm`` is parsed by one of these, so a bad value
(``nan``, ``inf``, ``1e400``, out of its physical range) is refused by argparse
with one line naming the option and the accepted range, before any work::

    p.add_argument("--tau", nargs=3, type=quantity("moment_Nm"))
    p.add_argument("--ci-level", type=float_in(0, 1, low_open=True, high_open=True))
    p.add_argument("--bootstrap", type=int_in(0, MAX_BOOTSTRAP))

Output paths are checked with :func:`check_outputs` at the start of a
command's ``run`` (writable, not a folder, not any input of the command).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Callable

import numpy as np

from .._fileio import check_output, check_output_dir
from .._limits import LIMITS, ROTVEC_MAX_NORM_RAD
from ..errors import InvalidInput


def _number(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text[:40]!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text[:40]!r}")
    return value


def finite_float(text: str) -> float:
    """Argparse type for any finite float (refuses ``nan``, ``inf`` and overflowing text)."""
    return _number(text)


def float_in(low: float, high: float, low_open: bool = False, high_open: bool = False,
             unit: str = "") -> Callable[[str], float]:
    """Argparse type factory for a finite float in ``[low, high]`` (ends open as asked).

    Parameters
    ----------
    low, high : float
        Bounds.
    low_open, high_open : bool
        Exclude the bound itself.
    unit : str
        Unit shown in the message.

    Returns
    -------
    callable
        ``str -> float``, raising ``argparse.ArgumentTypeError``.
    """
    shown = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}" + (f" {unit}" if unit else "")

    def parse(text: str) -> float:
        value = _number(text)
        if (value <= low if low_open else value < low) or (value >= high if high_open else value > high):
            raise argparse.ArgumentTypeError(f"expected a number in {shown}, got {text[:40]}")
        return value

    parse.__name__ = "number"
    return parse


def quantity(name: str) -> Callable[[str], float]:
    """Argparse type factory for a finite float within ``csjm_opt._limits.LIMITS[name]``."""
    lim = LIMITS[name]
    return float_in(lim.low, lim.high, low_open=lim.low_open, unit=lim.unit)


def int_in(low: int, high: int) -> Callable[[str], int]:
    """Argparse type factory for an integer in ``[low, high]`` (decimal digits, optional sign)."""

    def parse(text: str) -> int:
        t = text.strip()
        if not t.lstrip("+-").isdigit() or len(t) > 30:
            raise argparse.ArgumentTypeError(f"expected an integer in [{low:,}, {high:,}], got {text[:40]!r}")
        value = int(t)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected an integer in [{low:,}, {high:,}], got {value:,}")
        return value

    parse.__name__ = "integer"
    return parse


def rotvec_component(text: str) -> float:
    """Argparse type for one rotation-vector component, finite and within ``[-pi, pi]`` rad."""
    value = _number(text)
    if abs(value) > ROTVEC_MAX_NORM_RAD:
        raise argparse.ArgumentTypeError(f"expected a component in [-pi, pi] rad (a principal rotation "
                                         f"vector; degrees given as radians?), got {text[:40]}")
    return value


def check_rotvec(values: list[float] | np.ndarray, name: str = "--rotvec") -> np.ndarray:
    """The rotation vector as (3,) floats; refuses a norm above pi (the principal-value rule).

    Raises
    ------
    InvalidInput
        Naming ``name`` and the norm.
    """
    rv = np.asarray(values, dtype=float)
    norm = float(np.linalg.norm(rv))
    if not norm <= ROTVEC_MAX_NORM_RAD:
        raise InvalidInput(f"{name}: rotation vector of norm {norm:.4g} rad; expected norm <= pi "
                           "(a principal rotation vector)", name)
    return rv


def check_outputs(inputs: list[str | Path | None], files: dict[str, str | Path | None] | None = None,
                  dirs: dict[str, str | Path | None] | None = None, overwrite: dict[str, bool] | None = None) -> None:
    """Check every output of a command before it starts working.

    Parameters
    ----------
    inputs : list
        Files the command reads (``None`` entries ignored).
    files : dict
        Option name -> output file path (``None``: not asked; ``"-"``: stdout).
    dirs : dict
        Option name -> output folder path.
    overwrite : dict
        Option name -> whether an existing file may be replaced (default True).

    Raises
    ------
    InvalidInput
        For the first output that is a folder or special file, is not
        writable, names an input, or names the same path as another output.
    """
    files, dirs, overwrite = files or {}, dirs or {}, overwrite or {}
    seen: list[tuple[str, str | Path]] = []
    for name, path in files.items():
        if path is None or str(path) == "-":
            continue
        check_output(path, *inputs, name=name, overwrite=overwrite.get(name, True))
        for other, prev in seen:
            if Path(prev).resolve() == Path(path).resolve():
                raise InvalidInput(f"{name} and {other} name the same file {path}", name)
        seen.append((name, path))
    for name, path in dirs.items():
        check_output_dir(path, *inputs, name=name)


# ------------------------------------------------------------ options shared by every command
#: Old spellings still accepted, hidden from ``--help``: ``--output`` for ``-o/--out``.
HIDDEN_ALIASES = frozenset({"--output"})


class HelpFormatter(argparse.HelpFormatter):
    """The default help layout without the hidden alias spellings."""

    def _format_action_invocation(self, action: argparse.Action) -> str:
        if action.option_strings and HIDDEN_ALIASES & set(action.option_strings):
            shown = [s for s in action.option_strings if s not in HIDDEN_ALIASES]
            action = argparse.Action(shown, action.dest, nargs=action.nargs, metavar=action.metavar)
        return super()._format_action_invocation(action)


def rig_option(what: str = "rig TOML file") -> argparse.ArgumentParser:
    """A parent parser with ``--rig RIG.toml`` (default: the built-in paper rig), the same in every command."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("--rig", default=None, metavar="RIG.toml", help=f"{what} (default: the built-in paper rig)")
    return p


def json_option(what: str = "machine-readable output") -> argparse.ArgumentParser:
    """A parent parser with ``--json PATH`` (``-`` = stdout), the same in every command."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("--json", metavar="PATH", default=None, help=f"write {what} as JSON ('-' = stdout)")
    return p


def out_option(metavar: str, what: str, required: bool = True, default: str | None = None) -> argparse.ArgumentParser:
    """A parent parser with ``-o/--out`` (``--output`` a hidden alias), the same in every command.

    Parameters
    ----------
    metavar : str
        What the value looks like (``LOG.csv``, ``DIR``).
    what : str
        The help text.
    required : bool
        Whether the command needs it.
    default : str, optional
        Its default when not required.
    """
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("-o", "--out", "--output", dest="out", metavar=metavar, required=required, default=default,
                   help=what)
    return p


def workers_option() -> argparse.ArgumentParser:
    """A parent parser with ``--workers N``, the same in every command (default: :func:`workers_of`)."""
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("--workers", type=int_in(1, 256), default=None, metavar="N",
                   help="worker processes (default: CSJM_WORKERS if set, else the cores this process may use; "
                   "1: serial, in this process)")
    return p


def workers_of(args: argparse.Namespace) -> int:
    """``--workers`` resolved: the number given, else :func:`csjm_opt._workers.default_workers`."""
    from .._workers import default_workers

    return args.workers if args.workers is not None else default_workers()


def pose_option(required: bool = False) -> argparse.ArgumentParser:
    """A parent parser with ``--rotvec RX RY RZ`` and ``--tau TX TY TZ``, the same in every command.

    Parameters
    ----------
    required : bool
        Whether the command needs a pose (else the default is the identity, upright).
    """
    p = argparse.ArgumentParser(add_help=False)
    p.add_argument("--rotvec", nargs=3, type=rotvec_component, required=required,
                   default=None if required else (0.0, 0.0, 0.0), metavar=("RX", "RY", "RZ"),
                   help="orientation of {A} in {B} as a rotation vector (rad)"
                   + ("" if required else "; default identity"))
    p.add_argument("--tau", nargs=3, type=quantity("moment_Nm"), default=(0.0, 0.0, 0.0), metavar=("TX", "TY", "TZ"),
                   help="external moment about O in {A} (N m), platform weight excluded; default 0")
    return p


def pose_of(args: argparse.Namespace) -> tuple[np.ndarray, np.ndarray]:
    """``--rotvec`` and ``--tau`` of :func:`pose_option` as checked (3,) arrays (rad, N m).

    Raises
    ------
    InvalidInput
        A rotation vector of norm above pi.
    """
    from .._validate import as_vector3

    return as_vector3(check_rotvec(args.rotvec), "--rotvec"), as_vector3(args.tau, "--tau")
