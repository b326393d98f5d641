"""The diagnosis step of ``csjm demo``: inject an effect, find it, report it."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ..diagnose import diagnose
from ..model.rig import Rig
from ..report.diagnosis.report import write_report
from ..report.document import (
    Block,
    Cell,
    Column,
    Figure,
    Hyperlink,
    Links,
    Section,
    Table,
    format_number,
    quantity_table,
    sig,
)
from ..testbed import simulate_experiment
from ._step import DemoContext, StepOutput

NAME = "diagnose model-rig gap"
#: The effect the demo injects (friction: the paper's first suspect, Section IV-D).
DEMO_EFFECT = "friction"


def run_demo(rig: Rig, out_dir: Path, rng: np.random.Generator, effect: str = DEMO_EFFECT,
             severity: float = 1.0, n_cycles: int = 12, secondary: bool = True) -> dict:
    """Simulate a log with ``effect`` injected, diagnose it, write the report into ``out_dir``.

    Parameters
    ----------
    rig : Rig
    out_dir : Path
        Folder of the diagnosis report (``index.html``, ``index.md``, figures, ``diagnosis.json``, ``log.csv``).
    rng : numpy.random.Generator
    effect : str
        Effect injected into the simulated rig.
    severity : float
        Its size relative to the testbed's typical value.
    n_cycles : int
        Cycles of the simulated log.
    secondary : bool
        Also search for a second effect on top of the selected one (the costly part).

    Returns
    -------
    dict
        JSON-able summary (true and selected effect, gap, report paths relative to ``out_dir``).
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    log = simulate_experiment(rig, n_cycles, rng, effect=effect, severity=severity)
    log.to_csv(out_dir / "log.csv", overwrite=True)
    d = diagnose(rig, log, secondary=secondary)
    write_report(d, out_dir, "log.csv (simulated, effect injected: " + effect + ")", rig=rig)
    j = d.as_json()
    return {"injected": effect, "severity": severity, "selected": j["selected"],
            "correct": j["selected"] == effect, "confounded_with": j["confounded_with"],
            "gap": j["gap"], "noise_floor_rad": j["noise_floor_rad"], "rows": len(log),
            "candidates": {c["effect"]: c["heldout_rms_rad"] for c in j["candidates"]},
            "report": "index.md", "report_html": "index.html", "log": "log.csv", "n_cycles": n_cycles,
            "secondary_search": secondary,
            "secondary": (j.get("secondary") or {}).get("effect", "none"),
            "seconds": time.perf_counter() - t0}


def step(ctx: DemoContext) -> StepOutput:
    """The demo step: 6 cycles and no second-effect search when quick, 12 cycles and the search otherwise."""
    summary = run_demo(ctx.rig, ctx.out_dir / "diagnosis", ctx.rng, n_cycles=6 if ctx.quick else 12,
                       secondary=not ctx.quick)
    return StepOutput(summary, section(summary).rebase("diagnosis"))


def section(s: dict) -> Section:
    """The report section of :func:`run_demo`'s summary (paths relative to its folder)."""
    g = s["gap"]
    verdict = (f"Injected `{s['injected']}` (severity {s['severity']:g}) into a simulated log of "
               f"{s.get('n_cycles', '?')} cycles ({s['rows']} rows); the diagnosis selected `{s['selected']}`: "
               + ("correct, as expected" if s["correct"] else "NOT the injected effect")
               + (f" (confounded with {', '.join(s['confounded_with'])})" if s["confounded_with"] else "")
               + f". Held-out gap {sig(g['before_rad'], 3, 1e3)} -> {sig(g['after_rad'], 3, 1e3)} mrad RMS "
               f"(noise floor {sig(s['noise_floor_rad'], 3, 1e3)} mrad), "
               f"{format_number(g['fraction_explained'], 'fix0', 100)}% of the systematic gap closed.")
    facts = quantity_table([
        ("gap before (nominal model)", Cell(g["before_rad"], scale=1e3, src=("gap", "before_rad")), "mrad", ""),
        ("gap after (selected model)", Cell(g["after_rad"], scale=1e3, src=("gap", "after_rad")), "mrad",
         "near the noise floor"),
        ("noise floor", Cell(s["noise_floor_rad"], scale=1e3, src=("noise_floor_rad",)), "mrad", ""),
        ("share of the systematic gap closed", Cell(g["fraction_explained"], "fix1", 100.0,
                                                    ("gap", "fraction_explained")), "%", "close to 100"),
    ], expectation=True)
    cands = Table([Column("candidate effect"), Column("held-out RMS", "mrad", scale=1e3)],
                  [[name + (" (selected)" if name == s["selected"] else ""), Cell(v, src=("candidates", name))]
                   for name, v in s["candidates"].items()], "Held-out error of each candidate model")
    blocks: list[Block] = [facts, cands,
              Figure("candidates.png", "Held-out error of every candidate against the noise floor."),
              Links([Hyperlink(s.get("report_html", "index.html"), "diagnosis report",
                          "verdict, figures, fitted parameters with units, where the gap lies"),
                     Hyperlink(s["log"], "log.csv", "the simulated measurement log")])]
    return Section("Sim-to-real diagnosis", verdict, "ok" if s["correct"] and not s["confounded_with"] else "warn",
                   blocks)
