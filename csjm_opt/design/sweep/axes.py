"""Swept parameters of a sweep file: explicit grid values or a sampled range.

The cable count ``n_cables`` (m) is an axis like any other, but an integer one
(:data:`INTEGER_PARAMETERS`): its grid values, ``min`` and ``max`` must be
integers from 4 to 12, and random / Latin-hypercube sweeps draw integers
(each of ``min..max`` equally likely).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from .._value_checks import MAX_DESIGNS, _float, _int

#: Parameters that take integer values, with their smallest and largest value.
INTEGER_PARAMETERS: dict[str, tuple[int, int]] = {"n_cables": (4, 12)}


@dataclasses.dataclass(frozen=True)
class ParameterAxis:
    """One swept parameter: explicit ``values`` (grid) or a ``[low, high]`` range."""

    name: str
    values: tuple[float, ...] = ()
    low: float = math.nan
    high: float = math.nan
    log: bool = False

    @property
    def integer(self) -> bool:
        """Whether the parameter takes integer values only (:data:`INTEGER_PARAMETERS`)."""
        return self.name in INTEGER_PARAMETERS

    def value_at(self, x: float) -> float:
        """The parameter's value at ``x`` in [0, 1) of its range (random and Latin-hypercube sweeps).

        Parameters
        ----------
        x : float
            Position in the range (uniform, or log-uniform when ``log``).

        Returns
        -------
        float
            An integer value for an integer parameter (``min..max`` equally likely).
        """
        if self.integer:
            return float(min(self.high, math.floor(self.low + x * (self.high - self.low + 1))))
        if self.log:
            return float(math.exp(math.log(self.low) + x * (math.log(self.high) - math.log(self.low))))
        return float(self.low + x * (self.high - self.low))


def _axis(name: str, spec: Any, method: str, fail: Any) -> ParameterAxis:
    key = f"parameters.{name}"
    if not isinstance(spec, dict):
        raise fail("expected a table: {values = [...]} or {min = .., max = ..}", key)
    allowed = {"values", "min", "max", "num", "log"}
    for k in spec:
        if k not in allowed:
            raise fail(f"unknown key (expected one of {sorted(allowed)})", f"{key}.{k}")
    if "values" in spec:
        if method != "grid":
            raise fail("explicit values need method = 'grid'; give min and max", f"{key}.values")
        if {"min", "max", "num"} & set(spec):
            raise fail("give values or min/max/num, not both", f"{key}.values")
        values = spec["values"]
        if not isinstance(values, list) or not values:
            raise fail("expected a non-empty list of numbers", f"{key}.values")
        return _checked(ParameterAxis(name, tuple(_float(v, f"{key}.values", fail) for v in values)), key, fail)
    for k in ("min", "max"):
        if k not in spec:
            raise fail("missing key (or give values)", f"{key}.{k}")
    low, high = _float(spec["min"], f"{key}.min", fail), _float(spec["max"], f"{key}.max", fail)
    if not low < high:
        raise fail(f"min must be < max, got {low} and {high}", f"{key}.min")
    log = spec.get("log", False)
    if not isinstance(log, bool):
        raise fail(f"expected true or false, got {log!r}", f"{key}.log")
    if log and low <= 0:
        raise fail("log = true needs min > 0", f"{key}.min")
    if method == "grid":
        if "num" not in spec:
            raise fail("missing key (grid over min..max needs num)", f"{key}.num")
        num = _int(spec["num"], f"{key}.num", fail, minimum=1, maximum=MAX_DESIGNS)
        grid = np.geomspace(low, high, num) if log else np.linspace(low, high, num)
        _checked(ParameterAxis(name, (), low, high, log), key, fail)
        return _checked(ParameterAxis(name, tuple(float(v) for v in grid)), key, fail, "num")
    if "num" in spec:
        raise fail("num is for method = 'grid'; use sweep.designs", f"{key}.num")
    return _checked(ParameterAxis(name, (), low, high, log), key, fail)


def _checked(axis: ParameterAxis, key: str, fail: Any, grid_key: str = "values") -> ParameterAxis:
    """An integer parameter's values and range are integers within its bounds (:data:`INTEGER_PARAMETERS`)."""
    if not axis.integer:
        return axis
    low, high = INTEGER_PARAMETERS[axis.name]
    if axis.log:
        raise fail("an integer parameter takes no log = true", f"{key}.log")
    for where, values in ((f"{key}.min", (axis.low,)), (f"{key}.max", (axis.high,)),
                          (f"{key}.{grid_key}", axis.values)):
        for v in values:
            if not math.isnan(v) and (v != int(v) or not low <= v <= high):
                hint = " (a grid from min to max must land on integers)" if grid_key == "num" else ""
                raise fail(f"expected integers from {low} to {high}{hint}, got {v:g}", where)
    return axis


def _axis_size(name: str, spec: Any, fail: Any) -> int:
    """Number of grid values of one axis, read before any array is built."""
    key = f"parameters.{name}"
    if not isinstance(spec, dict):
        raise fail("expected a table: {values = [...]} or {min = .., max = ..}", key)
    if isinstance(spec.get("values"), list):
        return max(1, len(spec["values"]))
    if "num" in spec:
        return _int(spec["num"], f"{key}.num", fail, minimum=1, maximum=MAX_DESIGNS)
    return 1
