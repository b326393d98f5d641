"""The design-study page (document model) built from the report's numbers."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..document import (
    Block,
    Cell,
    Column,
    Document,
    Figure,
    Hyperlink,
    Paragraph,
    Section,
    Table,
    View,
    quantity_table,
    sig,
)
from .study import X_KEY, Y_KEY


def _unit(name: str) -> tuple[str, str, float]:
    """(label, unit, scale) of a design parameter for a table column."""
    for suffix, unit, scale in (("_deg", "deg", 1.0), ("_m", "mm", 1e3), ("_N_per_m", "N/m", 1.0), ("_N", "N", 1.0),
                                ("_kg", "kg", 1.0)):
        if name.endswith(suffix):
            return name[: -len(suffix)], unit, scale
    return name, "", 1.0


def document(s: dict[str, Any], geometry: bool, view: str | None = None) -> Document:
    """The design-study page of :meth:`DesignStudy.summary` output ``s`` (``view``: the 3-D page beside it)."""
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
        blocks: list[Block] = [Figure("geometry.png", "Top view of each design: platform holes A_i, base holes "
                                                      "B_i, cables between them (mm).")]
        if view:
            blocks.append(View(view, "The best designs side by side in 3-D, cables coloured by planned tension, "
                                     "compliance ellipsoid of K at O (long axis = soft direction), and each design's "
                                     "tilt cone as a ring.", 820))
        sections.append(Section("Geometry of the best designs", "Holes of the table's designs on the platform "
                                 "(circle) and base (square) hole circles, seen from above at the home pose.", "info",
                                 blocks))
    else:
        sections.append(Section("Geometry of the best designs", "", "info", [Paragraph(
            "Not drawn: the designs' geometry needs the sweep's fixed parameters (give --sweep SWEEP.toml).")]))
    invalid = s["invalid_designs"] + s["failed_designs"]
    lead = (f"Design sweep results `{Path(s['results']).name}`" + (f" ({invalid} invalid or failed designs left out)"
                                                                   if invalid else "") + ".")
    return Document("Design study", lead, sections, data_file="design_report.json",
                    links=[Hyperlink("design_report.json", "design_report.json", "every number of this page")])
