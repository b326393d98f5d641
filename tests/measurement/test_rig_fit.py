"""A log is checked against its rig: the equilibrium of its first rows with the rig's cables."""

from pathlib import Path

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.errors import InvalidInput, LogRigMismatch
from csjm_opt.measurement import MeasurementLog
from csjm_opt.measurement.rig_fit import check_log_rig, log_rig_fit
from csjm_opt.model.rig import Rig, paper_rig
from csjm_opt.model.statics import rest_lengths_for, solve_equilibrium

DATA = Path(__file__).resolve().parents[1] / "data"


def _statics_log(rig_true: Rig, n_cycles: int = 3) -> MeasurementLog:
    """A log made by forward statics on ``rig_true`` (the law, not the check): loads stepped up and down."""
    rng = np.random.default_rng(4)
    cycles, lengths, taus, poses = [], [], [], []
    for c in range(n_cycles):
        R_ref = so3.exp(rng.normal(0.0, 0.1, 3))
        l = rest_lengths_for(rig_true, R_ref, np.full(6, 40.0))
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        R = R_ref
        for s in (0.0, 0.4, 0.8, 1.2, 0.8, 0.4, 0.0):
            tau = s * direction
            R = solve_equilibrium(rig_true, l, tau, R_init=R).R
            cycles.append(c), lengths.append(l), taus.append(tau), poses.append(R)
    return MeasurementLog.from_arrays(np.array(cycles), np.array(lengths), np.array(taus), np.array(poses))


def test_a_log_made_by_the_rig_balances_exactly():
    fit = log_rig_fit(paper_rig(), _statics_log(paper_rig()))
    assert fit.ok and fit.residual_N.max() < 1e-6
    assert fit.stiffness_factor == pytest.approx(1.0, abs=1e-6)


def test_a_stiffness_factor_is_left_to_the_diagnosis():
    # the rig file says 4600 N/m, the cables are 20 % softer: the factor is fitted, the log passes
    log = _statics_log(paper_rig(0.8 * 4600.0))
    fit = check_log_rig(paper_rig(), log)
    assert fit.stiffness_factor == pytest.approx(0.8, rel=1e-6)
    assert fit.residual_N.max() < 1e-6


def _moved(rig: Rig, mm: float, seed: int) -> Rig:
    """Every hole moved by ``mm`` in a random direction (like the validation rigs b1, b2)."""
    d = np.random.default_rng(seed).normal(size=(2, 6, 3))
    d *= mm * 1e-3 / np.linalg.norm(d, axis=2, keepdims=True)
    return rig.replace(platform_holes_A_m=rig.platform_holes_A_m + d[0], base_holes_B_m=rig.base_holes_B_m + d[1])


def test_a_log_from_a_rig_with_holes_15_mm_elsewhere_is_refused():
    for seed in range(3):
        with pytest.raises(LogRigMismatch, match="--rig"):
            check_log_rig(paper_rig(), _statics_log(_moved(paper_rig(), 15.0, seed)))


def test_hole_offsets_of_a_millimetre_are_an_effect_not_another_rig():
    for seed in range(3):
        fit = check_log_rig(paper_rig(), _statics_log(_moved(paper_rig(), 1.0, seed)))
        assert fit.median_N < 0.5 * fit.tolerance_N


@pytest.mark.parametrize("log_name, rig_name", [("b1_none_first33.csv", "rig_b1.toml"),
                                                ("b2_tendon_friction_first33.csv", "rig_b2.toml")])
def test_validation_logs_pass_with_their_rig_and_fail_with_the_paper_rig(log_name, rig_name):
    log = MeasurementLog.from_csv(DATA / log_name)
    fit = check_log_rig(Rig.from_toml(DATA / rig_name), log)
    assert fit.median_N < 0.5 * fit.tolerance_N
    with pytest.raises(LogRigMismatch) as err:
        check_log_rig(paper_rig(), log)
    assert isinstance(err.value, InvalidInput) and err.value.source == str(DATA / log_name)
    assert err.value.residual_N > err.value.tolerance_N
    assert "\n" not in str(err.value) and log_name in str(err.value)


def test_identify_and_diagnose_refuse_a_log_of_another_rig_unless_told():
    from csjm_opt.diagnose import diagnose
    from csjm_opt.identification.log_identification import identify_log

    log = MeasurementLog.from_csv(DATA / "b1_none_first33.csv")
    with pytest.raises(LogRigMismatch):
        identify_log(log, paper_rig())
    with pytest.raises(LogRigMismatch):
        diagnose(paper_rig(), log, secondary=False, effects=["sensor_bias"], workers=1)
    assert len(identify_log(log, Rig.from_toml(DATA / "rig_b1.toml"), allow_ill_conditioned=True)) == 3
    assert len(identify_log(log, paper_rig(), check_rig=False, allow_ill_conditioned=True)) == 3
