"""``guide_radius``: geometry by hand, the exit point against brute force, statics against the energy,
``r = 0`` is the nominal model, and the radius recovered from the testbed's independent eyelet plant."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import EFFECTS, GuideRadius, guide_axis, make_effect
from csjm_opt.diagnose.effects.guide_radius import ring_exit_points
from csjm_opt.diagnose.fitting.augmented import AugmentedModel, Rows
from csjm_opt.diagnose.fitting.gauss_newton import fit_model
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed import make_plant, simulate_experiment

Z = np.array([0.0, 0.0, 1.0])


def _poses(n: int, seed: int = 0, max_angle: float = 0.4) -> np.ndarray:
    return so3.random_rotations(n, np.random.default_rng(seed), max_angle=max_angle)


def _rows(rig, R: np.ndarray, tension_N: float = 40.0) -> Rows:
    """Rows whose rest lengths leave every cable taut by ``tension_N / k`` at the poses ``R``."""
    from csjm_opt.model import kinematics as kin

    c, _ = kin.cable_terms(R, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    l = c - tension_N / np.asarray(rig.cable_stiffness_N_per_m)
    n = len(R)
    return Rows(l, np.zeros((n, 3)), np.zeros(n, int), np.zeros((n, 6)))


def test_planar_cable_by_hand():
    # one cable in the x-z plane: ring centre (0.05, 0, -0.1), platform hole at (0.08, 0, 0.02) with R = I,
    # ring radius 4 mm in the base plane z = const: the cable leaves at x = 0.054, length sqrt(0.026^2 + 0.12^2)
    A = np.tile([0.08, 0.0, 0.02], (6, 1))
    B = np.tile([0.05, 0.0, -0.1], (6, 1))
    X = ring_exit_points(np.eye(3)[None], A, B, 4e-3, Z)
    np.testing.assert_allclose(X[0, 0], [0.054, 0.0, -0.1], atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(A[0] - X[0, 0]), np.hypot(0.026, 0.12), rtol=1e-14)
    # the platform hole across the ring's centre: the cable leaves on the other side
    X2 = ring_exit_points(np.eye(3)[None], np.tile([0.02, 0.0, 0.02], (6, 1)), B, 4e-3, Z)
    np.testing.assert_allclose(X2[0, 0], [0.046, 0.0, -0.1], atol=1e-15)


def test_model_lengths_match_the_closed_form(rig):
    # in the rig's base plane (z = const): length = sqrt((|h| - r)^2 + dz^2), h the horizontal part of p - B
    R = _poses(7)
    r = 3e-3
    model = AugmentedModel(rig, [make_effect("guide_radius", rig)])
    _, ev = model.evaluate(R, _rows(rig, R), np.array([0.0, r]))
    B = np.asarray(rig.base_holes_B_m)
    assert np.ptp(B[:, 2]) < 1e-12                               # the paper rig's guides lie in one plane
    p = np.einsum("nij,kj->nki", R, np.asarray(rig.platform_holes_A_m))
    d = p - B
    expected = np.sqrt((np.hypot(d[..., 0], d[..., 1]) - r) ** 2 + d[..., 2] ** 2)
    np.testing.assert_allclose(ev.lengths_m, expected, rtol=1e-13)


def test_exit_point_is_the_shortest_path_over_the_ring():
    # brute force: the ring point nearest the platform hole (the drive side's length is the same for all)
    rng = np.random.default_rng(3)
    axis = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])      # a tilted base plane
    e1 = np.cross(axis, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    B = rng.normal(0, 0.05, (6, 3)) - 0.1 * axis
    A = rng.normal(0, 0.05, (6, 3)) + 0.05 * axis
    R = _poses(3, 4)
    r = 5e-3
    X = ring_exit_points(R, A, B, r, axis)
    th = np.linspace(0, 2 * np.pi, 200001)
    ring = r * (np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2)
    for n in range(len(R)):
        for i in range(6):
            p = R[n] @ A[i]
            dist = np.linalg.norm(B[i] + ring - p, axis=1)
            np.testing.assert_allclose(np.linalg.norm(X[n, i] - p), dist.min(), rtol=1e-9)
            np.testing.assert_allclose(X[n, i], B[i] + ring[np.argmin(dist)], atol=r * 1e-4)


def test_cable_moments_are_the_energy_gradient(rig):
    # statics: the moment of the cables J^T T equals -d(energy)/dzeta, the energy taken with each cable's
    # length over the ring by brute force (finite differences in body coordinates R exp(hat(zeta)))
    R = _poses(3, 5)
    r = 4e-3
    rows = _rows(rig, R)
    model = AugmentedModel(rig, [make_effect("guide_radius", rig)])
    theta = np.array([0.0, r])
    g, ev = model.evaluate(R, rows, theta)
    cable_moment = g - ev.tau_weight_A_Nm                          # tau_meas = 0 in these rows
    A, B = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    k = np.asarray(rig.cable_stiffness_N_per_m)
    th = np.linspace(0, 2 * np.pi, 20001)
    ring = r * np.stack([np.cos(th), np.sin(th), 0 * th], axis=1)

    def energy(Rn, l):
        c = np.array([np.linalg.norm(B[i] + ring - Rn @ A[i], axis=1).min() for i in range(6)])
        # the ring is sampled: refine by the parabola through the minimum's neighbours is not needed at
        # this resolution for a gradient taken over a step much larger than the sampling error
        e = np.maximum(c - l, 0.0)
        return 0.5 * float(np.sum(k * e ** 2))

    h = 1e-5
    for n in range(len(R)):
        grad = np.zeros(3)
        for j in range(3):
            dz = np.zeros(3)
            dz[j] = h
            grad[j] = (energy(R[n] @ so3.exp(dz), rows.rest_lengths_m[n])
                       - energy(R[n] @ so3.exp(-dz), rows.rest_lengths_m[n])) / (2 * h)
        np.testing.assert_allclose(cable_moment[n], -grad, rtol=2e-3, atol=2e-4)


def test_zero_radius_is_the_nominal_model_exactly(rig):
    R = _poses(5, 6)
    rows = _rows(rig, R)
    m0, m1 = AugmentedModel(rig), AugmentedModel(rig, [make_effect("guide_radius", rig)])
    for dl in (0.0, 2e-4):
        assert np.array_equal(m1.balance(R, rows, np.array([dl, 0.0])), m0.balance(R, rows, np.array([dl])))
    B = np.asarray(rig.base_holes_B_m)
    assert np.array_equal(ring_exit_points(R, rig.platform_holes_A_m, B, 0.0, Z), np.broadcast_to(B, (5, 6, 3)))
    # a tiny radius moves the balance by a tiny amount (continuity at the nominal model)
    d = m1.balance(R, rows, np.array([0.0, 1e-9])) - m0.balance(R, rows, np.array([0.0]))
    assert 0 < np.abs(d).max() < 1e-4


def test_guide_axis_is_the_base_plane_normal_towards_the_joint():
    rng = np.random.default_rng(8)
    n = np.array([0.2, 0.1, -1.0]) / np.linalg.norm([0.2, 0.1, -1.0])
    basis = np.linalg.svd(n[None])[2][1:]                        # two vectors in the plane
    B = 0.1 * n + rng.normal(0, 0.06, (6, 2)) @ basis            # holes in a plane 0.1 m from O along n
    np.testing.assert_allclose(guide_axis(B), -n, atol=1e-12)    # towards O
    np.testing.assert_allclose(guide_axis(-B), n, atol=1e-12)


def test_radius_recovered_from_the_testbeds_eyelet_plant(rig):
    # injected ground truth: the testbed's eyelet plant (written independently) at 3 mm, noise-free
    plant = make_plant(rig, "guide_radius", 1.0, np.random.default_rng(0))
    log = simulate_experiment(rig, 3, np.random.default_rng(1), effect=plant, noise=InstrumentNoise.none(), steps=3)
    t = compute_residuals(rig, log)
    fit = fit_model(AugmentedModel(rig, [make_effect("guide_radius", rig)]), t)
    assert fit.theta[1] == pytest.approx(plant.guide_radius_m, rel=1e-6)
    assert fit.rss < 1e-10 * fit_model(AugmentedModel(rig), t).rss


def test_registered_in_the_vocabulary_and_the_cli():
    import argparse

    from csjm_opt.cli.diagnose import register
    from csjm_opt.diagnose import VOCABULARY

    assert EFFECTS["guide_radius"] is GuideRadius and "guide_radius" in VOCABULARY
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    args = parser.parse_args(["diagnose", "log.csv", "--rig", "rig.toml", "--effects", "guide_radius", "hole_offsets"])
    assert args.effects == ["guide_radius", "hole_offsets"]
    e = make_effect("guide_radius", ranges={"guide_radius_m": (0.0, 0.02)})
    assert e.implausible(np.array([0.015])) == [] and e.implausible(np.array([0.025])) == ["guide_radius_m"]
    assert make_effect("guide_radius").implausible(np.array([0.015])) == ["guide_radius_m"]
