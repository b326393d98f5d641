"""``csjm demo``: the whole chain on the paper rig, step by step, into one report folder.

The pipeline (:mod:`csjm_opt.demo.pipeline`) runs its steps in order; each
step module holds one part of the job and its report section. The document
model and renderer the steps write with are in :mod:`csjm_opt.report`.
"""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .pipeline import STEPS
    from .pipeline import run as run_demo

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'STEPS': ('.pipeline', 'STEPS'),
    'run_demo': ('.pipeline', 'run'),
}
__getattr__, __dir__ = lazy_exports(__name__, _LAZY)

__all__ = ["STEPS", "run_demo"]
