"""Sim-to-real gap diagnosis: residuals, localisation, effects, selection, report.

Entry points: :func:`csjm_opt.diagnose.selection.decision.diagnose` (``csjm diagnose``) and
:func:`csjm_opt.diagnose.suggest.experiment.suggest_experiment` (``csjm diagnose --suggest N``).
"""

from __future__ import annotations

from .data.extra import append_log
from .effects import EFFECTS, Effect, make_effect
from .fitting.evidence import log_evidence
from .selection.decision import ALPHA, diagnose
from .selection.result import Diagnosis
from .suggest.dead_weights import Load, default_load_set, load_load_set
from .suggest.experiment import Suggestion, protocol_text, suggest_experiment, suggestion_markdown

#: The words ``selected`` can take.
VOCABULARY = ("none",) + tuple(EFFECTS) + ("unexplained",)

__all__ = ["ALPHA", "Diagnosis", "EFFECTS", "Effect", "Load", "Suggestion", "VOCABULARY", "append_log",
           "default_load_set", "diagnose", "load_load_set", "log_evidence", "make_effect",
           "protocol_text", "suggest_experiment", "suggestion_markdown"]
