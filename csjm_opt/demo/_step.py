"""What a ``csjm demo`` step gets and gives back.

A step is a function ``step(ctx: DemoContext) -> StepOutput``: it does its
work, writes its files under ``ctx.out_dir`` and returns its JSON-able summary
(stored in ``summary.json`` under the step's name) and its report section
(cell sources relative to that summary; figure paths relative to the report
folder). :data:`csjm_opt.demo.pipeline.STEPS` lists the steps in order.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from ..model.rig import Rig
from ..report.document import Section


@dataclasses.dataclass
class DemoContext:
    """Shared state of one demo run: rig, report folder, random generator, quick mode."""

    rig: Rig
    out_dir: Path
    rng: np.random.Generator
    quick: bool
    seed: int = 0
    summary: dict = dataclasses.field(default_factory=dict)
    shared: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass
class StepOutput:
    """A step's summary (JSON-able) and its report section."""

    summary: dict[str, Any]
    section: Section
