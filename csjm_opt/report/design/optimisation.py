"""The report of a ``csjm optimise`` result: front, geometry at the worst orientation, certified numbers.

``csjm report DIR`` (DIR holding ``result.json`` and ``design_000.toml``, ...) writes
``index.html`` + ``index.md`` with ``front.png`` (the optimised front: guaranteed
orientation-range scale against the certified smallest stiffness eigenvalue,
with sweep points and the paper's design when given) and ``geometry.png``
(the first design drawn at the orientation where its tightest requirement
binds: holes, cables, the link) into a report folder.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from ..._fileio import atomic_write_json
from ...errors import InvalidInput
from ...model.rig import Rig
from ..document import Cell, Column, Document, Figure, Paragraph, Section, Table, View, sig
from ..render import write_document

__all__ = ["front_figure", "geometry_3d_figure", "load_result", "write_optimisation_report"]


def load_result(result_dir: str | Path) -> dict[str, Any]:
    """Read ``result.json`` of a ``csjm optimise`` output folder.

    Parameters
    ----------
    result_dir : str or Path

    Returns
    -------
    dict

    Raises
    ------
    InvalidInput
        If the folder has no readable ``result.json`` with designs.
    """
    path = Path(result_dir) / "result.json"
    try:
        doc = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise InvalidInput(f"{path}: not a csjm optimise result ({exc})", "RESULTS") from exc
    if not isinstance(doc, dict) or not isinstance(doc.get("designs"), list):
        raise InvalidInput(f"{path}: not a csjm optimise result (no designs)", "RESULTS")
    return doc


def front_figure(doc: dict[str, Any], sweep_points: np.ndarray | None = None,
                 paper_point: tuple[float, float] | None = None, ax: Any = None) -> Any:
    """Optimised designs (range scale, certified stiffness) beside sweep points and the paper's design.

    Parameters
    ----------
    doc : dict
        ``result.json``.
    sweep_points : ndarray, shape (n, 2), optional
        Sweep designs in the same two quantities.
    paper_point : (float, float), optional
        The paper's design.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt

    ax = ax or plt.figure(figsize=(6, 4.5)).add_subplot()
    if sweep_points is not None and len(sweep_points):
        ax.scatter(sweep_points[:, 0], sweep_points[:, 1], s=10, c="0.65", label="sweep designs")
    pts = np.array([[d["objectives"]["range"], d["objectives"]["stiffness"]] for d in doc["designs"]])
    order = np.argsort(pts[:, 0])
    ax.plot(pts[order, 0], pts[order, 1], "o-", c="C0", label="optimised front (certified)")
    if paper_point is not None:
        ax.scatter([paper_point[0]], [paper_point[1]], marker="*", s=160, c="C3", zorder=5, label="paper's design")
    req = doc["requirements"]
    ax.set_xlabel(f"range scale s (tilt <= s x {req['max_tilt_deg']:g} deg, |torsion| <= s x "
                  f"{req['max_torsion_deg']:g} deg)")
    ax.set_ylabel("smallest eigenvalue of K over the range (N m/rad)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def geometry_3d_figure(rig: Rig, R: np.ndarray, ax: Any = None, title: str = "") -> Any:
    """Holes, cables at orientation ``R`` and the link (rod and ball), in {B} (mm).

    Parameters
    ----------
    rig : Rig
    R : ndarray, shape (3, 3)
    ax : matplotlib 3-D Axes, optional
    title : str

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt

    ax = ax or plt.figure(figsize=(6, 6)).add_subplot(projection="3d")
    top = (R @ rig.platform_holes_A_m.T).T * 1e3
    bottom = rig.base_holes_B_m * 1e3
    for i in range(len(top)):
        ax.plot(*np.c_[top[i], bottom[i]], c=f"C{i % 10}", lw=1.5)
        ax.text(*top[i], f"A{i + 1}", fontsize=7)
        ax.text(*bottom[i], f"B{i + 1}", fontsize=7)
    ax.plot(*np.vstack([top, top[:1]]).T, c="0.3", lw=0.8)
    ax.plot(*np.vstack([bottom, bottom[:1]]).T, c="0.3", lw=0.8)
    link = rig.link_or_default
    ax.plot([0, 0], [0, 0], [-link.rod_length_m * 1e3, 0], c="k", lw=max(1.0, link.rod_radius_m * 1e3))
    u, v = np.mgrid[0:2 * np.pi:16j, 0:np.pi:9j]
    r = link.ball_radius_m * 1e3
    ax.plot_wireframe(r * np.cos(u) * np.sin(v), r * np.sin(u) * np.sin(v), r * np.cos(v), color="k", lw=0.4)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.set_title(title, fontsize=9)
    return ax


def _worst(design: dict[str, Any]) -> tuple[str, dict[str, float]]:
    """The requirement with the smallest slack relative to its scale, and where."""
    scale = {"tension": 10.0, "stiffness": 10.0, "cable distance": 0.01, "link clearance": 0.01, "exit angle": 10.0}
    name = min(design["certified"], key=lambda k: design["certified"][k]["slack"]
               / scale.get(k, 1.0))
    return name, design["certified"][name]


def write_optimisation_report(result_dir: str | Path, out_dir: str | Path) -> Path:
    """Write the report of a ``csjm optimise`` folder into ``out_dir``; returns index.html.

    Parameters
    ----------
    result_dir : str or Path
        Folder with ``result.json`` and the design rig files.
    out_dir : str or Path
        Report folder.

    Returns
    -------
    Path
    """
    import matplotlib.pyplot as plt

    from ...design.sampling import tilt_torsion_rotations
    from ..folder import prepare_out_dir

    doc = load_result(result_dir)
    out = prepare_out_dir(Path(out_dir), "csjm optimisation report")
    atomic_write_json(out / "optimisation_report.json", doc)
    ax = front_figure(doc)
    ax.figure.savefig(out / "front.png", dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
    first = doc["designs"][0]
    blocks: list[Any] = []
    rig_file = Path(result_dir) / first.get("rig_file", "design_000.toml")
    if rig_file.is_file():
        name, at = _worst(first)
        R = tilt_torsion_rotations(*(np.radians([at[k]]) for k in ("tilt_deg", "azimuth_deg", "torsion_deg")))[0]
        ax = geometry_3d_figure(Rig.from_toml(rig_file), R, title=f"design_000 where '{name}' binds: tilt "
                                f"{at['tilt_deg']:.1f}, azimuth {at['azimuth_deg']:.1f}, torsion "
                                f"{at['torsion_deg']:.1f} deg")
        ax.figure.savefig(out / "geometry.png", dpi=120, bbox_inches="tight")
        plt.close(ax.figure)
        blocks.append(Figure("geometry.png", "design_000 at the orientation where its tightest requirement "
                                             "binds: holes, cables, the link (rod and ball), mm in {B}."))
        view = _certified_view(doc, Path(result_dir), out)
        if view is not None:
            blocks.append(View(view, "The designs side by side in 3-D (at most four), upright under their weight, "
                                     "each with its certified tilt range as a ring: the platform's centre at tilt "
                                     "s x max_tilt at every azimuth.", 820))
    else:
        blocks.append(Paragraph(f"Geometry not drawn: no rig file {rig_file.name} beside result.json."))
    names = list(doc["variables"])
    cols = [Column("design", fmt="text")] + [Column(n) for n in names] + [
        Column("range scale", fmt="fix3"), Column("min stiffness", "N m/rad"), Column("tension margin", "N"),
        Column("closest cables", "mm", scale=1e3), Column("link clearance", "mm", scale=1e3),
        Column("certified", fmt="text")]
    shaping = any("shaping" in d["objectives"] for d in doc["designs"])
    if shaping:      # the certified smallest LP shaping range, where the objective or the front holds it
        cols.insert(len(names) + 4, Column("shaping range", "N m/rad"))
    rows = []
    req = doc["requirements"]
    for k, d in enumerate(doc["designs"]):
        c = d["certified"]
        rows.append([f"design_{k:03d}"] + [Cell(d["params"][n], src=("designs", k, "params", n)) for n in names] + [
            Cell(d["objectives"]["range"], src=("designs", k, "objectives", "range")),
            Cell(d["objectives"]["stiffness"], src=("designs", k, "objectives", "stiffness")),
            Cell(d["objectives"]["tension_margin"], src=("designs", k, "objectives", "tension_margin"))] + (
            [Cell(d["objectives"]["shaping"], src=("designs", k, "objectives", "shaping"))
             if "shaping" in d["objectives"] else "-"] if shaping else []) + [
            c["cable distance"]["slack"] + req["min_cable_distance_m"],
            c["link clearance"]["slack"] + req["min_link_clearance_m"], "yes" if d["ok"] else "NO"])
    verdict = (f"{len(doc['designs'])} designs, every one re-checked on {doc['certify_orientations']} dense "
               f"orientations plus a local search from the worst; {doc['evaluations']} design evaluations.")
    status = "ok" if all(d["ok"] for d in doc["designs"]) else "warn"
    sections = [
        Section("Optimised front", verdict, status, [
            Figure("front.png", "Certified range scale against certified smallest stiffness eigenvalue."),
            Table(cols, rows, caption=f"objective: {doc['objective']}"
                  + (f", front against {doc['pareto_with']}" if doc.get("pareto_with") else ""))]),
        Section("Geometry at the worst orientation", "", "info", blocks),
        Section("Requirements certified", "", "info", [Paragraph(
            f"Tilt up to s x {req['max_tilt_deg']:g} deg, torsion up to s x {req['max_torsion_deg']:g} deg; "
            f"{len(req['loads'])} loads (N m in {{A}}): {req['loads']}; "
            f"tension margin {sig(req['tension_margin_N'])} N; "
            f"smallest K eigenvalue at least {sig(req['min_stiffness_Nm_per_rad'])} N m/rad (or the front's value); "
            f"cables at least {sig(req['min_cable_distance_m'] * 1e3)} mm apart and "
            f"{sig(req['min_link_clearance_m'] * 1e3)} mm from the link; exit angle at most "
            f"{sig(req['max_exit_angle_deg'])} deg.")])]
    return write_document(Document("Hole-geometry optimisation", f"Result folder `{Path(result_dir).name}`.",
                                   sections, data_file="optimisation_report.json"), out)


def _certified_view(doc: dict[str, Any], result_dir: Path, out: Path) -> str | None:
    """``designs.html``: the designs with rig files (at most four) side by side, certified tilt range as a ring."""
    from ...view import designs_view

    picked = []
    for k, d in enumerate(doc["designs"][:4]):
        path = result_dir / d.get("rig_file", f"design_{k:03d}.toml")
        if path.is_file():
            picked.append((f"design_{k:03d}", Rig.from_toml(path),
                           float(d["objectives"]["range"]) * float(doc["requirements"]["max_tilt_deg"])))
    if not picked:
        return None
    page = designs_view([r for _, r, _ in picked], [lab for lab, _, _ in picked],
                        certified_tilt_deg=[t for _, _, t in picked],
                        title="Optimised designs side by side (upright, under their weight)",
                        note="Green ring: the certified tilt range (range scale s x max_tilt), where the platform's "
                             "centre goes at its edge, at every azimuth.")
    page.write(out / "designs.html")
    return "designs.html"
