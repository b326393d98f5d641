"""Sim-to-real gap diagnosis: residuals, localisation, effects, selection, report.

Entry point: :func:`csjm_opt.diagnose.selection.diagnose` (``csjm diagnose``).
"""

from __future__ import annotations

from .effects import EFFECTS, Effect, make_effect
from .result import Diagnosis
from .selection import ALPHA, diagnose

#: The words ``selected`` can take.
VOCABULARY = ("none",) + tuple(EFFECTS) + ("unexplained",)

__all__ = ["ALPHA", "EFFECTS", "VOCABULARY", "Diagnosis", "Effect", "diagnose", "make_effect"]
