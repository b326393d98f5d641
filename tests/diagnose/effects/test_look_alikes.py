"""Look-alikes the log cannot tell apart, as laws of the balance (why some validation logs are missed).

A common stiffness factor ``s`` scales every tension: ``s J^T T + tau + W(mr) = 0`` is
``J^T T + tau / s + W(mr / s) = 0`` (the weight's moment ``W`` is linear in the first moment ``mr``).
The second is a sensor gain ``s`` with the first moment ``mr / s``: the two predict the same pose
for every row, whatever the rig, so no log of poses and loads separates stiffness scale + mass
from sensor gain + mass; only their priors differ.
"""

from __future__ import annotations

import numpy as np

import csjm_opt as co
from csjm_opt.diagnose.effects import MassCom, SensorGain, StiffnessScale
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows


def _rows(rig, n=8, seed=11):
    rng = np.random.default_rng(seed)
    R = np.stack([co.so3.exp(rng.normal(0, 0.15, 3)) for _ in range(n)])
    tau = rng.normal(0, 0.5, (n, 3))
    rest = np.stack([co.plan_tensions(rig, Ri, ti).rest_lengths_m for Ri, ti in zip(R, tau)])
    return R, Rows(rest, tau, np.zeros(n, int), np.zeros_like(rest))


def _poses(rig, effects, theta, R, rows):
    sol = AugmentedModel(rig, effects).predict_poses(rows, np.asarray(theta, float), R)
    return sol.R


def _angle(Ra, Rb):
    return max(np.linalg.norm(co.so3.log(a.T @ b)) for a, b in zip(Ra, Rb))


def test_stiffness_scale_and_mass_are_a_sensor_gain_and_another_mass(rig):
    R, rows = _rows(rig)
    mr0 = rig.platform_mass_kg * np.asarray(rig.com_A_m, float)
    s, dmr = 0.85, np.array([0.004, -0.006, 0.003])
    mass = MassCom(rig.platform_mass_kg)
    stiff = _poses(rig, [StiffnessScale(), mass], np.r_[0.0, np.log(s), dmr], R, rows)
    gain = _poses(rig, [SensorGain("common"), mass], np.r_[0.0, np.log(s), (mr0 + dmr) / s - mr0], R, rows)
    nominal = _poses(rig, [], [0.0], R, rows)
    assert _angle(stiff, nominal) > 1e-3            # the effects move the poses by mrad
    assert _angle(stiff, gain) < 1e-9               # and the two models move them alike


def test_a_stiffness_scale_alone_is_a_gain_and_a_lighter_platform(rig):
    R, rows = _rows(rig, seed=12)
    mr0 = rig.platform_mass_kg * np.asarray(rig.com_A_m, float)
    s = 1.2
    stiff = _poses(rig, [StiffnessScale()], np.r_[0.0, np.log(s)], R, rows)
    gain = _poses(rig, [SensorGain("common"), MassCom(rig.platform_mass_kg)],
                  np.r_[0.0, np.log(s), mr0 * (1.0 / s - 1.0)], R, rows)
    assert _angle(stiff, gain) < 1e-9
    # without the first moment's change the gain alone is not the scale (the weight tells them apart)
    alone = _poses(rig, [SensorGain("common")], np.r_[0.0, np.log(s)], R, rows)
    assert _angle(stiff, alone) > 1e-4


def test_the_look_alikes_share_one_prior_on_their_common_factor():
    # the two pairs above fit any log alike: with one prior on the shared factor the evidence chooses by the
    # first moment's prior, never by which factor has the narrower range (fails with gains in [0.6, 1.4])
    gain, = SensorGain("common").default_ranges().values()
    stiff, = StiffnessScale().default_ranges().values()
    assert np.allclose(gain, stiff)
    assert np.isclose(gain[0], -gain[1])            # symmetric in log: a gain and its inverse equally plausible
