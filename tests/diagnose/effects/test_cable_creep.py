"""The cable-creep probe (outside the vocabulary) against a balance written out cable by cable."""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt.diagnose.effects import EFFECTS
from csjm_opt.diagnose.effects.cable_creep import CableCreep, within_cycle_sum
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows

from ._by_hand import tensions_by_hand


def test_within_cycle_sum_restarts_at_every_cycle():
    cycle = np.array([0, 0, 0, 1, 1, 2, 2, 2, 2, 0, 0])      # an id that comes back is a new cycle
    values = np.arange(1.0, 12.0)
    expected, run = [], 0.0
    for i, v in enumerate(values):                            # a plain loop over the rows
        run = v if i == 0 or cycle[i] != cycle[i - 1] else run + v
        expected.append(run)
    positions = Rows(np.zeros((11, 6)), np.zeros((11, 3)), cycle, np.zeros((11, 6))).positions
    np.testing.assert_array_equal(within_cycle_sum(positions, values), expected)
    both = within_cycle_sum(positions, np.c_[values, -2 * values])
    np.testing.assert_array_equal(both[:, 1], -2 * np.asarray(expected))


def test_creep_is_a_rest_length_grown_by_the_tension_so_far(rig):
    # lambda = k kappa: each cable's rest length grows by kappa sum_{j <= i} T(j) over its cycle; the model's
    # balance must be the nominal balance at those grown rest lengths, with the tensions found row by row
    rng = np.random.default_rng(5)
    n = 7
    R = np.stack([co.so3.exp(rng.normal(0, 0.12, 3)) for _ in range(n)])
    tau = rng.normal(0, 0.4, (n, 3))
    rest = np.stack([co.plan_tensions(rig, Ri, ti).rest_lengths_m for Ri, ti in zip(R, tau)])
    cycle = np.array([0, 0, 0, 0, 1, 1, 1])
    lam = 0.01
    k = np.asarray(rig.cable_stiffness_N_per_m)
    T = tensions_by_hand(rig, R, rest)
    grown = rest.copy()
    for i in range(n):                       # the rest length grown by the tensions of the cycle so far
        start = np.flatnonzero(cycle[:i + 1] != cycle[i]).max(initial=-1) + 1
        grown[i] = rest[i] + (lam / k) * T[start:i + 1].sum(axis=0)
    rows = Rows(rest, tau, cycle, np.zeros_like(rest))
    nominal, crept = AugmentedModel(rig), AugmentedModel(rig, [CableCreep(6)])
    g = crept.balance(R, rows, np.r_[0.0, lam])
    g_grown = nominal.balance(R, Rows(grown, tau, cycle, np.zeros_like(rest)), np.r_[0.0])
    np.testing.assert_allclose(g, g_grown, atol=1e-9)
    assert np.abs(g - nominal.balance(R, rows, np.r_[0.0])).max() > 1e-3      # the creep moves the balance


def test_creep_is_a_probe_not_a_verdict():
    # the diagnosis never names it: it is outside the vocabulary
    assert "cable_creep" not in EFFECTS
    e = CableCreep(4)
    assert e.param_names == ("creep_per_row",)
    lo, hi = e.default_ranges()["creep_per_row"]
    assert lo == 0.0 and hi > 0.0 and e.prior_sd[0] == pytest.approx(hi / 2)
