"""Reports: the ``csjm demo`` job and its steps."""

from .demo import run as run_demo

__all__ = ["run_demo"]
