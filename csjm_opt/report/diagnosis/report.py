"""The diagnosis report as a document, built from ``diagnosis.json`` (``csjm diagnose --report``).

Leads with the verdict in one sentence (effect, gap before/after in mrad,
share of the systematic gap closed, confidence) and the figures that show
it; then the candidates, the selected effect's parameters with units and
standard errors, where the gap lies, and the second-effect search. Keys that
only newer diagnoses carry (``pairs``, ``plausible``, ``implausible_params``,
the verdict ``unexplained``) are shown when present.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ... import _plotting as plots
from ..._fileio import atomic_write_json
from ...diagnose import Diagnosis
from ...diagnose.selection.decision import ALPHA
from ...model.rig import Rig
from ..document import Document, Figure, Hyperlink, Paragraph, Section, View, format_number, sig
from ..render import write_document
from .figures import before_after, candidate_errors, hysteresis_loops, residual_map
from .sections import _candidates, _gap_table, _parameters, _secondary_and_pairs, _where, unit_of
from .verdict import headline

FIGURES = (("residual_map.png", "Held-out residual over the pose (tilt and azimuth), nominal model and selected "
                                "model, same colour scale."),
           ("hysteresis.png", "Residual along its main axis against the load, for a few cycles: loading and "
                              "unloading branches apart mean hysteresis (friction)."),
           ("candidates.png", "Held-out RMS error of every candidate model against the noise floor."),
           ("before_after.png", "Held-out residual per axis and its distribution, before and after."))


def document(j: dict[str, Any], data_name: str, alpha: float = 0.01, view: tuple[str, str] | None = None) -> Document:
    """The diagnosis report of ``diagnosis.json``'s content ``j`` (figures beside it).

    Parameters
    ----------
    j : dict
        :meth:`Diagnosis.as_json` output.
    data_name : str
        How to name the measurement log.
    alpha : float
        Family-wise significance level (shown when ``j`` does not carry it).
    view : (str, str), optional
        The 3-D page of the effect on the rig (path, what it shows), when one was written.

    Returns
    -------
    Document
    """
    verdict, status = headline(j, alpha)
    top = Section("Verdict", verdict, status, [Figure(path, caption) for path, caption in FIGURES])
    g = j["gap"]
    top.add(_gap_table(j))
    sig_ = j.get("significance", {})
    top.add(Paragraph(f"Held-out rows: {j.get('heldout', '')}. Decision rule: {sig_.get('test', '')}; family-wise "
                      f"alpha {sig(sig_.get('alpha', alpha), 2)}. Refitting the nominal model alone (nominal_refit) "
                      f"closes {format_number(g.get('fraction_explained_by_nominal_refit'), 'fix0', 100)}% "
                      "of the gap."))
    sections = [top, _candidates(j)]
    sel = next((c for c in j["candidates"] if c["effect"] == j["selected"] and not c.get("error")), None)
    if sel is not None:
        sections.append(_parameters(sel, j["candidates"].index(sel)))
    sections.append(_where(j))
    if view is not None:
        sections.append(Section("On the rig", f"The diagnosed effect drawn on the rig: {view[1]}.", "info",
                                [View(view[0], "The rig upright under its weight with the fitted effect drawn on it "
                                               "(drag to rotate, scroll to zoom).", 760)]))
    extra = _secondary_and_pairs(j)
    if extra is not None:
        sections.append(extra)
    return Document(f"Sim-to-real gap diagnosis: {data_name}",
                    "Where the nominal model and the rig disagree, which unmodelled effect explains it, and how "
                    "much of the gap it closes on held-out cycles.", sections, data_file="diagnosis.json",
                    links=[Hyperlink("diagnosis.json", "diagnosis.json", "every number of this page and more")])


__all__ = ["document", "headline", "unit_of"]


def write_report(d: Diagnosis, out_dir: str | Path, data_name: str = "log", rig: Rig | None = None) -> Path:
    """Write ``index.html``, ``index.md``, ``diagnosis.json`` and four figures into ``out_dir``.

    Parameters
    ----------
    d : Diagnosis
        The diagnosis to report.
    out_dir : str or Path
        Report folder (created).
    data_name : str
        How the page names the measurement log.
    rig : Rig, optional
        The diagnosis' rig: when the selected (or second) effect is hole offsets or friction,
        ``rig.html`` shows it on the rig (:func:`csjm_opt.view.diagnosis_view`).

    Returns
    -------
    Path
        ``index.md`` (the HTML page is beside it).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    plots.save(residual_map(d), out_dir / "residual_map.png")
    plots.save(hysteresis_loops(d), out_dir / "hysteresis.png")
    plots.save(candidate_errors(d).figure, out_dir / "candidates.png")
    plots.save(before_after(d), out_dir / "before_after.png")
    j = d.as_json()
    atomic_write_json(out_dir / "diagnosis.json", j)
    view = _rig_view(j, rig, out_dir) if rig is not None else None
    write_document(document(j, data_name, alpha=ALPHA, view=view), out_dir)
    return out_dir / "index.md"


def _rig_view(j: dict[str, Any], rig: Rig, out_dir: Path) -> tuple[str, str] | None:
    """``rig.html`` for the selected effect (else the second one) when it is drawn on the rig."""
    from ...view.diagnosis import DRAWN_EFFECTS, diagnosis_view

    for name in (j.get("selected"), (j.get("secondary") or {}).get("effect")):
        if name in DRAWN_EFFECTS:
            cand = next((c for c in j["candidates"] if c["effect"] == name and not c.get("error")), None)
            params = (j.get("secondary") or {}).get("params") if cand is None else cand.get("params")
            if params:
                page = diagnosis_view(rig, name, params, title=f"Where the gap lies: {name}")
                page.write(out_dir / "rig.html")
                return "rig.html", page.note
    return None
