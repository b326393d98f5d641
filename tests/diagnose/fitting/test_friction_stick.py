"""The stick condition of settled friction (csjm_opt.diagnose.friction_stick) against independent solutions."""

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from csjm_opt.diagnose.fitting.friction_stick import (
    StickFit,
    ZonotopeMeasures,
    expected_sq_distance,
    log_normaliser,
    log_normaliser_gradient,
    stick_residual,
)


def _rows(rng, n, m=6):
    return rng.normal(size=(n, 3)) * 3.0, rng.normal(size=(n, 3, m))


def test_distance_matches_scipy_bounded_least_squares():
    rng = np.random.default_rng(1)
    a, B = _rows(rng, 40)
    F = rng.uniform(0.1, 1.0, 6)
    r, f = stick_residual(a, B, F)
    ref = np.array([lsq_linear(B[i], -a[i], bounds=(-F, F)).fun for i in range(len(a))])
    assert np.all(np.abs(f) <= F + 1e-12)
    np.testing.assert_allclose(np.linalg.norm(r, axis=1), np.linalg.norm(ref, axis=1), atol=1e-6)


def test_row_balanced_by_forces_within_their_bounds_has_no_residual():
    rng = np.random.default_rng(2)
    _, B = _rows(rng, 20)
    F = np.full(6, 2.0)
    f_true = rng.uniform(-1.9, 1.9, (20, 6))
    a = -np.einsum("nij,nj->ni", B, f_true)
    r, f = stick_residual(a, B, F)
    # the facet-by-facet projection is exact: the row is balanced to round-off by forces within the band
    assert np.max(np.linalg.norm(r, axis=1)) < 1e-12 * np.mean(np.linalg.norm(a, axis=1))
    assert np.all(np.abs(f) <= F + 1e-12)


@pytest.mark.parametrize("m", [2, 3, 4, 6, 8, 12])
def test_projection_is_exact_against_scipy_bvls_with_bands_off(m):
    # scipy's bounded-variable least squares (an active-set solver) gives the distance to the zonotope;
    # a band of zero fixes its force at zero (scipy is given the other cables only)
    rng = np.random.default_rng(10 + m)
    for _ in range(60):
        B = rng.normal(size=(1, 3, m))
        F = rng.uniform(0.0, 1.0, m) * (rng.uniform(size=m) > 0.25)
        a = rng.normal(size=(1, 3)) * rng.choice([0.1, 1.0, 3.0])
        r, f = stick_residual(a, B, F)
        keep = F > 0
        ref = np.linalg.norm(a[0])
        if keep.any():
            sol = lsq_linear(B[0][:, keep], -a[0], bounds=(-F[keep], F[keep]), method="bvls", tol=1e-15)
            ref = np.linalg.norm(a[0] + B[0][:, keep] @ sol.x)
        assert np.all(np.abs(f) <= F + 1e-12) and np.all(f[0][~keep] == 0.0)
        np.testing.assert_allclose(r[0], a[0] + B[0] @ f[0], atol=1e-12)
        assert abs(np.linalg.norm(r[0]) - ref) <= 1e-10 * (1.0 + np.linalg.norm(a[0]))


@pytest.mark.parametrize("shape", ["parallel", "planar"])
def test_degenerate_stick_sets_fall_back_and_stay_right(shape):
    # two cables pulling along one line, or every cable in one plane: the facets are not parallelograms,
    # the exact answer fails its check and the iteration gives it (against scipy's bvls)
    rng = np.random.default_rng({"parallel": 21, "planar": 22}[shape])
    for _ in range(30):
        B = rng.normal(size=(1, 3, 5))
        if shape == "parallel":
            B[0, :, 1] = -0.6 * B[0, :, 0]
        else:
            B[0, 2, :] = 0.0
        F = rng.uniform(0.2, 1.0, 5)
        a = rng.normal(size=(1, 3))
        r, f = stick_residual(a, B, F)
        sol = lsq_linear(B[0], -a[0], bounds=(-F, F), method="bvls", tol=1e-15)
        assert np.all(np.abs(f) <= F + 1e-12)
        assert abs(np.linalg.norm(r[0]) - np.linalg.norm(a[0] + B[0] @ sol.x)) <= 1e-8


def test_one_cable_distance_is_the_distance_to_a_segment():
    rng = np.random.default_rng(3)
    b = rng.normal(size=3)
    F = 0.7
    a = rng.normal(size=(30, 3)) * 2.0
    r, _ = stick_residual(a, np.broadcast_to(b[:, None], (30, 3, 1)).copy(), np.array([F]))
    # closed form: the point -a against the segment {t b : |t| <= F}
    t = np.clip(-(a @ b) / (b @ b), -F, F)
    expected = np.linalg.norm(-a - t[:, None] * b, axis=1)
    np.testing.assert_allclose(np.linalg.norm(r, axis=1), expected, atol=1e-9)


def test_normaliser_and_mean_square_distance_of_a_rotated_box():
    # a box of half sides h (three orthogonal generators): exp(-d^2 / 2 s^2) factorises over its axes,
    # so Z = prod(2 h_k + sqrt(2 pi) s) and E[d^2] = sum sqrt(2 pi) s^3 / (2 h_k + sqrt(2 pi) s)
    rng = np.random.default_rng(4)
    Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    h, s = np.array([0.3, 1.2, 2.5]), 0.4
    meas = ZonotopeMeasures(Q[None])
    Z = np.prod(2 * h + np.sqrt(2 * np.pi) * s)
    np.testing.assert_allclose(log_normaliser(meas, h, s)[0], np.log(Z / (2 * np.pi * s ** 2) ** 1.5), rtol=1e-12)
    e = np.sum(np.sqrt(2 * np.pi) * s ** 3 / (2 * h + np.sqrt(2 * np.pi) * s))
    np.testing.assert_allclose(expected_sq_distance(meas, h, s)[0], e, rtol=1e-12)
    # no band: the Gaussian
    assert log_normaliser(meas, np.zeros(3), s)[0] == 0.0
    np.testing.assert_allclose(expected_sq_distance(meas, np.zeros(3), s)[0], 3 * s ** 2)


def test_normaliser_of_a_skew_zonotope_by_monte_carlo():
    rng = np.random.default_rng(5)
    B = rng.normal(size=(1, 3, 4)) * 0.5
    F, s = np.array([1.0, 0.5, 0.8, 0.3]), 0.3
    half = np.sum(np.abs(B[0]) * F, axis=1) + 5 * s
    z = rng.uniform(-half, half, (20000, 3))
    r, _ = stick_residual(-z, np.broadcast_to(B, (len(z), 3, 4)).copy(), F)
    Z_mc = np.prod(2 * half) * np.mean(np.exp(-np.sum(r ** 2, axis=1) / (2 * s ** 2)))
    Z = np.exp(log_normaliser(ZonotopeMeasures(B), F, s)[0]) * (2 * np.pi * s ** 2) ** 1.5
    assert abs(Z_mc / Z - 1) < 0.03


def _stick_rows(rng, n, F_true, s_true):
    """Rest poses uniform over each row's stick set (rejection from its bounding box, membership by scipy)."""
    B = rng.normal(size=(n, 3, len(F_true))) * 0.7
    a = np.empty((n, 3))
    for i in range(n):
        half = np.abs(B[i]) @ F_true
        while True:
            z = rng.uniform(-half, half)
            if lsq_linear(B[i], z, bounds=(-F_true, F_true)).cost < 1e-12:
                break
        a[i] = -z + rng.normal(size=3) * s_true
    return a, B


def test_band_by_likelihood_and_noise_by_held_out_rows():
    rng = np.random.default_rng(6)
    F_true, s_true = np.array([1.0, 2.0, 1.5, 1.0, 2.5, 1.2]), 0.3
    a, B = _stick_rows(rng, 120, F_true, s_true)
    a_h, B_h = _stick_rows(rng, 80, F_true, s_true)
    held = {}
    for s in (0.1, 0.2, 0.3, 0.45, 0.7):
        x, _ = StickFit(a, np.zeros_like(a), B).fit(10.0, starts=(0.3,), s=s)
        held[s] = StickFit(a_h, np.zeros_like(a_h), B_h).neg_log_lik(x)[0]
        if s == s_true:
            assert np.max(np.abs(x[1:-1] - F_true) / F_true) < 0.3
    assert min(held, key=held.get) in (0.2, 0.3, 0.45)
    # without a band, the same rows need a noise scale several times the true one
    assert np.sqrt(np.mean(np.sum(a ** 2, axis=1)) / 3) > 3 * s_true


def test_tied_box_likelihood_is_the_closed_form_of_a_cube():
    # one bound M for three orthogonal generators (joint friction's box): the density factorises over the axes,
    # p(a_k) = exp(-dist(a_k, [-M, M])^2 / 2 s^2) / (2 M + sqrt(2 pi) s)
    rng = np.random.default_rng(7)
    n, M, s = 50, 0.4, 0.25
    a = rng.normal(size=(n, 3)) * 0.6
    B = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    sf = StickFit(a, np.zeros((n, 3, 0)), B, tie=np.zeros(3, int))
    val, _ = sf.neg_log_lik(np.r_[M, np.log(s)])
    dist = np.maximum(np.abs(a) - M, 0.0)
    ref = np.sum(dist ** 2) / (2 * s ** 2) + 3 * n * np.log(2 * M + np.sqrt(2 * np.pi) * s)
    # neg_log_lik drops the constant 3 n log(sqrt(2 pi)) of every model's Gaussian
    np.testing.assert_allclose(val, ref - 1.5 * n * np.log(2 * np.pi), rtol=1e-7)


def test_gradient_with_tied_bands_and_point_parameters_matches_finite_differences():
    rng = np.random.default_rng(8)
    n = 30
    a = rng.normal(size=(n, 3))
    D = rng.normal(size=(n, 3, 2)) * 0.5
    B = rng.normal(size=(n, 3, 5)) * 0.7
    tie = np.array([0, 1, 1, 2, 0])
    sf = StickFit(a, D, B, tie)
    x = np.r_[0.3, -0.2, 0.5, 0.8, 0.3, np.log(0.4)]
    _, g = sf.neg_log_lik(x)
    num = np.empty_like(x)
    for j in range(len(x)):
        e = np.zeros_like(x)
        e[j] = 1e-6
        num[j] = (StickFit(a, D, B, tie).neg_log_lik(x + e)[0] - StickFit(a, D, B, tie).neg_log_lik(x - e)[0]) / 2e-6
    np.testing.assert_allclose(g, num, rtol=2e-4, atol=2e-4)


@pytest.mark.parametrize("m", [2, 3, 6])
def test_band_price_gradient_is_the_finite_difference_of_the_price(m):
    # the closed form against central differences of log(Z/Z0) itself; a band at 0 against a forward one
    rng = np.random.default_rng(m)
    B = rng.normal(size=(12, 3, m)) * 0.6
    meas = ZonotopeMeasures(B)
    F = rng.uniform(0.1, 1.5, size=m)
    F[0] = 0.0
    s, h = 0.37, 1e-6
    value, d_F, d_log_s = log_normaliser_gradient(meas, F, s)
    np.testing.assert_array_equal(value, log_normaliser(meas, F, s))
    for j in range(m):
        up, down = F.copy(), F.copy()
        up[j] += h
        down[j] = max(F[j] - h, 0.0)
        num = (log_normaliser(meas, up, s) - log_normaliser(meas, down, s)) / (up[j] - down[j])
        np.testing.assert_allclose(d_F[:, j], num, rtol=1e-5, atol=1e-8)
    num = (log_normaliser(meas, F, s * np.exp(h)) - log_normaliser(meas, F, s * np.exp(-h))) / (2 * h)
    np.testing.assert_allclose(d_log_s, num, rtol=1e-6, atol=1e-9)


def test_point_parameters_recovered_beside_the_bands():
    # rows at rest anywhere in the stick set, shifted by a known linear term D theta: the fit finds theta
    rng = np.random.default_rng(9)
    F_true, s_true, theta = np.array([1.0, 1.5, 0.8, 1.2]), 0.2, np.array([0.7, -0.4])
    a, B = _stick_rows(rng, 60, F_true, s_true)
    D = rng.normal(size=(60, 3, 2))
    x, _ = StickFit(a - np.einsum("nij,j->ni", D, theta), D, B).fit(10.0, starts=(0.3,), s=s_true)
    np.testing.assert_allclose(x[:2], theta, atol=0.1)


def test_settled_joint_friction_holds_a_testbed_log_of_a_stuck_ball_joint_within_its_bound():
    """The quasi-static plant's ball joint (its own friction code) left every row inside the box.

    The settled joint-friction stick set at the plant's bound holds every noise-free row (distance ~0);
    at half the bound it does not; cable friction of the same moment would need another shape.
    """
    import dataclasses

    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.friction_stick import stick_design
    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.testbed import make_plant, random_rig, simulate_experiment

    bound = 0.17942774468913208          # tests/testbed/test_joint_friction.py: a log whose joint slips and sticks
    rig, _ = random_rig(np.random.default_rng([1234, 9]))
    plant = dataclasses.replace(make_plant(rig, None, 1.0, np.random.default_rng(0)), joint_friction_Nm=bound)
    log = simulate_experiment(rig, 1, np.random.default_rng([9, 0, 30, 11313, 7, 3]), effect=plant,
                              noise=InstrumentNoise.none())
    table = compute_residuals(rig, log)
    model = AugmentedModel(rig, [make_effect("joint_friction", rig, memory="settled")])
    a, B, tie = stick_design(model, table, model.x0())
    assert B.shape == (len(log), 3, 3) and np.all(tie == 0)
    scale = np.mean(np.linalg.norm(a, axis=1))
    held = np.linalg.norm(stick_residual(a, B, np.full(3, bound * (1 + 1e-6)))[0], axis=1)
    assert held.max() < 1e-4 * scale
    half = np.linalg.norm(stick_residual(a, B, np.full(3, 0.5 * bound))[0], axis=1)
    assert half.max() > 0.1 * scale


def test_stick_residual_is_the_pose_offset_through_the_models_own_tangent():
    """A pose turned by a known small offset from the true equilibrium reads that offset at zero band.

    The plant's cables are 1.4x stiffer than the rig file's; the model with its stiffness scale at 1.4
    (and settled friction of zero band) must read the offset itself (to second order), not 1.4 times it
    as the nominal tangent would.
    """
    import dataclasses

    from csjm_opt import so3
    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.friction_stick import stick_design
    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.testbed import make_plant, random_rig, simulate_experiment

    rig, _ = random_rig(np.random.default_rng([1234, 3]))
    factor = 1.4
    plant = make_plant(rig, None, 1.0, np.random.default_rng(0))
    plant = dataclasses.replace(plant, rig=rig.replace(
        cable_stiffness_N_per_m=factor * np.asarray(rig.cable_stiffness_N_per_m)))
    log = simulate_experiment(rig, 1, np.random.default_rng(5), effect=plant, noise=InstrumentNoise.none())
    offset = np.random.default_rng(6).normal(size=(len(log), 3)) * 2e-3
    log = dataclasses.replace(log, rotvec_rad=so3.log(log.R @ so3.exp(offset)))
    table = compute_residuals(rig, log)
    model = AugmentedModel(rig, [make_effect("friction", rig, law="coulomb", memory="settled"),
                                 make_effect("stiffness_scale", rig)])
    theta = model.x0()
    theta[list(model.param_names).index("log_k_scale")] = np.log(factor)
    a, _, _ = stick_design(model, table, theta)
    pose = np.einsum("nij,nj->ni", np.linalg.inv(table.whiten), a)
    assert np.linalg.norm(pose - offset) < 0.01 * np.linalg.norm(offset)


def test_a_settled_leads_pair_holds_every_friction_of_the_rig_in_its_band(rig, monkeypatch):
    """A rig that came to rest by its own dynamics holds cable and joint friction in their bands at once.

    With the lead (cable friction) settled, the pair's joint friction is a second stick set, even where the
    joint friction single came out along its loading path: a path inside a stick set is a second hysteresis.
    """
    from csjm_opt.diagnose.fitting import model_fits
    from csjm_opt.diagnose.fitting.friction_stick import stick_layout

    seen = {}

    def scored(ctx, rig_, ranges, effects, scales=None):
        seen["effects"], seen["scales"] = list(effects), scales
        return "scored"

    monkeypatch.setattr(model_fits, "_settled", scored)
    options = {"friction": model_fits.SETTLED_VARIANTS["friction"], "joint_friction": {"memory": "step"}}
    got, error = model_fits.fit_pair(None, rig, None, options, {"friction": 0.7}, ("friction", "joint_friction"))
    assert (got, error) == ("scored", None) and seen["scales"] == [0.7]
    model = model_fits.AugmentedModel(rig, seen["effects"])
    _, band, stick = stick_layout(model)
    assert stick == [0, 1]                                       # both effects are stick sets
    assert len(band) == sum(e.n_params for e in model.effects)   # every friction parameter is a band


@pytest.mark.parametrize("partner", ["hole_offsets", "sensor_bias"])
def test_a_settled_pair_fit_ends_at_its_optimum(rig, partner):
    """Settled friction beside a partner's point parameters: the fit ends where a long second solver gains nothing.

    The reference continues from the fit with L-BFGS-B in the parameters' own units, many times longer (another
    path to the same optimum). Unpreconditioned and at 150 iterations, the centre fit of a pair with 36 hole offsets
    stopped hundreds of nats short; a sensor bias (units a thousand times a hole offset's) tens.
    """
    from scipy.optimize import minimize

    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.friction_stick import SettledModel, StickDesign
    from csjm_opt.testbed import simulate_experiment

    log = simulate_experiment(rig, 6, np.random.default_rng(5), effect=["coulomb_friction", partner])
    table = compute_residuals(rig, log)
    model = AugmentedModel(rig, [make_effect("friction", rig, law="coulomb", memory="settled"),
                                 make_effect(partner, rig)])
    design = StickDesign(model, table, model.x0())
    sm = SettledModel(model, design, 0.8)
    rows = np.arange(len(table))
    best = sm._nll(rows, sm.x, sm.s)[0]
    ref = minimize(lambda x: sm._nll(rows, x, sm.s), sm.x, jac=True, method="L-BFGS-B", bounds=sm.bounds,
                   options={"maxiter": 4000, "ftol": 1e-13, "gtol": 1e-9})
    assert ref.fun > best - 0.05, (best, ref.fun)
