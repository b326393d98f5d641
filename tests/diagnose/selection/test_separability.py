"""Separability of a settled (set-valued) single: taken on its loading-path twin, never the degenerate zero.

A stick set's pose is any point of the set, so its parameters have no point Jacobian (zero columns); a block
correlation computed from them is 0 and would call settled friction separable from anything.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import N_NUISANCE, AugmentedModel
from csjm_opt.diagnose.fitting.gauss_newton import data_jacobian
from csjm_opt.diagnose.fitting.model_fits import path_twin
from csjm_opt.diagnose.selection.pairs import all_separabilities
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed import simulate_experiment


@pytest.fixture(scope="module")
def friction_table(rig):
    log = simulate_experiment(rig, 2, np.random.default_rng(5), effect="coulomb_friction", severity=4.0,
                              noise=InstrumentNoise.paper(), steps=3)
    return compute_residuals(rig, log, InstrumentNoise.paper())


def _single(effect, theta):
    """What :func:`all_separabilities` reads of a single's score: its fit's effect and parameters."""
    return SimpleNamespace(fit=SimpleNamespace(model=SimpleNamespace(effects=[effect]), theta=theta))


def test_the_path_twin_keeps_the_bounds_and_starts_the_path_state(rig):
    settled = make_effect("friction", rig, {"F_*": (0.0, 9.0)}, law="coulomb", memory="settled")
    theta = np.r_[np.zeros(N_NUISANCE), np.arange(1.0, 7.0)]
    twin, theta_twin = path_twin(settled, theta, rig)
    assert (twin.law, twin.memory, twin.settled) == ("coulomb", "carried", False)
    assert twin.param_names[:6] == settled.param_names
    np.testing.assert_array_equal(theta_twin[:N_NUISANCE + 6], theta)
    np.testing.assert_array_equal(theta_twin[N_NUISANCE + 6:], twin.x0()[6:])
    assert twin.ranges()["F_1_N"] == settled.ranges()["F_1_N"] == (0.0, 9.0)
    point = make_effect("stiffness_scale", rig)
    assert path_twin(point, theta[:N_NUISANCE + 1], rig)[0] is point


def test_settled_friction_is_not_separable_by_default(rig, friction_table):
    """The stick set's own columns are zero (the reason for the twin); through the twin, friction and the
    partners have a block correlation well above zero (it was 1e-20 from the zero columns)."""
    settled = make_effect("friction", rig, law="coulomb", memory="settled")
    theta = np.r_[np.zeros(N_NUISANCE), np.full(6, 3.0)]
    J = data_jacobian(AugmentedModel(rig, [settled]), friction_table, theta)
    assert np.allclose(J[:, N_NUISANCE:], 0.0)
    singles = {"friction": _single(settled, theta),
               "stiffness_scale": _single(make_effect("stiffness_scale", rig), np.r_[np.zeros(N_NUISANCE), 0.1]),
               "sensor_bias": _single(make_effect("sensor_bias", rig), np.r_[np.zeros(N_NUISANCE), 0.0, 0.0, 0.0])}
    seps = all_separabilities(rig, friction_table, singles, ["friction", "stiffness_scale", "sensor_bias"])
    for pair in (("friction", "stiffness_scale"), ("friction", "sensor_bias")):
        assert 0.05 < seps[pair]["max_correlation"] <= 1.0, (pair, seps[pair])
