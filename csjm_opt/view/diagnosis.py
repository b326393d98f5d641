"""Where a diagnosis puts the gap, drawn on the rig: fitted hole offsets at the holes, sticking cables.

Reads only the diagnosis' fitted parameters (``csjm diagnose`` JSON names, cables and holes
indexed from 1):

* ``hole_offsets``: ``dA{i}_{x,y,z}_m`` (platform hole i, in {A}) and ``dB{i}_{x,y,z}_m`` (base
  hole i, in {B}) drawn as arrows from the nominal hole, magnified (the factor is on the page) and
  labelled with their size in mm;
* ``friction``: per-cable band sizes (``mu_beta_{i}`` or ``F_{i}_N``); the cables whose band is at
  least ``STICK_FRACTION`` of the largest are marked as the ones that stick, each labelled with its
  band.
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from ..model.rig import Rig
from .page import ViewPage, view_page
from .state import rig_state

__all__ = ["DRAWN_EFFECTS", "STICK_FRACTION", "diagnosis_view", "friction_bands", "hole_offsets_m"]

#: Effects this view draws.
DRAWN_EFFECTS = ("hole_offsets", "friction")
#: A cable "sticks" when its fitted band is at least this fraction of the largest band.
STICK_FRACTION = 0.25
#: Longest drawn offset arrow (m) after magnification.
ARROW_M = 0.03


def hole_offsets_m(params: dict[str, Any], n_cables: int) -> tuple[np.ndarray, np.ndarray]:
    """Fitted offsets ``(dA (m, 3) in {A}, dB (m, 3) in {B})`` in m; missing entries are 0."""
    dA, dB = np.zeros((n_cables, 3)), np.zeros((n_cables, 3))
    for name, value in params.items():
        m = re.fullmatch(r"d([AB])(\d+)_([xyz])_m", name)
        if m and 1 <= int(m.group(2)) <= n_cables:
            (dA if m.group(1) == "A" else dB)[int(m.group(2)) - 1, "xyz".index(m.group(3))] = float(value)
    return dA, dB


def friction_bands(params: dict[str, Any], n_cables: int) -> tuple[np.ndarray, str]:
    """Per-cable band sizes and their unit (``""`` for ``mu_beta``, ``"N"`` for Coulomb bands)."""
    bands, unit = np.zeros(n_cables), ""
    for name, value in params.items():
        m = re.fullmatch(r"([A-Za-z_]+?)_(\d+)(_N)?", name)
        if m and m.group(1) in ("mu_beta", "F", "band") and 1 <= int(m.group(2)) <= n_cables:
            bands[int(m.group(2)) - 1] = float(value)
            unit = "N" if m.group(3) else unit
    return bands, unit


def _offset_traces(rig: Rig, dA: np.ndarray, dB: np.ndarray) -> tuple[list[dict], str]:
    size = np.r_[np.linalg.norm(dA, axis=1), np.linalg.norm(dB, axis=1)]
    biggest = float(size.max()) if size.size else 0.0
    if biggest <= 0:
        return [], "no hole offset fitted"
    gain = ARROW_M / biggest
    traces: list[dict] = []
    xs: list[Any] = []
    ys: list[Any] = []
    zs: list[Any] = []
    tx: list[Any] = []
    ty: list[Any] = []
    tz: list[Any] = []
    text: list[str] = []
    for prefix, holes, d in (("A", rig.platform_holes_A_m, dA), ("B", rig.base_holes_B_m, dB)):
        for i, (h, v) in enumerate(zip(np.asarray(holes, float), d)):
            n = float(np.linalg.norm(v))
            if n <= 0.05 * biggest:
                continue
            tip = h + gain * v
            xs += [h[0], tip[0], None]
            ys += [h[1], tip[1], None]
            zs += [h[2], tip[2], None]
            tx.append(tip[0])
            ty.append(tip[1])
            tz.append(tip[2])
            text.append(f"{prefix}{i + 1}: {1e3 * n:.1f} mm")
    traces.append({"type": "scatter3d", "mode": "lines", "x": xs, "y": ys, "z": zs,
                   "line": {"color": "#cf222e", "width": 7}, "name": "fitted hole offsets", "hoverinfo": "name",
                   "showlegend": False})
    traces.append({"type": "scatter3d", "mode": "markers+text", "x": tx, "y": ty, "z": tz, "text": text,
                   "textposition": "top center", "textfont": {"color": "#cf222e", "size": 12},
                   "marker": {"size": 4, "color": "#cf222e"}, "hoverinfo": "text", "showlegend": False,
                   "name": "offset sizes"})
    return traces, f"fitted hole offsets drawn x{gain:.0f} (red arrows from the nominal holes, sizes in mm)"


def _friction_traces(rig: Rig, bands: np.ndarray, unit: str) -> tuple[list[dict], str]:
    top = float(bands.max()) if bands.size else 0.0
    if top <= 0:
        return [], "no friction band fitted"
    A, B = np.asarray(rig.platform_holes_A_m, float), np.asarray(rig.base_holes_B_m, float)
    stick = [i for i, b in enumerate(bands) if b >= STICK_FRACTION * top]
    xs: list[Any] = []
    ys: list[Any] = []
    zs: list[Any] = []
    for i in stick:
        xs += [B[i, 0], A[i, 0], None]
        ys += [B[i, 1], A[i, 1], None]
        zs += [B[i, 2], A[i, 2], None]
    mid = 0.5 * (A + B)
    label = [f"cable {i + 1}: band {bands[i]:.3g}{(' ' + unit) if unit else ''}" for i in stick]
    return ([{"type": "scatter3d", "mode": "lines", "x": xs, "y": ys, "z": zs,
              "line": {"color": "#cf222e", "width": 12}, "name": "cables that stick",
              "hoverinfo": "name", "showlegend": False},
             {"type": "scatter3d", "mode": "text", "x": mid[stick, 0].tolist(), "y": mid[stick, 1].tolist(),
              "z": mid[stick, 2].tolist(), "text": label, "textfont": {"color": "#cf222e", "size": 12},
              "hoverinfo": "skip", "showlegend": False, "name": "bands"}],
            f"cables that stick (fitted friction band at least {STICK_FRACTION:.0%} of the largest) in red: "
            + ", ".join(str(i + 1) for i in stick))


def diagnosis_view(rig: Rig, effect: str, params: dict[str, Any], title: str = "Where the gap lies") -> ViewPage:
    """The rig upright under its weight with a diagnosed effect drawn on it.

    Parameters
    ----------
    rig : Rig
        The rig of the diagnosis (nominal geometry).
    effect : str
        One of :data:`DRAWN_EFFECTS`.
    params : dict
        The effect's fitted parameters (diagnosis JSON ``candidates[k]["params"]``).
    title : str

    Returns
    -------
    ViewPage

    Raises
    ------
    InvalidInput
        ``effect`` is not one this view draws.
    """
    from ..errors import InvalidInput

    m = len(rig.platform_holes_A_m)
    if effect == "hole_offsets":
        extras, note = _offset_traces(rig, *hole_offsets_m(params, m))
    elif effect == "friction":
        extras, note = _friction_traces(rig, *friction_bands(params, m))
    else:
        raise InvalidInput(f"effect: expected one of {DRAWN_EFFECTS}, got {effect!r}", "effect")
    state = rig_state(rig, np.eye(3), np.zeros(3), "nominal rig, upright")
    return view_page([[state]], title, ["upright"], panel_titles=[f"{effect}: {note}"], note=note,
                     extras=[extras])
