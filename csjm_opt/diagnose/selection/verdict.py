"""The verdict of a diagnosis as typed values: what is named, why, and which warnings go with it.

:class:`Verdict` is built by :func:`csjm_opt.diagnose.selection.decision.diagnose` in small steps (the
rule is stated in the guide, ``docs/guide/diagnosis.md``, section "The decision rule"); its
:meth:`Verdict.as_json` gives the ``verdict`` object of ``csjm diagnose --json`` and
:meth:`Secondary.as_json` the ``secondary`` one (keys in docs/conventions.md and
:mod:`csjm_opt.diagnose.selection.result`).
"""

from __future__ import annotations

import dataclasses

from .scoring import CandidateScore


@dataclasses.dataclass(frozen=True)
class Secondary:
    """The second effect of a pair verdict (``effect == "none"`` when there is none)."""

    effect: str = "none"
    heldout_rms_rad: float = float("nan")
    params: dict = dataclasses.field(default_factory=dict)
    fraction_explained: float = float("nan")
    p_value: float = float("nan")
    improvement_rad: float = float("nan")
    separable: bool = True
    max_correlation: float = float("nan")
    plausible: bool = True
    implausible_params: list = dataclasses.field(default_factory=list)

    def as_json(self) -> dict:
        """``{"effect": "none"}``, or every field.

        Returns
        -------
        dict
        """
        if self.effect == "none":
            return {"effect": "none"}
        return dataclasses.asdict(self)


@dataclasses.dataclass
class Verdict:
    """What a diagnosis names, the model behind it, why, and what the log does not rule out."""

    selected: str                     # a vocabulary effect, "none" or "unexplained"
    reason: str
    final: CandidateScore             # the model behind the gap after (selected [+ secondary], or the null)
    secondary: Secondary = dataclasses.field(default_factory=Secondary)
    warnings: list[str] = dataclasses.field(default_factory=list)
    evidence_margin: float | None = None
    more_probable_rivals: list[str] = dataclasses.field(default_factory=list)
    alternatives: list[str] = dataclasses.field(default_factory=list)
    secondary_alternatives: list[str] = dataclasses.field(default_factory=list)
    unsettled_rivals: list[dict] = dataclasses.field(default_factory=list)
    #: few-number models that explain the log as well as a flexible verdict (named in its warning)
    look_alikes: list[str] = dataclasses.field(default_factory=list)
    #: effects a flexible verdict may stand in for (named in its warning; ``selection.decision.stand_ins``)
    stand_ins: list[str] = dataclasses.field(default_factory=list)
    #: the residual's trend over the log's time order (sample order), when it has one
    time_trend: dict | None = None
    #: linear cable creep (outside the vocabulary) when it explains the log as well as the verdict
    creep: dict | None = None
    #: drum slip above a threshold (outside the vocabulary) when it explains the log as well as the verdict
    drum_slip: dict | None = None

    @property
    def named(self) -> bool:
        """Whether an effect is named (not ``none`` or ``unexplained``)."""
        return self.selected not in ("none", "unexplained")

    @property
    def model_name(self) -> str:
        """The named model, ``a`` or ``a+b``."""
        return self.final.name

    def warn(self, text: str) -> None:
        """Add a warning (once).

        Parameters
        ----------
        text : str
        """
        if text not in self.warnings:
            self.warnings.append(text)

    def as_json(self) -> dict:
        """The ``verdict`` object of ``csjm diagnose --json``.

        Returns
        -------
        dict
        """
        return {"selected": self.selected, "warnings": list(self.warnings), "reason": self.reason,
                "evidence_margin": self.evidence_margin, "more_probable_rivals": list(self.more_probable_rivals),
                "alternatives": list(self.alternatives), "secondary_alternatives": list(self.secondary_alternatives),
                "unsettled_rivals": list(self.unsettled_rivals), "look_alikes": list(self.look_alikes),
                "stand_ins": list(self.stand_ins), "time_trend": self.time_trend, "creep": self.creep,
                "drum_slip": self.drum_slip}
