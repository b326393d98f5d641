"""The result of a diagnosis and its JSON form (``csjm diagnose --json``).

:meth:`Diagnosis.as_json` returns (strict JSON, non-finite numbers as ``null``)::

    baseline            {heldout_rms_rad, train_rms_rad, model, failed_forward_solves}
                        the rig file's model as given (no fitting): the gap the user sees
    nominal_refit       {heldout_rms_rad, train_rms_rad, bic, params, param_sd, model}
                        the null model: nominal + common rest-length offset
    noise_floor_rad     noise floor of the nominal model (rad); noise_floor_estimates: its parts
    candidates          [{effect, heldout_rms_rad, train_rms_rad, params, param_sd, nuisance, derived,
                          bic, p_eff, rank, n_params, condition, identifiable, failed_forward_solves,
                          fraction_explained, noise_floor_rad,
                          p_value (held-out paired test vs nominal_refit), f_stat, f_p_value
                          (linearised, training rows; informative only), improvement_rad,
                          significant (held-out test passed and improvement >= IMPROVE_MULT floors),
                          plausible, implausible_params, prior_ranges, closes_gap,
                          residual_signature_p}]
                        failed fits: {effect, error, significant: false, plausible: false}
    selected            one effect of the vocabulary, "none" or "unexplained"
    secondary           {"effect": name, heldout_rms_rad, params, fraction_explained, p_value,
                         improvement_rad, separable, max_correlation, plausible, implausible_params}
                        or {"effect": "none"}
    pairs               [{effects: [a, b], separable, max_correlation, fitted,
                          (searched pairs:) predicted_log_evidence (the screen's prediction, null where
                          none is made; a pair predicted far below is not fitted, model_fits.SCREEN_NATS),
                          (fitted pairs:) heldout_rms_rad, fraction_explained, p_value_vs_first,
                          improvement_rad, significant, plausible, implausible_params, bic}]
    steps               the greedy path: [{model, heldout_rms_rad, fraction_explained}]
    confounded_with     effects whose single fits are not separable from the selected one
                        and not significantly worse on held-out cycles
    verdict             {selected, reason, warnings[], alternatives[], secondary_alternatives[], look_alikes[],
                        time_trend, creep, drum_slip}: why, in
                        words; alternatives are detected effects not separable from the selected one on
                        this log; secondary_alternatives are effects that, paired with the selected one,
                        close the gap as well (evidence within LEAD_NATS) and are not separable from
                        the named second effect; more_probable_rivals are plausible models that
                        close the gap with higher evidence than the named one (not confirmed on
                        held-out cycles); evidence_margin is the named model's lead in nats;
                        unsettled_rivals are every model the log does not rule out (one adding an
                        effect with higher evidence, or one replacing the verdict with higher
                        evidence or within EVIDENCE_MIN nats while the verdict does not beat it
                        on held-out cycles; rivals.py); look_alikes are few-number models that explain
                        the log as well as a flexible verdict (hole offsets); time_trend is the trend of
                        the residual's cycle means over the log's time order (trend.py); creep is
                        {heldout_rms_rad, nats, heldout_p, percent_per_row} of linear cable creep (a probe
                        outside the vocabulary, effects/cable_creep.py) when it explains the log as well
                        as the verdict (else null); drum_slip likewise {heldout_rms_rad, nats, heldout_p,
                        slip_percent_of_excess, slip_threshold_N} of cables slipping on their drums above a
                        threshold (effects/drum_slip.py)
    significance        the decision rule's constants and tests
    gap                 {before_rad, after_rad, fraction_explained, systematic_before_rad,
                         systematic_after_rad, noise_floor_after_rad, fraction_explained_by_nominal_refit,
                         model}
    remaining_signature residual-structure test on the final model's held-out residuals
    gap_signature       the same test on nominal_refit's (is there a gap at all?)
    localisation        where the residual lies (by axis, tilt, azimuth, load, branch; hysteresis)
    rows, heldout       row counts (rows diagnosed); "test file" or "grouped K-fold by cycle"
    left_out_rows       [{log, sample, cycle, reason, ...}]: rows left out of the diagnosis. reason
                        "gross_residual" (with outlier_ratio): the model that fits the log does not come near
                        the row and it stands apart from its cycle (data.residuals.gross_rows);
                        "ill_conditioned" (with pose_noise_rad, median_pose_noise_rad): the rig file's model is
                        nearly singular at the measured pose (a cable slack in the model; pose noise above
                        data.residuals.ILL_ROW_FACTOR times the median)
    outlier_ratio_max   {log, test log}: each log's largest row outlier ratio (data.residuals.gross_rows; rows
                        above data.residuals.GROSS_ROW_FACTOR are gross), on the rows the diagnosis kept
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..data.noise import systematic
from ..data.residuals import ResidualTable
from .scoring import CandidateScore
from .verdict import Secondary, Verdict


@dataclasses.dataclass(frozen=True, eq=False)
class Diagnosis:
    """Everything ``csjm diagnose`` reports (see the module doc for :meth:`as_json`)."""

    train: ResidualTable
    test: ResidualTable | None
    baseline: CandidateScore          # nominal refit (null model of the tests)
    candidates: dict[str, CandidateScore]
    noise_floor_rad: float
    noise_estimates: dict
    tests: dict[str, dict]
    verdict: Verdict                  # what is named, the model behind it, why, the warnings
    confounded_with: list[str] = dataclasses.field(default_factory=list)
    localisation: dict = dataclasses.field(default_factory=dict)
    remaining: dict = dataclasses.field(default_factory=dict)
    failed: dict = dataclasses.field(default_factory=dict)   # effect -> error message
    pairs: list = dataclasses.field(default_factory=list)
    steps: list = dataclasses.field(default_factory=list)
    gap_signature: dict = dataclasses.field(default_factory=dict)
    rule: dict = dataclasses.field(default_factory=dict)
    pair_scores: dict = dataclasses.field(default_factory=dict)   # (a, b) -> CandidateScore of fitted pairs
    #: rows left out: gross outliers and rows where the rig file's model is nearly singular (decision._well_conditioned)
    left_out_rows: list = dataclasses.field(default_factory=list)
    #: each log's largest row outlier ratio on the rows kept ("log", "test log"; decision._gross_rows)
    outlier_ratio_max: dict = dataclasses.field(default_factory=dict)

    @property
    def selected(self) -> str:
        """The verdict's name: a vocabulary effect, ``none`` or ``unexplained``."""
        return self.verdict.selected

    @property
    def secondary(self) -> Secondary:
        """The second effect of a pair verdict (``effect == "none"`` else)."""
        return self.verdict.secondary

    @property
    def final(self) -> CandidateScore:
        """The model behind ``gap["after_rad"]`` (selected, or selected + secondary; the null model else)."""
        return self.verdict.final

    @property
    def selected_score(self) -> CandidateScore:
        """Score of the model behind the reported gap.

        Returns
        -------
        CandidateScore
            The final model (selected, or selected + secondary) if set, else the selected candidate,
            else the nominal refit.
        """
        return self.verdict.final

    @property
    def heldout_table(self) -> ResidualTable:
        """Residual table of the held-out rows.

        Returns
        -------
        ResidualTable
            The test log's table if one was given, else the training table (cross-validation).
        """
        return self.test if self.test is not None else self.train

    @property
    def nominal_heldout_rms_rad(self) -> float:
        """The rig file's model on the held-out rows (no fitting)."""
        return self.heldout_table.rms_rad

    def floor_of(self, sc: CandidateScore | None) -> float:
        """Noise floor of a model: the data's noise level propagated through the model's own tangent."""
        if sc is None:
            return self.noise_floor_rad
        return self.noise_estimates["noise_scale"] * sc.heldout_floor_rad

    def fraction(self, sc: CandidateScore) -> float:
        """``1 - systematic(after) / systematic(before)``, each against its own model's noise floor."""
        sb = systematic(self.nominal_heldout_rms_rad, self.noise_floor_rad)
        sa = systematic(sc.heldout_rms_rad, self.floor_of(sc))
        return float(1.0 - sa / sb) if sb > 0 else 0.0

    @property
    def gap(self) -> dict:
        """The model-rig gap before and after the selected model, on held-out rows.

        Returns
        -------
        dict
            ``before_rad`` and ``after_rad`` (RMS, rad), ``fraction_explained``, the systematic parts
            (rad) and noise floor after, the fraction the nominal refit alone explains, and ``model``.
        """
        sel = self.selected_score
        before, after = self.nominal_heldout_rms_rad, sel.heldout_rms_rad
        return {"before_rad": before, "after_rad": after, "fraction_explained": self.fraction(sel),
                "systematic_before_rad": systematic(before, self.noise_floor_rad),
                "systematic_after_rad": systematic(after, self.floor_of(sel)),
                "noise_floor_after_rad": self.floor_of(sel),
                "fraction_explained_by_nominal_refit": self.fraction(self.baseline), "model": sel.name}

    def as_json(self) -> dict:
        """The keys of the module doc; strict JSON: non-finite numbers become ``null``."""
        return _strict(self._as_dict())

    def _candidate(self, name: str, sc: CandidateScore) -> dict:
        f = sc.fit
        m = f.model
        return {"effect": name, "heldout_rms_rad": sc.heldout_rms_rad, "train_rms_rad": sc.train_rms_rad,
                "params": f.params(), "param_sd": f.param_sd(),
                "nuisance": {k: v for k, v in f.params(False).items() if k not in f.params()},
                "derived": {k: v for e, p in zip(m.effects, m.effect_params(f.theta))
                            for k, v in e.describe(p).items()},
                "prior_ranges": {k: list(v) for e in m.effects for k, v in e.ranges().items()},
                "bic": f.bic, "p_eff": f.p_eff, "rank": f.rank, "n_params": m.n_params,
                "condition": f.condition, "identifiable": f.identifiable, "failed_forward_solves": sc.failed_rows,
                "fraction_explained": self.fraction(sc), "noise_floor_rad": self.floor_of(sc),
                **self.tests.get(name, {})}

    def _as_dict(self) -> dict:
        cands = [self._candidate(n, sc) for n, sc in self.candidates.items()]
        for name, msg in self.failed.items():
            cands.append({"effect": name, "heldout_rms_rad": None, "params": {}, "bic": None, "significant": False,
                          "plausible": False, "implausible_params": [], "error": msg})
        b = self.baseline
        return {
            "baseline": {"heldout_rms_rad": self.nominal_heldout_rms_rad, "train_rms_rad": self.train.rms_rad,
                         "model": "nominal, rig file as given (no fitted parameters)",
                         "failed_forward_solves": int(np.sum(~self.train.converged))},
            "nominal_refit": {"heldout_rms_rad": b.heldout_rms_rad, "train_rms_rad": b.train_rms_rad,
                              "bic": b.fit.bic, "params": b.fit.params(False), "param_sd": b.fit.param_sd(False),
                              "model": "nominal + common rest-length offset; null model of the tests"},
            "noise_floor_rad": self.noise_floor_rad,
            "noise_floor_estimates": self.noise_estimates,
            "candidates": cands,
            "selected": self.selected,
            "secondary": self.secondary.as_json(),
            "pairs": self.pairs,
            "steps": self.steps,
            "confounded_with": self.confounded_with,
            "verdict": self.verdict.as_json(),
            "significance": self.rule,
            "heldout": "test file" if self.test is not None else "grouped K-fold by cycle",
            "gap": self.gap,
            "remaining_signature": self.remaining,
            "gap_signature": self.gap_signature,
            "localisation": self.localisation,
            "rows": {"train": len(self.train), "test": 0 if self.test is None else len(self.test)},
            "left_out_rows": self.left_out_rows,
            "outlier_ratio_max": self.outlier_ratio_max,
        }


def _strict(x):
    """Plain Python types, NaN/inf -> None (strict JSON)."""
    if isinstance(x, dict):
        return {str(k): _strict(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_strict(v) for v in x]
    if isinstance(x, np.ndarray):
        return _strict(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    return x
