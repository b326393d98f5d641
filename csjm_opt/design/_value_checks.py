"""Values of a sweep file: their size and value bounds, and the number checks.

The bounds are checked before anything is allocated; ``fail(message, key)`` builds the error naming the key.
"""

from __future__ import annotations

import math
from typing import Any

#: Most designs in one sweep (a 1e6-design sweep takes days on a workstation).
MAX_DESIGNS = 1_000_000
#: Most orientations sampled per design (the metrics hold a few arrays of this length per load).
MAX_ORIENTATIONS = 100_000
#: Most shaping poses per design (each solves a QP family).
MAX_SHAPING_POSES = 10_000
#: Most rows of ``loads.tau_ext``.
MAX_LOADS = 100
#: Largest magnitude of any number in a sweep file (parameters are m, deg, N, N/m, kg).
MAX_VALUE = 1e9
#: Largest seed (numpy's generators take any integer; this keeps it a 63-bit integer).
MAX_SEED = 2 ** 63 - 1


def _check_base_value(value: Any, key: str, fail: Any) -> None:
    """A number, or nested lists of numbers (hole rows), finite and within ``+-MAX_VALUE``."""
    if isinstance(value, list):
        if len(value) > 1000:
            raise fail(f"expected a short list, got {len(value)} entries", key)
        for v in value:
            _check_base_value(v, key, fail)
    elif not isinstance(value, str):
        _float(value, key, fail)


def _float(value: Any, key: str, fail: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"expected a finite number, got {value!r:.40}", key)
    if isinstance(value, int) and abs(value) > MAX_VALUE:
        raise fail(f"expected a number within +-{MAX_VALUE:g}, got an integer of {len(str(abs(value)))} digits", key)
    if not math.isfinite(value):
        raise fail(f"expected a finite number, got {value!r:.40}", key)
    if abs(value) > MAX_VALUE:
        raise fail(f"expected a number within +-{MAX_VALUE:g}, got {value:.6g}", key)
    return float(value)


def _int(value: Any, key: str, fail: Any, minimum: int, maximum: int = MAX_DESIGNS) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise fail(f"expected an integer >= {minimum}, got {value!r:.40}", key)
    if value > maximum:
        shown = f"{value:.3g}" if value < 10 ** 30 else f"an integer of {len(str(value))} digits"
        raise fail(f"expected an integer <= {maximum:,}, got {shown}", key)
    return value
