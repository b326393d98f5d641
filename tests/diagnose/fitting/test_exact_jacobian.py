"""The exact (forward-mode) derivative of the balance against central finite differences, for every effect.

:meth:`AugmentedModel.balance_derivative` carries tangents through the late hooks (loads, rest lengths,
tension laws, further moments); each column is compared with a central difference of the balance itself
(the code the fits ran before), on six- and four-cable rigs, for every effect and variant and for pairs
whose hooks chain (a gain after a bias, friction after drive offsets or hardening).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.diagnose.effects import EFFECTS, make_effect
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows, cable_steps, log_steps
from csjm_opt.diagnose.fitting.model_fits import VARIANTS
from csjm_opt.model import kinematics as kin
from csjm_opt.model.rig import Rig

RIGS = Path(__file__).resolve().parents[3] / "rigs"
VARIANTS_ALL = {**VARIANTS, "friction": VARIANTS["friction"] + [{"law": "coulomb", "memory": "settled"}],
                "joint_friction": [{"memory": "step"}, {"memory": "settled"}]}


@pytest.fixture(scope="module", params=[6, 4])
def setup(request):
    """A rig with m cables and rows of a log on it (poses, taut rest lengths, loads, steps, ramps)."""
    rig = Rig.from_toml(RIGS / ("paper.toml" if request.param == 6 else "four_cable.toml"))
    rng = np.random.default_rng(request.param)
    n, m = 24, rig.n_cables
    R = so3.exp(rng.normal(0.0, 0.12, (n, 3)))
    lengths, _ = kin.cable_terms(R, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    rest = lengths - rng.uniform(2e-3, 6e-3, (n, m))
    cycle = np.repeat(np.arange(4), n // 4)
    rows = Rows(rest, rng.normal(0.0, 0.3, (n, 3)), cycle, cable_steps(cycle, lengths),
                log_steps_m=log_steps(lengths), rest_steps_m=log_steps(rest),
                ramp_shape_m=rng.normal(0.0, 2e-5, (n, 8, m)))
    return rig, rows, R, rng


def _theta(model: AugmentedModel, rng) -> np.ndarray:
    """A parameter point away from nominal, inside the bounds (friction bands positive)."""
    th = model.x0() + 0.5 * model.scales * rng.standard_normal(model.n_params)
    lo, hi = model.lower_bounds, model.upper_bounds
    th = np.where(np.isfinite(lo) & (th < lo), 2 * lo - th, th)
    return np.clip(th, lo + 1e-6, hi - 1e-6)


def _check(model: AugmentedModel, rows: Rows, R: np.ndarray, theta: np.ndarray) -> np.ndarray:
    exact = np.flatnonzero(model.exact_params(rows))
    g, dg = model.balance_derivative(R, rows, theta, exact)
    np.testing.assert_array_equal(g, model.balance(R, rows, theta))       # the value is the forward one
    for c, j in enumerate(exact):
        h = 1e-6 * model.scales[j]
        up, down = theta.copy(), theta.copy()
        up[j] += h
        down[j] -= h
        fd = (model.balance(R, rows, up) - model.balance(R, rows, down)) / (2 * h)
        scale = max(np.abs(fd).max(), 1e-3)     # N m per unit: below, the differences are round-off
        assert np.abs(dg[..., c] - fd).max() <= 1e-5 * scale, (model.name, model.param_names[j])
    return exact


@pytest.mark.parametrize("name", list(EFFECTS))
def test_every_effect_against_central_differences(setup, name):
    rig, rows, R, rng = setup
    for opt in VARIANTS_ALL.get(name, [{}]):
        model = AugmentedModel(rig, [make_effect(name, rig, **opt)])
        exact = _check(model, rows, R, _theta(model, rng))
        # the guide's exit point and the registration carry no tangent: differences (the common offset is exact)
        assert len(exact) == (1 if name in ("guide_radius", "tracker_registration") else model.n_params)


PAIRS = [("sensor_bias", "sensor_gain"), ("sensor_gain", "sensor_bias"), ("drive_offsets", "friction"),
         ("cable_hardening", "friction"), ("stiffness_scale", "cable_hardening"), ("friction", "joint_friction"),
         ("mass_com", "link_compliance"), ("hole_offsets", "friction"), ("tracker_registration", "mass_com"),
         ("hole_offsets", "joint_friction"), ("link_compliance", "joint_friction"), ("hole_offsets", "link_compliance"),
         ("friction", "link_compliance"), ("guide_radius", "hole_offsets"), ("sensor_gain", "link_compliance"),
         ("guide_radius", "link_compliance")]


@pytest.mark.parametrize("pair", PAIRS)
def test_pairs_whose_hooks_chain(setup, pair):
    rig, rows, R, rng = setup
    for law in ("capstan", "coulomb"):
        effects = [make_effect(e, rig, **({"law": law} if e == "friction" else {})) for e in pair]
        model = AugmentedModel(rig, effects)
        exact = _check(model, rows, R, _theta(model, rng))
        names = {model.param_names[j] for j in exact}
        if "guide_radius" in pair:       # no tangent of the exit point: hole and link parameters by differences
            assert not any(n.startswith(("dA", "dB", "C_")) for n in names)
        elif "tracker_registration" not in pair:
            assert len(exact) == model.n_params


def test_a_sequential_prediction_falls_back_to_differences(setup):
    """Friction stepped row by row (a prediction) gives no tangent: the Jacobian is all differences there."""
    rig, rows, R, _ = setup
    model = AugmentedModel(rig, [make_effect("friction", rig)])
    seq = dataclasses.replace(rows, state_prev=np.zeros(rows.rest_lengths_m.shape),
                              lengths_prev_m=np.full(rows.rest_lengths_m.shape, np.nan))
    assert not model.exact_params(seq).any() and model.exact_params(rows).all()


def test_the_fit_jacobian_agrees_with_its_forward_differences(setup, monkeypatch):
    """``data_jacobian`` (exact columns where it can) against the forward differences it replaced."""
    from csjm_opt.diagnose.fitting import gauss_newton as gn

    rig, rows, R, rng = setup
    model = AugmentedModel(rig, [make_effect("friction", rig), make_effect("hole_offsets", rig)])
    theta = _theta(model, rng)
    table = type("Table", (), {"rows": rows, "R_meas": R, "whiten": np.broadcast_to(np.eye(3) * 300.0,
                                                                                   (len(rows), 3, 3))})()
    exact = gn.data_jacobian(model, table, theta)                  # type: ignore[arg-type]
    monkeypatch.setattr(AugmentedModel, "exact_params", lambda self, rows: np.zeros(self.n_params, bool))
    fd = gn.data_jacobian(model, table, theta)                     # type: ignore[arg-type]
    scale = np.abs(fd).max(axis=0)
    assert np.all(np.abs(exact - fd).max(axis=0) <= 1e-4 * scale + 1e-6)
