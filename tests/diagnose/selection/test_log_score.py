"""Held-out log scores: a point model and a stick set (settled friction) compared as densities.

References independent of the code under test: scipy's multivariate normal density, scipy's paired
t-test, and a simulated log where the truth is known.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from scipy import stats

from csjm_opt.diagnose.selection.scoring import (
    CandidateScore,
    by_heldout,
    log_score_test,
    paired_heldout_test,
    point_nll,
)


def _whitening(rng, n):
    """Per-row whitening matrices ``W`` (lower triangular, positive diagonal)."""
    W = np.tril(rng.normal(0.0, 0.3, (n, 3, 3)))
    W[:, np.arange(3), np.arange(3)] = rng.uniform(500.0, 2000.0, (n, 3))
    return W


def test_point_nll_is_the_gaussian_log_density_at_the_fitted_noise_scale():
    rng = np.random.default_rng(3)
    n_tr, n_ho, p_eff = 40, 12, 5.0
    train = SimpleNamespace(whiten=_whitening(rng, n_tr))
    held = SimpleNamespace(whiten=_whitening(rng, n_ho))
    zeta_tr = rng.normal(0.0, 1e-3, (n_tr, 3))
    zeta_ho = rng.normal(0.0, 1e-3, (n_ho, 3))
    got = point_nll(train, zeta_tr, p_eff, held, zeta_ho)
    # the scale: whitened training residual variance with p_eff degrees of freedom spent
    w_tr = np.einsum("nij,nj->ni", train.whiten, zeta_tr)
    s2 = np.sum(w_tr ** 2) / (3 * n_tr - p_eff)
    for i in range(n_ho):
        W = held.whiten[i]
        cov_rad = s2 * np.linalg.inv(W.T @ W)           # the residual's covariance in rad
        logpdf = stats.multivariate_normal(np.zeros(3), cov_rad).logpdf(zeta_ho[i])
        # -2 log p in whitened units: less 3 log 2 pi, and the whitening's Jacobian (+2 log |det W|)
        expected = -2.0 * logpdf - 3.0 * np.log(2.0 * np.pi) + 2.0 * np.log(abs(np.linalg.det(W)))
        assert np.isclose(got[i], expected, rtol=1e-9, atol=1e-9)


def test_a_point_models_misfit_does_not_buy_it_a_wide_gaussian():
    # a within-cycle noise estimate far below the model's training residual variance (a misfit inflates
    # the latter): the log score is taken at the within-cycle scale
    rng = np.random.default_rng(6)
    n = 30
    train = SimpleNamespace(whiten=np.repeat(np.eye(3)[None] * 1000.0, n, axis=0))
    zeta_tr = rng.normal(0.0, 3e-3, (n, 3))                     # whitened variance about 9
    zeta_ho = rng.normal(0.0, 3e-3, (n, 3))
    got = point_nll(train, zeta_tr, 2.0, train, zeta_ho, local=(1.1, 200.0))
    w = 1000.0 * zeta_ho
    expected = np.sum(w ** 2, axis=1) / 1.1 ** 2 + 3.0 * np.log(1.1 ** 2)
    assert np.allclose(got, expected, rtol=1e-12)
    # without the estimate, its own variance: a far lower -2 log p for the same residuals
    assert np.sum(point_nll(train, zeta_tr, 2.0, train, zeta_ho)) < np.sum(got) - 100.0


def test_the_log_score_test_is_a_paired_t_test_over_cycles():
    rng = np.random.default_rng(4)
    a = {c: float(v) for c, v in enumerate(rng.normal(40.0, 3.0, 9))}
    b = {c: a[c] - float(d) for c, d in enumerate(rng.normal(1.0, 2.0, 9))}
    ref = stats.ttest_rel(list(a.values()), list(b.values()), alternative="greater").pvalue
    assert np.isclose(log_score_test(a, b), ref, rtol=1e-9)
    assert log_score_test(a, dict(a)) == 1.0            # identical predictions: no improvement


def _score(name, cycle, zeta_rad, nll, density=None):
    return CandidateScore(name, None, zeta_rad, cycle, zeta_rad, 0, 1e-3, 1.0, 1e-3, (),
                          heldout_density=density, heldout_nll=nll)


def test_a_stick_set_at_a_small_noise_scale_of_its_own_is_not_flattered():
    # the truth is a point model with unit whitened noise; a stick set whose band takes up a fifth of every
    # residual, scored at its own noise scale s = 0.35: its squared errors at that scale (s^2 q) are below
    # the truth's, its density is not (the rows lie many of its own sd away from the set)
    rng = np.random.default_rng(5)
    n, cycles, s = 144, 12, 0.35
    cycle = np.repeat(np.arange(cycles), n // cycles)
    w = rng.normal(0.0, 1.0, (n, 3))                     # whitened held-out residuals of the true model
    var = np.full(n, 1e-6)                               # rad^2 per whitened unit^2
    truth = _score("truth", cycle, w * 1e-3, np.sum(w ** 2, axis=1))   # its own scale 1: -2 log p less 3 log 2 pi
    d2 = 0.64 * np.sum(w ** 2, axis=1)
    pen = np.full(n, 0.5)                                # 2 log(Z / Z0): the band's price
    q = d2 / s ** 2 + pen
    stick = _score("stick", cycle, 0.8 * w * 1e-3, q + 6.0 * np.log(s), density=(q, var, s))
    # the squared errors at the stick's own scale favour it on every cycle ...
    assert stick.heldout_mse < truth.heldout_mse
    assert all(stick.cycle_mse()[c] < truth.cycle_mse()[c] for c in range(cycles))
    # ... the densities favour the truth, and the paired test reads densities
    sim_nll = d2 / s ** 2 + pen + 6 * np.log(s)
    assert np.sum(sim_nll) > np.sum(truth.heldout_nll)
    assert paired_heldout_test(truth, stick) > 0.5             # the stick set is not better
    assert paired_heldout_test(stick, truth) < 1e-3            # the truth is
    assert by_heldout([stick, truth])[0] is truth
    # two point models are still compared by squared errors (log ratio per cycle)
    worse = _score("worse", cycle, 1.3 * w * 1e-3, 1.69 * np.sum(w ** 2, axis=1))
    assert paired_heldout_test(worse, truth) < 1e-3 and by_heldout([worse, truth])[0] is truth
