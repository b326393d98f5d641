"""The ``csjm`` command line: a thin layer over the public functions.

Each subcommand lives in a module of this package exposing ``register(subparsers)``,
which adds its parser and sets ``func(args) -> int``. Any
:class:`~csjm_opt.errors.CsjmError` (and any usage error) becomes one line
on stderr and exit status 2; no traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from typing import NoReturn

from ..errors import CsjmError, UsageError

#: Modules that register subcommands, in help order.
COMMAND_MODULES = ("core", "demo", "shape", "identify", "diagnose", "sweep", "report", "export_mjcf", "simulate")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:  # one line, exit 2 (argparse prints usage too)
        raise UsageError(f"{self.prog}: {message}")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="csjm", description="Cable-driven spherical joint modules: model, plan, "
                     "identify, shape, diagnose, design.")
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"csjm_opt.cli.{name}").register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``csjm`` with ``argv`` (default ``sys.argv[1:]``); return the exit status.

    The command line writes figures to files only, so it selects matplotlib's
    non-interactive Agg backend here, before any command runs (library code
    never chooses a backend).
    """
    import matplotlib

    matplotlib.use("Agg")
    try:
        args = build_parser().parse_args(argv)
        return int(args.func(args) or 0)
    except CsjmError as exc:
        print(f"csjm: error: {exc}".replace("\n", " "), file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("csjm: interrupted", file=sys.stderr)
        return 130


def _version() -> str:
    from .. import __version__

    return f"csjm_opt {__version__}"


if __name__ == "__main__":
    sys.exit(main())
