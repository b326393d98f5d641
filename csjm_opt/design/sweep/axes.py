"""Swept parameters of a sweep file: explicit grid values or a sampled range."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from .._value_checks import MAX_DESIGNS, _float, _int


@dataclasses.dataclass(frozen=True)
class ParameterAxis:
    """One swept parameter: explicit ``values`` (grid) or a ``[low, high]`` range."""

    name: str
    values: tuple[float, ...] = ()
    low: float = math.nan
    high: float = math.nan
    log: bool = False


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
        return ParameterAxis(name, tuple(_float(v, f"{key}.values", fail) for v in values))
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
        return ParameterAxis(name, tuple(float(v) for v in grid))
    if "num" in spec:
        raise fail("num is for method = 'grid'; use sweep.designs", f"{key}.num")
    return ParameterAxis(name, (), low, high, log)


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
