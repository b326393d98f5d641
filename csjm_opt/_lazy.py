"""Packages whose re-exported names are imported on first use (PEP 562).

A package's ``__init__`` lists its public names and the module each comes from; importing the
package (or any module inside it) then costs nothing, and ``from csjm_opt.model import Model``
imports :mod:`csjm_opt.model.numeric` (and CasADi) only when it runs. A command's ``--help``
thereby loads no numerical library.
"""

from __future__ import annotations

import importlib
import sys
from typing import Any, Callable


def lazy_exports(package: str, names: dict[str, tuple[str, str | None]]
                 ) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``__getattr__`` and ``__dir__`` for ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : dict
        Public name -> ``(relative module, attribute)``; attribute ``None``: the module itself.

    Returns
    -------
    tuple
        The module-level ``__getattr__`` and ``__dir__`` functions.
    """

    def __getattr__(name: str) -> Any:
        if name not in names:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        module_name, attr = names[name]
        module = importlib.import_module(module_name, package)
        value = module if attr is None else getattr(module, attr)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__
