"""Scoring one model: fit on the training rows, residuals on held-out cycles, paired tests.

Held-out rows are ``TEST.csv`` when given, else grouped K-fold
cross-validation by ``cycle`` (K = min(5, cycles), cycles dealt to folds in
order of appearance; never random row splits). A fold's parameters are the
full fit moved by one Gauss-Newton step on the fold's training rows
(:meth:`~csjm_opt.diagnose.fitting.gauss_newton.FitResult.refit_rows`): exact for the
linearised problem the fits solve, and about five times cheaper than
refitting every fold. Fits use linearised,
whitened pose residuals (:mod:`.fit`); held-out residuals use full forward
statics of the fitted model on rows the fit did not see.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from ...errors import InvalidInput
from ..data.noise import combine_scales
from ..data.residuals import ResidualTable, pose_noise_cov, pose_residuals, rms
from ..data.tails import f_sf, t_greater
from ..fitting.augmented import AugmentedModel, with_entry
from ..fitting.evidence import log_evidence
from ..fitting.friction_path import along, on_predicted_path
from ..fitting.friction_ramp import predict_ramps
from ..fitting.gauss_newton import FitResult, data_jacobian, fit_model, objective

#: Held-out MSE ratios within this of 1 (as a log) are ties: immaterial, a thousandth of a cycle's MSE against
#: the 27 % sampling spread of one nine-row cycle's. A paired test over cycles calls a difference every cycle
#: shares significant however small: a joint-friction stick set beside a guide radius fitted to 0 (on its bound)
#: predicted every cycle 0.002-0.05 % better through its relinearised nuisance (p = 0.000-0.005), and 3 of the 10
#: step-loaded joint-friction logs were warned that the guide radius may be present too (at 1e-6, round-off).
TIE_LOG_RATIO = 1e-3


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
    heldout_floor_rad: float = float("nan")   # RMS held-out error of this model if it were right: noise
                                    # plus its parameters' estimation error (per unit noise scale)
    heldout_blocks: tuple = ()      # ((held-out row indices, whitened prediction covariance), ...) per fold
    # a set-valued model (settled friction, :mod:`..fitting.friction_stick`): per held-out row its -2 log density in
    # whitened units less the Gaussian constant at its own noise scale s (``d^2 / s^2 + 2 log(Z / Z0)``), the
    # row's mean noise variance per axis (rad^2), and s; its squared errors are then -2 s^2 log p less the
    # Gaussian's constant, as a point model's at s (:func:`equivalent_mse`). None: a point model
    heldout_density: tuple[np.ndarray, np.ndarray, float] | None = None
    # per held-out row its -2 log p (whitened units, less the Gaussian's 3 log 2 pi) at the model's noise scale:
    # ``|W zeta|^2 / s^2 + 6 log s`` for a point model (:func:`point_nll`), ``q + 6 log s`` for a set-valued one
    # at its own s (:func:`log_score_test`); None: not computed (a hand-made score)
    heldout_nll: np.ndarray | None = None
    # what the mixture over the model's variants adds to its fit's log evidence (nats, <= 0; 0: no variants,
    # or a model whose variant the evidence did not choose): :func:`..fitting.model_fits.variant_fit`
    variant_log_weight: float = 0.0

    @property
    def set_valued(self) -> bool:
        """Whether the model predicts a set of poses per row (settled friction), scored by a density."""
        return self.heldout_density is not None

    @property
    def set_scale(self) -> float | None:
        """A set-valued model's own noise scale (whitened); None for a point model."""
        return None if self.heldout_density is None else float(self.heldout_density[2])

    def cycle_nll(self) -> dict[int, float] | None:
        """Held-out ``-2 log p`` summed over each cycle (None when not computed)."""
        if self.heldout_nll is None:
            return None
        return {int(c): float(np.sum(self.heldout_nll[self.heldout_cycle == c])) for c in np.unique(self.heldout_cycle)}

    @property
    def heldout_log_score(self) -> float:
        """Held-out ``-2 log p`` of all rows at the model's noise scale (nan when not computed)."""
        return float("nan") if self.heldout_nll is None else float(np.sum(self.heldout_nll))

    def _mse(self, mask: np.ndarray) -> float:
        if self.heldout_density is None:
            return float(np.mean(np.sum(self.heldout_zeta_rad[mask] ** 2, axis=1)))
        q, var, s = self.heldout_density
        return equivalent_mse(q[mask], var[mask], s)

    @property
    def heldout_rms_rad(self) -> float:
        """RMS held-out pose residual.

        Returns
        -------
        float
            ``sqrt(mean ||zeta_i||^2)`` (rad).
        """
        return float(np.sqrt(self.heldout_mse))

    @property
    def heldout_mse(self) -> float:
        """Mean squared held-out pose residual.

        Returns
        -------
        float
            ``mean ||zeta_i||^2`` (rad^2).
        """
        return self._mse(np.ones(len(self.heldout_cycle), bool))

    @property
    def train_rms_rad(self) -> float:
        """RMS forward-statics pose residual on the training rows (full fit).

        Returns
        -------
        float
            ``sqrt(mean ||zeta_i||^2)`` (rad).
        """
        return rms(self.train_zeta_rad)

    def cycle_mse(self) -> dict[int, float]:
        """Held-out mean ``||zeta||^2`` of each cycle."""
        return {int(c): self._mse(self.heldout_cycle == c) for c in np.unique(self.heldout_cycle)}

    def implausible(self) -> list[str]:
        """Names of fitted effect parameters outside their prior ranges by more than their uncertainty.

        A free parameter the data do not determine at all (no information: zero variance from the
        pseudo-inverse) is not evidence against the effect wherever it drifts.
        """
        m = self.fit.model
        sd_all = self.fit.stderr.copy()
        if self.fit.free is not None:
            sd_all[self.fit.free & (sd_all <= 0)] = np.inf
        return [n for e, p, sd in zip(m.effects, m.effect_params(self.fit.theta), m.effect_params(sd_all))
                for n in e.implausible(p, sd)]


def equivalent_mse(q: np.ndarray, var_rad2: np.ndarray, s: float) -> float:
    """Mean squared error that ranks a held-out density with the point models' squared errors (rad^2).

    For rows with ``-2 log p_i = q_i + 3 log(2 pi s^2)`` (whitened units, noise scale ``s``), ``s^2 q_i``
    is what a point model's squared (whitened) error is at the same noise scale: ``-2 s^2 log p`` less
    the Gaussian's constant. Scaled by each row's mean noise variance it is in rad^2, and equals a point
    model's MSE for ``q = |r|^2 / s^2``.

    Parameters
    ----------
    q : numpy.ndarray
        Per-row ``-2 log p`` less the Gaussian constant (whitened).
    var_rad2 : numpy.ndarray
        Each row's mean noise variance per axis (rad^2 per whitened unit^2).
    s : float
        The noise scale (whitened) both are taken at.

    Returns
    -------
    float
    """
    return float(np.mean(var_rad2 * q) * s ** 2)


def folds_by_cycle(cycle: np.ndarray, k: int = 5) -> list[np.ndarray]:
    """Held-out row sets: cycles (in order of appearance) dealt round-robin to ``k`` folds.

    Raises
    ------
    InvalidInput
        Fewer than two cycles.
    """
    ids = list(dict.fromkeys(int(c) for c in cycle))
    if len(ids) < 2:
        raise InvalidInput(f"held-out scoring needs at least 2 cycles (got {len(ids)}) or a --test file", "cycle")
    k = min(k, len(ids))
    return [np.flatnonzero(np.isin(cycle, ids[f::k])) for f in range(k)]


def fit_on_path(model: AugmentedModel, train: ResidualTable,
                fit: FitResult | None = None) -> tuple[FitResult, ResidualTable]:
    """The fit of ``model`` on all of ``train`` that a diagnosis scores, and the table it was fitted on.

    A path-dependent model (friction with memory) is refitted with its state driven along the poses
    it predicts itself (:func:`~csjm_opt.diagnose.fitting.friction_path.on_predicted_path`); that fit is kept
    when it fits the rows better.

    Parameters
    ----------
    model : AugmentedModel
    train : ResidualTable
    fit : FitResult, optional
        ``fit_model(model, train)`` when the caller has it already (e.g. the fit that chose a
        friction law): used instead of fitting again (the fit is deterministic, so nothing changes).

    Returns
    -------
    tuple of (FitResult, ResidualTable)
    """
    full = fit_model(model, train) if fit is None else fit
    if model.path_dependent:          # friction state along the model's own path, if it fits better
        path = on_predicted_path(model, train, full.theta)
        on_path = fit_model(model, path, full.theta)
        if on_path.rss < full.rss:
            return on_path, path
    return full, train


def score(model: AugmentedModel, train: ResidualTable, test: ResidualTable | None,
          folds: list[np.ndarray] | None, fit: FitResult | None = None,
          local: tuple[float, float] | None = None) -> CandidateScore:
    """Fit on all training rows; held-out residuals from ``test`` or the folds.

    ``fit``: the plain fit of ``model`` on ``train`` (:func:`fit_on_path`), when the caller has it.
    ``local``: the within-cycle noise estimate ``(scale, dof)`` (:func:`point_nll`).
    """
    full, path = fit_on_path(model, train, fit)
    on_path, train = path is not train, path
    train_rows = with_entry(model, train.rows, train.R_meas, full.theta)
    if on_path and test is not None:
        # the held-out log's path and the training rows' prediction in one pass (the same numbers as one by one)
        test_rows = with_entry(model, test.rows, test.R_meas, full.theta)
        (ho, ho_shape), (sol, _) = predict_ramps(model, [(test_rows, test.R_meas), (train_rows, train.R_meas)],
                                                 full.theta)
        test = along(model, test, full.theta, ho, ho_shape)
    else:
        sol = model.predict_poses(train_rows, full.theta, train.R_meas)
    train_zeta = pose_residuals(sol.R, train.R_meas)
    failed = int(np.sum(~sol.converged(1e-6)))
    blocks: list[tuple[np.ndarray, np.ndarray]] = []
    if test is not None:
        ho = model.predict_poses(with_entry(model, test.rows, test.R_meas, full.theta), full.theta, test.R_meas)
        zeta, cyc = pose_residuals(ho.R, test.R_meas), test.cycle
        failed += int(np.sum(~ho.converged(1e-6)))
        blocks.append((np.arange(len(test)), full.prediction_cov(None, data_jacobian(model, test, full.theta))))
    else:
        zeta, cyc = np.empty((len(train), 3)), train.cycle
        for held in folds or []:
            keep = np.setdiff1d(np.arange(len(train)), held)
            theta = _fold_fit(model, full, train.take(keep), keep)
            part = train.take(held)
            ho = model.predict_poses(with_entry(model, train.rows, train.R_meas, theta).take(held), theta, part.R_meas)
            zeta[held] = pose_residuals(ho.R, part.R_meas)
            failed += int(np.sum(~ho.converged(1e-6)))
            blocks.append((held, full.prediction_cov(keep, full.held_rows_jacobian(held))))

    # the model's own noise propagation: a softer model turns the same moment noise into more pose noise
    cov = pose_noise_cov(model.tangent(train.R_meas, train.rows, full.theta, h=1e-6), train.noise)
    instrument = float(np.sqrt(np.mean(np.trace(cov, axis1=1, axis2=2))))
    r = np.linalg.solve(np.linalg.cholesky(cov), train_zeta[..., None])[..., 0]
    ratio2 = float(np.sum(r ** 2) / max(r.size - full.p_eff, 1.0))
    held_table = test if test is not None else train
    return CandidateScore(model.name, full, zeta, cyc, train_zeta, failed, instrument, ratio2,
                          heldout_floor(held_table, instrument, blocks), tuple(blocks),
                          heldout_nll=point_nll(train, train_zeta, full.p_eff, held_table, zeta, local))


def point_nll(train: ResidualTable, train_zeta: np.ndarray, p_eff: float, held: ResidualTable,
              heldout_zeta: np.ndarray, local: tuple[float, float] | None = None) -> np.ndarray:
    """A point model's held-out ``-2 log p`` per row at its noise scale (whitened, less ``3 log 2 pi``).

    The rows are whitened as a set-valued model's are (the tables' instrument whitening). The scale is
    the model's whitened training residual variance ``RSS / (3 n - p_eff)``, combined with the within-cycle
    estimate ``local = (scale, dof)`` where given as the diagnosis combines them
    (:func:`~csjm_opt.diagnose.data.noise.combine_scales`: pooled when they agree, else the smaller, a
    misfit only inflating an estimate): a model that misses the log does not buy a wide Gaussian with its
    own misfit, and one that fits its training rows closely and predicts held-out rows poorly pays for both.
    """
    w_tr = np.einsum("nij,nj->ni", train.whiten, train_zeta)
    dof = max(w_tr.size - p_eff, 1.0)
    s2 = float(np.sum(w_tr ** 2) / dof)
    if local is not None and np.isfinite(local[0]) and local[0] > 0:
        s2 = combine_scales(local[0], 3.0 * local[1], float(np.sqrt(s2)), dof) ** 2
    s2 = max(s2, 1e-300)
    w = np.einsum("nij,nj->ni", held.whiten, heldout_zeta)
    return np.sum(w ** 2, axis=1) / s2 + 3.0 * np.log(s2)


def _fold_fit(model: AugmentedModel, full: FitResult, kept: ResidualTable, keep: np.ndarray) -> np.ndarray:
    """A fold's parameters: one Gauss-Newton step from the full fit, or a refit where the step fails.

    The step (:meth:`FitResult.refit_rows`) is trusted only when it fits the fold's own rows at
    least as well as the full fit does (a least-squares estimate on rows ``keep`` cannot fit
    them worse than any other parameter vector, the full fit's included); otherwise the step
    left the region where the linearisation holds (a weakly determined direction, a bound) and
    the fold is refitted from the full fit's parameters.
    """
    theta = full.refit_rows(keep)
    if objective(model, kept, theta) <= objective(model, kept, full.theta) * (1 + 1e-9):
        return theta
    return fit_model(model, kept, theta0=full.theta).theta


def heldout_floor(held: ResidualTable, instrument_floor_rad: float, blocks) -> float:
    """Held-out RMS a correctly specified model still shows: ``sqrt(floor^2 + mean prediction variance)``.

    In rad, per unit noise scale: a many-parameter model pays for its estimation error.
    """
    Linv = np.linalg.inv(held.whiten)           # whitened -> rad
    extra, n = 0.0, 0
    for idx, P in blocks:
        h = len(idx)
        Pii = P.reshape(h, 3, h, 3)[np.arange(h), :, np.arange(h), :]      # (h, 3, 3) diagonal blocks
        extra += float(np.einsum("nij,njk,nlk->", Linv[idx], Pii, Linv[idx]))
        n += h
    return float(np.sqrt(instrument_floor_rad ** 2 + (extra / n if n else 0.0)))


def nested_f_test(base: FitResult, cand: FitResult) -> tuple[float, float]:
    """``(F, p)`` of the candidate's extra parameters on the same training rows (linearised; informative only)."""
    dp = max(cand.p_eff - base.p_eff, 1e-9)
    dof = max(cand.n_obs - cand.p_eff, 1.0)
    F = max(base.rss - cand.rss, 0.0) / dp / (cand.rss / dof)
    return float(F), f_sf(F, dp, dof)


def paired_heldout_test(a: CandidateScore, b: CandidateScore) -> float:
    """One-sided p-value that ``b``'s per-cycle held-out MSE is lower than ``a``'s.

    When the two are not taken at one noise scale (a set-valued model, settled friction, against a point
    model, or two stick sets at different scales) and both carry held-out log scores, the test is
    :func:`log_score_test`: a stick set's errors are a density at its own noise scale, and squared errors
    at that scale flatter it against a point model when the scale is small. Two point models, or two stick
    sets at one scale, are compared by their squared errors.

    Paired t-test over cycles of ``log(MSE_a / MSE_b)``: cycles with large loads have large
    errors under both models, and the log ratio keeps them from drowning the rest. Ratios within
    ``TIE_LOG_RATIO`` of 1 are ties (immaterial: a model whose added effect fitted to zero predicts
    the same cycles to round-off, or to a few 1e-4 through its refitted nuisance), so such predictions
    give ``p = 1``, not a "significant" improvement that every cycle shares.
    """
    if _scales_differ(a, b):
        la, lb = cycle_nll_of(a), cycle_nll_of(b)
        if la is not None and lb is not None:
            return log_score_test(la, lb)
    ma, mb = a.cycle_mse(), b.cycle_mse()
    tiny = 1e-30
    d = np.array([np.log((ma[c] + tiny) / (mb[c] + tiny)) for c in ma])
    d[np.abs(d) < TIE_LOG_RATIO] = 0.0
    if len(d) < 2 or np.allclose(d, d[0], rtol=0.0, atol=TIE_LOG_RATIO):
        return 0.0 if d.mean() > 0 else 1.0
    return t_greater(d)


def evidence_of(sc, noise_scale: float, at_fit: bool = False) -> float:
    """Laplace log evidence of score ``sc``'s model at ``noise_scale``: its fit's, plus its variants' log weight.

    :func:`~csjm_opt.diagnose.fitting.evidence.log_evidence` of ``sc.fit`` (``at_fit`` as there) plus
    ``sc.variant_log_weight`` (:func:`~csjm_opt.diagnose.fitting.model_fits.variant_fit`; 0 where absent).
    """
    return log_evidence(sc.fit, float(noise_scale), at_fit=at_fit) + getattr(sc, "variant_log_weight", 0.0)


def cycle_nll_of(sc) -> dict | None:
    """``sc``'s per-cycle held-out log scores (:meth:`CandidateScore.cycle_nll`), or None where it has none."""
    f = getattr(sc, "cycle_nll", None)
    return f() if f is not None else None


def _scales_differ(a, b) -> bool:
    """Whether ``a`` and ``b`` are not scored at one noise scale (a stick set and a point model, or two sets)."""
    return getattr(a, "set_scale", None) != getattr(b, "set_scale", None)


def log_score_test(nll_a: dict, nll_b: dict) -> float:
    """One-sided p-value that model ``b`` predicts the held-out cycles better than ``a`` by log score.

    Paired t-test over cycles of ``sum(-2 log p_a) - sum(-2 log p_b)``, each model at its noise scale
    (a proper scoring rule: a point model and a stick set are compared as densities). Differences below
    ``TIE_LOG_RATIO`` per cycle are ties; identical predictions give ``p = 1``.

    Parameters
    ----------
    nll_a, nll_b : dict
        Cycle -> held-out ``-2 log p`` of the cycle's rows (:meth:`CandidateScore.cycle_nll`).

    Returns
    -------
    float
    """
    d = np.array([nll_a[c] - nll_b[c] for c in nll_a if c in nll_b])
    d[np.abs(d) < TIE_LOG_RATIO] = 0.0
    if len(d) < 2 or np.allclose(d, d[0], rtol=0.0, atol=TIE_LOG_RATIO):
        return 0.0 if len(d) and d.mean() > 0 else 1.0
    return t_greater(d)


def heldout_key(scores) -> Callable[[CandidateScore], float]:
    """The held-out error to rank ``scores`` by: MSE at one noise scale, else log score (as the paired test)."""
    scores = list(scores)
    if len({getattr(sc, "set_scale", None) for sc in scores}) > 1 and all(sc.heldout_nll is not None for sc in scores):
        return lambda sc: sc.heldout_log_score
    return lambda sc: sc.heldout_mse


def by_heldout(scores) -> list[CandidateScore]:
    """``scores`` from the lowest held-out error (:func:`heldout_key`)."""
    scores = list(scores)
    return sorted(scores, key=heldout_key(scores))


def improvement_rad(a: CandidateScore, b: CandidateScore) -> float:
    """Systematic held-out improvement of ``b`` over ``a``: ``sqrt(max(MSE_a - MSE_b, 0))`` (rad)."""
    return float(np.sqrt(max(a.heldout_mse - b.heldout_mse, 0.0)))
