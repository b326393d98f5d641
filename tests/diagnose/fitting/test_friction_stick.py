"""The stick condition of settled friction (csjm_opt.diagnose.friction_stick) against independent solutions."""

import numpy as np
from scipy.optimize import lsq_linear

from csjm_opt.diagnose.fitting.friction_stick import (
    StickFit,
    ZonotopeMeasures,
    expected_sq_distance,
    log_normaliser,
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
    r, _ = stick_residual(a, B, F)
    # the projected-gradient solve stops at a relative step of 1e-6: far below any noise
    assert np.max(np.linalg.norm(r, axis=1)) < 1e-4 * np.mean(np.linalg.norm(a, axis=1))


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
