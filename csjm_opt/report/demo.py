"""``csjm demo``: the main job on the built-in paper rig, end to end.

Steps: plan tensions and compute K over a set of poses; shape the stiffness
and run a short closed loop; simulate an experiment; identify K and verify it
on held-out loads; diagnose a model-rig gap; controllers with dynamics in a
closed loop on MuJoCo. Everything lands in one report
folder (figures, data, ``summary.json``, ``README.md``).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Callable

import numpy as np

from .. import _plotting as plots, so3
from ..errors import InvalidInput
from .._fileio import atomic_write_json, atomic_write_text
from ..model.numeric import Model
from ..planning.planner import plan_tensions_batch
from ..model.rig import Rig, paper_rig

MARKER = ".csjm_report"


@dataclasses.dataclass
class DemoContext:
    rig: Rig
    out_dir: Path
    rng: np.random.Generator
    quick: bool
    seed: int = 0
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
    from .shaping_step import run_demo

    return run_demo(ctx.rig, ctx.out_dir / "shaping")


def step_experiment_identify_verify(ctx: DemoContext) -> dict:
    """A simulated identification experiment (paper noise), then identify, verify, fit parameters."""
    from .identify_step import run_demo
    from ..testbed.identification import simulate_identification_experiment

    log = simulate_identification_experiment(ctx.rig, n_cycles=3 if ctx.quick else 6, rng=ctx.rng,
                                             loads_per_cycle=20)
    data = ctx.out_dir / "experiment"
    data.mkdir(exist_ok=True)
    log.to_csv(data / "log.csv", overwrite=True)
    out = run_demo(ctx.rig, log, data)  # held out: every other load row of each cycle
    out["log"] = "experiment/log.csv"
    return out


def step_diagnose(ctx: DemoContext) -> dict:
    from .diagnose_step import run_demo

    return run_demo(ctx.rig, ctx.out_dir / "diagnosis", ctx.rng)


def step_mujoco(ctx: DemoContext) -> dict:
    from .mujoco_step import step

    return step(ctx)


STEPS: list[tuple[str, Callable[[DemoContext], dict]]] = [
    ("plan tensions and stiffness", step_core),
    ("stiffness shaping and closed loop", step_shaping),
    ("simulate experiment, identify, verify", step_experiment_identify_verify),
    ("diagnose model-rig gap", step_diagnose),
    ("dynamic closed loop on MuJoCo", step_mujoco),
]


def run(out_dir: str | Path = "csjm_report", seed: int = 0, quick: bool = False,
        rig: Rig | None = None, progress: bool = True) -> dict:
    """Run every step; returns the summary (also written to ``summary.json``)."""
    from tqdm import tqdm

    ctx = DemoContext(rig or paper_rig(), prepare_out_dir(Path(out_dir)), np.random.default_rng(seed), quick,
                      seed)
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
    """The report folder's README.md: every step's numbers, then every figure."""
    lines = ["# csjm demo report", "",
             f"Rig: the paper rig (Section IV-A, `rigs/paper.toml`); seed {ctx.seed}; "
             f"{'quick' if ctx.quick else 'full'} run. Numbers are SI (rad, N, N m, N m/rad).", ""]
    for name, result in ctx.summary.items():
        lines += [f"## {name}", ""] + _render(result) + [""]
    lines += ["## Figures", ""]
    for p in sorted(ctx.out_dir.rglob("*.png")):
        rel = p.relative_to(ctx.out_dir).as_posix()
        lines += [f"### {rel}", "", f"![{p.stem}]({rel})", ""]
    return "\n".join(lines) + "\n"


def _render(value, depth: int = 0) -> list[str]:
    """Markdown bullets for a JSON-able summary (matrices inline, long lists shortened)."""
    pad = "  " * depth
    out: list[str] = []
    for key, item in value.items():
        if isinstance(item, dict):
            out.append(f"{pad}- {key}:")
            out += _render(item, depth + 1)
        elif isinstance(item, list) and item and all(isinstance(x, dict) for x in item):
            out.append(f"{pad}- {key}: {len(item)} entries")
            for entry in item[:8]:
                scalars = {k: v for k, v in entry.items() if not isinstance(v, (list, dict))}
                out.append(f"{pad}  - " + ", ".join(f"{k} {_fmt(v)}" for k, v in scalars.items()))
        else:
            out.append(f"{pad}- {key}: {_fmt(item)}")
    return out


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, list):
        arr = np.asarray(v, dtype=object)
        if arr.ndim == 2 and arr.size <= 16 and all(isinstance(x, (int, float)) for x in arr.ravel()):
            return "`" + np.array2string(np.asarray(v, float), precision=3, suppress_small=True,
                                         separator=", ").replace("\n", "") + "`"
        if len(v) > 8:
            return f"[{', '.join(_fmt(x) for x in v[:6])}, ... ({len(v)} items)]"
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)
