"""The decision rule's thresholds and the state one diagnosis shares across its candidate models.

The rule itself is stated in :mod:`csjm_opt.diagnose.selection.decision`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..model.rig import Rig
from .data.localisation import remaining_signature
from .data.noise import combine_scales, noise_floor, systematic
from .data.residuals import ResidualTable
from .fitting.augmented import AugmentedModel
from .selection.scoring import (
    CandidateScore,
    evidence_of,
    folds_by_cycle,
    improvement_rad,
    nested_f_test,
    paired_heldout_test,
    score,
)

ALPHA = 0.01
IMPROVE_MULT = 1.0
CLOSE_FRACTION = 0.8
HELDOUT_ALPHA = 0.10
#: Log Bayes factor (nats) by which a pair must beat every rival on the evidence route (>100: decisive).
EVIDENCE_MIN = 5.0
#: Models within this many nats of log evidence of the best are leading hypotheses (alternatives, --suggest).
LEAD_NATS = 10.0
#: Remaining structure matters (a stand-in warning) when its systematic part is this share of the floor.
MATERIAL_SHARE = 0.5
#: Singles a pair search starts from (the first effect, then the lowest held-out errors); 8 = the whole
#: vocabulary: every pair is fitted (with 3, the right pair was never tried on 2 of 17 separable pairs).
PAIR_SEEDS = 8
#: A model with more effective parameters than this share of 3 x cycles is *flexible* (36 hole offsets on a
#: short log): it never beats a few-number model that explains the log as well, and is named with a warning
#: only when such a model is not ruled out (selection.parsimonious, selection._look_alike_warning).
SHORT_LOG_SHARE = 0.5
#: A few-number look-alike of a flexible verdict must close this share of CLOSE_FRACTION (1: close the gap).
LOOK_ALIKE_SHARE = 1.0


class _Context:
    """Rows, held-out design and noise estimates shared by every model of one diagnosis."""

    def __init__(self, rig: Rig, train: ResidualTable, test: ResidualTable | None):
        self.rig, self.train, self.test = rig, train, test
        self.folds = None if test is not None else folds_by_cycle(train.cycle)
        self.held = test if test is not None else train
        self.local, self.local_dof = noise_floor(train)
        self.instrument = train.instrument_floor_rad
        self.sigma = 1.0                          # noise scale of the evidence (set once the floor is known)
        self._evidence: dict[int, float] = {}

    def evidence(self, sc: CandidateScore) -> float:
        """Laplace log evidence of ``sc`` at the diagnosis's noise scale (:mod:`.evidence`), over its variants."""
        if id(sc) not in self._evidence:
            self._evidence[id(sc)] = evidence_of(sc, self.sigma)
        return self._evidence[id(sc)]

    def score(self, effects: Sequence) -> CandidateScore:
        return score(AugmentedModel(self.rig, effects), self.train, self.test, self.folds, local=self.local_scale)

    @property
    def local_scale(self) -> tuple[float, float]:
        """The within-cycle noise estimate as ``(scale relative to the instrument model, dof)``."""
        local = self.local / self.instrument if np.isfinite(self.local) and self.instrument > 0 else float("nan")
        return float(local), float(self.local_dof)

    def scale(self, sc: CandidateScore) -> float:
        """Noise scale (relative to the instrument model) with ``sc`` as the model."""
        local, dof = self.local_scale
        return combine_scales(local, 3 * dof, float(np.sqrt(sc.noise_ratio2)),
                              3 * len(self.train) - sc.fit.p_eff)

    def noise_floor(self, sc: CandidateScore) -> float:
        """Noise floor of ``sc`` (rad): the noise alone, the yardstick of an improvement."""
        return self.scale(sc) * sc.instrument_floor_rad

    def floor(self, sc: CandidateScore) -> float:
        """Held-out noise floor of ``sc``: noise plus its parameters' estimation error (rad)."""
        return self.scale(sc) * sc.heldout_floor_rad

    def fraction(self, sc: CandidateScore) -> float:
        s = self.scale(sc)
        before = systematic(self.held.rms_rad, s * self.instrument)
        after = systematic(sc.heldout_rms_rad, s * sc.heldout_floor_rad)
        return float(1 - after / before) if before > 0 else 0.0

    def signature(self, sc: CandidateScore) -> dict:
        return remaining_signature(self.held, sc.heldout_zeta_rad, self.floor(sc), ALPHA, sc.heldout_blocks)

    def closes(self, sc: CandidateScore) -> bool:
        """Whether ``sc`` explains at least ``CLOSE_FRACTION`` of the systematic held-out gap."""
        return bool(self.fraction(sc) >= CLOSE_FRACTION)

    def compare(self, base: CandidateScore, sc: CandidateScore, level: float, floor: float) -> dict:
        F, p_f = nested_f_test(base.fit, sc.fit)
        p = paired_heldout_test(base, sc)
        imp = improvement_rad(base, sc)
        bad = sc.implausible()
        return {"p_value": p, "f_stat": F, "f_p_value": p_f, "improvement_rad": imp, "level": level,
                "significant": bool(p < level and imp >= IMPROVE_MULT * floor),
                "plausible": not bad, "implausible_params": bad}
