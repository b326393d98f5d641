"""The design-study report of ``csjm sweep`` results (``csjm report RESULTS``).

The Pareto front of workspace fraction against minimum stiffness (every
design, the front, the paper's design marked), the best designs in a table,
and their hole geometry drawn on the two circles. Written as ``index.html``
+ ``index.md`` with ``pareto.png``, ``geometry.png`` and ``design_report.json``
(every number of the page) into a report folder.
"""

from __future__ import annotations

from pathlib import Path

from ... import _plotting as plots
from ..._fileio import atomic_write_json
from ...errors import DesignError
from ..document import sig
from ..folder import prepare_out_dir
from ..render import write_document
from .figures import geometry_figure, pareto_figure
from .page import document
from .study import X_KEY, Y_KEY, DesignStudy, load_study, paper_value, pareto_layers, pareto_mask

__all__ = ["DesignStudy", "X_KEY", "Y_KEY", "document", "geometry_figure", "load_study", "paper_value",
           "pareto_figure", "pareto_layers", "pareto_mask", "write_design_report"]


def write_design_report(results: str | Path, out_dir: str | Path, sweep: str | Path | None = None,
                        top: int = 8) -> Path:
    """Write the design-study report of a ``csjm sweep`` result file into ``out_dir``; returns index.html.

    Parameters
    ----------
    results : str or Path
        Result file (JSON Lines).
    out_dir : str or Path
        Report folder (created; a non-empty folder must be a previous report).
    sweep : str or Path, optional
        The sweep file of the results (see :func:`load_study`).
    top : int
        Best designs shown in the table and drawn.

    Returns
    -------
    Path
        The report's ``index.html``.

    Raises
    ------
    DesignError
        ``top`` below 1, no result file or no valid design in it, or a sweep file whose
        settings differ from the results' (see :func:`load_study`).
    """
    if top < 1:
        raise DesignError(f"expected an integer >= 1, got {top}", "--top")
    study = load_study(results, sweep)
    out = prepare_out_dir(Path(out_dir), "csjm design study")
    s = study.summary(top)
    atomic_write_json(out / "design_report.json", s)
    plots.save(pareto_figure(study, s["best"]).figure, out / "pareto.png")
    shown = [(f"design {k + 1}: workspace {sig(d[X_KEY])}, min K {sig(d[Y_KEY])} N m/rad",
              {**study.base, **d["params"]}) for k, d in enumerate(s["best"][:5])]
    if study.paper is not None:
        shown.append(("paper's design", {} if sweep is not None else study.paper["params"]))
    geometry_fig = geometry_figure(shown)
    geometry = geometry_fig is not None
    view = None
    if geometry_fig is not None:
        plots.save(geometry_fig, out / "geometry.png")
        view = _designs_view(s, study, sweep, out)
    return write_document(document(s, geometry, view), out)


def _designs_view(s: dict, study: DesignStudy, sweep: str | Path | None, out: Path) -> str | None:
    """``designs.html``: the best designs (at most 4) and the paper's side by side, each with its tilt cone."""
    from ...design.geometry import design_rig
    from ...view import designs_view

    picked = [(f"design {k + 1}", {**study.base, **d["params"]}, d.get("tilt_cone_deg"))
              for k, d in enumerate(s["best"][:4])]
    if study.paper is not None:
        paper = s.get("paper_design", {})
        picked.append(("paper's design", {} if sweep is not None else study.paper["params"],
                       paper.get("tilt_cone_deg")))
    try:
        rigs = [design_rig(p) for _, p, _ in picked]
    except DesignError:
        return None
    cones = [float(c) if c is not None else 0.0 for _, _, c in picked]
    page = designs_view(rigs, [lab for lab, _, _ in picked], certified_tilt_deg=cones,
                        title="The best designs side by side (upright, under their weight)",
                        note="Green ring: where the platform's centre goes at the edge of the design's tilt cone "
                             "(the sweep's tilt_cone_deg: every tilt within it, at any azimuth, holds the sweep's "
                             "loads).")
    page.write(out / "designs.html")
    return "designs.html"
