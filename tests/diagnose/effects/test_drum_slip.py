"""The drum-slip probe (outside the vocabulary) against a balance written out cable by cable."""

from __future__ import annotations

import numpy as np

import csjm_opt as co
from csjm_opt.diagnose.effects import EFFECTS
from csjm_opt.diagnose.effects.drum_slip import DrumSlip
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows

from ._by_hand import tensions_by_hand


def test_slip_is_a_rest_length_grown_by_the_excess_of_earlier_rows(rig):
    # share = k c_slip: each cable's rest length grows by c_slip max(T(j) - T_s, 0) for every earlier row j of its
    # cycle; the model's balance must be the nominal balance at those grown rest lengths
    rng = np.random.default_rng(6)
    n = 8
    R = np.stack([co.so3.exp(rng.normal(0, 0.12, 3)) for _ in range(n)])
    tau = rng.normal(0, 0.6, (n, 3))
    rest = np.stack([co.plan_tensions(rig, Ri, ti).rest_lengths_m for Ri, ti in zip(R, tau)])
    cycle = np.array([0, 0, 0, 0, 0, 1, 1, 1])
    k = np.asarray(rig.cable_stiffness_N_per_m)
    T = tensions_by_hand(rig, R, rest)
    share, threshold = 0.4, float(np.median(T))
    grown = rest.copy()
    for i in range(n):
        start = np.flatnonzero(cycle[:i + 1] != cycle[i]).max(initial=-1) + 1
        grown[i] = rest[i] + (share / k) * np.maximum(T[start:i] - threshold, 0.0).sum(axis=0)
    rows = Rows(rest, tau, cycle, np.zeros_like(rest))
    nominal, slipped = AugmentedModel(rig), AugmentedModel(rig, [DrumSlip(6, rig.t_max_N)])
    g = slipped.balance(R, rows, np.r_[0.0, share, threshold])
    g_grown = nominal.balance(R, Rows(grown, tau, cycle, np.zeros_like(rest)), np.r_[0.0])
    np.testing.assert_allclose(g, g_grown, atol=1e-9)
    assert np.abs(g - nominal.balance(R, rows, np.r_[0.0])).max() > 1e-3      # the slip moves the balance
    # a cycle's first row has no earlier row; a threshold above every tension is no slip
    np.testing.assert_allclose(g[[0, 5]], nominal.balance(R, rows, np.r_[0.0])[[0, 5]], atol=1e-12)
    np.testing.assert_allclose(slipped.balance(R, rows, np.r_[0.0, share, T.max() + 1.0]),
                               nominal.balance(R, rows, np.r_[0.0]), atol=1e-12)


def test_drum_slip_is_a_probe_not_a_verdict(rig):
    assert "drum_slip" not in EFFECTS
    e = DrumSlip(4, rig.t_max_N)
    assert e.param_names == ("slip_share", "slip_threshold_N")
    assert e.default_ranges()["slip_threshold_N"] == (0.0, rig.t_max_N)
    assert np.all(e.lower_bounds == 0.0) and not np.isfinite(e.prior_sd[1])
