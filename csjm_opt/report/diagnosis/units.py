"""Units and cells of diagnosis numbers: the unit shown for a parameter from its name's suffix."""

from __future__ import annotations

from ..document import Cell

#: Unit of a parameter from its name's suffix: (suffix, unit shown, scale, format).
_UNITS = (("_rad_per_Nm", "rad/(N m)", 1.0, "sig3"), ("_per_m", "1/m", 1.0, "sig3"), ("_Nm", "N m", 1.0, "sig3"),
          ("_kgm", "kg m", 1.0, "sig3"), ("_mm", "mm", 1.0, "sig3"), ("_m", "mm", 1e3, "sig3"),
          ("_rad", "mrad", 1e3, "sig3"), ("_deg", "deg", 1.0, "sig3"), ("_percent", "%", 1.0, "sig3"),
          ("_N", "N", 1.0, "sig3"), ("_kg", "kg", 1.0, "sig3"))


def _cell(d: dict, key: str, where: tuple, fmt: str | None = None, scale: float | None = None) -> Cell:
    """A number of ``d`` with its JSON source ``where + (key,)``; "n/a" without a source when absent."""
    return Cell(d[key], fmt, scale, where + (key,)) if key in d else Cell(None, fmt, scale)


def unit_of(name: str) -> tuple[str, float]:
    """(unit shown, display scale) of a parameter from the unit suffix of its name ("" for none)."""
    for suffix, unit, scale, _ in _UNITS:
        if name.endswith(suffix):
            return unit, scale
    return "", 1.0
