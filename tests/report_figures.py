"""Record every figure a report saves (title, axis labels, legend placement) for the report tests."""

from __future__ import annotations

import contextlib
from pathlib import Path

#: Axis labels that name a count or an index, which has no unit.
UNITLESS = ("index", "case", "number of", "rows", "axis of", "cycle", "design", "candidate", "pose (")


@contextlib.contextmanager
def record_figures():
    """Patch ``Figure.savefig`` to describe each figure before it is written; yields name -> description."""
    import pytest
    from matplotlib.figure import Figure

    seen: dict[str, dict] = {}
    original = Figure.savefig

    def savefig(fig, fname, *args, **kwargs):
        name = Path(str(fname)).name.lstrip(".").split(".")[0]
        seen[name] = describe(fig)
        return original(fig, fname, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Figure, "savefig", savefig)
        yield seen


def describe(fig) -> dict:
    sup = fig._suptitle.get_text() if fig._suptitle is not None else ""
    axes = []
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>" or not ax.get_visible():
            continue
        has_data = bool(ax.lines or ax.collections or ax.patches or ax.images)
        siblings = [a for a in ax.get_shared_y_axes().get_siblings(ax) if a is not ax]
        leg = ax.get_legend()
        legend = None
        if leg is not None:
            legend = {"loc": leg._loc, "anchored": leg._bbox_to_anchor is not None}
        axes.append({"title": ax.get_title() or ax.get_title("left"), "xlabel": ax.get_xlabel(),
                     "ylabel": ax.get_ylabel() or next((a.get_ylabel() for a in siblings if a.get_ylabel()), ""),
                     "data": has_data, "legend": legend})
    return {"suptitle": sup, "axes": axes, "figure_legends": len(fig.legends)}


def problems(name: str, d: dict) -> list[str]:
    """What a figure lacks: titles, labelled axes with units, legends that may cover data."""
    out = []
    for i, ax in enumerate(a for a in d["axes"] if a["data"]):
        where = f"{name} axes {i}"
        if not (ax["title"] or d["suptitle"]):
            out.append(f"{where}: no title")
        for key in ("xlabel", "ylabel"):
            label = ax[key]
            if not label:
                out.append(f"{where}: no {key}")
            elif "(" not in label and not any(w in label for w in UNITLESS):
                out.append(f"{where}: {key} {label!r} has no unit")
        if ax["legend"] is not None and ax["legend"]["loc"] != 0 and not ax["legend"]["anchored"]:
            out.append(f"{where}: legend at a fixed place inside the axes (use loc='best' or outside)")
    return out
