"""Stiffness identification on data from the project's own simulator (csjm_opt.testbed.scripted)."""

import json

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt._plotting import save
from csjm_opt.cli import main
from csjm_opt.errors import IllConditionedData
from csjm_opt.identification.figures import convergence_curve, plot_convergence
from csjm_opt.identification.identify_pose import identify_stiffness
from csjm_opt.identification.log_identification import identify_log
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed.scripted import add_noise, load_directions, simulate_cycle, simulate_log

ROTVEC_REF = np.array([0.12, -0.06, 0.03])
TAU_PRE = np.array([0.2, -0.5, 0.3])


@pytest.fixture(scope="module")
def small_cycle(rig, model):
    """Load increments of 0.01 N m (displacements ~ 5e-4 rad), noise-free."""
    inc = load_directions(18, np.random.default_rng(1)) * 0.01
    return simulate_cycle(rig, ROTVEC_REF, TAU_PRE, inc, model)


@pytest.fixture(scope="module")
def big_log(rig, model):
    """One cycle with 1 N m increments (displacements ~ 0.05 rad), noise-free, as a log."""
    inc = load_directions(30, np.random.default_rng(2)) * 1.0
    log, refs = simulate_log(rig, [(ROTVEC_REF, TAU_PRE, inc)], model)
    return log, refs[0]


def rel(A, B):
    return np.max(np.abs(A - B)) / np.max(np.abs(B))


def test_true_K_is_model_stiffness_at_reference(small_cycle, model):
    R, tau, l, ref = small_cycle
    K_true = model.stiffness(ref.R, ref.tensions_N)
    np.testing.assert_allclose(ref.K, K_true, rtol=1e-12, atol=1e-12)
    assert np.allclose(K_true, K_true.T) and np.all(np.linalg.eigvalsh(K_true) > 0)


def test_noise_free_recovery_1e_6(small_cycle, model):
    R, tau, l, ref = small_cycle
    e = identify_stiffness(R, tau, model, order=2)
    assert rel(e.K, ref.K) < 1e-6
    assert rel(e.K_sym, ref.K) < 1e-6
    assert e.symmetry_error < 1e-6
    # the paper's (49)-(50), first order: finite-displacement error O(dzeta)
    assert rel(e.K_paper, ref.K) < 1e-3


def test_load_and_cable_views_agree(small_cycle, model):
    """Erratum 2: identified K_D = dtau_load/dzeta = -d(J^T T)/dzeta at fixed rest lengths."""
    R, tau, l, ref = small_cycle
    e = identify_stiffness(R, tau, model, order=2)
    h, D = 1e-6, np.zeros((3, 3))
    for j in range(3):
        Rp, Rm = ref.R @ so3.exp(h * np.eye(3)[j]), ref.R @ so3.exp(-h * np.eye(3)[j])
        tp = model.cable_moment(Rp, model.tensions_from_rest(Rp, l))
        tm = model.cable_moment(Rm, model.tensions_from_rest(Rm, l))
        D[:, j] = -(tp - tm) / (2 * h)
    assert rel(e.K_D, D) < 1e-6
    np.testing.assert_allclose(e.K_D - e.K_D.T, so3.hat(ref.tau_load_A_Nm), atol=1e-5)


def test_one_sided_loads_first_order_bias_removed_by_order_2(rig, model):
    """One-sided load increments (no +- pairs): the linear fit has an O(dzeta) bias."""
    inc = np.abs(load_directions(20, np.random.default_rng(6))) * 1.0
    log, refs = simulate_log(rig, [(ROTVEC_REF, TAU_PRE, inc)], model)
    e1 = identify_stiffness(log.R, log.tau_ext_A_Nm, model, order=1)
    e2 = identify_stiffness(log.R, log.tau_ext_A_Nm, model, order=2)
    assert rel(e2.K, refs[0].K) < 0.2 * rel(e1.K, refs[0].K)


def _coverage(log, ref, model, seeds, **kw):
    noise = InstrumentNoise.paper()
    hits = {"K": [], "K_sym": []}
    for s in range(seeds):
        noisy = add_noise(log, noise, np.random.default_rng(100 + s))
        e = identify_stiffness(noisy.R, noisy.tau_ext_A_Nm, model, order=2, **kw)
        hits["K"].append(e.covers(ref.K).mean())
        hits["K_sym"].append(e.covers(ref.K, "K_sym").mean())
    return {k: float(np.mean(v)) for k, v in hits.items()}


def test_ci_coverage_near_nominal_residual_based(big_log, model):
    log, ref = big_log
    cov = _coverage(log, ref, model, 120)
    assert 0.92 <= cov["K"] <= 0.98, cov
    assert 0.92 <= cov["K_sym"] <= 0.98, cov


def test_ci_coverage_near_nominal_instrument_model(big_log, model):
    log, ref = big_log
    cov = _coverage(log, ref, model, 120, noise=InstrumentNoise.paper())
    assert 0.92 <= cov["K"] <= 0.98, cov
    assert 0.92 <= cov["K_sym"] <= 0.98, cov


def test_chi2_consistent_with_instrument_noise(big_log, model):
    log, _ = big_log
    noise = InstrumentNoise.paper()
    chi = [identify_stiffness(*(lambda n: (n.R, n.tau_ext_A_Nm))(add_noise(log, noise, np.random.default_rng(s))),
                              model, order=2, noise=noise).chi2_per_dof for s in range(20)]
    assert 0.8 < np.mean(chi) < 1.2


def test_symmetric_estimate_is_tighter(big_log, model):
    log, _ = big_log
    noisy = add_noise(log, InstrumentNoise.paper(), np.random.default_rng(7))
    e = identify_stiffness(noisy.R, noisy.tau_ext_A_Nm, model)
    assert np.allclose(e.K_sym, e.K_sym.T)
    assert np.all(e.K_sym_std <= e.K_std * 1.05)


def test_two_directions_is_ill_conditioned(rig, model):
    d = np.array([[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [1, 1, 0], [1, -1, 0]]) * 0.01
    R, tau, _, _ = simulate_cycle(rig, ROTVEC_REF, TAU_PRE, d, model)
    with pytest.raises(IllConditionedData) as info:
        identify_stiffness(R, tau, model)
    assert info.value.condition > 1e3
    # with the paper's noise, planar loads of realistic size are flagged against the noise floor
    noise = InstrumentNoise.paper()
    R, tau, _, _ = simulate_cycle(rig, ROTVEC_REF, TAU_PRE, d * 100, model)
    Rn = R @ so3.exp(np.random.default_rng(0).normal(size=(len(R), 3)) * noise.angle_sigma_rad)
    with pytest.raises(IllConditionedData):
        identify_stiffness(Rn, tau, model, noise=noise, max_condition=np.inf)


def test_too_few_rows(small_cycle, model):
    R, tau, _, _ = small_cycle
    with pytest.raises(IllConditionedData):
        identify_stiffness(R[:4], tau[:4], model)
    with pytest.raises(IllConditionedData):
        identify_stiffness(R[:9], tau[:9], model, order=2)


def test_convergence_curve_converges(big_log, model, tmp_path):
    log, ref = big_log
    noisy = add_noise(log, InstrumentNoise.paper(), np.random.default_rng(3))
    curve = convergence_curve(noisy.R, noisy.tau_ext_A_Nm, model)
    det_true = np.linalg.det(ref.K)
    assert abs(curve.det_K[-1] - det_true) < 3 * curve.det_K_std[-1] + 0.05 * det_true
    assert curve.det_K_std[-1] < curve.det_K_std[np.isfinite(curve.det_K_std)][0]
    ax = plot_convergence(curve)
    np.testing.assert_array_equal(ax.get_lines()[0].get_xdata(), curve.n)
    assert save(ax.figure, tmp_path / "fig5.png").stat().st_size > 1000


def test_bootstrap_interval_contains_estimate(big_log, model):
    log, _ = big_log
    noisy = add_noise(log, InstrumentNoise.paper(), np.random.default_rng(4))
    e = identify_stiffness(noisy.R, noisy.tau_ext_A_Nm, model, bootstrap=100)
    lo, hi = e.bootstrap_K_ci
    assert np.all(lo <= e.K) and np.all(e.K <= hi)
    json.dumps(e.as_dict())


def test_identify_log_and_cli(rig, model, tmp_path, capsys):
    rng = np.random.default_rng(5)
    cycles = [(ROTVEC_REF, TAU_PRE, load_directions(12, rng) * 0.5),
              (np.array([-0.05, 0.1, 0.0]), np.zeros(3), load_directions(12, rng) * 0.5)]
    log, refs = simulate_log(rig, cycles, model)
    ests = identify_log(log, rig, model=model)
    assert [e.cycle for e in ests] == [0, 1]
    for e, ref in zip(ests, refs):
        assert rel(e.K, ref.K) < 0.02
    path = tmp_path / "log.csv"
    log.to_csv(path)
    out = tmp_path / "id.json"
    assert main(["identify", str(path), "--json", str(out), "--figures", str(tmp_path / "figs"),
                 "--order", "2", "--fit-parameters", "shared"]) == 0
    data = json.loads(out.read_text())
    assert data["parameters"]["parameters"]["k"]["value"] == pytest.approx(rig.cable_stiffness_N_per_m[0], rel=1e-6)
    assert [c["cycle"] for c in data["cycles"]] == [0, 1]
    assert all({"K_D", "K", "K_sym", "condition", "K_ci"} <= set(c) for c in data["cycles"])
    assert len(list((tmp_path / "figs").glob("*.png"))) == 2
    capsys.readouterr()
    assert main(["identify", str(path), "--cycle", "7"]) == 2
    assert "no cycle 7" in capsys.readouterr().err
    assert main(["identify", str(tmp_path / "missing.csv")]) == 2
    capsys.readouterr()
    assert main(["identify", str(path), "--json", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "refusing" in err


def test_order_3_removes_finite_displacement_bias_at_paper_sized_loads(rig, model):
    """Loads up to 3 N m (dzeta ~ 0.2 rad) with varied magnitudes, as in the paper's 85 rows."""
    rng = np.random.default_rng(8)
    inc = load_directions(85, rng) * 3.0 * rng.uniform(0.1, 1.0, size=(85, 1))
    log, refs = simulate_log(rig, [(ROTVEC_REF, TAU_PRE, inc)], model)
    errs = [rel(identify_stiffness(log.R, log.tau_ext_A_Nm, model, order=o).K, refs[0].K) for o in (1, 2, 3)]
    assert errs[2] < 0.1 * errs[0]
    noise = InstrumentNoise.paper()
    hits = [identify_stiffness(*(lambda n: (n.R, n.tau_ext_A_Nm))(add_noise(log, noise, np.random.default_rng(s))),
                               model, order=3).covers(refs[0].K).mean() for s in range(60)]
    assert 0.9 <= np.mean(hits) <= 0.99


def test_problems_flag_asymmetry(big_log, model):
    log, _ = big_log
    noisy = add_noise(log, InstrumentNoise.paper(), np.random.default_rng(9))
    e = identify_stiffness(noisy.R, noisy.tau_ext_A_Nm, model, noise=InstrumentNoise.paper())
    assert e.problems() == []
    # an unmodelled non-conservative moment (e.g. friction-like), antisymmetric in dzeta
    dz = so3.log(noisy.R[0].T @ noisy.R)
    tau = noisy.tau_ext_A_Nm + dz @ (3.0 * so3.hat([0.0, 0.0, 1.0])).T
    bad = identify_stiffness(noisy.R, tau, model, noise=InstrumentNoise.paper())
    assert any("asymmetric" in p for p in bad.problems())


def test_identify_cli_skips_cycles_that_cannot_determine_K(tmp_path, capsys):
    """A diagnosis-style cycle (one load direction) is reported as skipped, the others identified."""
    import csjm_opt as co
    from csjm_opt import cli
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.testbed import simulate_experiment
    from csjm_opt.testbed.identification import simulate_identification_experiment

    rig = co.paper_rig()
    rng = np.random.default_rng(5)
    good = simulate_identification_experiment(rig, 1, rng, loads_per_cycle=12)
    one_direction = simulate_experiment(rig, 1, rng, first_cycle=7)
    mixed = MeasurementLog.from_arrays(
        np.r_[good.cycle, one_direction.cycle], np.vstack([good.rest_lengths_m, one_direction.rest_lengths_m]),
        np.vstack([good.tau_ext_A_Nm, one_direction.tau_ext_A_Nm]),
        np.vstack([good.rotvec_rad, one_direction.rotvec_rad]))
    path = tmp_path / "mixed.csv"
    mixed.to_csv(path)
    capsys.readouterr()
    assert cli.main(["identify", str(path), "--json", str(tmp_path / "out.json"), "--no-progress"]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(warned) == 1 and "1 of 2 cycles skipped" in warned[0] and "7" in warned[0]
    out = json.loads((tmp_path / "out.json").read_text())
    assert [c["cycle"] for c in out["cycles"]] == [0]
    assert [s["cycle"] for s in out["skipped"]] == [7]
    assert "three directions" in out["skipped"][0]["reason"]
    capsys.readouterr()
    assert cli.main(["identify", str(path), "--cycle", "7"]) == 2
    assert "cycle 7" in capsys.readouterr().err
