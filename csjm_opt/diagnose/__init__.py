"""Sim-to-real gap diagnosis: residuals, localisation, effects, selection, report.

Entry point: :func:`csjm_opt.diagnose.selection.diagnose` (``csjm diagnose``).
"""

from __future__ import annotations

from .effects import EFFECTS, Effect, make_effect
from .selection import ALPHA, Diagnosis, diagnose

#: The docs/conventions.md vocabulary of ``effect`` / ``selected``.
VOCABULARY = ("none",) + tuple(EFFECTS)

__all__ = ["ALPHA", "EFFECTS", "VOCABULARY", "Diagnosis", "Effect", "diagnose", "make_effect"]
