"""K_ml and the Cramér-Rao bound: checked against finite differences, a brute-force information,
noise-free ground truth and a small Monte Carlo on the testbed (an independent plant)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.cli.app import main
from csjm_opt.identification.cramer_rao import crlb, sym_entries
from csjm_opt.identification.curvature import model_curvature, right_jacobian, weight_slopes
from csjm_opt.identification.experiment_design import paper_protocol
from csjm_opt.identification.log_identification import identify_log
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model.numeric import Model
from csjm_opt.model.rig import paper_rig
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed.protocol_runner import run_protocol

RIG = paper_rig()
NOISE = InstrumentNoise((0.02, 0.02, 0.02), 3e-4)


@pytest.fixture(scope="module")
def design():
    des = paper_protocol(RIG, 20, np.random.default_rng(3), noise=NOISE)
    l = des.protocol.rest_lengths_m[0]
    return des, sym_entries(solve_equilibrium(RIG, l, R_init=np.eye(3)).K)


def test_right_jacobian_matches_exp():
    rng = np.random.default_rng(0)
    z, dz = rng.normal(size=(4, 3)) * 0.3, rng.normal(size=(4, 3)) * 1e-6
    lhs = so3.log(np.swapaxes(so3.exp(z), 1, 2) @ so3.exp(z + dz))
    assert np.allclose(lhs, np.einsum("nij,nj->ni", right_jacobian(z), dz), atol=1e-11)


def test_curvature_and_weight_slopes_by_finite_differences():
    model = Model(RIG)
    R_ref = so3.exp([0.05, -0.1, 0.02])
    l = model.rest_lengths(R_ref, np.full(6, 30.0))
    z = np.array([[0.03, -0.02, 0.05], [-0.06, 0.01, 0.0]])

    def load(zz):  # the load moment that holds the pose: minus the cable moment (independent path)
        R = R_ref @ so3.exp(zz)
        return -model.cable_moment(R, model.tensions_from_rest(R, l))

    c, dc = model_curvature(model, R_ref, l, z)
    h = 1e-6
    G0 = np.column_stack([(load(h * e) - load(-h * e)) / (2 * h) for e in np.eye(3)])
    for i in range(2):
        assert np.allclose(c[i], load(z[i]) - load(np.zeros(3)) - G0 @ z[i], atol=1e-9)
        D = np.column_stack([(load(z[i] + h * e) - load(z[i] - h * e)) / (2 * h) for e in np.eye(3)])
        assert np.allclose(dc[i], D - G0, atol=1e-6)
        Wfd = np.column_stack([(model.weight_moment(R_ref @ so3.exp(z[i] + h * e))
                                - model.weight_moment(R_ref @ so3.exp(z[i] - h * e))) / (2 * h) for e in np.eye(3)])
        assert np.allclose(weight_slopes(model, (R_ref @ so3.exp(z[i]))[None], z[i:i + 1])[0], Wfd, atol=1e-8)


def test_bound_equals_brute_force_joint_information():
    """Woodbury elimination of the nuisance displacements == Schur complement of the joint information."""
    rng = np.random.default_rng(1)
    n = 7
    zeta, tau0 = rng.normal(size=(n, 3)) * 0.05, np.array([0.3, -0.2, 0.1])
    K = np.array([[20.0, 1.0, -2.0], [1.0, 18.0, 0.5], [-2.0, 0.5, 9.0]])
    s_tau, s_ang = np.array([0.02, 0.03, 0.025]), 3e-4

    def mean(theta, z):  # the measurement model written out directly
        t0, s = theta[:3], theta[3:]
        S = np.array([[s[0], s[3], s[4]], [s[3], s[1], s[5]], [s[4], s[5], s[2]]])
        return np.concatenate([(np.eye(3) - 0.5 * so3.hat(zi)) @ t0 + S @ zi for zi in z] + [z.ravel()])

    theta = np.r_[tau0, sym_entries(K)]
    x0 = np.r_[theta, zeta.ravel()]
    h = 1e-6
    Jm = np.column_stack([(mean(*split(x0 + h * e)) - mean(*split(x0 - h * e))) / (2 * h)
                          for e in np.eye(len(x0))])
    w = np.r_[np.tile(1 / s_tau ** 2, n), np.full(3 * n, 1 / s_ang ** 2)]
    info = Jm.T @ (w[:, None] * Jm)
    brute = np.linalg.inv(info)[3:9, 3:9]
    ours = crlb(zeta, tau0, K, np.diag(s_tau ** 2), s_ang)
    assert np.allclose(ours, brute, rtol=1e-5)


def split(x):
    return x[:9], x[9:].reshape(-1, 3)


def test_noise_free_log_gives_the_true_stiffness(design):
    des, K_true = design
    log = run_protocol(RIG, des.protocol, np.random.default_rng(0), InstrumentNoise.none())
    e = identify_log(log, RIG, noise=InstrumentNoise((1e-6,) * 3, 1e-9), allow_ill_conditioned=True)[0]
    assert e.curvature == "model"
    assert np.allclose(sym_entries(e.K_ml), K_true, atol=1e-6)
    lin = identify_log(log, RIG, noise=InstrumentNoise((1e-6,) * 3, 1e-9), curvature="none",
                       allow_ill_conditioned=True)[0]
    assert np.max(np.abs(sym_entries(lin.K_ml) - K_true)) > 1e-3     # the curvature does matter


def test_small_monte_carlo_unbiased_at_the_bound(design):
    des, K_true = design
    rng = np.random.default_rng(7)
    errs, bounds, cover = [], [], []
    for _ in range(30):
        e = identify_log(run_protocol(RIG, des.protocol, rng, NOISE), RIG, noise=NOISE,
                         allow_ill_conditioned=True)[0]
        errs.append(sym_entries(e.K_ml) - K_true)
        bounds.append(np.diag(e.crlb6))
        cover.append(e.covers(_full(K_true), "K_ml"))
    errs, B = np.array(errs), np.array(bounds)
    z = errs / np.sqrt(B)
    assert np.all(np.abs(z.mean(0)) < 3.5 / np.sqrt(30) * np.maximum(z.std(0), 0.5))
    ratio = np.sum(errs.var(0)) / np.sum(B.mean(0))
    assert 0.6 < ratio < 1.5
    assert np.mean(cover) > 0.85


def _full(s):
    K = np.diag(s[:3])
    K[0, 1] = K[1, 0] = s[3]
    K[0, 2] = K[2, 0] = s[4]
    K[1, 2] = K[2, 1] = s[5]
    return K


def test_cli_reports_the_default_estimator(design, tmp_path, capsys):
    des, _ = design
    log = run_protocol(RIG, des.protocol, np.random.default_rng(2), NOISE)
    path = tmp_path / "log.csv"
    log.to_csv(path)
    assert main(["identify", str(path), "--json", str(tmp_path / "o.json"), "--no-progress",
                 "--allow-ill-conditioned"]) == 0
    c = json.loads((tmp_path / "o.json").read_text())["cycles"][0]
    assert c["estimator"] == "K_ml" and np.shape(c["K_ml_ci"]) == (2, 3, 3) and len(c["crlb_std"]) == 6
    lo, hi = np.array(c["K_ml_ci"])
    assert np.all(lo <= np.array(c["K_ml"])) and np.all(np.array(c["K_ml"]) <= hi)
    for key in ("K_D", "K", "K_sym", "condition", "K_ml_cov", "efficiency"):
        assert key in c
    assert main(["identify", str(path), "--tau-sigma", "0.02"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--angle-sigma" in err[0]


def test_dilution_correction_is_the_expected_noise_term():
    """The corrected normal equations subtract E[A(z)^T W A(z)] - A^T W A (and the rhs term), by sampling."""
    from csjm_opt.identification.cramer_rao import design_rows
    from csjm_opt.identification.ml_estimator import _dilution

    rng = np.random.default_rng(4)
    zeta = rng.normal(size=(3, 3)) * 0.05
    Vi = np.linalg.inv(np.diag([1.0, 2.0, 0.5]) + 0.1)[None].repeat(3, 0)
    G = rng.normal(size=(3, 3, 3))
    sigma, m = 0.01, 20000
    e = rng.normal(size=(m // 2, 3, 3)) * sigma
    e = np.concatenate([e, -e])                     # antithetic: the terms linear in e cancel exactly
    A0 = design_rows(zeta)
    Az = design_rows((zeta[None] + e).reshape(-1, 3)).reshape(m, 3, 3, 9)
    N = np.einsum("snia,nij,snjb->ab", Az, Vi, Az) / m - np.einsum("nia,nij,njb->ab", A0, Vi, A0)
    r = np.einsum("snia,nij,njk,snk->a", Az, Vi, G, e) / m
    dN, dr = _dilution(Vi, G, sigma)
    assert np.allclose(N, dN, atol=5e-2 * np.abs(dN).max())
    assert np.allclose(r, dr, atol=5e-2 * np.abs(dr).max())
