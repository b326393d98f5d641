"""The design-study report of ``csjm sweep`` results (``csjm report RESULTS``).

The Pareto front of workspace fraction against minimum stiffness (every
design, the front, the paper's design marked), the best designs in a table,
and their hole geometry drawn on the two circles. Written as ``index.html``
+ ``index.md`` with ``pareto.png``, ``geometry.png`` and ``design_report.json``
(every number of the page) into a report folder.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from .. import _plotting as plots
from .._fileio import atomic_write_json
from ..design.geometry import design_holes
from ..design.store import read_records, unique_records
from ..errors import CsjmError, DesignError
from .document import Cell, Column, Document, Figure, Link, Paragraph, Section, Table, quantity_table, sig
from .render import write_document

X_KEY, Y_KEY = "workspace_fraction", "min_stiffness_Nm_per_rad"


def pareto_mask(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Designs that no other design beats in both ``x`` and ``y`` (both maximised).

    Parameters
    ----------
    x, y : (n,) arrays

    Returns
    -------
    (n,) bool array
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    better_eq = (x[None, :] >= x[:, None]) & (y[None, :] >= y[:, None])
    strictly = (x[None, :] > x[:, None]) | (y[None, :] > y[:, None])
    return ~np.any(better_eq & strictly, axis=1)


def pareto_layers(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Layer of each design: 1 for the Pareto front, 2 for the front of the rest, and so on."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    layer = np.zeros(len(x), int)
    k = 0
    while np.any(layer == 0):
        k += 1
        left = np.flatnonzero(layer == 0)
        layer[left[pareto_mask(x[left], y[left])]] = k
    return layer


@dataclasses.dataclass
class DesignStudy:
    """Valid designs of a sweep, their Pareto front and (when known) the paper's design."""

    records: list[dict[str, Any]]            # every record of the result file
    ok: list[dict[str, Any]]                 # valid designs with both metrics
    front: np.ndarray                        # indices into ``ok``, by increasing workspace
    layers: np.ndarray                       # Pareto layer of each design of ``ok`` (1: the front)
    base: dict[str, Any]                     # fixed design parameters (sweep file's [base])
    paper: dict[str, Any] | None             # the paper design's record (evaluated or found), if any
    source: str

    def summary(self, top: int) -> dict[str, Any]:
        """JSON-able numbers of the report (``design_report.json``)."""
        x = np.array([r[X_KEY] for r in self.ok])
        ranked = sorted(range(len(self.ok)), key=lambda i: (self.layers[i], -x[i]))
        best = [{**_row(self.ok[i]), "pareto_layer": int(self.layers[i])} for i in ranked[:top]]
        out: dict[str, Any] = {
            "results": self.source, "designs": len(self.records), "valid_designs": len(self.ok),
            "invalid_designs": sum(r.get("status") == "invalid" for r in self.records),
            "failed_designs": sum(r.get("status") == "error" for r in self.records),
            "base": self.base, "pareto_front_size": int(len(self.front)),
            "best": best, "pareto_front": [_row(self.ok[i]) for i in self.front]}
        if self.paper is not None:
            x = np.array([r[X_KEY] for r in self.ok])
            y = np.array([r[Y_KEY] for r in self.ok])
            px, py = self.paper[X_KEY], self.paper[Y_KEY]
            dominating = int(np.sum((x >= px) & (y >= py) & ((x > px) | (y > py))))
            out["paper_design"] = {**_row(self.paper), "designs_dominating_it": dominating,
                                   "on_pareto_front": dominating == 0,
                                   "workspace_percentile": float(100 * np.mean(x <= px)),
                                   "min_stiffness_percentile": float(100 * np.mean(y <= py))}
        return out


def _row(r: dict[str, Any]) -> dict[str, Any]:
    m = r.get("metrics") or {}
    return {"params": r.get("params", {}), X_KEY: r[X_KEY], Y_KEY: r[Y_KEY],
            "tilt_cone_deg": m.get("tilt_cone_deg"),
            "median_min_stiffness_Nm_per_rad": m.get("median_min_stiffness_Nm_per_rad")}


def load_study(results: str | Path, sweep: str | Path | None = None) -> DesignStudy:
    """Read a result file; with the sweep file, also evaluate the paper's design under the same settings.

    Parameters
    ----------
    results : str or Path
        ``csjm sweep --out`` file (JSON Lines).
    sweep : str or Path, optional
        The sweep description the results came from: gives the fixed ``[base]`` parameters (to draw
        the geometry) and the settings to evaluate the paper's design with. Without it the base is
        taken as the paper's and the paper's design is marked only when it is among the results.

    Returns
    -------
    DesignStudy

    Raises
    ------
    DesignError
        No result file, no valid design, or a sweep file whose settings differ from the results'.
    """
    records = list(unique_records(read_records(results)[0])[0].values())  # repeated lines count once
    if not records:
        raise DesignError("no designs in the result file (run csjm sweep first)", "RESULTS", str(results))
    ok = [r for r in records if r.get("status") == "ok" and r.get(X_KEY) is not None and r.get(Y_KEY) is not None]
    if not ok:
        raise DesignError("no valid design with a non-empty workspace in the results", "RESULTS", str(results))
    base: dict[str, Any] = {}
    paper = None
    if sweep is not None:
        from ..design.sweep import evaluate_design
        from ..design.sweep_file import SweepSpec

        spec = SweepSpec.from_toml(sweep)
        if any(r.get("settings") != spec.settings.digest() for r in records):
            raise DesignError("the results were evaluated with other settings than this sweep file", "--sweep",
                              str(sweep))
        base = dict(spec.settings.base)
        record = evaluate_design({}, dataclasses.replace(spec.settings, base={}))
        paper = record if record["status"] == "ok" and record[Y_KEY] is not None else None
    else:
        paper_holes = design_holes({})
        for r in ok:
            try:
                holes = design_holes({**base, **r["params"]})
            except CsjmError:
                continue
            if all(np.allclose(a, b, atol=1e-9) for a, b in zip(holes, paper_holes)):
                paper = r
                break
    x = np.array([r[X_KEY] for r in ok])
    y = np.array([r[Y_KEY] for r in ok])
    layers = pareto_layers(x, y)
    front = np.flatnonzero(layers == 1)
    front = front[np.argsort(x[front], kind="stable")]
    if paper is not None and sweep is not None:
        names = list(dict.fromkeys(k for r in ok for k in r["params"]))
        paper = {**paper, "params": {n: paper_value(n) for n in names}}
    return DesignStudy(records, ok, front, layers, base, paper, str(results))


def paper_value(name: str) -> float | None:
    """The paper design's value of a design parameter (circle radius and gamma derived from its chords)."""
    from ..design.geometry import PAPER_DESIGN
    from ..model import hexagon

    if name in PAPER_DESIGN:
        return float(PAPER_DESIGN[name])
    body = name.split("_", 1)[0]
    if body not in ("platform", "base"):
        return 0.0 if name[:1] in "AB" and name.endswith("_m") else None   # per-hole offsets
    chords = hexagon.PAPER_PLATFORM_CHORDS_M if body == "platform" else hexagon.PAPER_BASE_CHORDS_M
    radius, gamma = hexagon.circle_from_chords(*chords)
    if name.endswith("_radius_m"):
        return float(radius)
    if name.endswith("_gamma_deg"):
        return float(np.degrees(gamma))
    return None


def pareto_figure(study: DesignStudy, best: list[dict], path: Path, ax=None):
    """Workspace against minimum stiffness: every design, the front, the best numbered, the paper starred."""
    plt = plots.figure()
    fig = None
    if ax is None:
        fig, ax = plt.subplots(figsize=(7.5, 5.5), constrained_layout=True)
    x = np.array([r[X_KEY] for r in study.ok])
    y = np.array([r[Y_KEY] for r in study.ok])
    ax.scatter(x, y, s=14, color="0.6", label=f"designs ({len(study.ok)} valid)")
    f = study.front
    ax.plot(x[f], y[f], "o-", color="tab:red", ms=5, label="Pareto front")
    for k, r in enumerate(best, start=1):
        ax.annotate(str(k), (r[X_KEY], r[Y_KEY]), textcoords="offset points", xytext=(5, 5), fontsize=9)
    if study.paper is not None:
        ax.scatter([study.paper[X_KEY]], [study.paper[Y_KEY]], marker="*", s=260, color="gold", edgecolor="black",
                   zorder=5, label="paper's design")
    ax.set_xlabel("workspace fraction (wrench-feasible orientations, all loads)")
    ax.set_ylabel("minimum stiffness over the workspace (N m/rad)")
    ax.set_title("Workspace against minimum stiffness (numbers: the table's best designs)")
    ax.legend(loc="best", fontsize=8)
    if fig is not None:
        plots.save(fig, path)
    return ax


def geometry_figure(designs: list[tuple[str, dict]], path: Path) -> Path | None:
    """Top view (x-y, mm) of each design's holes on the platform and base circles, cables as lines.

    ``designs``: (label, complete design parameters) pairs; designs whose geometry cannot be built are skipped.
    """
    drawn = []
    for label, params in designs:
        try:
            drawn.append((label, *design_holes(params)))
        except CsjmError:
            continue
    if not drawn:
        return None
    plt = plots.figure()
    n = len(drawn)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.3 * rows), squeeze=False, constrained_layout=True)
    t = np.linspace(0, 2 * np.pi, 200)
    for ax, (label, A, B) in zip(axes.flat, drawn):
        for holes, name, marker, color in ((A, "platform holes A_i", "o", "tab:blue"),
                                           (B, "base holes B_i", "s", "tab:orange")):
            r = 1e3 * float(np.mean(np.linalg.norm(holes[:, :2], axis=1)))
            ax.plot(r * np.cos(t), r * np.sin(t), color=color, lw=0.8, alpha=0.5)
            ax.scatter(1e3 * holes[:, 0], 1e3 * holes[:, 1], marker=marker, color=color, zorder=3, label=name)
            for i, (hx, hy) in enumerate(1e3 * holes[:, :2]):
                ax.annotate(str(i + 1), (hx, hy), textcoords="offset points", xytext=(4, 3), fontsize=7, color=color)
        for a, b in zip(A, B):
            ax.plot(1e3 * np.array([a[0], b[0]]), 1e3 * np.array([a[1], b[1]]), color="0.4", lw=0.8)
        ax.set_aspect("equal")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    for ax in list(axes.flat)[n:]:
        ax.set_visible(False)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=2, fontsize=9)
    fig.suptitle("Hole positions seen from above (home pose; grey: cables A_i B_i)")
    return plots.save(fig, path)


def _unit(name: str) -> tuple[str, str, float]:
    """(label, unit, scale) of a design parameter for a table column."""
    for suffix, unit, scale in (("_deg", "deg", 1.0), ("_m", "mm", 1e3), ("_N_per_m", "N/m", 1.0), ("_N", "N", 1.0),
                                ("_kg", "kg", 1.0)):
        if name.endswith(suffix):
            return name[: -len(suffix)], unit, scale
    return name, "", 1.0


def document(s: dict[str, Any], geometry: bool) -> Document:
    """The design-study page of :meth:`DesignStudy.summary` output ``s``."""
    names = list(dict.fromkeys(k for d in s["best"] for k in d["params"]))
    paper = s.get("paper_design")
    best = s["best"]
    text = (f"{s['designs']} designs, {s['valid_designs']} valid with a non-empty workspace; {s['pareto_front_size']} "
            f"of them on the Pareto front of workspace fraction against minimum stiffness (no other design is better "
            f"in both). Largest workspace {sig(max(d[X_KEY] for d in s['pareto_front']))}, stiffest "
            f"{sig(max(d[Y_KEY] for d in s['pareto_front']))} N m/rad. ")
    status = "info"
    if paper is not None:
        if paper["on_pareto_front"]:
            text += "The paper's design is on the front: no design of this sweep beats it in both."
            status = "ok"
        else:
            text += (f"The paper's design (workspace {sig(paper[X_KEY])}, minimum stiffness {sig(paper[Y_KEY])} "
                     f"N m/rad) is dominated by {paper['designs_dominating_it']} designs.")
            status = "warn"
    else:
        text += "The paper's design is not among the results (give --sweep SWEEP.toml to evaluate and mark it)."
    cols = [Column("design", fmt="int"), Column("Pareto layer", fmt="int")]
    cols += [Column(*_unit(n)[:2], scale=_unit(n)[2]) for n in names] + [
        Column("workspace fraction", fmt="fix3"), Column("min stiffness", "N m/rad"), Column("tilt cone", "deg"),
        Column("median min stiffness", "N m/rad")]
    keys = (X_KEY, Y_KEY, "tilt_cone_deg", "median_min_stiffness_Nm_per_rad")
    rows: list[list[Any]] = [[k + 1, Cell(d["pareto_layer"], src=("best", k, "pareto_layer"))]
            + [Cell(d["params"].get(n), src=("best", k, "params", n)) for n in names]
            + [Cell(d[key], src=("best", k, key)) for key in keys] for k, d in enumerate(best)]
    if paper is not None:
        rows.append(["paper", None] + [Cell(paper["params"].get(n), src=("paper_design", "params", n))
                                       if n in paper["params"] else None for n in names]
                    + [Cell(paper[key], src=("paper_design", key)) for key in keys])
    front = Section("Pareto front", text, status, [
        Table(cols, rows, "Best designs: by Pareto layer (1: the front; 2: the front once it is removed; ...), "
                          "then by workspace (the whole front: design_report.json)"),
        Figure("pareto.png", "Every valid design (grey), the Pareto front (red), the table's designs numbered"
               + (", the paper's design starred." if paper is not None else "."))])
    sections = [front]
    if paper is not None:
        sections.append(Section("Where the paper's design sits", "", "info", [quantity_table([
            ("workspace fraction", Cell(paper[X_KEY], "fix3", src=("paper_design", X_KEY)), "", ""),
            ("percentile of workspace", Cell(paper["workspace_percentile"], "fix0",
                                             src=("paper_design", "workspace_percentile")), "%", ""),
            ("minimum stiffness", Cell(paper[Y_KEY], src=("paper_design", Y_KEY)), "N m/rad", ""),
            ("percentile of minimum stiffness", Cell(paper["min_stiffness_percentile"], "fix0",
                                                     src=("paper_design", "min_stiffness_percentile")), "%", ""),
            ("designs better in both", Cell(paper["designs_dominating_it"], "int",
                                            src=("paper_design", "designs_dominating_it")), "", ""),
        ])]))
    if geometry:
        sections.append(Section("Geometry of the best designs", "Holes of the table's designs on the platform "
                                 "(circle) and base (square) hole circles, seen from above at the home pose.", "info",
                                 [Figure("geometry.png", "Top view of each design: platform holes A_i, base holes "
                                                         "B_i, cables between them (mm).")]))
    else:
        sections.append(Section("Geometry of the best designs", "", "info", [Paragraph(
            "Not drawn: the designs' geometry needs the sweep's fixed parameters (give --sweep SWEEP.toml).")]))
    invalid = s["invalid_designs"] + s["failed_designs"]
    lead = (f"Design sweep results `{Path(s['results']).name}`" + (f" ({invalid} invalid or failed designs left out)"
                                                                   if invalid else "") + ".")
    return Document("Design study", lead, sections, data_file="design_report.json",
                    links=[Link("design_report.json", "design_report.json", "every number of this page")])


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
    """
    from .demo import prepare_out_dir

    if top < 1:
        raise DesignError(f"expected an integer >= 1, got {top}", "--top")
    study = load_study(results, sweep)
    out = prepare_out_dir(Path(out_dir), "csjm design study")
    s = study.summary(top)
    atomic_write_json(out / "design_report.json", s)
    pareto_figure(study, s["best"], out / "pareto.png")
    shown = [(f"design {k + 1}: workspace {sig(d[X_KEY])}, min K {sig(d[Y_KEY])} N m/rad",
              {**study.base, **d["params"]}) for k, d in enumerate(s["best"][:5])]
    if study.paper is not None:
        shown.append(("paper's design", {} if sweep is not None else study.paper["params"]))
    geometry = geometry_figure(shown, out / "geometry.png") is not None
    return write_document(document(s, geometry), out)
