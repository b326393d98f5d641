"""Persistent cycles of the quasi-static testbed: each cycle starts where the previous one settled."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.testbed import TestbedPlant, design_cycles, make_plant, simulate_experiment


def _two_same_cycles(rig, seed=11):
    """Two identical load cycles (same rest lengths, same loads) in a row."""
    c = design_cycles(rig, 1, np.random.default_rng(seed), steps=3)[0]
    m = len(c.alphas)
    l = np.repeat(c.rest_lengths_m[None], 2 * m, 0)
    tau = np.vstack([c.tau_ext_A_Nm, c.tau_ext_A_Nm])
    cycle = np.repeat([0, 1], m)
    R0 = np.repeat(c.R_ref[None], 2 * m, 0)
    return (l, tau, cycle, R0), m


@pytest.mark.parametrize("effect", ["coulomb_friction", "friction"])
def test_friction_state_is_carried_into_the_next_cycle(rig, effect):
    args, m = _two_same_cycles(rig)
    plant = make_plant(rig, effect, 4.0, np.random.default_rng(0))
    R_p = plant.respond(*args)
    R_r = dataclasses.replace(plant, persistent=False).respond(*args)
    # hysteresis: loading then unloading to the same load does not return to the start
    assert so3.angle_between(R_p[0], R_p[m - 1]) > 1e-3
    # persistent: the second cycle starts where the first settled (same rest lengths, same load: nothing moves)
    assert so3.angle_between(R_p[m], R_p[m - 1]) < 2e-5     # (the rounded play: 0.002 N)
    # ... and the second cycle repeats the first one's unloading branch, not its virgin start
    assert so3.angle_between(R_p[m], R_p[0]) > 1e-3
    # relaxed cycles: the second cycle repeats the first exactly
    for i in range(m):
        assert so3.angle_between(R_r[m + i], R_r[i]) < 1e-9


def test_without_friction_loading_and_unloading_return_to_the_start(rig):
    args, m = _two_same_cycles(rig)
    plant = dataclasses.replace(make_plant(rig, "coulomb_friction", 0.0, np.random.default_rng(0)))
    assert not plant.has_friction
    R = plant.respond(*args)
    for i in range(m):
        assert so3.angle_between(R[i], R[m - 1 - i]) < 1e-9       # up and down branches coincide
        assert so3.angle_between(R[m + i], R[i]) < 1e-9


def test_coulomb_band_width_scales_the_hysteresis(rig):
    """The loop's width grows with the friction force (about linearly for small forces)."""
    args, m = _two_same_cycles(rig, seed=12)
    up, down = 1, m - 2
    widths = []
    for F in (0.25, 0.5):
        plant = dataclasses.replace(TestbedPlant.nominal(rig), friction_coulomb_N=np.full(6, F))
        R = plant.respond(*args)
        widths.append(so3.angle_between(R[up], R[down]))
    assert widths[0] > 1e-4
    assert 1.5 < widths[1] / widths[0] < 2.5


def test_simulate_experiment_persists_by_default(rig):
    kw = dict(effect="coulomb_friction", severity=3.0, steps=2)
    a = simulate_experiment(rig, 3, np.random.default_rng(5), **kw)
    b = simulate_experiment(rig, 3, np.random.default_rng(5), persistent=True, **kw)
    c = simulate_experiment(rig, 3, np.random.default_rng(5), persistent=False, **kw)
    np.testing.assert_array_equal(a.rotvec_rad, b.rotvec_rad)
    first = a.cycle_rows(0)
    np.testing.assert_allclose(a.rotvec_rad[first], c.rotvec_rad[first], atol=1e-12)   # same history so far
    later = np.r_[a.cycle_rows(1), a.cycle_rows(2)]
    assert np.abs(a.rotvec_rad[later] - c.rotvec_rad[later]).max() > 1e-4
