"""Figures of the design report: the Pareto plot and the hole geometry of the best designs."""

from __future__ import annotations

import numpy as np

from ... import _plotting as plots
from ...design.geometry import design_holes
from ...errors import CsjmError
from .study import X_KEY, Y_KEY, DesignStudy


def pareto_figure(study: DesignStudy, best: list[dict], ax=None):
    """Workspace against minimum stiffness: every design, the front, the best numbered, the paper starred.

    Parameters
    ----------
    study : DesignStudy
        The sweep's valid designs, front and the paper's design.
    best : list of dict
        Designs numbered on the plot (the report table's best).
    ax : matplotlib Axes, optional
        Axes to draw into (a new figure when ``None``).

    Returns
    -------
    matplotlib Axes
        The axes drawn.
    """
    if ax is None:
        ax = plots.figure().figure(figsize=(7.5, 5.5), layout="constrained").subplots()
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
    return ax


def geometry_figure(designs: list[tuple[str, dict]], fig=None):
    """Top view (x-y, mm) of each design's holes on the platform and base circles, cables as lines.

    Parameters
    ----------
    designs : list of (str, dict)
        (label, complete design parameters) pairs; designs whose geometry cannot be built are skipped.
    fig : matplotlib Figure, optional
        Figure to draw into (a new one when ``None``).

    Returns
    -------
    matplotlib Figure or None
        The figure drawn, or ``None`` when no design could be drawn.
    """
    drawn = []
    for label, params in designs:
        try:
            drawn.append((label, *design_holes(params)))
        except CsjmError:
            continue
    if not drawn:
        return None
    n = len(drawn)
    cols = min(n, 3)
    rows = (n + cols - 1) // cols
    if fig is None:
        fig = plots.figure().figure(figsize=(4.2 * cols, 4.3 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False)
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
    return fig
