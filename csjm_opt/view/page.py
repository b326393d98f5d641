"""The self-contained 3-D view page: plotly.js inlined, frames of rig states, numbers from the toolkit.

A page holds one or more *frames* (poses, cycles of a log, designs of a sweep), chosen with a
slider; each frame holds one or more *panels* drawn side by side, each one rig at one pose
(:class:`~csjm_opt.view.state.RigState`). Every number the page shows (tensions, K's
eigenvalues, the pose, the load, the verdict) is formatted here, in Python, from the toolkit's
results and embedded per frame; the page's script only swaps them in and redraws.
"""

from __future__ import annotations

import html
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .. import so3
from .._fileio import atomic_write_text
from .plotly_js import plotly_js_gzip_base64
from .state import RigState
from .traces import PanelScale, panel_scale, state_traces

__all__ = ["TENSION_DECIMALS", "EIGENVALUE_DECIMALS", "ViewPage", "view_page"]

#: Decimals the page shows for tensions (N) and K's eigenvalues (N m/rad).
TENSION_DECIMALS = 2
EIGENVALUE_DECIMALS = 2
PLOT_HEIGHT_PX = 560


class ViewPage:
    """One self-contained HTML page (``.html``); in a notebook it shows itself in an iframe.

    Attributes
    ----------
    html : str
        The whole page.
    frames : list of list of RigState
        The states shown, ``frames[f][p]`` for frame ``f``, panel ``p``.
    frame_labels : list of str
    note : str
        The sentence under the title (what is drawn besides the rig).
    """

    def __init__(self, html_text: str, frames: list[list[RigState]], frame_labels: list[str], note: str = ""):
        self.html = html_text
        self.frames = frames
        self.frame_labels = frame_labels
        self.note = note

    def write(self, path: str | Path) -> Path:
        """Write the page atomically (readable by others) and return its path."""
        return atomic_write_text(path, self.html)

    def _repr_html_(self) -> str:
        height = PLOT_HEIGHT_PX + 330
        return (f'<iframe srcdoc="{html.escape(self.html, quote=True)}" style="width:100%;height:{height}px;'
                f'border:1px solid #ddd" sandbox="allow-scripts"></iframe>')

    def __len__(self) -> int:
        return len(self.html.encode("utf-8"))


def _fmt(x: float, decimals: int) -> str:
    return f"{x:.{decimals}f}"


def _numbers_html(state: RigState, title: str, panel: int) -> str:
    rig = state.rig
    e = html.escape
    rows = []
    for i in range(state.n_cables):
        bound = state.at_bounds.get(i, "")
        rows.append(f'<tr><td>{i + 1}</td><td class="num" data-q="tension" data-i="{i + 1}">'
                    f'{_fmt(float(state.tensions_N[i]), TENSION_DECIMALS)}</td><td>{e(bound)}</td></tr>')
    if state.eigenvalues_Nm_per_rad is not None:
        eig = " ".join(f'<span class="num" data-q="eig" data-i="{k + 1}">'
                       f'{_fmt(float(v), EIGENVALUE_DECIMALS)}</span>'
                       for k, v in enumerate(state.eigenvalues_Nm_per_rad))
        w = state.eigenvalues_Nm_per_rad
        eig_line = (f"<p>K's eigenvalues (N m/rad): {eig}; stiffest/softest {w.max() / w.min():.2f}:1. "
                    "Ellipsoid: compliance, axes &prop; 1/&lambda;.</p>")
    else:
        eig_line = "<p>K's eigenvalues: none (the load is not held, so the rig has no equilibrium here).</p>"
    rv = np.round(so3.log(state.R), 4).tolist()
    tau = np.round(state.tau_ext_A_Nm, 4).tolist()
    status = "ok" if state.feasible else "bad"
    tension_head = "tension (N)" if state.feasible else "nearest tension (N)"
    return (f'<div class="panel" data-panel="{panel}"><h3>{e(title)}</h3>'
            f'<p class="status {status}" data-q="status">{e(state.message)}</p>'
            f"<p>pose rotvec {rv} rad, load &tau;<sub>ext</sub> {tau} N m in {{A}}; "
            f"bounds [{rig.t_min_N:g}, {rig.t_max_N:g}] N</p>"
            f"<table><tr><th>cable</th><th>{tension_head}</th><th>bound</th></tr>{''.join(rows)}</table>"
            f"{eig_line}</div>")


def _layout(n_panels: int, scales: list[PanelScale], titles: list[str]) -> dict:
    layout: dict = {"height": PLOT_HEIGHT_PX, "margin": {"l": 0, "r": 0, "t": 30, "b": 0},
                    "showlegend": False, "uirevision": "keep", "paper_bgcolor": "white", "annotations": []}
    for p, sc in enumerate(scales):
        name = "scene" if p == 0 else f"scene{p + 1}"
        h = sc.half_width_m
        ax = {"range": [-h, h], "showbackground": True, "backgroundcolor": "#f6f8fa", "zeroline": False}
        layout[name] = {
            "domain": {"x": [p / n_panels, (p + 1) / n_panels - 0.06 / n_panels], "y": [0, 1]},
            "aspectmode": "cube", "uirevision": "keep",
            "xaxis": {**ax, "title": {"text": "x_B (m)"}}, "yaxis": {**ax, "title": {"text": "y_B (m)"}},
            "zaxis": {**ax, "title": {"text": "z_B (m)"}},
            "camera": {"eye": {"x": 1.1, "y": -1.1, "z": 0.6}}}
        layout["annotations"].append({"text": titles[p], "x": (p + 0.47) / n_panels, "y": 1.0, "xref": "paper",
                                      "yref": "paper", "showarrow": False, "yanchor": "bottom",
                                      "font": {"size": 13}})
    return layout


_SCRIPT = r"""
const CSJM = JSON.parse(document.getElementById('csjm-data').textContent);
async function csjmLoadPlotly() {
  const b64 = document.getElementById('csjm-plotly').textContent.trim();
  const bin = Uint8Array.fromBase64 ? Uint8Array.fromBase64(b64) : Uint8Array.from(atob(b64), c => c.charCodeAt(0));
  const stream = new Blob([bin]).stream().pipeThrough(new DecompressionStream('gzip'));
  (0, eval)(await new Response(stream).text());
}
function csjmShow(i) {
  const f = CSJM.frames[i];
  document.getElementById('numbers').innerHTML = f.numbers;
  document.getElementById('frame-label').textContent = f.label;
  document.getElementById('frame').value = String(i);
  return Plotly.react('plot', f.traces, CSJM.layout, CSJM.config).then(() => {
    document.body.dataset.frame = String(i);
  });
}
window.csjmView = {show: csjmShow, nFrames: CSJM.frames.length};
csjmLoadPlotly().then(() => {
  document.getElementById('frame').addEventListener('input', e => csjmShow(Number(e.target.value)));
  return csjmShow(CSJM.initial);
}).then(() => { document.body.dataset.ready = '1'; }).catch(err => {
  document.getElementById('plot').textContent = '3-D view unavailable: ' + err;
  console.error('csjm view:', err);
});
"""

_STYLE = """
body { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; margin: 0.6rem 1rem; color: #1d2125; }
h1 { font-size: 1.2rem; margin: 0.2rem 0; } h3 { font-size: 1rem; margin: 0.3rem 0; }
#controls { display: flex; gap: 1rem; align-items: center; margin: 0.3rem 0; }
#frame { width: 22rem; }
#numbers { display: flex; gap: 1.5rem; flex-wrap: wrap; font-size: 0.88rem; }
.panel { flex: 1 1 18rem; }
table { border-collapse: collapse; } th, td { border: 1px solid #d0d7de; padding: 0.1rem 0.45rem; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.status.ok { color: #1a7f37; } .status.bad { color: #cf222e; font-weight: 600; }
"""


def view_page(frames: Sequence[Sequence[RigState]], title: str = "csjm view",
              frame_labels: Sequence[str] | None = None, panel_titles: Sequence[str] | None = None,
              initial: int = 0, note: str = "", extras: Sequence[Sequence[dict]] | None = None) -> ViewPage:
    """A self-contained page of rig states: ``frames[f][p]`` is frame ``f``'s panel ``p``.

    Parameters
    ----------
    frames : sequence of sequences of RigState
        Every frame has the same number of panels (1 for a pose path, k for k designs side by side).
    title : str
        Page title.
    frame_labels : sequence of str, optional
        Slider labels (default: each frame's first state's label, else its index).
    panel_titles : sequence of str, optional
        Titles above the panels (default: the states' labels in the initial frame).
    initial : int
        Frame shown first.
    note : str
        A sentence under the title (plain text).
    extras : sequence of sequences of dict, optional
        Per panel, plotly traces drawn in every frame (e.g. a workspace boundary); their
        ``scene`` is set to the panel's.

    Returns
    -------
    ViewPage
    """
    frames_: list[list[RigState]] = [list(f) for f in frames]
    frames = frames_
    if not frames or not frames[0]:
        from ..errors import InvalidInput

        raise InvalidInput("a view needs at least one frame with one panel", "frames")
    n_panels = len(frames[0])
    if any(len(f) != n_panels for f in frames):
        from ..errors import InvalidInput

        raise InvalidInput("every frame of a view needs the same number of panels", "frames")
    labels = list(frame_labels) if frame_labels is not None else [f[0].label or f"frame {i}"
                                                                    for i, f in enumerate(frames)]
    initial = int(min(max(initial, 0), len(frames) - 1))
    titles = list(panel_titles) if panel_titles is not None else [s.label for s in frames[initial]]
    scales = [panel_scale([f[p] for f in frames]) for p in range(n_panels)]
    data_frames = []
    for i, f in enumerate(frames):
        traces: list[dict] = []
        for p, s in enumerate(f):
            scene = "scene" if p == 0 else f"scene{p + 1}"
            traces += state_traces(s, scales[p], scene, colorbar_x=(p + 1) / n_panels - 0.05 / n_panels,
                                   show_colorbar=p == n_panels - 1)
            if extras is not None:
                traces += [{**t, "scene": scene} for t in extras[p]]
        numbers = "".join(_numbers_html(s, titles[p] if len(frames) == 1 else (s.label or titles[p]), p)
                          for p, s in enumerate(f))
        data_frames.append({"label": labels[i], "traces": traces, "numbers": numbers})
    data = {"frames": data_frames, "layout": _layout(n_panels, scales, titles), "initial": initial,
            "config": {"displaylogo": False, "responsive": True, "showLink": False, "showSendToCloud": False,
                       "modeBarButtonsToRemove": ["toImage"], "scrollZoom": True}}
    data_json = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("</", "<\\/")
    slider_style = "" if len(frames) > 1 else ' style="display:none"'
    e = html.escape
    text = (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{e(title)}</title>'
            f"<style>{_STYLE}</style></head><body>\n<h1>{e(title)}</h1>"
            + (f"<p>{e(note)}</p>" if note else "")
            + f'<div id="controls"><span{slider_style}>pose <input id="frame" type="range" min="0" '
            f'max="{len(frames) - 1}" step="1" value="{initial}"></span>'
            f'<span id="frame-label">{e(labels[initial])}</span>'
            f"<span>drag to rotate, scroll to zoom; cables coloured by tension (N), holes numbered as in "
            f"the rig file</span></div>\n"
            f'<div id="plot" style="width:100%;height:{PLOT_HEIGHT_PX}px"></div>\n'
            f'<div id="numbers">{data_frames[initial]["numbers"]}</div>\n'
            f'<script type="application/json" id="csjm-data">{data_json}</script>\n'
            f'<script type="text/plain" id="csjm-plotly">{plotly_js_gzip_base64()}</script>\n'
            f"<script>{_SCRIPT}</script>\n</body></html>\n")
    return ViewPage(text, frames_, labels, note)
