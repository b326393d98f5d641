"""The batched pose tangent and the remembered weight moment change no number.

``AugmentedModel.tangent`` evaluates the rows three times over in one pass where rows are
independent; it is compared with central finite differences of the balance (an independent
derivative: second-order accurate, other steps) and with the three separate evaluations it replaces.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model import cable_terms
from csjm_opt.model import kinematics as kin
from csjm_opt.testbed import simulate_experiment


@pytest.fixture(scope="module")
def table(rig):
    log = simulate_experiment(rig, 2, np.random.default_rng(3), effect="friction", severity=3.0,
                              noise=InstrumentNoise.paper(), steps=3)
    return compute_residuals(rig, log)


def _central(model, R, rows, theta, h=1e-6):
    """Central finite differences of the balance under ``R exp(hat(zeta))`` (n, 3, 3)."""
    G = np.empty((len(R), 3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        G[..., j] = (model.balance(R @ so3.exp(e), rows, theta) - model.balance(R @ so3.exp(-e), rows, theta)) / (2 * h)
    return G


def _theta(model, rng):
    return model.x0() + 0.3 * model.scales * rng.standard_normal(model.n_params) * (model.upper_bounds > 0)


@pytest.mark.parametrize("names", [[], ["hole_offsets"], ["link_compliance", "sensor_bias"], ["friction"],
                                   ["friction", "tracker_registration"], ["joint_friction"]])
def test_tangent_matches_central_differences_and_the_separate_evaluations(rig, table, names):
    model = AugmentedModel(rig, [make_effect(n, rig) for n in names])
    theta = np.clip(_theta(model, np.random.default_rng(1)), model.lower_bounds, model.upper_bounds)
    rows, R = table.rows, table.R_meas
    if model.path_dependent:     # a sequential prediction's rows: each with the previous row's state
        n, m = rows.rest_lengths_m.shape
        _, ev = model.evaluate(R, rows, theta)
        rows = dataclasses.replace(rows, state_prev=np.vstack([np.zeros((1, m)), ev.state_out[:-1]])
                                   if ev.state_out is not None else np.zeros((n, m)),
                                   lengths_prev_m=np.vstack([np.full((1, m), np.nan), ev.lengths_m[:-1] + 1e-5]))
    assert model.rows_independent(rows)
    G = model.tangent(R, rows, theta, h=1e-7)
    G_sep = kin.tangent(lambda RR: model.balance(RR, rows, theta), R, h=1e-7)
    np.testing.assert_allclose(G, G_sep, rtol=0, atol=1e-12 * np.abs(G_sep).max())
    G_c = _central(model, R, rows, theta)
    scale = np.abs(G_c).max(axis=(1, 2), keepdims=True)
    np.testing.assert_allclose(G, G_c, rtol=0, atol=1e-4 * scale.max())


def test_coupled_rows_keep_the_separate_evaluations(rig, table):
    """A fit at the measured poses runs the friction state over the log: rows are not independent there."""
    model = AugmentedModel(rig, [make_effect("friction", rig)])
    theta = model.x0()
    theta[1:7] = 0.05
    assert not model.rows_independent(table.rows)
    G = model.tangent(table.R_meas, table.rows, theta, h=1e-6)
    G_sep = kin.tangent(lambda RR: model.balance(RR, table.rows, theta), table.R_meas, h=1e-6)
    np.testing.assert_array_equal(G, G_sep)


def test_rows_three_times_over(table):
    rows = table.rows
    tiled = rows.tiled3
    n = len(rows)
    assert len(tiled) == 3 * n
    for k in range(3):
        np.testing.assert_array_equal(tiled.rest_lengths_m[k * n:(k + 1) * n], rows.rest_lengths_m)
        np.testing.assert_array_equal(tiled.tau_meas_A_Nm[k * n:(k + 1) * n], rows.tau_meas_A_Nm)


def test_remembered_weight_moment_follows_the_pose(rig, table):
    """The remembered weight moment is the closed form ``(m r) x (R^T g)`` at every new pose."""
    model = AugmentedModel(rig, [make_effect("mass_com", rig)])
    mr = rig.platform_mass_kg * np.asarray(rig.com_A_m)
    g = np.asarray(rig.gravity_B_m_per_s2)
    for R in (table.R_meas, table.R_meas @ so3.exp([0.01, 0.0, 0.0]), table.R_meas):
        tau = model.weight_moment(R, mr)
        np.testing.assert_allclose(tau, np.cross(mr, np.einsum("nji,j->ni", R, g)), atol=1e-15)
        with pytest.raises(ValueError):
            tau[0, 0] = 1.0                    # read-only: a hook cannot change the remembered one
    mr2 = 1.5 * mr
    np.testing.assert_allclose(model.weight_moment(table.R_meas, mr2),
                               np.cross(mr2, np.einsum("nji,j->ni", table.R_meas, g)), atol=1e-15)


def test_cross_broadcasts_like_numpy():
    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((6, 3)), rng.standard_normal((4, 6, 3))
    np.testing.assert_allclose(cable_terms._cross(a, b), np.cross(a, b), rtol=0, atol=1e-15)


def test_solve_poses_with_the_batched_tangent_is_the_same_solve(rig, table):
    model = AugmentedModel(rig, [make_effect("stiffness_scale", rig)])
    theta = model.x0()
    rows, R = table.rows, table.R_meas

    def g(RR):
        return model.balance(RR, rows, theta)

    a = kin.solve_poses(g, R)
    b = kin.solve_poses(g, R, tangent_fn=lambda RR, g0: model.tangent(RR, rows, theta, g0))
    np.testing.assert_array_equal(a.R, b.R)
    assert a.iterations == b.iterations
