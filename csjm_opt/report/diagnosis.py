"""The diagnosis report as a document, built from ``diagnosis.json`` (``csjm diagnose --report``).

Leads with the verdict in one sentence (effect, gap before/after in mrad,
share of the systematic gap closed, confidence) and the figures that show
it; then the candidates, the selected effect's parameters with units and
standard errors, where the gap lies, and the second-effect search. Keys that
only newer diagnoses carry (``pairs``, ``plausible``, ``implausible_params``,
the verdict ``unexplained``) are shown when present.
"""

from __future__ import annotations

from typing import Any

from .document import Cell, Column, Document, Figure, Link, Paragraph, Section, Table, format_number, sig

FIGURES = (("residual_map.png", "Held-out residual over the pose (tilt and azimuth), nominal model and selected "
                                "model, same colour scale."),
           ("hysteresis.png", "Residual along its main axis against the load, for a few cycles: loading and "
                              "unloading branches apart mean hysteresis (friction)."),
           ("candidates.png", "Held-out RMS error of every candidate model against the noise floor."),
           ("before_after.png", "Held-out residual per axis and its distribution, before and after."))
#: Unit of a parameter from its name's suffix: (suffix, unit shown, scale, format).
_UNITS = (("_rad_per_Nm", "rad/(N m)", 1.0, "sig3"), ("_per_m", "1/m", 1.0, "sig3"), ("_Nm", "N m", 1.0, "sig3"),
          ("_kgm", "kg m", 1.0, "sig3"), ("_mm", "mm", 1.0, "sig3"), ("_m", "mm", 1e3, "sig3"),
          ("_rad", "mrad", 1e3, "sig3"), ("_deg", "deg", 1.0, "sig3"), ("_percent", "%", 1.0, "sig3"),
          ("_N", "N", 1.0, "sig3"), ("_kg", "kg", 1.0, "sig3"))


def unit_of(name: str) -> tuple[str, float]:
    """(unit shown, display scale) of a parameter from the unit suffix of its name ("" for none)."""
    for suffix, unit, scale, _ in _UNITS:
        if name.endswith(suffix):
            return unit, scale
    return "", 1.0


def headline(j: dict[str, Any], alpha: float = 0.01) -> tuple[str, str]:
    """The verdict sentence of a diagnosis and its status."""
    g, sel = j["gap"], j["selected"]
    floor = j["noise_floor_rad"]
    gap = (f"held-out error {sig(g['before_rad'], 3, 1e3)} -> {sig(g['after_rad'], 3, 1e3)} mrad RMS "
           f"(noise floor {sig(floor, 3, 1e3)} mrad)")
    cand = next((c for c in j["candidates"] if c["effect"] == sel), None)
    if cand is not None:
        share = g.get("fraction_explained")
        sig_ = j.get("significance", {})
        text = (f"`{sel}` explains the model-rig gap: {gap}, {format_number(share, 'fix0', 100)}% of the systematic "
                f"gap closed. Confidence: F-test p = {sig(cand.get('p_value'), 2)} (threshold "
                f"{sig(sig_.get('per_candidate_alpha', alpha), 2)}), held-out paired test p = "
                f"{sig(cand.get('heldout_p_value'), 2)} (threshold {sig(sig_.get('heldout_alpha'), 2)}).")
        status = "ok"
        if j.get("confounded_with"):
            text += f" It cannot be told apart from {', '.join(f'`{c}`' for c in j['confounded_with'])} on these data."
            status = "warn"
        second = (j.get("secondary") or {}).get("effect", "none")
        if second not in (None, "none"):
            text += f" A second effect on top of it is significant: `{second}`."
        if cand.get("plausible") is False:
            text += " Its fitted parameters are physically implausible: treat it as a stand-in."
            status = "warn"
        return text, status
    if sel == "unexplained":
        return (f"A systematic gap remains that no candidate explains: {gap}. Look at where it lies (tables "
                "below) and consider an effect outside the candidate list.", "warn")
    return (f"No candidate effect is needed: {gap}; no candidate passes the decision rule, so the nominal "
            f"model (with its stiffness scale and pretension refitted) is the explanation on these data.", "info")


def document(j: dict[str, Any], data_name: str, alpha: float = 0.01) -> Document:
    """The diagnosis report of ``diagnosis.json``'s content ``j`` (figures beside it).

    Parameters
    ----------
    j : dict
        :meth:`Diagnosis.as_json` output.
    data_name : str
        How to name the measurement log.
    alpha : float
        Family-wise significance level (shown when ``j`` does not carry it).

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
                      f"alpha {sig(sig_.get('alpha', alpha), 2)}. "
                      "A recalibration of stiffness and pretension alone "
                      f"closes {format_number(g.get('fraction_explained_by_nominal_refit'), 'fix0', 100)}"
                      "% of the gap."))
    sections = [top, _candidates(j)]
    sel = next((c for c in j["candidates"] if c["effect"] == j["selected"] and not c.get("error")), None)
    if sel is not None:
        sections.append(_parameters(sel, j["candidates"].index(sel)))
    sections.append(_where(j))
    extra = _secondary_and_pairs(j)
    if extra is not None:
        sections.append(extra)
    return Document(f"Sim-to-real gap diagnosis: {data_name}",
                    "Where the nominal model and the rig disagree, which unmodelled effect explains it, and how "
                    "much of the gap it closes on held-out cycles.", sections, data_file="diagnosis.json",
                    links=[Link("diagnosis.json", "diagnosis.json", "every number of this page and more")])


def _gap_table(j: dict) -> Table:
    g = j["gap"]
    rows = [("held-out RMS before (nominal model, rig file)", "before_rad"),
            ("held-out RMS after (selected model)", "after_rad"),
            ("systematic part before", "systematic_before_rad"), ("systematic part after", "systematic_after_rad")]
    body = [[name, Cell(g.get(key), scale=1e3, src=("gap", key)), "mrad"] for name, key in rows if key in g]
    body.append(["noise floor", Cell(j["noise_floor_rad"], scale=1e3, src=("noise_floor_rad",)), "mrad"])
    body.append(["share of the systematic gap closed",
                 Cell(g.get("fraction_explained"), "fix1", 100.0, ("gap", "fraction_explained")), "%"])
    return Table([Column("gap"), Column("value"), Column("unit")], body)


def _candidates(j: dict) -> Section:
    plaus = any("plausible" in c for c in j["candidates"])
    cols = [Column("effect"), Column("held-out RMS", "mrad", scale=1e3), Column("train RMS", "mrad", scale=1e3),
            Column("BIC", fmt="fix1"), Column("F-test p", fmt="sig2"), Column("held-out p", fmt="sig2"),
            Column("significant"), Column("rank / params"), Column("condition"),
            Column("share closed", "%", "fix0", 100.0)] + ([Column("plausible")] if plaus else [])
    b, n = j["baseline"], j.get("nominal_refit", {})
    rows = [["nominal (rig file)", Cell(b["heldout_rms_rad"], src=("baseline", "heldout_rms_rad")),
             Cell(b.get("train_rms_rad"), src=("baseline", "train_rms_rad")), None, None, None, "", "0", None, 0.0]
            + ([""] if plaus else [])]
    if n:
        rows.append(["nominal_refit", Cell(n["heldout_rms_rad"], src=("nominal_refit", "heldout_rms_rad")),
                     Cell(n.get("train_rms_rad"), src=("nominal_refit", "train_rms_rad")),
                     Cell(n.get("bic"), src=("nominal_refit", "bic")), None, None, "", "2", None,
                     Cell(j["gap"].get("fraction_explained_by_nominal_refit"),
                          src=("gap", "fraction_explained_by_nominal_refit"))] + ([""] if plaus else []))
    for i, c in enumerate(j["candidates"]):
        name = c["effect"] + (" (selected)" if c["effect"] == j["selected"] else "")
        if c.get("error"):
            rows.append([name, c["error"]] + [None] * (len(cols) - 2))
            continue
        rows.append([name] + [Cell(c.get(k), src=("candidates", i, k)) for k in
                              ("heldout_rms_rad", "train_rms_rad", "bic", "p_value", "heldout_p_value")]
                    + [bool(c.get("significant")), f"{c.get('rank')} / {c.get('n_params')}",
                       Cell(c.get("condition"), src=("candidates", i, "condition")),
                       Cell(c.get("fraction_explained"), src=("candidates", i, "fraction_explained"))]
                    + ([_plausible_text(c)] if plaus else []))
    best = min((c for c in j["candidates"] if c.get("heldout_rms_rad") is not None),
               key=lambda c: c["heldout_rms_rad"], default=None)
    text = (f"{len(j['candidates'])} candidate effects, each fitted together with the nominal stiffness scale and "
            "pretension and scored on held-out cycles"
            + (f"; lowest held-out error: `{best['effect']}` ({sig(best['heldout_rms_rad'], 3, 1e3)} mrad)." if best
               else "."))
    return Section("Candidates", text, "info", [Table(cols, rows, "Candidate models (share closed: of the "
                                                                  "systematic gap, against each model's noise floor)")])


def _plausible_text(c: dict) -> str:
    if "plausible" not in c:
        return ""
    bad = c.get("implausible_params") or []
    return "yes" if c["plausible"] else ("no" + (f" ({', '.join(bad)})" if bad else ""))


def _parameters(c: dict, index: int) -> Section:
    bad = set(c.get("implausible_params") or [])
    rows = []
    for key, value in c.get("params", {}).items():
        unit, scale = unit_of(key)
        rows.append([key + (" (implausible)" if key in bad else ""),
                     Cell(value, "sig4", scale, ("candidates", index, "params", key)),
                     Cell(c.get("param_sd", {}).get(key), "sig2", scale, ("candidates", index, "param_sd", key)), unit])
    for key, value in c.get("nuisance", {}).items():
        unit, scale = unit_of(key)
        rows.append([f"{key} (nuisance)", Cell(value, "sig4", scale, ("candidates", index, "nuisance", key)),
                     None, unit])
    table = Table([Column("parameter"), Column("value"), Column("standard error"), Column("unit")], rows,
                  "Fitted parameters (+- 1 standard error; nuisance: common stiffness scale and pretension)")
    sec = Section(f"Fitted parameters of {c['effect']}", "", "info", [table])
    derived = c.get("derived") or {}
    drows = []
    for key, value in derived.items():
        unit, scale = unit_of(key)
        if isinstance(value, list):
            text = ", ".join(format_number(v, "sig3", scale) for v in value)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            text = format_number(value, "sig3", scale)
        else:
            text = str(value)
        drows.append([key, text, unit])
    if drows:
        sec.add(Table([Column("derived quantity"), Column("value"), Column("unit")], drows))
    if c.get("identifiable") is False:
        sec.verdict = (f"The augmented fit is ill-conditioned (condition {sig(c.get('condition'))}, "
                       f"rank {c.get('rank')} "
                       f"of {c.get('n_params')}): some parameter combinations are not determined by these data.")
        sec.status = "warn"
    else:
        sec.verdict = (f"{len(c.get('params', {}))} parameters and {len(c.get('nuisance', {}))} nuisance parameters, "
                       f"all determined by the data (rank {c.get('rank')} of {c.get('n_params')}, condition "
                       f"{sig(c.get('condition'))}).")
    return sec


def _where(j: dict) -> Section:
    loc = j["localisation"]
    rows = []
    for key in ("by_tilt", "by_azimuth", "by_load_magnitude", "by_load_direction", "by_branch"):
        for i, grp in enumerate(loc.get(key, [])):
            rows.append([key[3:].replace("_", " "), grp["group"], Cell(grp["rows"], "int"),
                         Cell(grp["rms_before_rad"], src=("localisation", key, i, "rms_before_rad")),
                         Cell(grp["rms_after_rad"], src=("localisation", key, i, "rms_after_rad"))])
    for a, v in loc.get("by_axis", {}).items():
        rows.append(["axis", a, None, Cell(v["rms_before_rad"], src=("localisation", "by_axis", a, "rms_before_rad")),
                     Cell(v["rms_after_rad"], src=("localisation", "by_axis", a, "rms_after_rad"))])
    table = Table([Column("breakdown"), Column("group"), Column("rows", fmt="int"),
                   Column("before", "mrad", scale=1e3), Column("after", "mrad", scale=1e3)], rows)
    hb, ha = loc.get("hysteresis_before", {}), loc.get("hysteresis_after", {})
    text = "Held-out residual RMS by group, before and after the selected model."
    if hb.get("pairs"):
        text = (f"Loading minus unloading at matched loads ({hb['pairs']} pairs): "
                f"{sig(hb.get('rms_up_minus_down_rad'), 3, 1e3)} mrad before (noise alone "
                f"{sig(hb.get('expected_from_noise_rad'), 3, 1e3)}, p = {sig(hb.get('p_value'), 2)}), "
                f"{sig(ha.get('rms_up_minus_down_rad'), 3, 1e3)} mrad after.")
    rem = j.get("remaining_signature", {})
    if rem:
        text += (f" Remaining signature after the selected model: {'yes' if rem.get('significant') else 'no'} "
                 f"(p = {sig(rem.get('p_value'), 2)}, systematic part {sig(rem.get('systematic_rad'), 3, 1e3)} mrad).")
    return Section("Where the gap lies", text, "info", [table])


def _secondary_and_pairs(j: dict) -> Section | None:
    sec = j.get("secondary") or {}
    pairs = j.get("pairs") or []
    if not sec.get("tried") and not pairs:
        return None
    effect = sec.get("effect", "none")
    out = Section("Second effects", f"Second effect on top of the selected one: `{effect}`"
                  + (f" (held-out {sig(sec.get('heldout_rms_rad'), 3, 1e3)} mrad)." if effect not in ("none", None)
                     else " (none significant)."), "info")
    if sec.get("tried"):
        rows = [[t["effect"], Cell(t.get("heldout_rms_rad"), src=("secondary", "tried", i, "heldout_rms_rad")),
                 Cell(t.get("p_value"), "sig2", src=("secondary", "tried", i, "p_value")),
                 Cell(t.get("heldout_p_value"), "sig2", src=("secondary", "tried", i, "heldout_p_value")),
                 bool(t.get("significant")) if "error" not in t else t["error"]]
                for i, t in enumerate(sec["tried"])]
        out.add(Table([Column("added effect"), Column("held-out RMS", "mrad", scale=1e3), Column("F-test p"),
                       Column("held-out p"), Column("significant")], rows))
    if pairs and all(isinstance(p, dict) for p in pairs):
        keys = list(dict.fromkeys(k for p in pairs for k in p if not isinstance(p[k], (dict, list))))
        rows = [[Cell(p.get(k), src=("pairs", i, k)) if isinstance(p.get(k), (int, float)) and
                 not isinstance(p.get(k), bool) else p.get(k, "") for k in keys] for i, p in enumerate(pairs)]
        cols = []
        for k in keys:
            unit, scale = unit_of(k)
            cols.append(Column(k, unit, scale=scale))
        out.add(Table(cols, rows, "Pairs of effects"))
    elif pairs:
        out.add(Paragraph("Pairs: " + "; ".join(str(p) for p in pairs)))
    return out


__all__ = ["document", "headline", "unit_of"]
