"""``csjm simulate``: protocols run on either plant, logs written atomically, bad protocols refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.cli import main
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.model.rig import paper_rig
from csjm_opt.model.statics import solve_equilibrium
from csjm_opt.testbed import design_cycles, random_rig, read_protocol, simulate_protocol

EXTRA = ",intended_tau_x,intended_tau_y,intended_tau_z,planned_rx,planned_ry,planned_rz"


def protocol_text(rig, seed=31, n_cycles=2, planned=True):
    """A protocol: designed cycles, measured columns empty, intended moments and planned poses."""
    rows = ["sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz" + (EXTRA if planned else
                                                                           EXTRA[:EXTRA.index(",planned")])]
    k = 0
    for c, d in enumerate(design_cycles(rig, n_cycles, np.random.default_rng(seed), steps=1)):
        for tau in d.tau_ext_A_Nm:
            eq = solve_equilibrium(rig, d.rest_lengths_m, tau, R_init=d.R_ref)
            cells = [str(k), str(c), *map(_num, d.rest_lengths_m), "", "", "", "", "", "", *map(_num, tau)]
            rows.append(",".join(cells + (list(map(_num, so3.log(eq.R))) if planned else [])))
            k += 1
    return "\n".join(rows) + "\n"


def _num(x) -> str:
    return repr(float(x))


@pytest.fixture(scope="module")
def proto(tmp_path_factory, rig):
    path = tmp_path_factory.mktemp("sim") / "protocol.csv"
    path.write_text(protocol_text(rig))
    return path


def test_protocol_on_both_plants_gives_the_toolkit_statics(proto, rig, tmp_path):
    """Without effects or noise both plants settle where the toolkit's statics say; extra columns are kept."""
    p = read_protocol(proto)
    for plant in ("quasi-static", "mujoco"):
        out, js = tmp_path / f"{plant}.csv", tmp_path / f"{plant}.json"
        assert main(["simulate", str(proto), "--plant", plant, "--noise", "none", "-o", str(out),
                     "--json", str(js)]) == 0
        log = MeasurementLog.from_csv(out)
        assert len(log) == len(p) == json.loads(js.read_text())["rows"]
        assert "planned_rx" in log.extra and "intended_tau_z" in log.extra
        np.testing.assert_allclose(log.tau_ext_A_Nm, p.tau_fixed_A_Nm, atol=1e-12)
        for i in range(len(p)):
            eq = solve_equilibrium(rig, p.rest_lengths_m[i], p.tau_fixed_A_Nm[i], R_init=p.planned_R[i])
            assert so3.angle_between(log.R[i], eq.R) < 1e-8


def test_effects_and_seed_are_reported_and_change_the_log(proto, tmp_path):
    a, b, c = (tmp_path / f"{x}.csv" for x in "abc")
    assert main(["simulate", str(proto), "--effect", "sensor_bias=2", "--noise", "none", "-o", str(a),
                 "--json", str(tmp_path / "a.json")]) == 0
    assert main(["simulate", str(proto), "--noise", "none", "-o", str(b)]) == 0
    truth = json.loads((tmp_path / "a.json").read_text())["truth"]
    bias = np.asarray(truth["sensor_bias_A_Nm"])
    assert np.linalg.norm(bias) == pytest.approx(2 * 0.12)
    la, lb = MeasurementLog.from_csv(a), MeasurementLog.from_csv(b)
    np.testing.assert_allclose(la.tau_ext_A_Nm - lb.tau_ext_A_Nm, np.tile(bias, (len(la), 1)), atol=1e-12)
    assert main(["simulate", str(proto), "-o", str(c), "--seed", "3"]) == 0           # paper noise
    assert np.abs(MeasurementLog.from_csv(c).rotvec_rad - lb.rotvec_rad).max() > 1e-5


def test_never_writes_over_the_input_and_bad_effects_are_one_line(proto, tmp_path, capsys):
    before = proto.read_text()
    assert main(["simulate", str(proto), "-o", str(proto)]) == 2
    assert proto.read_text() == before
    assert main(["simulate", str(proto), "--effect", "gremlins=1", "-o", str(tmp_path / "x.csv")]) == 2
    assert main(["simulate", str(proto), "--effect", "friction=-1", "-o", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and "gremlins" in err[1] and not (tmp_path / "x.csv").exists()


def test_protocol_of_another_rig_or_outside_the_limits_is_refused(proto, rig, tmp_path, capsys):
    other, _ = random_rig(np.random.default_rng(7))
    other_path = tmp_path / "other.toml"
    other.to_toml(other_path)
    assert main(["simulate", str(proto), "--rig", str(other_path), "-o", str(tmp_path / "x.csv")]) == 2
    assert "protocol.csv" in capsys.readouterr().err
    # rest lengths 30 mm shorter: the cables pull beyond t_max
    lines = proto.read_text().splitlines()
    cells = lines[3].split(",")
    cells[2:8] = [repr(float(v) - 0.03) for v in cells[2:8]]
    bad = tmp_path / "short.csv"
    bad.write_text("\n".join(lines[:3] + [",".join(cells)] + lines[4:]) + "\n")
    assert main(["simulate", str(bad), "-o", str(tmp_path / "x.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "short.csv:4" in err and "outside the rig's limits" in err
    # a half-filled measured group, an empty rest length
    cells = lines[2].split(",")
    cells[3] = ""
    bad.write_text("\n".join(lines[:2] + [",".join(cells)] + lines[3:]) + "\n")
    assert main(["simulate", str(bad), "-o", str(tmp_path / "x.csv")]) == 2
    assert "short.csv:3" in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists()


def test_dead_weight_rows_measure_the_weight_moment_at_the_reached_pose(rig):
    """A dead weight's moment follows the pose: the log's moment is (m p) x (R^T g) at the measured pose."""
    text = protocol_text(rig, planned=False)
    lines = text.splitlines()
    lines[0] += ",load_kg,load_x_A_m,load_y_A_m,load_z_A_m"
    lines[1:] = [ln + (",0.2,0.04,0.0,0.02" if i % 2 else ",0,0,0,0") for i, ln in enumerate(lines[1:])]
    log = simulate_protocol(rig, "\n".join(lines) + "\n", None, noise=InstrumentNoise.none())
    g = np.asarray(rig.gravity_B_m_per_s2)
    for i in range(1, len(log), 2):
        np.testing.assert_allclose(log.tau_ext_A_Nm[i], np.cross(0.2 * np.array([0.04, 0.0, 0.02]), log.R[i].T @ g),
                                   atol=1e-12)


def test_after_starts_the_protocol_where_the_earlier_experiment_settled(rig, proto, tmp_path):
    """With friction, running an earlier experiment first changes the protocol's poses; without, it does not."""
    from csjm_opt.testbed import make_plant, simulate_experiment

    earlier = simulate_experiment(rig, 2, np.random.default_rng(8), steps=2, noise=InstrumentNoise.none())
    clean = InstrumentNoise.none()
    for effect, differs in (("coulomb_friction", True), (None, False)):
        truth = make_plant(rig, effect, 4.0, np.random.default_rng(9))
        fresh = simulate_protocol(rig, proto, truth, noise=clean)
        cont = simulate_protocol(rig, proto, truth, noise=clean, after=earlier)
        gap = np.abs(fresh.rotvec_rad - cont.rotvec_rad).max()
        assert (gap > 1e-4) if differs else (gap < 1e-9)
    out = tmp_path / "after.csv"
    earlier.to_csv(tmp_path / "earlier.csv")
    assert main(["simulate", str(proto), "--after", str(tmp_path / "earlier.csv"), "-o", str(out)]) == 0


def test_plan_experiment_protocol_runs_on_both_plants_and_identifies(tmp_path):
    """``csjm plan-experiment`` -> ``csjm simulate`` (either plant) -> ``csjm identify``: one chain.

    The reference is the other plant: MuJoCo settles the pulley loads in its own engine, the
    quasi-static plant by the toolkit's statics; both must reach the same poses and moments.
    """
    import csjm_opt as co

    proto = tmp_path / "proto.csv"
    assert main(["plan-experiment", "--budget", "8", "-o", str(proto)]) == 0
    rig = co.paper_rig()
    logs = [simulate_protocol(rig, proto, plant=plant, noise=InstrumentNoise.none())
            for plant in ("quasi-static", "mujoco")]
    assert np.max(so3.angle_between(logs[0].R, logs[1].R)) < 1e-6
    assert np.allclose(logs[0].tau_ext_A_Nm, logs[1].tau_ext_A_Nm, atol=1e-6)
    # the measured moment of a pulley load is p x (R^T f) at the reached pose (written here from the file)
    table = np.genfromtxt(proto, delimiter=",", names=True)
    f_B = table["load_N"][:, None] * np.column_stack([table["dir_x"], table["dir_y"], table["dir_z"]])
    p_A = np.column_stack([table["point_x"], table["point_y"], table["point_z"]])
    expected = np.cross(p_A, np.einsum("nji,nj->ni", logs[1].R, f_B))
    assert np.allclose(logs[1].tau_ext_A_Nm, expected, atol=1e-9)
    log = tmp_path / "log.csv"
    assert main(["simulate", str(proto), "--plant", "mujoco", "-o", str(log)]) == 0
    assert main(["identify", str(log), "--json", str(tmp_path / "k.json")]) == 0
    K = np.array(json.loads((tmp_path / "k.json").read_text())["cycles"][0]["K_ml"])
    K_true = co.stiffness(rig, logs[0].R[0], co.solve_equilibrium(rig, logs[0].rest_lengths_m[0],
                                                                   R_init=logs[0].R[0]).tensions_N)
    assert np.linalg.norm(K - K_true) < 0.2 * np.linalg.norm(K_true)


# ---- the true parameters of every effect, the guide radius's name, progress (issue 30)
@pytest.fixture(scope="module")
def proto1(tmp_path_factory, rig):
    path = tmp_path_factory.mktemp("sim_truth") / "protocol.csv"
    path.write_text(protocol_text(rig, n_cycles=1))
    return path


def test_truth_reports_the_rig_effects_by_their_documented_laws(proto1, tmp_path, capsys):
    js = tmp_path / "s.json"
    assert main(["simulate", str(proto1), "-o", str(tmp_path / "log.csv"), "--json", str(js), "--no-progress",
                 "--effect", "stiffness_scale=2", "--effect", "mass_com", "--effect", "hole_offsets"]) == 0
    truth = json.loads(js.read_text())["truth"]
    nominal = paper_rig()
    # testbed.injection's laws: stiffness times exp(+-0.03 severity), mass times (1 + 0.2 severity)^(+-1),
    # COM moved 15 mm * severity, every hole coordinate ~ N(0, 1 mm)
    factor = np.array(truth["stiffness_scale"]["factor"])
    assert np.allclose(np.abs(np.log(factor)), 0.06)
    assert np.allclose(truth["stiffness_scale"]["cable_stiffness_N_per_m"], factor * nominal.cable_stiffness_N_per_m)
    assert min(abs(truth["mass_com"]["mass_ratio"] - 1.2), abs(truth["mass_com"]["mass_ratio"] - 1 / 1.2)) < 1e-12
    assert np.linalg.norm(truth["mass_com"]["com_shift_A_m"]) == pytest.approx(15e-3)
    dA, dB = np.array(truth["hole_offsets"]["dA_m"]), np.array(truth["hole_offsets"]["dB_m"])
    assert dA.shape == dB.shape == (6, 3) and 2e-4 < np.std(np.r_[dA, dB]) < 3e-3
    np.testing.assert_allclose(truth["hole_offsets"]["base_holes_B_m"], nominal.base_holes_B_m + dB, atol=1e-15)
    assert capsys.readouterr().err == ""                                   # --no-progress


def test_guide_radius_is_the_name_and_eyelet_radius_an_alias_that_warns(proto1, tmp_path, capsys):
    js = tmp_path / "s.json"
    assert main(["simulate", str(proto1), "-o", str(tmp_path / "a.csv"), "--json", str(js),
                 "--effect", "guide_radius=2"]) == 0
    assert json.loads(js.read_text())["truth"]["guide_radius_m"] == pytest.approx(6e-3)   # 3 mm * severity
    err = capsys.readouterr().err
    assert "simulate (quasi-static)" in err                                # progress, also when not a terminal
    assert main(["simulate", str(proto1), "-o", str(tmp_path / "b.csv"), "--json", str(js), "--no-progress",
                 "--effect", "eyelet_radius"]) == 0
    assert json.loads(js.read_text())["truth"]["guide_radius_m"] == pytest.approx(3e-3)
    assert "eyelet_radius is now called guide_radius" in capsys.readouterr().err
    from csjm_opt.testbed import make_plant

    with pytest.warns(DeprecationWarning, match="guide_radius"):
        plant = make_plant(paper_rig(), "eyelet_radius", 1.0, np.random.default_rng(0))
    assert plant.guide_radius_m == 3e-3


def test_step_loading_and_static_friction_on_the_mujoco_plant(proto, tmp_path, capsys):
    """``--loading step --static-friction-ratio``: a MuJoCo log, reported in the summary; refused elsewhere."""
    out, js = tmp_path / "step.csv", tmp_path / "step.json"
    assert main(["simulate", str(proto), "--plant", "mujoco", "--effect", "coulomb_friction=3", "--loading", "step",
                 "--static-friction-ratio", "1.5", "--noise", "none", "-o", str(out), "--json", str(js)]) == 0
    summary = json.loads(js.read_text())
    assert summary["loading"] == "step" and summary["static_friction_ratio"] == 1.5
    assert len(MeasurementLog.from_csv(out)) == len(read_protocol(proto))
    capsys.readouterr()
    bad = tmp_path / "bad.csv"
    assert main(["simulate", str(proto), "--plant", "mujoco", "--static-friction-ratio", "0.5", "-o", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "static_friction_ratio" in err[0]
    assert not bad.exists()


def test_step_loading_and_static_friction_on_the_quasi_static_plant(proto, tmp_path, capsys):
    """The same options on the quasi-static plant: a log whose rows differ from the ramped one's; bad ratios refused."""
    logs = {}
    for loading, ratio in (("ramp", "1"), ("step", "1.5")):
        out, js = tmp_path / f"{loading}.csv", tmp_path / f"{loading}.json"
        assert main(["simulate", str(proto), "--effect", "coulomb_friction=3", "--loading", loading,
                     "--static-friction-ratio", ratio, "--noise", "none", "--no-progress", "-o", str(out),
                     "--json", str(js)]) == 0
        summary = json.loads(js.read_text())
        assert summary["plant"] == "quasi-static" and summary["loading"] == loading
        assert summary["static_friction_ratio"] == float(ratio)
        logs[loading] = MeasurementLog.from_csv(out)
    assert len(logs["step"]) == len(read_protocol(proto))
    gap = max(so3.angle_between(a, b) for a, b in zip(logs["ramp"].R, logs["step"].R))
    assert gap > 1e-4                     # the path matters with friction
    capsys.readouterr()
    bad = tmp_path / "bad.csv"
    for extra in (["--loading", "step", "--static-friction-ratio", "0.5"],
                  ["--loading", "step", "--static-friction-ratio", "nan"],
                  ["--loading", "step", "--static-friction-ratio", "inf"],
                  ["--static-friction-ratio", "1.5"]):                 # a ratio on ramped loads
        assert main(["simulate", str(proto), "--effect", "coulomb_friction", *extra, "-o", str(bad)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "static_friction_ratio" in err[0], err
    assert not bad.exists()
