"""The MuJoCo plant's friction rows are quasi-static: its ramps are slow enough for dry friction.

MuJoCo's tendon friction (soft, with noslip) stays below its bound on a tendon that slides
slowly, so on a fast ramp the platform slides on past the quasi-static stop and the settled
pose depends on the ramp's speed. The reference here is the quasi-static plant's own play
operator (Coulomb friction, a nearly rigid platform-side segment), which the MuJoCo plant does
not use: at the plant's friction ramps the two agree; at the former 0.3 s / 2 s ramps they did
not (the test would fail there, which the second assertion shows).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.testbed import TestbedPlant, as_mujoco, design_cycles, make_plant, random_rig


@pytest.fixture(scope="module")
def carried():
    """Random rig 0 of the studies, Coulomb friction at 3x, two carried load cycles (18 rows)."""
    rig, _ = random_rig(np.random.default_rng([1234, 0]))
    cycles = design_cycles(rig, 2, np.random.default_rng(21), steps=2)
    l = np.concatenate([np.repeat(c.rest_lengths_m[None], len(c.alphas), 0) for c in cycles])
    tau = np.concatenate([c.tau_ext_A_Nm for c in cycles])
    cyc = np.concatenate([np.full(len(c.alphas), k) for k, c in enumerate(cycles)])
    R = np.concatenate([np.repeat(c.R_ref[None], len(c.alphas), 0) for c in cycles])
    plant = make_plant(rig, "coulomb_friction", 3.0, np.random.default_rng(6))
    args = (l, tau, cyc, R)
    R_q = dataclasses.replace(plant, friction_platform_fraction=0.01).respond(*args)
    R_n = TestbedPlant.nominal(rig).respond(*args)
    size = np.array([so3.angle_between(a, b) for a, b in zip(R_n, R_q)])
    return plant, args, R_q, size


def _relative_gap(R_m, R_q, size):
    return max(so3.angle_between(a, b) / s for a, b, s in zip(R_m[1:], R_q[1:], size[1:]))


def test_mujoco_friction_rows_agree_with_the_quasi_static_play_operator(carried):
    plant, args, R_q, size = carried
    assert size[1:].min() > 5e-3                              # friction moves the platform by mrad
    assert _relative_gap(as_mujoco(plant).respond(*args), R_q, size) < 0.08


def test_fast_ramps_were_not_quasi_static(carried):
    plant, args, R_q, size = carried
    fast = as_mujoco(plant, friction_ramp_s=0.3, cycle_ramp_s=2.0).respond(*args)
    assert _relative_gap(fast, R_q, size) > 0.15
