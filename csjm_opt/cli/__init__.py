"""The ``csjm`` command line: one module per command group, each with ``register(subparsers)``."""

from ..errors import UsageError
from .app import build_parser, main

__all__ = ["UsageError", "build_parser", "main"]
