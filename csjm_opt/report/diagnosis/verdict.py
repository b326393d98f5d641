"""The verdict sentence of a diagnosis report and its status."""

from __future__ import annotations

from typing import Any

from ..document import format_number, sig


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
