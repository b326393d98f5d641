"""Plotly traces (plain dicts, no plotly import) of one :class:`~csjm_opt.view.state.RigState`.

Drawn in the base frame {B} (m), joint centre O at the origin: the base and platform plates
through their holes (labelled ``B1..Bm`` and ``A1..Am`` in the rig file's order), the cables
coloured by tension on one scale ``[t_min, t_max]``, the external load moment as an arrow
(right-hand rule about O, length proportional to its size), the weight at the centre of mass,
and the compliance ellipsoid at O: semi-axes along K's eigenvectors, proportional to
``1/lambda_i`` (longest = ``ELLIPSOID_FRACTION`` of the platform radius), so the soft direction
is the long axis and a 2:1 ratio of eigenvalues is a 2:1 ratio of axes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .state import RigState

__all__ = ["ARROW_FRACTION", "ELLIPSOID_FRACTION", "PanelScale", "panel_scale", "state_traces"]

#: Longest ellipsoid semi-axis, as a fraction of the platform holes' largest radius.
ELLIPSOID_FRACTION = 0.55
#: Length of the largest load arrow in a panel, as a fraction of the panel's half-width.
ARROW_FRACTION = 0.8
COLORSCALE = "Viridis"


class PanelScale:
    """Sizes shared by every frame of one panel: axis half-width (m) and the load of the longest arrow (N m)."""

    def __init__(self, half_width_m: float, tau_ref_Nm: float, ellipsoid_m: float):
        self.half_width_m = float(half_width_m)
        self.tau_ref_Nm = float(tau_ref_Nm)
        self.ellipsoid_m = float(ellipsoid_m)


def panel_scale(states: list[RigState]) -> PanelScale:
    """A :class:`PanelScale` that fits every state of a panel (the same axes in every frame)."""
    reach = max(max(np.linalg.norm(s.rig.base_holes_B_m, axis=1).max(),
                    np.linalg.norm(s.rig.platform_holes_A_m, axis=1).max()) for s in states)
    radius = max(np.linalg.norm(s.rig.platform_holes_A_m[:, :2], axis=1).max() for s in states)
    tau_ref = max(float(np.linalg.norm(s.tau_ext_A_Nm)) for s in states)
    return PanelScale(1.25 * reach, tau_ref, ELLIPSOID_FRACTION * radius)


def _xyz(points: np.ndarray) -> dict[str, list]:
    pts = np.asarray(points, float)
    return {"x": _r(pts[..., 0]), "y": _r(pts[..., 1]), "z": _r(pts[..., 2])}


def _r(a: np.ndarray) -> Any:
    """Rounded to the micrometre, NaN (a gap between line pieces) as ``None`` (JSON null)."""
    arr = np.round(np.asarray(a, float), 6)
    if not np.isnan(arr).any():
        return arr.tolist()
    out = arr.astype(object)
    out[np.isnan(arr)] = None
    return out.tolist()


def _plate(points_B: np.ndarray, name: str, color: str, scene: str) -> list[dict]:
    """A flat plate through the holes (fan from the centroid, holes sorted by angle) and its outline."""
    c = points_B.mean(axis=0)
    u, _, vt = np.linalg.svd(points_B - c)
    e1, e2 = vt[0], vt[1]
    order = np.argsort(np.arctan2((points_B - c) @ e2, (points_B - c) @ e1))
    ring = points_B[order]
    verts = np.vstack([c, ring])
    m = len(ring)
    mesh = {"type": "mesh3d", **_xyz(verts), "i": [0] * m, "j": list(range(1, m + 1)),
            "k": [(q % m) + 1 for q in range(1, m + 1)], "color": color, "opacity": 0.25, "name": name,
            "hoverinfo": "name", "showlegend": False, "scene": scene, "flatshading": True}
    outline = {"type": "scatter3d", "mode": "lines+markers", **_xyz(np.vstack([ring, ring[:1]])), "name": name,
               "line": {"color": color, "width": 3}, "marker": {"size": 3, "color": color}, "hoverinfo": "skip",
               "showlegend": False, "scene": scene}
    return [mesh, outline]


def _hole_labels(points_B: np.ndarray, prefix: str, color: str, scene: str) -> dict:
    """``A1..Am`` (or ``B1..``) placed outward from the plate's centre, clear of the neighbouring hole."""
    c = points_B.mean(axis=0)
    out = points_B + 0.3 * (points_B - c)
    labels = [f"{prefix}{i + 1}" for i in range(len(points_B))]
    return {"type": "scatter3d", "mode": "text", **_xyz(out), "text": labels, "textposition": "middle center",
            "textfont": {"size": 12, "color": color}, "hoverinfo": "skip", "showlegend": False, "scene": scene,
            "name": f"{prefix} holes"}


def _arrow(start: np.ndarray, vec: np.ndarray, color: str, text: str, scene: str, name: str) -> list[dict]:
    tip = start + vec
    line = {"type": "scatter3d", "mode": "lines+text", **_xyz(np.vstack([start, tip])), "text": ["", text],
            "textposition": "top center", "textfont": {"color": color, "size": 12},
            "line": {"color": color, "width": 6}, "name": name, "hoverinfo": "name", "showlegend": False,
            "scene": scene}
    size = 0.25 * float(np.linalg.norm(vec))
    cone = {"type": "cone", **{k: [v] for k, v in zip("xyz", _r(tip))},
            **{k: [v] for k, v in zip("uvw", _r(vec / max(np.linalg.norm(vec), 1e-300)))},
            "anchor": "tip", "sizemode": "absolute", "sizeref": size, "showscale": False,
            "colorscale": [[0, color], [1, color]], "hoverinfo": "skip", "scene": scene, "name": name}
    return [line, cone]


def _ellipsoid(state: RigState, scale: PanelScale, scene: str) -> list[dict]:
    assert state.eigenvalues_Nm_per_rad is not None and state.eigenvectors_A is not None
    w = np.asarray(state.eigenvalues_Nm_per_rad, float)
    V_B = state.R @ state.eigenvectors_A
    semi = scale.ellipsoid_m * w.min() / w            # compliance: long axis = soft direction
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 33), np.linspace(0, np.pi, 17))
    sphere = np.stack([np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)], axis=-1)
    pts = sphere @ (V_B * semi).T
    surf = {"type": "surface", **_xyz(pts), "opacity": 0.45, "showscale": False,
            "colorscale": [[0, "#d62728"], [1, "#ff9896"]], "surfacecolor": _r(pts @ V_B[:, 0] ** 2 / semi[0] ** 2),
            "hoverinfo": "skip", "scene": scene, "name": "compliance ellipsoid", "cmin": 0, "cmax": 1}
    ends = np.concatenate([[-V_B[:, k] * semi[k], V_B[:, k] * semi[k], [np.nan] * 3] for k in range(3)])
    axes = {"type": "scatter3d", "mode": "lines+text", **_xyz(ends.reshape(-1, 3)),
            "text": sum((["", f"λ{k + 1}", ""] for k in range(3)), []), "textposition": "middle right",
            "textfont": {"color": "#8c1c13", "size": 11}, "line": {"color": "#8c1c13", "width": 3},
            "hoverinfo": "skip", "showlegend": False, "scene": scene, "name": "principal axes"}
    return [surf, axes]


def state_traces(state: RigState, scale: PanelScale, scene: str = "scene", colorbar_x: float = 1.0,
                 show_colorbar: bool = True) -> list[dict]:
    """Every trace of one rig at one pose, in the plotly scene ``scene``.

    Parameters
    ----------
    state : RigState
        The rig, pose, load and numbers.
    scale : PanelScale
        Sizes shared by the panel's frames.
    scene : str
        Plotly scene id (``"scene"``, ``"scene2"``, ...).
    colorbar_x : float
        Horizontal position of the tension colour bar (paper coordinates).
    show_colorbar : bool
        Whether this panel draws the colour bar.

    Returns
    -------
    list of dict
        Plotly trace objects (JSON-ready).
    """
    rig, R = state.rig, state.R
    A_B = rig.platform_holes_A_m @ R.T
    B_B = np.asarray(rig.base_holes_B_m, float)
    lo, hi = rig.t_min_N, rig.t_max_N
    traces: list[dict] = []
    traces += _plate(B_B, "base", "#6e7781", scene)
    traces += _plate(A_B, "platform", "#1f77b4", scene)
    m = state.n_cables
    T = np.asarray(state.tensions_N, float)
    ends = np.stack([B_B, A_B, np.full((m, 3), np.nan)], axis=1).reshape(-1, 3)
    hover = [f"cable {i + 1}: {T[i]:.2f} N" + (f" ({state.at_bounds[i]})" if i in state.at_bounds else "")
             for i in range(m)]
    traces.append({
        "type": "scatter3d", "mode": "lines", **_xyz(ends),
        "line": {"color": _r(np.repeat(T, 3)), "colorscale": COLORSCALE, "cmin": lo, "cmax": hi, "width": 9,
                 "showscale": bool(show_colorbar),
                 "colorbar": {"title": {"text": "tension (N)"}, "x": colorbar_x, "len": 0.6, "thickness": 14}},
        "name": "cables", "hovertext": sum(([h, h, ""] for h in hover), []), "hoverinfo": "text",
        "showlegend": False, "scene": scene})
    stuck = [i for i in state.at_bounds if not state.feasible]
    if stuck:   # the cables that cannot hold the load: dashed red overlay
        pts = np.stack([B_B[stuck], A_B[stuck], np.full((len(stuck), 3), np.nan)], axis=1).reshape(-1, 3)
        traces.append({"type": "scatter3d", "mode": "lines", **_xyz(pts),
                       "line": {"color": "#cf222e", "width": 4, "dash": "dash"}, "name": "at a bound",
                       "hoverinfo": "skip", "showlegend": False, "scene": scene})
    traces.append(_hole_labels(A_B, "A", "#0b3d91", scene))
    traces.append(_hole_labels(B_B, "B", "#24292f", scene))
    traces.append({"type": "scatter3d", "mode": "markers+text", "x": [0.0], "y": [0.0], "z": [0.0], "text": ["O"],
                   "textposition": "bottom left", "marker": {"size": 5, "color": "black", "symbol": "diamond"},
                   "name": "joint centre O", "hoverinfo": "name", "showlegend": False, "scene": scene})
    if state.feasible:
        traces += _ellipsoid(state, scale, scene)
    tau = np.asarray(state.tau_ext_A_Nm, float)
    if np.linalg.norm(tau) > 0 and scale.tau_ref_Nm > 0:
        vec = R @ tau / scale.tau_ref_Nm * ARROW_FRACTION * scale.half_width_m / 1.25
        traces += _arrow(np.zeros(3), vec, "#d9480f", f"τ_ext {np.linalg.norm(tau):.3g} N m", scene, "load moment")
    com_B = R @ rig.com_A_m
    weight = rig.platform_mass_kg * float(np.linalg.norm(rig.gravity_B_m_per_s2))
    g_dir = rig.gravity_B_m_per_s2 / max(np.linalg.norm(rig.gravity_B_m_per_s2), 1e-300)
    traces += _arrow(com_B, 0.25 * scale.half_width_m * g_dir, "#2b8a3e", f"weight {weight:.3g} N", scene, "weight")
    return traces
