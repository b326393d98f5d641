"""The ``csjm`` command line: a thin layer over the public functions.

Each subcommand lives in a module of this package exposing ``register(subparsers)``,
which adds its parser and sets ``func(args) -> int``. Any
:class:`~csjm_opt.errors.CsjmError` (and any usage error) becomes one line
on stderr and exit status 2; no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from typing import NoReturn

from ..errors import CsjmError, UsageError
from ._options import HelpFormatter
from .commands import COMMANDS

#: Modules that register subcommands, in help order.
COMMAND_MODULES = tuple(dict.fromkeys(module for module, _ in COMMANDS.values()))


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", HelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:  # one line, exit 2 (argparse prints usage too)
        err = UsageError(message)
        err.prog = self.prog  # type: ignore[attr-defined]  # "csjm plan-experiment": main's prefix, printed once
        raise err


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The ``csjm`` argument parser.

    Parameters
    ----------
    argv : list of str, optional
        The arguments it will parse. When they name a command, only the
        module of that command is imported and registered in full; every
        other command gets a light entry (name and one-line help, from
        :data:`csjm_opt.cli.commands.COMMANDS`), so ``csjm --help`` and any one
        command do not pay for the imports of the others. Without ``argv``
        every command is registered in full.

    Returns
    -------
    argparse.ArgumentParser
        A parser whose usage errors raise :class:`~csjm_opt.errors.UsageError`
        instead of exiting.
    """
    parser = _Parser(prog="csjm", description="Cable-driven spherical joint modules: model, plan, "
                     "identify, shape, diagnose, design.")
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    if argv is None:
        full = set(COMMAND_MODULES)
    else:
        named = next((a for a in argv if not a.startswith("-")), None)
        full = {COMMANDS[named][0]} if named in COMMANDS else set()
    registered: set[str] = set()
    for name, (module, help_text) in COMMANDS.items():
        if module in full and module not in registered:
            importlib.import_module(f"csjm_opt.cli.{module}").register(sub)
            registered.add(module)
        elif module not in full:
            sub.add_parser(name, help=help_text)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``csjm`` with ``argv`` (default ``sys.argv[1:]``); return the exit status.

    The command line writes figures to files only, so it selects matplotlib's
    non-interactive Agg backend here, before any command runs (library code
    never chooses a backend).
    """
    try:
        argv = sys.argv[1:] if argv is None else argv
        args = build_parser(argv).parse_args(argv)
        _agg_backend()
        return int(args.func(args) or 0)
    except CsjmError as exc:
        command = getattr(exc, "prog", "csjm").partition(" ")[2]     # "plan-experiment", or "" for csjm itself
        print(f"csjm: error: {command + ': ' if command else ''}{exc}".replace("\n", " "), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("csjm: interrupted", file=sys.stderr)
        return 130


def _agg_backend() -> None:
    """Figures go to files: matplotlib's Agg backend, without importing matplotlib for a command that draws none."""
    if "matplotlib" in sys.modules:
        import matplotlib

        matplotlib.use("Agg")
    else:
        os.environ["MPLBACKEND"] = "Agg"


def _version() -> str:
    from .. import __version__

    return f"csjm_opt {__version__}"


if __name__ == "__main__":
    sys.exit(main())
