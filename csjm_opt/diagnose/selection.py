"""Candidate scoring and selection: held-out by cycle, BIC, a significance test.

The *baseline* is the nominal model exactly as the rig file gives it (no
fitting: its held-out and training errors are its plain errors on those
rows); this is the sim-to-real gap the user sees. Every candidate is the
nominal model with its nuisance parameters (stiffness scale, common
rest-length offset) plus one effect; the *null* model ``nominal_refit`` has
the nuisance parameters only, so a candidate must explain more than a
recalibration of the nominal parameters would. Fits use linearised,
whitened pose residuals (:mod:`.fit`); held-out scores use full forward
statics of the fitted model on rows the fit did not see: ``TEST.csv`` when
given, else grouped K-fold cross-validation by ``cycle`` (K = min(5, cycles),
cycles dealt to folds in order; never random row splits).

Decision (stated level ``ALPHA = 0.01``): a candidate *beats the nominal
model significantly* when (1) the nested F-test of its effect parameters on
the training rows rejects "all zero" at ``ALPHA / 6`` (Bonferroni over the six
candidates, family-wise level ``ALPHA``), and (2) its held-out RMS is below
``nominal_refit``'s with a one-sided paired t-test over held-out cycles at
``HELDOUT_ALPHA = 0.10``. Among those, the lowest BIC is selected; otherwise
``none``. Other significant candidates whose held-out errors are not
significantly worse than the selected one's are reported as confounded.

Noise floor: the data's noise level relative to the instrument model
(Tables 1-2) comes from two estimates, both of which can only overestimate it when a
model misses something: the within-cycle estimate
(:mod:`.noise`) and the selected model's (``nominal_refit`` for ``none``)
whitened forward-statics residual on its training rows
(``sqrt(RSS / (N - p_eff))``; the selection does not use the floor),
pooled when they agree within sampling error, else the smaller one. A model's floor is that level
propagated through the model's own tangent (a softer model turns the same
moment noise into more pose noise); ``noise_floor_rad`` is the nominal
model's. The gap's systematic part is ``sqrt(rms^2 - floor^2)`` against each
model's own floor; ``fraction_explained = 1 - systematic(after) /
systematic(before)``.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Sequence

import numpy as np
from scipy import stats

from ..errors import InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.rig import Rig
from .augmented import AugmentedModel
from .effects import EFFECTS, make_effect
from .fit import FitResult, fit_model
from .noise import noise_floor, systematic
from ..model import kinematics as kin
from .residuals import ResidualTable, compute_residuals, pose_noise_cov, pose_residuals, rms

ALPHA = 0.01
HELDOUT_ALPHA = 0.10


@dataclasses.dataclass(frozen=True, eq=False)
class CandidateScore:
    """One model's fit on all training rows and its held-out residuals."""

    name: str
    fit: FitResult
    heldout_zeta_rad: np.ndarray    # (n_heldout, 3)
    heldout_cycle: np.ndarray       # (n_heldout,)
    train_zeta_rad: np.ndarray      # forward-statics residuals on training rows (full fit)
    failed_rows: int                # forward solves that did not converge
    instrument_floor_rad: float     # instrument noise propagated through this model's own tangent
    noise_ratio2: float             # whitened (own tangent) training residual variance, RSS / (N - p_eff)

    @property
    def heldout_rms_rad(self) -> float:
        return rms(self.heldout_zeta_rad)

    @property
    def train_rms_rad(self) -> float:
        return rms(self.train_zeta_rad)


    def cycle_mse(self) -> dict[int, float]:
        sq = np.sum(self.heldout_zeta_rad ** 2, axis=1)
        return {int(c): float(sq[self.heldout_cycle == c].mean()) for c in np.unique(self.heldout_cycle)}


@dataclasses.dataclass(frozen=True, eq=False)
class Diagnosis:
    """Everything ``csjm diagnose`` reports (see :meth:`as_json`)."""

    train: ResidualTable
    test: ResidualTable | None
    baseline: CandidateScore          # nominal refit (null model of the tests)
    candidates: dict[str, CandidateScore]
    noise_floor_rad: float
    noise_estimates: dict
    tests: dict[str, dict]
    selected: str
    confounded_with: list[str]
    localisation: dict
    remaining: dict
    secondary: dict
    failed: dict = dataclasses.field(default_factory=dict)   # effect -> error message

    @property
    def selected_score(self) -> CandidateScore:
        return self.baseline if self.selected == "none" else self.candidates[self.selected]

    @property
    def heldout_table(self) -> ResidualTable:
        return self.test if self.test is not None else self.train

    @property
    def nominal_heldout_rms_rad(self) -> float:
        """The rig file's model on the held-out rows (no fitting)."""
        return self.heldout_table.rms_rad

    def floor_of(self, sc: CandidateScore | None) -> float:
        """Noise floor of a model: the data's noise level propagated through the model's own tangent."""
        if sc is None:
            return self.noise_floor_rad
        return self.noise_estimates["noise_scale"] * sc.instrument_floor_rad

    def fraction(self, sc: CandidateScore) -> float:
        """``1 - systematic(after) / systematic(before)``, each against its own model's noise floor."""
        sb = systematic(self.nominal_heldout_rms_rad, self.noise_floor_rad)
        sa = systematic(sc.heldout_rms_rad, self.floor_of(sc))
        return float(1.0 - sa / sb) if sb > 0 else 0.0

    @property
    def gap(self) -> dict[str, float]:
        sel = self.selected_score
        before, after = self.nominal_heldout_rms_rad, sel.heldout_rms_rad
        return {"before_rad": before, "after_rad": after, "fraction_explained": self.fraction(sel),
                "systematic_before_rad": systematic(before, self.noise_floor_rad),
                "systematic_after_rad": systematic(after, self.floor_of(sel)),
                "noise_floor_after_rad": self.floor_of(sel),
                "fraction_explained_by_nominal_refit": self.fraction(self.baseline)}

    def as_json(self) -> dict:
        """docs/conventions.md keys (and more); strict JSON: non-finite numbers become ``null``."""
        return _strict(self._as_dict())

    def _as_dict(self) -> dict:
        cands = []
        for name, sc in self.candidates.items():
            f = sc.fit
            cands.append({"effect": name, "heldout_rms_rad": sc.heldout_rms_rad, "train_rms_rad": sc.train_rms_rad,
                          "params": f.params(), "param_sd": f.param_sd(),
                          "nuisance": {k: v for k, v in f.params(False).items() if k not in f.params()},
                          "derived": f.model.effects[0].describe(f.theta[2:]),
                          "bic": f.bic, "p_eff": f.p_eff, "rank": f.rank, "n_params": f.model.n_params,
                          "condition": f.condition, "identifiable": f.identifiable,
                          "failed_forward_solves": sc.failed_rows,
                          "fraction_explained": self.fraction(sc), "noise_floor_rad": self.floor_of(sc),
                          **self.tests[name]})
        for name, msg in self.failed.items():
            cands.append({"effect": name, "heldout_rms_rad": None, "params": {}, "bic": None, "significant": False,
                          "error": msg})
        b = self.baseline
        return {
            "baseline": {"heldout_rms_rad": self.nominal_heldout_rms_rad, "train_rms_rad": self.train.rms_rad,
                         "model": "nominal, rig file as given (no fitted parameters)",
                         "failed_forward_solves": int(np.sum(~self.train.converged))},
            "nominal_refit": {"heldout_rms_rad": b.heldout_rms_rad, "train_rms_rad": b.train_rms_rad,
                              "bic": b.fit.bic, "params": b.fit.params(False), "param_sd": b.fit.param_sd(False),
                              "model": "nominal + common stiffness scale + common rest-length offset; "
                                       "null model of the significance tests"},
            "noise_floor_rad": self.noise_floor_rad,
            "noise_floor_estimates": self.noise_estimates,
            "candidates": cands,
            "selected": self.selected,
            "confounded_with": self.confounded_with,
            "significance": {"alpha": ALPHA, "per_candidate_alpha": ALPHA / len(EFFECTS),
                             "heldout_alpha": HELDOUT_ALPHA,
                             "test": "nested F-test on whitened linearised residuals (training rows), "
                                     "Bonferroni over candidates, and one-sided paired t-test of "
                                     "per-cycle held-out MSE, both against nominal_refit; "
                                     "held-out RMS must also be lower"},
            "heldout": "test file" if self.test is not None else "grouped K-fold by cycle",
            "gap": self.gap,
            "remaining_signature": self.remaining,
            "secondary": {k: v for k, v in self.secondary.items() if k != "score"}
            | ({"fraction_explained": self.fraction(self.secondary["score"])} if "score" in self.secondary else {}),
            "localisation": self.localisation,
            "rows": {"train": len(self.train), "test": 0 if self.test is None else len(self.test)},
        }


def combine_scales(s1: float, dof1: float, s2: float, dof2: float) -> float:
    """Noise level from two estimates (relative sd ``sqrt(2/dof)`` each in variance): pooled when they
    agree within 2.5 sd, else the smaller one (a misfit only inflates an estimate)."""
    if not np.isfinite(s1) or dof1 <= 0:
        return s2
    v1, v2 = s1 ** 2, s2 ** 2
    sd = np.hypot(v1 * np.sqrt(2 / dof1), v2 * np.sqrt(2 / max(dof2, 1)))
    if abs(v1 - v2) <= 2.5 * sd:
        return float(np.sqrt((v1 * dof1 + v2 * dof2) / (dof1 + dof2)))
    return float(min(s1, s2))


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


def folds_by_cycle(cycle: np.ndarray, k: int = 5) -> list[np.ndarray]:
    """Held-out row sets: cycles (in order of appearance) dealt round-robin to ``k`` folds."""
    ids = list(dict.fromkeys(int(c) for c in cycle))
    if len(ids) < 2:
        raise InvalidInput(f"held-out scoring needs at least 2 cycles (got {len(ids)}) or a --test file", "cycle")
    k = min(k, len(ids))
    return [np.flatnonzero(np.isin(cycle, ids[f::k])) for f in range(k)]


def score(model: AugmentedModel, train: ResidualTable, test: ResidualTable | None,
          folds: list[np.ndarray] | None) -> CandidateScore:
    """Fit on all training rows; held-out residuals from ``test`` or the folds."""
    full = fit_model(model, train)
    sol = model.predict_poses(train.rows, full.theta, train.R_meas)
    train_zeta = pose_residuals(sol.R, train.R_meas)
    failed = int(np.sum(~sol.converged(1e-6)))
    if test is not None:
        ho = model.predict_poses(test.rows, full.theta, test.R_meas)
        zeta, cyc = pose_residuals(ho.R, test.R_meas), test.cycle
        failed += int(np.sum(~ho.converged(1e-6)))
    else:
        zeta, cyc = np.empty((len(train), 3)), train.cycle
        for held in folds or ():
            keep = np.setdiff1d(np.arange(len(train)), held)
            f = fit_model(model, train.take(keep), theta0=full.theta)
            part = train.take(held)
            ho = model.predict_poses(part.rows, f.theta, part.R_meas)
            zeta[held] = pose_residuals(ho.R, part.R_meas)
            failed += int(np.sum(~ho.converged(1e-6)))
    # the model's own noise propagation: a softer model turns the same moment noise into more pose noise
    def g(R: np.ndarray) -> np.ndarray:
        return model.balance(R, train.rows, full.theta)

    cov = pose_noise_cov(kin.tangent(g, train.R_meas, h=1e-6), train.noise)
    instrument = float(np.sqrt(np.mean(np.trace(cov, axis1=1, axis2=2))))
    r = np.linalg.solve(np.linalg.cholesky(cov), train_zeta[..., None])[..., 0]
    ratio2 = float(np.sum(r ** 2) / max(r.size - full.p_eff, 1.0))
    return CandidateScore(model.name, full, zeta, cyc, train_zeta, failed, instrument, ratio2)


def nested_f_test(base: FitResult, cand: FitResult) -> tuple[float, float]:
    """``(F, p)`` for the candidate's extra parameters on the same rows."""
    dp = max(cand.p_eff - base.p_eff, 1e-9)
    dof = max(cand.n_obs - cand.p_eff, 1.0)
    F = max(base.rss - cand.rss, 0.0) / dp / (cand.rss / dof)
    return float(F), float(stats.f.sf(F, dp, dof))


def paired_heldout_test(a: CandidateScore, b: CandidateScore) -> float:
    """One-sided p-value that ``b``'s per-cycle held-out MSE is lower than ``a``'s."""
    ma, mb = a.cycle_mse(), b.cycle_mse()
    d = np.array([ma[c] - mb[c] for c in ma])
    if len(d) < 2 or np.allclose(d, d[0]):
        return 0.0 if d.mean() > 0 else 1.0
    return float(stats.ttest_1samp(d, 0.0, alternative="greater").pvalue)


def diagnose(rig: Rig, log: MeasurementLog, test: MeasurementLog | None = None,
             effects: Sequence[str] | None = None, noise: InstrumentNoise | None = None,
             progress: Callable | None = None, secondary: bool = True) -> Diagnosis:
    """Residuals, noise floor, every candidate scored, the selection, localisation.

    ``secondary=False`` skips the search for a second effect (it does not change ``selected``).
    """
    from .localisation import localise, remaining_signature

    names = list(EFFECTS) if effects is None else list(effects)
    train = compute_residuals(rig, log, noise)
    test_table = compute_residuals(rig, test, noise) if test is not None else None
    folds = None if test is not None else folds_by_cycle(train.cycle)
    steps = [None] + names
    total = len(steps) + (len(names) - 1 if secondary else 0)
    bar = progress(total=total, desc="diagnose: fitting candidates") if progress else None
    baseline = score(AugmentedModel(rig), train, test_table, folds)
    if bar:
        bar.update(1)
    cands: dict[str, CandidateScore] = {}
    failed: dict[str, str] = {}
    for name in names:
        try:
            cands[name] = score(AugmentedModel(rig, [make_effect(name, rig)]), train, test_table, folds)
        except (np.linalg.LinAlgError, ValueError) as exc:   # a candidate that cannot be fitted is reported
            failed[name] = f"fit failed: {exc}"
        if bar:
            bar.update(1)
    tests, significant = {}, []
    for name, sc in cands.items():
        F, p_f = nested_f_test(baseline.fit, sc.fit)
        p_h = paired_heldout_test(baseline, sc)
        ok = p_f < ALPHA / len(EFFECTS) and p_h < HELDOUT_ALPHA and sc.heldout_rms_rad < baseline.heldout_rms_rad
        tests[name] = {"f_stat": F, "p_value": p_f, "heldout_p_value": p_h, "significant": bool(ok)}
        if ok:
            significant.append(name)
    selected = min(significant, key=lambda n: cands[n].fit.bic) if significant else "none"
    confounded = []
    if selected != "none":
        for name in significant:
            if name != selected and paired_heldout_test(cands[name], cands[selected]) >= HELDOUT_ALPHA:
                confounded.append(name)
    sel_score = baseline if selected == "none" else cands[selected]
    local, dof = noise_floor(train)
    instrument = train.instrument_floor_rad
    scale_fit = float(np.sqrt(sel_score.noise_ratio2))
    scale = combine_scales(local / instrument if np.isfinite(local) else float("nan"), 3 * dof,
                           scale_fit, 3 * len(train) - sel_score.fit.p_eff)
    floor = scale * instrument
    estimates = {"within_cycle_rad": local, "within_cycle_dof": dof, "selected_fit_rad": scale_fit * instrument,
                 "instrument_model_rad": instrument, "noise_scale": scale,
                 "per_model_rad": {n: scale * c.instrument_floor_rad for n, c in
                                   [("nominal_refit", baseline), *cands.items()]}}
    second = {"effect": "none", "tried": []}
    if secondary and selected != "none" and len(names) > 1:
        second = secondary_effect(rig, train, test_table, folds, selected, sel_score, names,
                                  tick=bar.update if bar else None)
    if bar:
        bar.close()
    held_table = test_table if test_table is not None else train
    loc = localise(held_table, held_table.zeta_rad, sel_score.heldout_zeta_rad, floor)
    remaining = remaining_signature(held_table, sel_score.heldout_zeta_rad, floor)
    return Diagnosis(train, test_table, baseline, cands, floor, estimates, tests, selected, confounded, loc,
                     remaining, second, failed)


def secondary_effect(rig: Rig, train: ResidualTable, test: ResidualTable | None, folds, selected: str,
                     sel: CandidateScore, names: Sequence[str], tick: Callable | None = None) -> dict:
    """Is a second effect on top of the selected one significant (same two tests, Bonferroni over the rest)?

    Reported beside ``selected`` (which stays one word of the vocabulary) for logs with several effects.
    """
    rest = [n for n in names if n != selected]
    tried, ok = [], []
    for name in rest:
        try:
            sc = score(AugmentedModel(rig, [make_effect(selected, rig), make_effect(name, rig)]), train, test, folds)
        except (np.linalg.LinAlgError, ValueError) as exc:
            tried.append({"effect": name, "error": f"fit failed: {exc}", "significant": False})
            continue
        finally:
            if tick:
                tick(1)
        F, p = nested_f_test(sel.fit, sc.fit)
        ph = paired_heldout_test(sel, sc)
        significant = p < ALPHA / len(rest) and ph < HELDOUT_ALPHA and sc.heldout_rms_rad < sel.heldout_rms_rad
        tried.append({"effect": name, "heldout_rms_rad": sc.heldout_rms_rad, "bic": sc.fit.bic, "p_value": p,
                      "heldout_p_value": ph, "significant": bool(significant)})
        if significant:
            ok.append((sc.fit.bic, name, sc))
    if not ok:
        return {"effect": "none", "tried": tried}
    _, name, sc = min(ok, key=lambda t: t[0])
    return {"effect": name, "heldout_rms_rad": sc.heldout_rms_rad, "params": sc.fit.params(),
            "tried": tried, "score": sc}
