"""Residual rows left out as gross outliers: the detector against hand-made residuals with a known answer."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.diagnose.data.residuals import (
    GROSS_ROW_FACTOR,
    GROSS_ROW_SHARE,
    compute_residuals,
    cycle_deviation,
    gross_rows,
)
from csjm_opt.testbed import simulate_experiment


@pytest.fixture(scope="module")
def table(rig):
    """An effect-free log's residual table: 8 cycles of 7 rows, instrument noise only."""
    return compute_residuals(rig, simulate_experiment(rig, 8, np.random.default_rng(5), steps=3))


def noise_like(table, rng) -> np.ndarray:
    """Residuals drawn from each row's instrument noise (``W^-1`` times a standard normal)."""
    return (np.linalg.inv(table.whiten) @ rng.standard_normal((len(table), 3, 1)))[..., 0]


def test_cycle_deviation_is_the_residual_less_its_neighbours_mean():
    z = np.array([[0.0, 0, 0], [1, 0, 0], [4, 0, 0], [9, 0, 0], [5, 5, 5], [7, 7, 7]])
    d = cycle_deviation(z, np.array([0, 0, 0, 0, 1, 1]))
    np.testing.assert_allclose(d[:4, 0], [0 - 1, 1 - 2, 4 - 5, 9 - 4])      # ends: one neighbour
    np.testing.assert_allclose(d[4:], [[-2, -2, -2], [2, 2, 2]])
    line = np.outer(np.arange(6.0), [1, -2, 3])                             # a ramp within a cycle: zero inside
    np.testing.assert_allclose(cycle_deviation(line, np.zeros(6, int))[1:-1], 0, atol=1e-12)


def test_noise_alone_has_no_gross_rows(table):
    for seed in range(20):
        z = noise_like(table, np.random.default_rng(seed))
        bad, ratio = gross_rows(table, z, z)
        assert bad.size == 0 and ratio.max() < 0.7 * GROSS_ROW_FACTOR


def test_a_spike_in_one_row_is_found(table):
    z = noise_like(table, np.random.default_rng(1))
    i = 17
    z[i] += 20 * np.linalg.inv(table.whiten[i]) @ np.array([1.0, 0, 0])   # 20 sigma along one whitened axis
    bad, ratio = gross_rows(table, z, z)
    assert list(bad) == [i] and ratio[i] > GROSS_ROW_FACTOR


def test_an_effect_a_model_follows_or_smooth_within_cycles_is_not_an_outlier(table):
    """A large smooth effect the nominal model misses, and a model that follows it: nothing is left out."""
    rng = np.random.default_rng(2)
    noise = noise_like(table, rng)
    effect = np.zeros_like(noise)
    for c in np.unique(table.cycle):                    # 40 sigma at each cycle's last row, growing along it
        idx = np.flatnonzero(table.cycle == c)
        effect[idx] = 40 * np.outer(np.linspace(0, 1, len(idx)) ** 2, np.linalg.inv(table.whiten[idx[0]])[:, 0])
    nominal = noise + effect
    assert gross_rows(table, nominal, nominal)[0].size == 0           # smooth within cycles
    jump = noise.copy()
    jump[20:] += 30 * np.linalg.inv(table.whiten[20])[:, 0]             # a step that persists: no model follows it
    follows = noise + 0.1 * jump                                        # one that does: its residuals are small
    assert 20 in gross_rows(table, jump, jump)[0] or gross_rows(table, jump, jump)[0].size == 0
    assert gross_rows(table, follows, jump)[0].size == 0


def test_many_spikes_are_not_dropped(table):
    """More than GROSS_ROW_SHARE of the log off is heavy-tailed noise or an effect: nothing is dropped."""
    z = noise_like(table, np.random.default_rng(3))
    rows = np.arange(0, len(table), 9)[: int(np.ceil(GROSS_ROW_SHARE * len(table))) + 1]
    for i in rows:
        z[i] += 20 * np.linalg.inv(table.whiten[i])[:, 1]
    bad, ratio = gross_rows(table, z, z)
    assert bad.size == 0 and np.all(ratio[rows] > GROSS_ROW_FACTOR)
