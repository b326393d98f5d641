"""Geometry study around the paper's design: heat maps, Pareto front, where the paper sits.

Usage::

    python -m studies.paper_sweep.paper_sweep OUTDIR [--sweep studies/paper_sweep/paper_sweep.toml] [--workers 2]
                                         [--scheduler ADDRESS | --dask]

Runs the sweep (resumable: results go to ``OUTDIR/paper_sweep.jsonl``, a rerun
skips finished designs), evaluates the paper's own design (Section IV-A) with
the same sampling, loads and metrics, and writes into ``OUTDIR``:

* ``heatmaps.png``: workspace fraction, tilt cone, minimum and median
  smallest stiffness eigenvalue over the first two swept parameters
  (grid sweeps), the paper's design marked with a star;
* ``pareto.png``: workspace fraction against minimum stiffness for every
  design, the Pareto front (no other design is better in both), the paper's
  design marked;
* ``summary.json`` / ``summary.md``: the paper's metrics, its percentile
  among the designs, how many designs dominate it, the Pareto designs.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from csjm_opt._fileio import atomic_write_json, atomic_write_text
from csjm_opt.design.geometry import PAPER_DESIGN
from csjm_opt.design.sweep.runner import evaluate_design, run_sweep
from csjm_opt.design.sweep.spec import SweepSpec
from csjm_opt.errors import CsjmError
from csjm_opt.model import hexagon

HERE = Path(__file__).resolve().parent
X_KEY, Y_KEY = "workspace_fraction", "min_stiffness_Nm_per_rad"


def paper_coordinate(name: str) -> float:
    """The paper design's value of a design parameter (gamma and radius derived from its chords)."""
    if name in PAPER_DESIGN:
        return float(PAPER_DESIGN[name])
    body = name.split("_", 1)[0]
    chords = hexagon.PAPER_PLATFORM_CHORDS_M if body == "platform" else hexagon.PAPER_BASE_CHORDS_M
    radius, gamma = hexagon.circle_from_chords(*chords)
    if name.endswith("_radius_m"):
        return radius
    if name.endswith("_gamma_deg"):
        return math.degrees(gamma)
    return 0.0  # per-hole offsets


def pareto_mask(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Designs no other design beats in both x and y (both maximised)."""
    better_eq = (x[None, :] >= x[:, None]) & (y[None, :] >= y[:, None])
    strictly = (x[None, :] > x[:, None]) | (y[None, :] > y[:, None])
    return ~np.any(better_eq & strictly, axis=1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--sweep", type=Path, default=HERE.parent / "paper_sweep" / "paper_sweep.toml")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scheduler", default=None)
    parser.add_argument("--dask", action="store_true")
    args = parser.parse_args(argv)
    try:
        spec = SweepSpec.from_toml(args.sweep)
        result = run_sweep(spec, args.outdir / "paper_sweep.jsonl", workers=args.workers,
                           scheduler=args.scheduler, dask=args.dask)
    except CsjmError as exc:
        print(f"paper_sweep: error: {exc}", file=sys.stderr)
        return 2
    paper_settings = dataclasses.replace(spec.settings, base={})
    paper = evaluate_design({}, paper_settings)
    summary = summarise(spec, result.records, paper)
    atomic_write_json(args.outdir / "summary.json", summary)
    atomic_write_text(args.outdir / "summary.md", summary_markdown(summary))
    figures(spec, result.records, paper, summary, args.outdir)
    print(summary_markdown(summary))
    print(f"figures and summary in {args.outdir}")
    return 0


def summarise(spec: SweepSpec, records: list[dict], paper: dict) -> dict:
    ok = [r for r in records if r["status"] == "ok" and r[Y_KEY] is not None]
    x = np.array([r[X_KEY] for r in ok])
    y = np.array([r[Y_KEY] for r in ok])
    front = pareto_mask(x, y)
    px, py = paper[X_KEY], paper[Y_KEY]
    dominating = int(np.sum((x >= px) & (y >= py) & ((x > px) | (y > py))))
    return {
        "sweep": str(spec.path), "designs": len(records), "valid_designs": len(ok),
        "paper_design": {"params": {a.name: paper_coordinate(a.name) for a in spec.axes},
                         "metrics": paper["metrics"],
                         "workspace_percentile": float(100 * np.mean(x <= px)),
                         "min_stiffness_percentile": float(100 * np.mean(y <= py)),
                         "designs_dominating_it": dominating,
                         "on_pareto_front": dominating == 0},
        "pareto_front": sorted(({"params": r["params"], X_KEY: r[X_KEY], Y_KEY: r[Y_KEY]}
                                for r, f in zip(ok, front) if f), key=lambda d: d[X_KEY]),
        "best_workspace": max(ok, key=lambda r: r[X_KEY])["params"] if ok else None,
        "best_min_stiffness": max(ok, key=lambda r: r[Y_KEY])["params"] if ok else None,
    }


def summary_markdown(s: dict) -> str:
    p = s["paper_design"]
    m = p["metrics"]
    lines = [f"# Design sweep: {s['sweep']}", "",
             f"{s['designs']} designs, {s['valid_designs']} of them valid with a non-empty workspace.", "",
             "## Where the paper's design sits", "",
             f"- parameters: {', '.join(f'{k} = {v:.4g}' for k, v in p['params'].items())}",
             f"- workspace fraction {m['workspace_fraction']:.3f} (percentile {p['workspace_percentile']:.0f}), "
             f"tilt cone {m['tilt_cone_deg']:.1f} deg",
             f"- minimum stiffness {m['min_stiffness_Nm_per_rad']:.2f} N m/rad "
             f"(percentile {p['min_stiffness_percentile']:.0f}), median {m['median_min_stiffness_Nm_per_rad']:.2f}",
             f"- {p['designs_dominating_it']} designs are better in both workspace and minimum stiffness"
             + (" (on the Pareto front)" if p["on_pareto_front"] else ""), "",
             "## Pareto front (workspace fraction vs minimum stiffness)", ""]
    for d in s["pareto_front"]:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in d["params"].items())
        lines.append(f"- {d[X_KEY]:.3f}, {d[Y_KEY]:.2f} N m/rad: {params}")
    return "\n".join(lines) + "\n"


def figures(spec: SweepSpec, records: list[dict], paper: dict, summary: dict, outdir: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    star = dict(marker="*", s=260, color="white", edgecolor="black", zorder=5, label="paper's design")
    if spec.method == "grid" and len(spec.axes) >= 2:
        ax_x, ax_y = spec.axes[0], spec.axes[1]
        xs, ys = np.array(ax_x.values), np.array(ax_y.values)
        panels = [(X_KEY, "workspace fraction"), ("tilt_cone_deg", "tilt cone (deg)"),
                  (Y_KEY, "min eigenvalue of K (N m/rad)"),
                  ("median_min_stiffness_Nm_per_rad", "median min eigenvalue of K (N m/rad)")]
        fig, axes = plt.subplots(2, 2, figsize=(11, 9), constrained_layout=True)
        for (key, title), ax in zip(panels, axes.flat):
            Z = np.full((ys.size, xs.size), np.nan)
            for r in records:
                if r["status"] != "ok":
                    continue
                i = int(np.argmin(np.abs(ys - r["params"][ax_y.name])))
                j = int(np.argmin(np.abs(xs - r["params"][ax_x.name])))
                value = r["metrics"].get(key)
                Z[i, j] = np.nan if value is None else value
            mesh = ax.pcolormesh(_edges(xs), _edges(ys), np.ma.masked_invalid(Z), shading="flat", cmap="viridis")
            fig.colorbar(mesh, ax=ax)
            ax.scatter([paper_coordinate(ax_x.name)], [paper_coordinate(ax_y.name)], **star)
            ax.set(title=title, xlabel=ax_x.name, ylabel=ax_y.name)
        axes.flat[0].legend(loc="lower right", fontsize=8)
        fig.suptitle("Designs around the paper's CSJM (blank: no feasible orientation, or invalid design)")
        fig.savefig(outdir / "heatmaps.png", dpi=120)
        plt.close(fig)
    ok = [r for r in records if r["status"] == "ok" and r[Y_KEY] is not None]
    x = np.array([r[X_KEY] for r in ok])
    y = np.array([r[Y_KEY] for r in ok])
    front = pareto_mask(x, y)
    fig, ax = plt.subplots(figsize=(7, 5.5), constrained_layout=True)
    ax.scatter(x, y, s=14, color="0.6", label="designs")
    order = np.argsort(x[front])
    ax.plot(x[front][order], y[front][order], "o-", color="tab:red", label="Pareto front")
    ax.scatter([paper[X_KEY]], [paper[Y_KEY]], **{**star, "color": "gold"})
    ax.set(xlabel="workspace fraction (wrench-feasible, all loads)",
           ylabel="min eigenvalue of K over the workspace (N m/rad)",
           title=f"{summary['paper_design']['designs_dominating_it']} designs dominate the paper's")
    ax.legend()
    fig.savefig(outdir / "pareto.png", dpi=120)
    plt.close(fig)


def _edges(v: np.ndarray) -> np.ndarray:
    if v.size == 1:
        return np.array([v[0] - 0.5, v[0] + 0.5])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate([[2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]])


if __name__ == "__main__":
    sys.exit(main())
