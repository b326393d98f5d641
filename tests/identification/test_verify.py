"""Verification (61)-(65) on simulator data: K_D is the right first-order predictor, K is not."""

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt._plotting import save
from csjm_opt.errors import InvalidInput
from csjm_opt.identification.figures import plot_verification
from csjm_opt.identification.identify_pose import identify_stiffness
from csjm_opt.identification.log_identification import identify_log
from csjm_opt.identification.verify import (
    estimation_error,
    predict_pose,
    predict_pose_external,
    verify_increments,
    verify_log,
)
from csjm_opt.testbed.scripted import load_directions, simulate_cycle, simulate_log

ROTVEC_REF = np.array([0.1, 0.05, -0.08])
TAU_PRE = np.array([0.4, -1.2, 0.5])     # a sizeable pre-load: K and K_D differ by 1/2 hat(tau_load)


def test_predict_pose_is_61_62():
    rng = np.random.default_rng(0)
    R0 = so3.exp(rng.normal(size=3) * 0.3)
    K = np.diag([30.0, 29.0, 7.0]) + 0.5
    dtau = rng.normal(size=(4, 3))
    R = predict_pose(R0, K, dtau)
    for i in range(4):
        z = np.linalg.solve(K, dtau[i])
        assert np.allclose(so3.log(R0.T @ R[i]), z, atol=1e-12)
    assert np.allclose(estimation_error(R, R), 0)
    # E_theta is the rotation angle of R_act^-1 R_est (63)-(65)
    ang = 0.123
    assert estimation_error(R0, R0 @ so3.exp([0, ang, 0])) == pytest.approx(ang)


def test_K_D_predicts_to_second_order_K_does_not(rig, model):
    rng = np.random.default_rng(1)
    train = load_directions(12, rng) * 0.01
    R, tau, l, ref = simulate_cycle(rig, ROTVEC_REF, TAU_PRE, train, model)
    e = identify_stiffness(R, tau, model, order=2)
    for scale in (0.01, 0.1):
        dtau = load_directions(8, rng)[6:] * scale
        Ra, ta, _, _ = simulate_cycle(rig, ROTVEC_REF, TAU_PRE, dtau, model)
        dload = ta[1:] + model.weight_moment(Ra[1:]) - (ta[0] + model.weight_moment(Ra[0]))
        v_KD = verify_increments(e.R_ref, e.K_D, dload, Ra[1:], use="K_D")
        v_K = verify_increments(e.R_ref, e.K, dload, Ra[1:], use="K")
        disp = np.linalg.norm(so3.log(Ra[0].T @ Ra[1:]), axis=1)
        assert np.all(v_KD.E_theta_rad < 0.05 * disp * (disp / 0.01 + 1e-3))  # O(disp^2)
        assert np.all(v_K.E_theta_rad > 10 * v_KD.E_theta_rad)
        assert np.all(v_K.E_theta_rad > 0.01 * disp)                        # O(disp)


def test_external_load_prediction_reevaluates_weight(rig, model):
    rng = np.random.default_rng(2)
    R, tau, l, ref = simulate_cycle(rig, ROTVEC_REF, TAU_PRE, load_directions(12, rng) * 0.01, model)
    e = identify_stiffness(R, tau, model, order=2)
    new = TAU_PRE + np.array([0.02, -0.01, 0.015])
    Ra, _, _, _ = simulate_cycle(rig, ROTVEC_REF, TAU_PRE, [new - TAU_PRE], model)
    R_est = predict_pose_external(e.R_ref, e.K_D, e.tau_load_ref_A_Nm, new, model)
    assert estimation_error(Ra[1], R_est) < 1e-6
    # ignoring the weight's change would be worse
    R_naive = predict_pose(e.R_ref, e.K_D, new - TAU_PRE)
    assert estimation_error(Ra[1], R_naive) > 5 * estimation_error(Ra[1], R_est)


def test_verify_log_on_held_out_rows(rig, model, tmp_path):
    rng = np.random.default_rng(3)
    log, _ = simulate_log(rig, [(ROTVEC_REF, TAU_PRE, load_directions(16, rng) * 0.05),
                                (-ROTVEC_REF, np.zeros(3), load_directions(16, rng) * 0.05)], model)
    train_rows = np.concatenate([log.cycle_rows(c)[::2] for c in log.cycle_ids])
    test_rows = np.setdiff1d(np.arange(len(log)), train_rows)
    ests = identify_log(log.subset(train_rows), rig, model=model)
    held = log.subset(test_rows)
    v = verify_log(ests, held, model)
    v_ext = verify_log(ests, held, model, load="external")
    v_K = verify_log(ests, held, model, use="K")
    assert v.rms_rad < 1e-4 and v_ext.rms_rad < 1e-4
    assert v_K.rms_rad > 3 * v.rms_rad
    assert "rms" in v.table() and len(v.as_dict()["cases"]) == len(held)
    ax = plot_verification([v, v_K])
    assert len(ax.patches) == 2 * len(held)                  # one bar per case and series
    assert save(ax.figure, tmp_path / "v.png").stat().st_size > 1000
    with pytest.raises(InvalidInput):
        verify_log(ests, held, model, use="K_L")
