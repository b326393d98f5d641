"""Preprocessing raw instrument CSV: rigid fit, pose (53)-(54), adjoint (55), weight (56)."""

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from csjm_opt import so3
from csjm_opt.cli import main
from csjm_opt.errors import DataFileError, IllConditionedData
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.measurement.preprocess import fit_rigid_transform, preprocess_text, weight_moment_A, wrench_to_A
from csjm_opt.testbed.raw_instruments import raw_text_from_log

R_LB = so3.exp(np.array([0.3, -1.2, 2.0]))
P_LB = np.array([2.5, -0.7, 0.4])
R_AS = so3.exp(np.array([0.0, 0.0, np.pi / 3]))
P_AS = np.array([0.0, 0.0, 0.12])
BASE_B = np.array([[0.2, 0.0, 0.0], [-0.1, 0.17, 0.0], [-0.1, -0.17, 0.0], [0.0, 0.0, -0.15], [0.15, 0.15, -0.05]])
PLAT_A = np.array([[0.05, 0.0, 0.1], [-0.03, 0.04, 0.1], [-0.03, -0.04, 0.1], [0.0, 0.0, 0.16]])


@pytest.fixture(scope="module")
def truth():
    rng = np.random.default_rng(0)
    n = 12
    R = so3.exp(rng.normal(size=(n, 3)) * 0.2)
    tau = rng.normal(size=(n, 3))
    l = 0.15 + 0.01 * rng.random((n, 6))
    return MeasurementLog.from_arrays(np.repeat([3, 4], n // 2), l, tau, R, sample=np.arange(10, 10 + n))


def test_rigid_fit_recovers_transform_least_squares():
    rng = np.random.default_rng(1)
    P = rng.normal(size=(8, 3))
    Q = P @ R_LB.T + P_LB
    R, p, rms = fit_rigid_transform(P, Q)
    np.testing.assert_allclose(R, R_LB, atol=1e-12)
    np.testing.assert_allclose(p, P_LB, atol=1e-12)
    assert rms < 1e-12
    # with noise, the fit minimises the residual: a perturbed transform is never better
    Qn = Q + rng.normal(size=Q.shape) * 1e-3
    R, p, rms = fit_rigid_transform(P, Qn)
    for _ in range(20):
        dR = so3.exp(rng.normal(size=3) * 1e-3)
        r2 = np.sqrt(np.mean(np.sum((P @ (dR @ R).T + p - Qn) ** 2, axis=1)))
        assert r2 >= rms
    with pytest.raises(IllConditionedData):
        fit_rigid_transform(P[:2], Q[:2])
    with pytest.raises(IllConditionedData):
        fit_rigid_transform(np.outer(np.arange(4.0), [1, 2, 3]), np.outer(np.arange(4.0), [1, 2, 3]))


def test_wrench_transform_is_adjoint_transpose():
    """(55): W_A = Ad_{T_SA}^T W_S with W = (f, tau), T_SA = T_AS^-1, Ad = [[R, hat(p) R], [0, R]]."""
    rng = np.random.default_rng(2)
    f_S, tau_S = rng.normal(size=3), rng.normal(size=3)
    R_SA, p_SA = R_AS.T, -R_AS.T @ P_AS
    Ad = np.block([[R_SA, so3.hat(p_SA) @ R_SA], [np.zeros((3, 3)), R_SA]])
    W_A = Ad.T @ np.r_[f_S, tau_S]
    f_A, tau_A = wrench_to_A(f_S, tau_S, R_AS, P_AS)
    np.testing.assert_allclose(np.r_[f_A, tau_A], W_A, atol=1e-14)


def test_weight_moment_matches_model(rig, model):
    R = so3.exp(np.random.default_rng(3).normal(size=(5, 3)) * 0.4)
    np.testing.assert_allclose(weight_moment_A(rig, R), model.weight_moment(R), atol=1e-13)


def test_round_trip_exact(rig, truth):
    text = raw_text_from_log(truth, rig, R_LB, P_LB, R_AS, P_AS, BASE_B, np.random.default_rng(4),
                             force_A_N=np.random.default_rng(5).normal(size=(len(truth), 3)) * 10)
    log, info = preprocess_text(text, rig)
    np.testing.assert_array_equal(log.sample, truth.sample)
    np.testing.assert_array_equal(log.cycle, truth.cycle)
    np.testing.assert_allclose(log.R, truth.R, atol=1e-12)
    np.testing.assert_allclose(log.tau_ext_A_Nm, truth.tau_ext_A_Nm, atol=1e-12)
    np.testing.assert_allclose(log.rest_lengths_m, truth.rest_lengths_m)
    assert info["base_fit_rms_m"] < 1e-12 and info["max_origin_offset_m"] < 1e-12


def test_round_trip_with_noise_and_platform_points_and_weight(rig, truth):
    sigma = 16.5e-6  # Table 1 at 3 m, as a standard deviation
    text = raw_text_from_log(truth, rig, R_LB, P_LB, R_AS, P_AS, BASE_B, np.random.default_rng(6),
                             point_sigma_m=sigma, tau_sigma_Nm=0.03, platform_points_A=PLAT_A,
                             ft_includes_weight=True)
    log, info = preprocess_text(text, rig, ft_includes_weight=True)
    err = so3.angle_between(log.R, truth.R)
    assert np.max(err) < 20 * sigma / 0.1            # orientation noise ~ sigma / lever arm
    assert np.max(np.abs(log.tau_ext_A_Nm - truth.tau_ext_A_Nm)) < 0.15
    assert 0.3 * sigma < info["base_fit_rms_m"] < 3 * sigma
    w = np.array([[float(log.extra[f"tauw_{a}"][i]) for a in "xyz"] for i in range(len(log))])
    np.testing.assert_allclose(w, weight_moment_A(rig, log.R), atol=1e-12)


def test_origin_mismatch_names_line(rig, truth):
    text = raw_text_from_log(truth, rig, R_LB, P_LB + np.array([0.0, 0.0, 0.01]), R_AS, P_AS, BASE_B,
                             np.random.default_rng(7))
    # base points were written with the shifted p_LB too; shift the base points back by editing one pose row
    lines = text.splitlines()
    i = next(k for k, s in enumerate(lines) if s.startswith("sample,"))
    cells = lines[i].split(",")
    cells[4] = repr(float(cells[4]) + 0.005)   # x of the platform origin in {L}
    lines[i] = ",".join(cells)
    with pytest.raises(DataFileError) as info:
        preprocess_text("\n".join(lines), rig, source="raw.csv")
    assert f"raw.csv:{i + 1}" in str(info.value) and "mm from the origin" in str(info.value)


@pytest.mark.parametrize("edit, message", [
    (lambda L: L[:1] + ["bogus" + L[1][L[1].index(","):]] + L[2:], "unknown record"),
    (lambda L: L[:1] + [L[1].replace("H1", "H1", 1).rsplit(",", 1)[0] + ",7"] + L[2:], "has no 'l6'"),
    (lambda L: [L[0]] + L[4:], "at least 3 base_point"),
    (lambda L: L + [L[-1]], "duplicate sample id"),
])
def test_malformed_raw_rows(rig, truth, edit, message):
    text = raw_text_from_log(truth, rig, R_LB, P_LB, R_AS, P_AS, BASE_B[:3], np.random.default_rng(8))
    with pytest.raises(DataFileError, match=message):
        preprocess_text("\n".join(edit(text.splitlines())), rig)


def test_cli_preprocess(rig, truth, tmp_path, capsys):
    raw = tmp_path / "raw.csv"
    raw.write_text(raw_text_from_log(truth, rig, R_LB, P_LB, R_AS, P_AS, BASE_B, np.random.default_rng(9)))
    out = tmp_path / "log.csv"
    assert main(["preprocess", str(raw), "-o", str(out), "--json", str(tmp_path / "s.json")]) == 0
    log = MeasurementLog.from_csv(out)
    np.testing.assert_allclose(log.tau_ext_A_Nm, truth.tau_ext_A_Nm, atol=1e-12)
    assert json.loads((tmp_path / "s.json").read_text())["rows"] == len(truth)
    before = out.read_text()
    capsys.readouterr()
    assert main(["preprocess", str(raw), "-o", str(out)]) == 2          # exists, no --force
    assert "refusing" in capsys.readouterr().err
    assert main(["preprocess", str(raw), "-o", str(out), "--force"]) == 0
    assert out.read_text() == before
    assert main(["preprocess", str(raw), "-o", str(raw)]) == 2          # never the input
    assert "input" in capsys.readouterr().err
    assert main(["preprocess", str(tmp_path / "none.csv"), "-o", str(tmp_path / "x.csv")]) == 2


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=3, max_size=3), st.lists(st.floats(-5, 5), min_size=3, max_size=3),
       st.integers(3, 9), st.integers(0, 2**31 - 1))
def test_rigid_fit_law(rotvec, shift, n_points, seed):
    """Law: the fit of exactly transformed points returns the transform (any rotation, any shift)."""
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(n_points, 3))
    R_true = so3.exp(np.array(rotvec))
    R, p, rms = fit_rigid_transform(P, P @ R_true.T + np.array(shift))
    assert np.allclose(R, R_true, atol=1e-9) and np.allclose(p, shift, atol=1e-9) and rms < 1e-9


@pytest.mark.parametrize("rig_file", ["eight_cable.toml", "four_cable.toml"])
def test_round_trip_on_an_m_cable_rig(rig_file, tmp_path, capsys):
    """The raw file of an m-cable rig carries l1..lm and preprocesses back to its log; a 6-cable raw file is refused."""
    from pathlib import Path

    from csjm_opt.model.rig import Rig

    rig = Rig.from_toml(Path(__file__).resolve().parents[2] / "rigs" / rig_file)
    m = rig.n_cables
    rng = np.random.default_rng(8)
    n = 8
    R = so3.exp(rng.normal(size=(n, 3)) * 0.2)
    l = 0.15 + 0.01 * rng.random((n, m))
    truth = MeasurementLog.from_arrays(np.repeat([0, 1], n // 2), l, rng.normal(size=(n, 3)), R)
    text = raw_text_from_log(truth, rig, R_LB, P_LB, R_AS, P_AS, BASE_B, np.random.default_rng(4))
    header = text.splitlines()[0].split(",")
    assert [h for h in header if h.startswith("l")] == [f"l{i}" for i in range(1, m + 1)]
    log, _ = preprocess_text(text, rig)
    np.testing.assert_array_equal(log.rest_lengths_m, truth.rest_lengths_m)
    np.testing.assert_allclose(log.R, truth.R, atol=1e-12)
    # the same raw file against a rig of another cable count: one line naming the file, line 1 and a column
    six = raw_text_from_log(MeasurementLog.from_arrays(truth.cycle, l[:, :6] if m >= 6 else np.c_[l, l][:, :6],
                                                       truth.tau_ext_A_Nm, R), rig, R_LB, P_LB, R_AS, P_AS, BASE_B,
                            np.random.default_rng(4))
    with pytest.raises(DataFileError, match=r"raw\.csv:1.*rest-length columns.*l1\.\.l" + str(m)) as exc:
        preprocess_text(six, rig, "raw.csv")
    assert exc.value.column == ("l5" if m == 4 else "l7")      # the first column too many, or the first missing
    raw = tmp_path / "raw.csv"
    raw.write_text(six)
    rig_path = Path(__file__).resolve().parents[2] / "rigs" / rig_file
    capsys.readouterr()
    assert main(["preprocess", str(raw), "--rig", str(rig_path), "-o", str(tmp_path / "log.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "raw.csv" in err[0] and f"l1..l{m}" in err[0]
