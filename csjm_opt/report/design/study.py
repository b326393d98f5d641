"""A sweep's results read for the design report: valid designs, Pareto layers, the paper's design."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from ...design.geometry import design_holes
from ...design.sweep.store import read_records, unique_records
from ...errors import CsjmError, DesignError

X_KEY, Y_KEY = "workspace_fraction", "min_stiffness_Nm_per_rad"


@dataclasses.dataclass
class DesignStudy:
    """Valid designs of a sweep, their Pareto front and (when known) the paper's design."""

    records: list[dict[str, Any]]            # every record of the result file
    ok: list[dict[str, Any]]                 # valid designs with both metrics
    front: np.ndarray                        # indices into ``ok``, by increasing workspace
    layers: np.ndarray                       # Pareto layer of each design of ``ok`` (1: the front)
    base: dict[str, Any]                     # fixed design parameters (sweep file's [base])
    paper: dict[str, Any] | None             # the paper design's record (evaluated or found), if any
    source: str

    def summary(self, top: int) -> dict[str, Any]:
        """JSON-able numbers of the report (``design_report.json``)."""
        x = np.array([r[X_KEY] for r in self.ok])
        ranked = sorted(range(len(self.ok)), key=lambda i: (self.layers[i], -x[i]))
        best = [{**_row(self.ok[i]), "pareto_layer": int(self.layers[i])} for i in ranked[:top]]
        out: dict[str, Any] = {
            "results": self.source, "designs": len(self.records), "valid_designs": len(self.ok),
            "invalid_designs": sum(r.get("status") == "invalid" for r in self.records),
            "failed_designs": sum(r.get("status") == "error" for r in self.records),
            "base": self.base, "pareto_front_size": int(len(self.front)),
            "best": best, "pareto_front": [_row(self.ok[i]) for i in self.front]}
        if self.paper is not None:
            x = np.array([r[X_KEY] for r in self.ok])
            y = np.array([r[Y_KEY] for r in self.ok])
            px, py = self.paper[X_KEY], self.paper[Y_KEY]
            dominating = int(np.sum((x >= px) & (y >= py) & ((x > px) | (y > py))))
            out["paper_design"] = {**_row(self.paper), "designs_dominating_it": dominating,
                                   "on_pareto_front": dominating == 0,
                                   "workspace_percentile": float(100 * np.mean(x <= px)),
                                   "min_stiffness_percentile": float(100 * np.mean(y <= py))}
        return out


def _row(r: dict[str, Any]) -> dict[str, Any]:
    m = r.get("metrics") or {}
    return {"params": r.get("params", {}), X_KEY: r[X_KEY], Y_KEY: r[Y_KEY],
            "tilt_cone_deg": m.get("tilt_cone_deg"),
            "median_min_stiffness_Nm_per_rad": m.get("median_min_stiffness_Nm_per_rad")}


def load_study(results: str | Path, sweep: str | Path | None = None) -> DesignStudy:
    """Read a result file; with the sweep file, also evaluate the paper's design under the same settings.

    Parameters
    ----------
    results : str or Path
        ``csjm sweep --out`` file (JSON Lines).
    sweep : str or Path, optional
        The sweep description the results came from: gives the fixed ``[base]`` parameters (to draw
        the geometry) and the settings to evaluate the paper's design with. Without it the base is
        taken as the paper's and the paper's design is marked only when it is among the results.

    Returns
    -------
    DesignStudy

    Raises
    ------
    DesignError
        No result file, no valid design, or a sweep file whose settings differ from the results'.
    """
    records = list(unique_records(read_records(results)[0])[0].values())  # repeated lines count once
    if not records:
        raise DesignError("no designs in the result file (run csjm sweep first)", "RESULTS", str(results))
    ok = [r for r in records if r.get("status") == "ok" and r.get(X_KEY) is not None and r.get(Y_KEY) is not None]
    if not ok:
        raise DesignError("no valid design with a non-empty workspace in the results", "RESULTS", str(results))
    base: dict[str, Any] = {}
    paper = None
    if sweep is not None:
        from ...design.sweep.runner import evaluate_design
        from ...design.sweep.spec import SweepSpec

        spec = SweepSpec.from_toml(sweep)
        if any(r.get("settings") != spec.settings.digest() for r in records):
            raise DesignError("the results were evaluated with other settings than this sweep file", "--sweep",
                              str(sweep))
        base = dict(spec.settings.base)
        record = evaluate_design({}, dataclasses.replace(spec.settings, base={}))
        paper = record if record["status"] == "ok" and record[Y_KEY] is not None else None
    else:
        paper_holes = design_holes({})
        for r in ok:
            try:
                holes = design_holes({**base, **r["params"]})
            except CsjmError:
                continue
            if all(np.allclose(a, b, atol=1e-9) for a, b in zip(holes, paper_holes)):
                paper = r
                break
    x = np.array([r[X_KEY] for r in ok])
    y = np.array([r[Y_KEY] for r in ok])
    layers = pareto_layers(x, y)
    front = np.flatnonzero(layers == 1)
    front = front[np.argsort(x[front], kind="stable")]
    if paper is not None and sweep is not None:
        names = list(dict.fromkeys(k for r in ok for k in r["params"]))
        paper = {**paper, "params": {n: paper_value(n) for n in names}}
    return DesignStudy(records, ok, front, layers, base, paper, str(results))


def paper_value(name: str) -> float | None:
    """The paper design's value of a design parameter (circle radius and gamma derived from its chords)."""
    from ...design.geometry import PAPER_DESIGN
    from ...model import hexagon

    if name in PAPER_DESIGN:
        return float(PAPER_DESIGN[name])
    if name == "n_cables":
        return 6.0                                                         # the paper's six cables
    body = name.split("_", 1)[0]
    if body not in ("platform", "base"):
        return 0.0 if name[:1] in "AB" and name.endswith("_m") else None   # per-hole offsets
    chords = hexagon.PAPER_PLATFORM_CHORDS_M if body == "platform" else hexagon.PAPER_BASE_CHORDS_M
    radius, gamma = hexagon.circle_from_chords(*chords)
    if name.endswith("_radius_m"):
        return float(radius)
    if name.endswith("_gamma_deg"):
        return float(np.degrees(gamma))
    return None


def pareto_mask(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Designs that no other design beats in both ``x`` and ``y`` (both maximised).

    Parameters
    ----------
    x, y : (n,) arrays

    Returns
    -------
    (n,) bool array
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    better_eq = (x[None, :] >= x[:, None]) & (y[None, :] >= y[:, None])
    strictly = (x[None, :] > x[:, None]) | (y[None, :] > y[:, None])
    return ~np.any(better_eq & strictly, axis=1)


def pareto_layers(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Layer of each design: 1 for the Pareto front, 2 for the front of the rest, and so on."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    layer = np.zeros(len(x), int)
    k = 0
    while np.any(layer == 0):
        k += 1
        left = np.flatnonzero(layer == 0)
        layer[left[pareto_mask(x[left], y[left])]] = k
    return layer
