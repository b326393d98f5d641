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


def _cell(d: dict, key: str, where: tuple, fmt: str | None = None, scale: float | None = None) -> Cell:
    """A number of ``d`` with its JSON source ``where + (key,)``; "n/a" without a source when absent."""
    return Cell(d[key], fmt, scale, where + (key,)) if key in d else Cell(None, fmt, scale)


def unit_of(name: str) -> tuple[str, float]:
    """(unit shown, display scale) of a parameter from the unit suffix of its name ("" for none)."""
    for suffix, unit, scale, _ in _UNITS:
        if name.endswith(suffix):
            return unit, scale
    return "", 1.0


def _tests(c: dict) -> tuple[str | None, str | None]:
    """Keys of (held-out paired test p, F-test p) in a candidate: newer diagnoses use p_value / f_p_value."""
    if "f_p_value" in c:
        return "p_value", "f_p_value"
    return ("heldout_p_value" if "heldout_p_value" in c else None), ("p_value" if "p_value" in c else None)


def headline(j: dict[str, Any], alpha: float = 0.01) -> tuple[str, str]:
    """The verdict sentence of a diagnosis and its status (``ok``, ``warn`` or ``info``)."""
    g, sel = j["gap"], j["selected"]
    v = j.get("verdict") or {}
    warnings = list(v.get("warnings") or [])
    gap = (f"held-out error {sig(g['before_rad'], 3, 1e3)} -> {sig(g['after_rad'], 3, 1e3)} mrad RMS "
           f"(noise floor {sig(j['noise_floor_rad'], 3, 1e3)} mrad)")
    cand = next((c for c in j["candidates"] if c["effect"] == sel), None)
    if cand is not None:
        sig_ = j.get("significance", {})
        second = (j.get("secondary") or {}).get("effect", "none")
        model = f"`{sel}`" + (f" with `{second}` on top" if second not in (None, "none") else "")
        held, ftest = _tests(cand)
        level = cand.get("level", sig_.get("per_candidate_alpha", alpha))
        text = (f"{model} explains the model-rig gap: {gap}, "
                f"{format_number(g.get('fraction_explained'), 'fix0', 100)}% of the systematic gap closed. "
                f"Confidence: held-out paired test p = {sig(cand.get(held) if held else None, 2)} "
                f"(threshold {sig(level, 2)})")
        if "improvement_rad" in cand:
            text += f", improvement {sig(cand['improvement_rad'], 3, 1e3)} mrad"
        elif ftest:
            text += f", F-test p = {sig(cand.get(ftest), 2)}"
        text += "."
        status = "ok"
        if j.get("confounded_with"):
            text += f" It cannot be told apart from {', '.join(f'`{c}`' for c in j['confounded_with'])} on these data."
            status = "warn"
        if cand.get("plausible") is False:
            text += " Its fitted parameters are physically implausible: treat it as a stand-in."
            status = "warn"
        if warnings:
            text += " Warnings: " + "; ".join(warnings) + "."
            status = "warn"
        return text, status
    reason = v.get("reason")
    if sel == "unexplained":
        return (f"A systematic gap remains that no candidate explains: {gap}"
                + (f"; {reason}" if reason else "") + "."
                + (" " + "; ".join(warnings) + "." if warnings else "")
                + " Look at where it lies (below) and consider an effect outside the candidate list.", "warn")
    return (f"No unmodelled effect is needed: {gap}; "
            + (reason or "no candidate passes the decision rule") + ".", "info")


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
                      f"alpha {sig(sig_.get('alpha', alpha), 2)}. Refitting the nominal model alone (nominal_refit) "
                      f"closes {format_number(g.get('fraction_explained_by_nominal_refit'), 'fix0', 100)}% "
                      "of the gap."))
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
                 _cell(g, "fraction_explained", ("gap",), "fix1", 100.0), "%"])
    return Table([Column("gap"), Column("value"), Column("unit")], body)


def _candidates(j: dict) -> Section:
    cands = j["candidates"]
    plaus = any("plausible" in c for c in cands)
    improve = any("improvement_rad" in c for c in cands)
    cols = [Column("effect"), Column("held-out RMS", "mrad", scale=1e3), Column("train RMS", "mrad", scale=1e3)]
    cols += [Column("improvement", "mrad", scale=1e3)] if improve else []
    cols += [Column("held-out p", fmt="sig2"), Column("F-test p", fmt="sig2"), Column("BIC", fmt="fix1"),
             Column("significant")] + ([Column("plausible")] if plaus else [])
    cols += [Column("share closed", "%", "fix0", 100.0), Column("rank / params"), Column("condition")]
    width = len(cols)

    def fixed(name: str, key: str, share: Any, rank: str) -> list[Any]:
        m = j.get(key) or {}
        row = [name, _cell(m, "heldout_rms_rad", (key,)), _cell(m, "train_rms_rad", (key,))]
        row += [None] if improve else []
        row += [None, None, Cell(m["bic"], src=(key, "bic")) if "bic" in m else None, ""]
        row += [""] if plaus else []
        return row + [share, rank, None]

    rows = [fixed("nominal (rig file)", "baseline", 0.0, "0")]
    if j.get("nominal_refit"):
        rows.append(fixed("nominal_refit", "nominal_refit",
                          Cell(j["gap"]["fraction_explained_by_nominal_refit"],
                               src=("gap", "fraction_explained_by_nominal_refit"))
                          if "fraction_explained_by_nominal_refit" in j["gap"] else None,
                          str(len(j["nominal_refit"].get("params", {})))))
    for i, c in enumerate(cands):
        name = c["effect"] + (" (selected)" if c["effect"] == j["selected"] else "")
        if c.get("error"):
            rows.append([name, c["error"]] + [None] * (width - 2))
            continue
        held, ftest = _tests(c)
        def num(key: str | None, c: dict = c, i: int = i) -> Cell | None:
            return Cell(c.get(key), src=("candidates", i, key)) if key and key in c else None

        row = [name, num("heldout_rms_rad"), num("train_rms_rad")] + ([num("improvement_rad")] if improve else [])
        row += [num(held), num(ftest), num("bic"), bool(c.get("significant"))]
        row += [_plausible_text(c)] if plaus else []
        row += [num("fraction_explained"), f"{c.get('rank')} / {c.get('n_params')}", num("condition")]
        rows.append(row)
    best = min((c for c in cands if c.get("heldout_rms_rad") is not None),
               key=lambda c: c["heldout_rms_rad"], default=None)
    text = (f"{len(cands)} candidate effects, each fitted together with the nominal pretension and scored on "
            "held-out cycles"
            + (f"; lowest held-out error: `{best['effect']}` ({sig(best['heldout_rms_rad'], 3, 1e3)} mrad)." if best
               else "."))
    caption = ("Candidate models. Held-out p: paired test of per-cycle held-out error against nominal_refit; "
               "F-test p: linearised, on training rows (informative); share closed: of the systematic gap.")
    return Section("Candidates", text, "info", [Table(cols, rows, caption)])


def _plausible_text(c: dict) -> str:
    if "plausible" not in c:
        return ""
    bad = c.get("implausible_params") or []
    return "yes" if c["plausible"] else ("no" + (f" ({', '.join(bad)})" if bad else ""))


def _parameters(c: dict, index: int) -> Section:
    bad = set(c.get("implausible_params") or [])
    ranges = c.get("prior_ranges") or {}
    sd = c.get("param_sd") or {}
    rows = []
    for key, value in c.get("params", {}).items():
        unit, scale = unit_of(key)
        rng = ranges.get(key)
        span = (f"{format_number(rng[0], 'sig3', scale)} to {format_number(rng[1], 'sig3', scale)}"
                if isinstance(rng, (list, tuple)) and len(rng) == 2 else None)
        rows.append([key, Cell(value, "sig4", scale, ("candidates", index, "params", key)),
                     Cell(sd.get(key), "sig2", scale, ("candidates", index, "param_sd", key)) if key in sd else None,
                     unit] + ([span, "no" if key in bad else "yes"] if ranges else []))
    for key, value in (c.get("nuisance") or {}).items():
        unit, scale = unit_of(key)
        rows.append([f"{key} (nuisance)", Cell(value, "sig4", scale, ("candidates", index, "nuisance", key)), None,
                     unit] + ([None, None] if ranges else []))
    cols = [Column("parameter"), Column("value"), Column("standard error"), Column("unit")]
    cols += [Column("plausible range"), Column("plausible")] if ranges else []
    table = Table(cols, rows, "Fitted parameters (+- 1 standard error; nuisance: fitted with every candidate)")
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
    pairs = [p for p in (j.get("pairs") or []) if isinstance(p, dict)]
    steps = [st for st in (j.get("steps") or []) if isinstance(st, dict)]
    if not sec.get("tried") and not pairs and not steps and sec.get("effect", "none") in ("none", None):
        return None
    effect = sec.get("effect", "none")
    out = Section("Second effects and pairs", f"Second effect on top of the selected one: `{effect}`"
                  + (f" (held-out {sig(sec.get('heldout_rms_rad'), 3, 1e3)} mrad)." if effect not in ("none", None)
                     else " (none needed or none significant)."), "info")
    if steps:
        out.add(Table([Column("model"), Column("held-out RMS", "mrad", scale=1e3),
                       Column("share closed", "%", "fix0", 100.0)],
                      [[st.get("model", ""), _cell(st, "heldout_rms_rad", ("steps", i)),
                        _cell(st, "fraction_explained", ("steps", i))]
                       for i, st in enumerate(steps)], "The path of the selection, one model after the other"))
    if sec.get("tried"):                                  # older diagnoses: every second effect tried
        rows = [[t["effect"], _cell(t, "heldout_rms_rad", ("secondary", "tried", i)),
                 _cell(t, "p_value", ("secondary", "tried", i), "sig2"),
                 bool(t.get("significant")) if "error" not in t else t["error"]]
                for i, t in enumerate(sec["tried"]) if "p_value" in t or "error" in t]
        out.add(Table([Column("added effect"), Column("held-out RMS", "mrad", scale=1e3), Column("p"),
                       Column("significant")], rows))
    if pairs:
        def num(i: int, p: dict, key: str, fmt: str | None = None) -> Any:
            return Cell(p[key], fmt, src=("pairs", i, key)) if isinstance(p.get(key), (int, float)) \
                and not isinstance(p.get(key), bool) else None

        rows = [[" + ".join(p.get("effects", [])), p.get("separable"), num(i, p, "max_correlation", "fix2"),
                 p.get("fitted"), num(i, p, "heldout_rms_rad"), num(i, p, "fraction_explained"),
                 num(i, p, "p_value_vs_first", "sig2"), p.get("significant"),
                 _plausible_text(p) if "plausible" in p else None] for i, p in enumerate(pairs)]
        out.add(Table([Column("pair"), Column("separable"), Column("max correlation"), Column("fitted"),
                       Column("held-out RMS", "mrad", scale=1e3), Column("share closed", "%", "fix0", 100.0),
                       Column("p vs first"), Column("significant"), Column("plausible")], rows,
                      "Pairs of effects: separable when their parameter blocks are not strongly correlated"))
    return out


__all__ = ["document", "headline", "unit_of"]
