"""Number checks of sweep-file values; ``fail(message, key)`` builds the error naming the key."""

from __future__ import annotations

import math
from typing import Any

from ._sweep_limits import MAX_DESIGNS, MAX_VALUE


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
