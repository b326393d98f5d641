"""Physical bounds on every number the toolkit reads (files and command-line options).

One table, :data:`LIMITS`, states for each quantity the accepted range and why;
``docs/guide/input-files.md`` prints the same table. The bounds are wide
enough for any bench-top cable-driven joint (the paper's rig is ~0.1 m across,
holds a few N m and tensions up to 150 N) and narrow enough that a wrong unit,
a corrupt cell or an overflowing integer is refused with a message naming the
quantity and the bound, before any array is allocated or solver run.

Use :func:`check_array` (vectorised) or :func:`check_value` with a ``fail``
callable that turns a message into the caller's error type.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable, NoReturn

import numpy as np


@dataclasses.dataclass(frozen=True)
class Limit:
    """Accepted range of one quantity: ``low <= x <= high`` (``low < x`` when ``low_open``)."""

    quantity: str
    low: float
    high: float
    unit: str
    why: str
    low_open: bool = False
    integer: bool = False

    def describe(self) -> str:
        """The range as text, e.g. ``"(0, 10] m"``."""
        lo = "(" if self.low_open else "["
        return f"{lo}{self.low:g}, {self.high:g}]" + (f" {self.unit}" if self.unit else "")

    def contains(self, x: np.ndarray) -> np.ndarray:
        """Elementwise membership (NaN is outside)."""
        x = np.asarray(x, dtype=float)
        above = x > self.low if self.low_open else x >= self.low
        ok = above & (x <= self.high)
        if self.integer:
            ok &= np.floor(x) == x
        return ok


#: Largest integer stored exactly in a float64 (ids, seeds and counts stay below it).
MAX_EXACT_INT = 2 ** 53 - 1

LIMITS: dict[str, Limit] = {l.quantity: l for l in (
    Limit("position_m", -10.0, 10.0, "m", "every coordinate of a hole, centre of mass, tracker point or "
          "sensor offset; a CSJM is centimetres across, 10 m covers any lab rig and catches mm-for-m slips"),
    Limit("rest_length_m", 0.0, 10.0, "m", "commanded cable rest length: positive, at most the position bound",
          low_open=True),
    Limit("moment_Nm", -1e4, 1e4, "N m", "each component of a measured or requested moment; the paper's "
          "loads are ~1 N m, 1e4 N m would break any such joint"),
    Limit("force_N", -1e5, 1e5, "N", "each component of a force reading (F/T sensor)"),
    Limit("tension_N", 0.0, 1e5, "N", "tension bounds t_min, t_max and reference tension; cables only pull"),
    Limit("cable_stiffness_N_per_m", 0.0, 1e8, "N/m", "stiffness of a cable with its drive; steel rope "
          "of 1 m is ~1e7 N/m", low_open=True),
    Limit("mass_kg", 0.0, 1e3, "kg", "moving platform mass"),
    Limit("gravity_m_per_s2", -100.0, 100.0, "m/s^2", "each component of gravity (about 10x Earth's)"),
    Limit("stiffness_Nm_per_rad", -1e6, 1e6, "N m/rad", "each entry of a stiffness matrix (shaping target)"),
    Limit("weight", 0.0, 1e6, "", "objective weights (relative, non-negative)"),
    Limit("id", -MAX_EXACT_INT, MAX_EXACT_INT, "", "sample and cycle ids: integers stored exactly in "
          "float64 and int64 (2^53 - 1)", integer=True),
)}

#: Rotation vectors are principal values: norm at most pi (plus round-off).
ROTVEC_MAX_NORM_RAD = math.pi + 1e-9
#: Smallest distance of a hole from the joint centre O, and between two holes of one body (m).
MIN_HOLE_RADIUS_M = 1e-3
MIN_HOLE_SPACING_M = 1e-3

#: Most bootstrap resamples per identified cycle (2000 give percentile intervals to ~1 %).
MAX_BOOTSTRAP = 10_000

Fail = Callable[[str], Exception]


def _raise(fail: Fail, message: str) -> NoReturn:
    raise fail(message)


def check_value(x: Any, quantity: str, name: str, fail: Fail) -> float:
    """One finite number within ``LIMITS[quantity]``; returns it as float.

    Parameters
    ----------
    x : Any
        The value (int, float or numeric string is not accepted: convert first).
    quantity : str
        Key of :data:`LIMITS`.
    name : str
        Name used in the message (option or key).
    fail : callable
        Turns a message into the exception to raise.

    Returns
    -------
    float

    Raises
    ------
    Exception
        ``fail(message)`` when ``x`` is not a finite number within the bound.
    """
    lim = LIMITS[quantity]
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)):
        _raise(fail, f"{name}: expected a number, got {x!r:.40}")
    try:
        v = float(x)
    except OverflowError:
        _raise(fail, f"{name}: {str(x)[:12]}... is too large ({lim.quantity} must lie in {lim.describe()})")
    if not math.isfinite(v):
        _raise(fail, f"{name}: expected a finite number, got {v}")
    if not lim.contains(np.array(v)):
        kind = "an integer" if lim.integer else "a value"
        _raise(fail, f"{name}: expected {kind} in {lim.describe()} ({lim.why.split(';')[0]}), got {v:.6g}")
    return v


def check_array(arr: np.ndarray, quantity: str, name: str, fail: Fail,
                where: Callable[[int], str] | None = None) -> None:
    """Every entry of ``arr`` finite and within ``LIMITS[quantity]`` (vectorised).

    ``where(row)`` names the offending row in the message (e.g. its file line);
    rows are the first axis of ``arr``.

    Raises
    ------
    Exception
        ``fail(message)`` for the first offending entry.
    """
    lim = LIMITS[quantity]
    a = np.asarray(arr, dtype=float)
    ok = lim.contains(a)
    if ok.all():
        return
    flat = int(np.argmin(ok.ravel()))
    value = a.ravel()[flat]
    row = np.unravel_index(flat, a.shape)[0] if a.ndim else 0
    at = where(int(row)) if where is not None else ""
    what = "not finite" if not math.isfinite(value) else f"{value:.6g} outside {lim.describe()}"
    _raise(fail, f"{at}{name}: {what} ({lim.quantity}: {lim.why.split(';')[0]})")


def check_rotvecs(rotvec: np.ndarray, name: str, fail: Fail, where: Callable[[int], str] | None = None) -> None:
    """Rotation vectors (n, 3) finite with norm <= pi (principal values, not wrapped).

    A vector of norm > pi describes the same rotation as a shorter one, but no
    tracker writes it: it means a corrupt or mis-scaled cell (degrees for
    radians), so it is refused rather than wrapped.
    """
    rv = np.asarray(rotvec, dtype=float).reshape(-1, 3)
    with np.errstate(over="ignore", invalid="ignore"):
        norm = np.sqrt(np.sum(rv * rv, axis=1))
    bad = ~(norm <= ROTVEC_MAX_NORM_RAD)
    if bad.any():
        i = int(np.argmax(bad))
        at = where(i) if where is not None else ""
        shown = "not finite" if not np.isfinite(norm[i]) else f"norm {norm[i]:.6g} rad"
        _raise(fail, f"{at}{name}: rotation vector {shown}; expected a principal rotation vector "
               "(norm <= pi; degrees given as radians?)")
