"""The diagnosis's tail probabilities against ``scipy.stats`` (an independent implementation of each law)."""

import numpy as np
import pytest
from scipy import stats

from csjm_opt.diagnose.data import tails


@pytest.mark.parametrize("x, dof", [(0.5, 1), (3.0, 3), (40.0, 27), (1e-3, 5), (200.0, 108)])
def test_chi2_sf(x, dof):
    assert tails.chi2_sf(x, dof) == pytest.approx(stats.chi2.sf(x, dof), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("x, n, d", [(0.3, 1, 10), (2.5, 3, 200), (9.0, 36, 600), (1.0, 4, 4)])
def test_f_sf(x, n, d):
    assert tails.f_sf(x, n, d) == pytest.approx(stats.f.sf(x, n, d), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("z", [-2.0, 0.0, 1.5, 3.3, 8.0])
def test_normal_tails(z):
    assert tails.norm_sf(z) == pytest.approx(stats.norm.sf(z), rel=1e-12, abs=1e-300)
    p = stats.norm.sf(z)
    if 0 < p < 1:
        assert tails.norm_isf(p) == pytest.approx(z, rel=1e-9, abs=1e-12)


def test_one_sided_t_test_matches_scipy():
    rng = np.random.default_rng(3)
    for n in (2, 3, 8, 20):
        for shift in (-0.5, 0.0, 0.7):
            d = rng.normal(shift, 1.0, n)
            ref = stats.ttest_1samp(d, 0.0, alternative="greater").pvalue
            assert tails.t_greater(d) == pytest.approx(ref, rel=1e-10)


def test_linear_trend_matches_linregress():
    rng = np.random.default_rng(4)
    for n in (4, 6, 12, 30):
        x = np.arange(n, dtype=float)
        for slope in (0.0, 0.1, -2.0):
            y = slope * x + rng.normal(0.0, 1.0, n)
            ref = stats.linregress(x, y)
            s, p = tails.linear_trend(x, y)
            assert s == pytest.approx(ref.slope, rel=1e-10, abs=1e-14)
            assert p == pytest.approx(ref.pvalue, rel=1e-9, abs=1e-300)
    # a perfect line is certain; a constant carries no trend
    assert tails.linear_trend(np.arange(5.0), 2.0 * np.arange(5.0))[1] == pytest.approx(
        stats.linregress(np.arange(5.0), 2.0 * np.arange(5.0)).pvalue, abs=1e-12)
    assert tails.linear_trend(np.arange(5.0), np.ones(5))[1] == 1.0
