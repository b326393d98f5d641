"""One design evaluated under a sweep's settings: its identifier and its result-file record."""

from __future__ import annotations

import hashlib
import json
import time
from typing import Any

from ..errors import CsjmError
from .evaluation_settings import EvaluationSettings
from .geometry import design_rig
from .metrics import evaluate

#: Record keys that depend on the machine, not on the design (left out of comparisons).
TIMING_KEYS = ("seconds",)


def design_id(settings_digest: str, params: dict[str, float]) -> str:
    """Stable identifier of a design under given settings."""
    text = json.dumps({"settings": settings_digest, "params": params}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:20]


def evaluate_design(params: dict[str, float], settings: EvaluationSettings) -> dict[str, Any]:
    """Metrics record of one design, as stored in a sweep's result file.

    Parameters
    ----------
    params : dict of str to float
        Design parameters (names in :data:`csjm_opt.design.PARAMETERS`).
    settings : EvaluationSettings
        Base design, sampling, loads and metric options of the sweep.

    Returns
    -------
    dict
        ``{"params", "status", "workspace_fraction", "min_stiffness_Nm_per_rad", "metrics",
        "error"}``; ``status`` is ``"ok"``, ``"invalid"`` (geometry rejected, ``error`` says why)
        or ``"error"``. Never raises for a bad design: the record carries the reason.
    """
    start = time.perf_counter()
    try:
        rig = design_rig({**settings.base, **params}, settings.limits)
    except CsjmError as exc:
        return {"params": params, "status": "invalid", "error": str(exc), "metrics": None,
                "workspace_fraction": None, "min_stiffness_Nm_per_rad": None,
                "seconds": time.perf_counter() - start}
    try:
        m = evaluate(rig, settings.sampling, settings.loads, settings.options).as_dict()
    except CsjmError as exc:  # deterministic: recorded, so a resumed run does not retry it
        return {"params": params, "status": "error", "error": f"{type(exc).__name__}: {exc}",
                "metrics": None, "workspace_fraction": None, "min_stiffness_Nm_per_rad": None,
                "seconds": time.perf_counter() - start}
    broken = settings.interference.violation(m) if settings.interference is not None else None
    if broken is not None:
        return {"params": params, "status": "invalid", "error": f"interference: {broken}", "metrics": m,
                "workspace_fraction": None, "min_stiffness_Nm_per_rad": None,
                "seconds": time.perf_counter() - start}
    return {"params": params, "status": "ok", "error": None, "metrics": m,
            "workspace_fraction": m["workspace_fraction"],
            "min_stiffness_Nm_per_rad": m["min_stiffness_Nm_per_rad"],
            "seconds": time.perf_counter() - start}
