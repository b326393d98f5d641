"""Sim-to-real gap diagnosis: residuals, localisation, effects, selection, report.

Entry points: :func:`csjm_opt.diagnose.selection.decision.diagnose` (``csjm diagnose``) and
:func:`csjm_opt.diagnose.suggest.experiment.suggest_experiment` (``csjm diagnose --suggest N``).
"""


from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from .data.extra import append_log
    from .effects import EFFECTS, Effect, make_effect
    from .fitting.evidence import log_evidence
    from .selection.decision import ALPHA, diagnose
    from .selection.result import Diagnosis
    from .suggest.dead_weights import DeadWeight, default_dead_weights, read_dead_weights
    from .suggest.experiment import Suggestion, protocol_text, suggest_experiment, suggestion_markdown

#: Public name -> (module, attribute): imported on first use (PEP 562), so importing this package is free.
_LAZY: dict[str, tuple[str, str | None]] = {
    'append_log': ('.data.extra', 'append_log'),
    'EFFECTS': ('.effects', 'EFFECTS'),
    'Effect': ('.effects', 'Effect'),
    'make_effect': ('.effects', 'make_effect'),
    'log_evidence': ('.fitting.evidence', 'log_evidence'),
    'ALPHA': ('.selection.decision', 'ALPHA'),
    'diagnose': ('.selection.decision', 'diagnose'),
    'Diagnosis': ('.selection.result', 'Diagnosis'),
    'DeadWeight': ('.suggest.dead_weights', 'DeadWeight'),
    'default_dead_weights': ('.suggest.dead_weights', 'default_dead_weights'),
    'read_dead_weights': ('.suggest.dead_weights', 'read_dead_weights'),
    'Suggestion': ('.suggest.experiment', 'Suggestion'),
    'protocol_text': ('.suggest.experiment', 'protocol_text'),
    'suggest_experiment': ('.suggest.experiment', 'suggest_experiment'),
    'suggestion_markdown': ('.suggest.experiment', 'suggestion_markdown'),
}
_getattr, _dir = lazy_exports(__name__, _LAZY)


def __getattr__(name: str):
    """The lazy names, and ``VOCABULARY``: ``none``, the effects, ``unexplained``."""
    if name == "VOCABULARY":
        from .effects import EFFECTS

        return ("none",) + tuple(EFFECTS) + ("unexplained",)
    return _getattr(name)


def __dir__() -> list[str]:
    """Every public name, the lazy ones included."""
    return sorted(set(_dir()) | {"VOCABULARY"})

__all__ = ["ALPHA", "Diagnosis", "EFFECTS", "Effect", "DeadWeight", "Suggestion", "VOCABULARY", "append_log",
           "default_dead_weights", "diagnose", "read_dead_weights", "log_evidence", "make_effect",
           "protocol_text", "suggest_experiment", "suggestion_markdown"]
