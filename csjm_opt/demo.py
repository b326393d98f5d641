"""``csjm demo``: the main job on the built-in paper rig, end to end.

Steps: plan tensions and compute K over a set of poses; shape the stiffness
and run a short closed loop; simulate an experiment; identify K and verify it
on held-out loads; diagnose a model-rig gap. Everything lands in one report
folder (figures, data, ``summary.json``, ``README.md``).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Callable

import numpy as np

from . import plots, so3
from .errors import InvalidInput
from .fileio import atomic_write_json, atomic_write_text
from .model import Model
from .planner import plan_tensions_batch
from .rig import Rig, paper_rig

MARKER = ".csjm_report"


@dataclasses.dataclass
class DemoContext:
    rig: Rig
    out_dir: Path
    rng: np.random.Generator
    quick: bool
    summary: dict = dataclasses.field(default_factory=dict)
    shared: dict = dataclasses.field(default_factory=dict)


def prepare_out_dir(out_dir: Path) -> Path:
    """Create the report folder; refuse a non-empty folder that is not a previous report."""
    out_dir = Path(out_dir)
    if out_dir.exists():
        if not out_dir.is_dir():
            raise InvalidInput(f"{out_dir} exists and is not a folder", "--out")
        if any(out_dir.iterdir()) and not (out_dir / MARKER).exists():
            raise InvalidInput(f"{out_dir} is a non-empty folder that is not a csjm report; "
                               "refusing to write into it (choose another --out)", "--out")
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / MARKER).write_text("csjm demo report folder\n")
    return out_dir


def step_core(ctx: DemoContext) -> dict:
    """Tensions and K over a ring of tilted poses under the platform's own weight."""
    rig, model = ctx.rig, Model(ctx.rig)
    tilts = np.deg2rad([0.0, 5.0, 10.0, 15.0, 20.0])
    azimuths = np.deg2rad([0.0, 60.0, 120.0])
    rotvecs = [np.zeros(3)] + [t * np.array([np.cos(a), np.sin(a), 0.0]) for t in tilts[1:] for a in azimuths]
    labels = ["upright"] + [f"tilt {np.rad2deg(t):.0f} deg @ {np.rad2deg(a):.0f}" for t in tilts[1:]
                            for a in azimuths]
    Rs = so3.exp(np.array(rotvecs))
    plans = plan_tensions_batch(rig, Rs, np.zeros((len(Rs), 3)))
    K = model.stiffness(Rs, plans.tensions_N)
    eig = np.linalg.eigvalsh(K)
    plots.tensions_and_ellipsoids(labels, plans.tensions_N, K, rig.t_min_N, rig.t_max_N,
                                  ctx.out_dir / "tensions_and_stiffness.png")
    rows = [{"pose": lab, "rotvec": rv.tolist(), "tensions_N": t.tolist(), "K": k.tolist(),
             "eigenvalues_Nm_per_rad": e.tolist()}
            for lab, rv, t, k, e in zip(labels, rotvecs, plans.tensions_N, K, eig)]
    return {"poses": rows, "max_equilibrium_residual_Nm": float(plans.equilibrium_residual_Nm.max()),
            "min_eigenvalue_Nm_per_rad": float(eig.min()), "figure": "tensions_and_stiffness.png"}


def step_shaping(ctx: DemoContext) -> dict:
    from .demo_shaping import run_demo

    return run_demo(ctx.rig, ctx.out_dir / "shaping")


def step_experiment_identify_verify(ctx: DemoContext) -> dict:
    from .demo_identify import run_demo
    from .testbed import simulate_experiment

    n_cycles = 4 if ctx.quick else 8
    log = simulate_experiment(ctx.rig, n_cycles=n_cycles, rng=ctx.rng)
    test_log = simulate_experiment(ctx.rig, n_cycles=2, rng=ctx.rng)
    data = ctx.out_dir / "experiment"
    data.mkdir(exist_ok=True)
    log.to_csv(data / "log.csv", overwrite=True)
    test_log.to_csv(data / "test_log.csv", overwrite=True)
    out = run_demo(ctx.rig, log, data, test_log=test_log)
    out["log"] = "experiment/log.csv"
    return out


def step_diagnose(ctx: DemoContext) -> dict:
    from .demo_diagnose import run_demo

    return run_demo(ctx.rig, ctx.out_dir / "diagnosis", ctx.rng)


STEPS: list[tuple[str, Callable[[DemoContext], dict]]] = [
    ("plan tensions and stiffness", step_core),
    ("stiffness shaping and closed loop", step_shaping),
    ("simulate experiment, identify, verify", step_experiment_identify_verify),
    ("diagnose model-rig gap", step_diagnose),
]


def run(out_dir: str | Path = "csjm_report", seed: int = 0, quick: bool = False,
        rig: Rig | None = None, progress: bool = True) -> dict:
    """Run every step; returns the summary (also written to ``summary.json``)."""
    from tqdm import tqdm

    ctx = DemoContext(rig or paper_rig(), prepare_out_dir(Path(out_dir)), np.random.default_rng(seed), quick)
    bar = tqdm(STEPS, desc="csjm demo", unit="step", disable=not progress)
    for name, step in bar:
        bar.set_postfix_str(name)
        t0 = time.perf_counter()
        result = step(ctx)
        result["seconds"] = round(time.perf_counter() - t0, 2)
        ctx.summary[name] = result
    atomic_write_json(ctx.out_dir / "summary.json", ctx.summary)
    atomic_write_text(ctx.out_dir / "README.md", _report(ctx))
    return ctx.summary


def _report(ctx: DemoContext) -> str:
    lines = ["# csjm demo report", "", f"Rig: paper rig (Section IV-A); seed {ctx.rng.bit_generator.state['state']['state'] % 1000}.", ""]
    for name, result in ctx.summary.items():
        lines += [f"## {name}", ""]
        for key, value in result.items():
            if isinstance(value, (int, float, str)):
                lines.append(f"- {key}: {value}")
        for fig in sorted(ctx.out_dir.rglob("*.png")):
            pass
        lines.append("")
    lines += ["## Figures", ""] + [f"![{p.stem}]({p.relative_to(ctx.out_dir).as_posix()})"
                                   for p in sorted(ctx.out_dir.rglob("*.png"))]
    return "\n".join(lines) + "\n"
