"""``csjm demo``: the main job on the built-in paper rig, end to end.

Steps (:data:`STEPS`, in order): plan tensions and compute K over a set of
poses; shape the stiffness and run a short closed loop; simulate an
experiment, identify K and verify it on held-out loads; diagnose a model-rig
gap; controllers with dynamics in a closed loop on MuJoCo. Each step is a
function ``step(ctx) -> StepOutput`` (see :mod:`csjm_opt.demo._step`)
returning its summary and its report section; adding a step is adding one
entry to :data:`STEPS`. Everything lands in one
report folder: ``index.html`` (open it in a browser) and its Markdown twin
``README.md``, figures beside them, ``summary.json`` with every number, and the
sub-reports ``experiment/index.html`` and ``diagnosis/index.html``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import numpy as np

from .._fileio import atomic_write_json
from ..model.rig import Rig, paper_rig
from ..report.document import Document, Hyperlink
from ..report.folder import prepare_out_dir
from ..report.render import write_document
from . import core_step, diagnose_step, identify_step, mujoco_step, shaping_step
from ._step import DemoContext, StepOutput

#: The demo's steps: (name = key in summary.json, step function), in order.
STEPS: list[tuple[str, Callable[[DemoContext], StepOutput]]] = [
    (core_step.NAME, core_step.step),
    (shaping_step.NAME, shaping_step.step),
    (identify_step.NAME, identify_step.step),
    (diagnose_step.NAME, diagnose_step.step),
    (mujoco_step.NAME, mujoco_step.step),
]

__all__ = ["STEPS", "DemoContext", "StepOutput", "run"]


def run(out_dir: str | Path = "csjm_report", seed: int = 0, quick: bool = False,
        rig: Rig | None = None, progress: bool = True) -> dict:
    """Run every step; returns the summary (also written to ``summary.json``).

    Parameters
    ----------
    out_dir : str or Path
        Report folder (created; a non-empty folder must be a previous report).
    seed : int
        Seed of the simulated experiments.
    quick : bool
        Shorter steps (smaller experiments, no second-effect search): a smoke test.
    rig : Rig, optional
        Default: the paper rig.
    progress : bool
        tqdm bar on stderr.

    Returns
    -------
    dict
        Step name -> that step's summary (plus ``seconds``).
    """
    from tqdm import tqdm

    ctx = DemoContext(rig or paper_rig(), prepare_out_dir(Path(out_dir)), np.random.default_rng(seed), quick,
                      seed)
    sections = []
    start = time.perf_counter()
    bar = tqdm(STEPS, desc="csjm demo", unit="step", disable=not progress)
    for name, step in bar:
        bar.set_postfix_str(name)
        t0 = time.perf_counter()
        out = step(ctx)
        out.summary["seconds"] = round(time.perf_counter() - t0, 2)
        ctx.summary[name] = out.summary
        sections.append(out.section.prefix_sources((name,)))
    atomic_write_json(ctx.out_dir / "summary.json", ctx.summary)
    write_document(_document(ctx, sections, time.perf_counter() - start), ctx.out_dir, md_name="README.md")
    return ctx.summary


def _document(ctx: DemoContext, sections: list, seconds: float) -> Document:
    lead = (f"The main job of csjm_opt on the paper rig (Section IV-A, `rigs/paper.toml`), every step with "
            f"simulated data: seed {ctx.seed}, {'quick' if ctx.quick else 'full'} run, {seconds:.0f} s. Each "
            "section starts with what was done, what came out and whether that is what one should expect; "
            "numbers are rounded for reading, `summary.json` keeps every digit.")
    links = [Hyperlink("summary.json", "summary.json", "every number of this report, by step")]
    for name, href, note in (("experiment/index.html", "identification report", "the identification step in full"),
                             ("diagnosis/index.html", "diagnosis report", "the diagnosis step in full")):
        if (ctx.out_dir / name).exists():
            links.append(Hyperlink(name, href, note))
    return Document("csjm demo report", lead, sections, data_file="summary.json", links=links)
