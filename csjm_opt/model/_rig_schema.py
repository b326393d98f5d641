"""Checks of a rig's nested TOML layout: sections, keys, shapes, bounds and hole placement."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._limits import LIMITS, MIN_HOLE_RADIUS_M, MIN_HOLE_SPACING_M
from ..errors import RigFileError
from .cable_terms import cable_lengths
from .hole_pattern import MAX_CABLES, MIN_CABLES

#: Bound (csjm_opt._limits.LIMITS key) of each rig entry.
_QUANTITY = {"platform_holes": "position_m", "base_holes": "position_m", "stiffness": "cable_stiffness_N_per_m",
             "t_min": "tension_N", "t_max": "tension_N", "mass": "mass_kg", "com": "position_m",
             "gravity": "gravity_m_per_s2"}

#: Shapes of each entry; ``-1`` stands for m, the number of cables (rows of ``geometry.platform_holes``).
_SCHEMA: dict[str, dict[str, tuple[int, ...]]] = {
    "geometry": {"platform_holes": (-1, 3), "base_holes": (-1, 3)},
    "cables": {"stiffness": (-1,), "t_min": (), "t_max": ()},
    "platform": {"mass": (), "com": (3,), "gravity": (3,)},
}


def _check(data: Any, path: str | None) -> None:
    if not isinstance(data, dict):
        raise RigFileError(f"expected a table, got {type(data).__name__}", path)
    for section in data:
        if section not in _SCHEMA:
            known = sorted([*_SCHEMA, "dynamics", "link", "workspace"])
            raise RigFileError(f"unknown section (expected one of {known})", path, section)
    m = -1
    for section, keys in _SCHEMA.items():
        table = data.get(section)
        if not isinstance(table, dict):
            raise RigFileError("missing section", path, section)
        for key in table:
            if key not in keys:
                raise RigFileError(f"unknown key (expected one of {sorted(keys)})", path,
                                   f"{section}.{key}")
        for key, shape in keys.items():
            dotted = f"{section}.{key}"
            if key not in table:
                raise RigFileError("missing key", path, dotted)
            value = table[key]
            if isinstance(value, bool) or _has_non_number(value):
                raise RigFileError(f"expected numbers, got {value!r:.60}", path, dotted)
            if _has_huge_int(value):
                raise RigFileError(f"integer too large (expected {LIMITS[_QUANTITY[key]].describe()})",
                                   path, dotted)
            arr = np.asarray(value, dtype=float) if _rectangular(value) else None
            if dotted == "geometry.platform_holes" and arr is not None and arr.ndim == 2 and arr.shape[1] == 3:
                m = arr.shape[0]
                if not MIN_CABLES <= m <= MAX_CABLES:
                    raise RigFileError(f"expected {MIN_CABLES} to {MAX_CABLES} rows (one per cable), got {m}"
                                       + (": fewer than 4 cables cannot hold 3 rotations by pulling"
                                          if m < MIN_CABLES else ""), path, dotted)
            want_shape = tuple(m if n == -1 else n for n in shape)
            if arr is None or arr.shape != want_shape:
                got = "ragged rows" if arr is None else f"shape {arr.shape}"
                want = "a number" if shape == () else f"shape {want_shape}"
                if -1 in shape and m > 0:
                    want += f" (one per cable: platform_holes has {m} rows)"
                elif -1 in shape:
                    want = f"shape (m, 3) with {MIN_CABLES} <= m <= {MAX_CABLES}"
                raise RigFileError(f"expected {want}, got {got}", path, dotted)
            if not np.all(np.isfinite(arr)):
                raise RigFileError("expected finite numbers (no nan or inf)", path, dotted)
    c, p, g = data["cables"], data["platform"], data["geometry"]
    k = np.asarray(c["stiffness"], dtype=float)
    if np.any(k <= 0):
        raise RigFileError(f"cable stiffness must be positive, got {k.tolist()}", path, "cables.stiffness")
    if not float(c["t_min"]) >= 0:
        raise RigFileError(f"t_min must be >= 0 (cables only pull), got {c['t_min']}", path, "cables.t_min")
    if not float(c["t_min"]) < float(c["t_max"]):
        raise RigFileError(f"t_min must be < t_max, got t_min={c['t_min']}, t_max={c['t_max']}",
                           path, "cables.t_max")
    if float(p["mass"]) < 0:
        raise RigFileError(f"mass must be >= 0, got {p['mass']}", path, "platform.mass")
    for section, keys in _SCHEMA.items():
        for key in keys:
            arr, lim = np.asarray(data[section][key], dtype=float), LIMITS[_QUANTITY[key]]
            ok = lim.contains(arr)
            if not ok.all():
                bad = float(arr.ravel()[int(np.argmin(ok.ravel()))])
                raise RigFileError(f"{bad:.6g} outside {lim.describe()} ({lim.why.split(';')[0]})",
                                   path, f"{section}.{key}")
    A, B = np.asarray(g["platform_holes"], float), np.asarray(g["base_holes"], float)
    gaps = cable_lengths(np.eye(3), A, B)  # cable lengths at R = I
    if np.any(gaps < 1e-6):
        i = int(np.argmin(gaps))
        raise RigFileError(f"platform hole {i + 1} coincides with base hole {i + 1} at R = I",
                           path, "geometry.base_holes")
    for name, P in (("platform_holes", A), ("base_holes", B)):
        r = np.linalg.norm(P, axis=1)
        if np.any(r < MIN_HOLE_RADIUS_M):
            i = int(np.argmin(r))
            raise RigFileError(f"hole {i + 1} is {r[i] * 1e3:.3g} mm from the joint centre O (at least "
                               f"{MIN_HOLE_RADIUS_M * 1e3:g} mm: a cable through O has no moment arm)",
                               path, f"geometry.{name}")
        d = np.linalg.norm(P[:, None, :] - P[None, :, :], axis=-1) + np.eye(len(P)) * 1e9
        if d.min() < MIN_HOLE_SPACING_M:
            i, j = (int(x) for x in np.unravel_index(int(np.argmin(d)), d.shape))
            raise RigFileError(f"holes {i + 1} and {j + 1} are {d[i, j] * 1e3:.3g} mm apart (at least "
                               f"{MIN_HOLE_SPACING_M * 1e3:g} mm: duplicated row?)", path, f"geometry.{name}")


def _has_non_number(value: Any) -> bool:
    if isinstance(value, list):
        return any(_has_non_number(v) for v in value)
    return isinstance(value, bool) or not isinstance(value, (int, float))


def _has_huge_int(value: Any) -> bool:
    if isinstance(value, list):
        return any(_has_huge_int(v) for v in value)
    return isinstance(value, int) and not isinstance(value, bool) and abs(value) > 2 ** 53


def _rectangular(value: Any) -> bool:
    try:
        np.asarray(value, dtype=float)
    except ValueError:
        return False
    return True
