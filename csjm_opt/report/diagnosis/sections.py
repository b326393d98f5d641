"""The detail sections of the diagnosis report.

Gap table, candidates, parameters, where the gap lies, second effects and pairs; the unit shown for a
parameter from its name's suffix (:func:`unit_of`).
"""

from __future__ import annotations

from typing import Any

from ..document import Cell, Column, Section, Table, format_number, sig
from .verdict import _tests


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
