"""The whole chain on the shipped 8-cable and 4-cable rigs, small sizes, through the command line.

plan-experiment -> simulate (quasi-static and MuJoCo plants) -> identify -> diagnose -> codegen ->
export-mjcf -> sweep. The two plants are independent simulators of the same statics (a
quasi-static equilibrium solver and a damped MuJoCo model that settles); they must agree on every
row, and the exported MJCF must settle at the planned pose.
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import cli
from csjm_opt.planning import export_mjcf

RIGS = Path(__file__).resolve().parents[1] / "rigs"


@pytest.fixture(scope="module", params=["eight_cable.toml", "four_cable.toml"])
def chain(request, tmp_path_factory):
    """Runs plan-experiment and both simulations once per rig; the tests read the files."""
    d = tmp_path_factory.mktemp(request.param.split(".")[0])
    rig = str(RIGS / request.param)
    assert cli.main(["plan-experiment", "--rig", rig, "--budget", "20", "--poses", "0,0,0", "0.05,0,0",
                     "-o", str(d / "protocol.csv")]) == 0
    for plant in ("quasi-static", "mujoco"):
        assert cli.main(["simulate", str(d / "protocol.csv"), "--rig", rig, "--plant", plant, "--noise", "none",
                         "-o", str(d / f"{plant}.csv")]) == 0
    return rig, d


def test_protocol_and_logs_have_m_rest_lengths(chain):
    rig_path, d = chain
    m = co.Rig.from_toml(rig_path).n_cables
    for name in ("protocol.csv", "quasi-static.csv", "mujoco.csv"):
        header = (d / name).read_text().splitlines()[0].split(",")
        assert header[2:2 + m] == [f"l{i}" for i in range(1, m + 1)] and header[2 + m] == "tau_x"


def test_the_two_plants_agree_on_the_statics(chain):
    rig_path, d = chain
    qs = co.MeasurementLog.from_csv(d / "quasi-static.csv")
    mj = co.MeasurementLog.from_csv(d / "mujoco.csv")
    assert np.array_equal(qs.rest_lengths_m, mj.rest_lengths_m)
    assert np.max(co.so3.angle_between(qs.R, mj.R)) < 1e-8
    assert np.max(np.abs(qs.tau_ext_A_Nm - mj.tau_ext_A_Nm)) < 1e-8


def test_identify_recovers_the_model_stiffness(chain, capsys):
    """Noise-free logs: K_ml equals the model's K at the reference pose (settled on the rig model)."""
    rig_path, d = chain
    rig = co.Rig.from_toml(rig_path)
    capsys.readouterr()
    assert cli.main(["identify", str(d / "quasi-static.csv"), "--rig", rig_path, "--json", "-"]) == 0
    cycles = json.loads(capsys.readouterr().out)["cycles"]
    log = co.MeasurementLog.from_csv(d / "quasi-static.csv")
    for c in cycles:
        first = int(np.flatnonzero(log.cycle == c["cycle"])[0])
        K_model = co.stiffness(rig, log.R[first], rest_lengths_m=log.rest_lengths_m[first])
        K = np.asarray(c[c["estimator"]])
        assert np.linalg.norm(K - K_model) < 0.05 * np.linalg.norm(K_model)


def test_diagnose_runs(chain, capsys):
    rig_path, d = chain
    assert cli.main(["diagnose", str(d / "quasi-static.csv"), "--rig", rig_path, "--json", str(d / "diag.json"),
                     "--no-progress"]) == 0


@pytest.mark.parametrize("rig_file", ["eight_cable.toml", "four_cable.toml"])
def test_diagnose_names_and_places_injected_drive_offsets(rig_file):
    """A per-cable effect (one drive offset per cable) injected into the testbed plant is named on the m-cable
    rig, and the fitted offsets give the injected offsets' moments cable by cable.

    Small on purpose (4 cycles, three candidates through the API): every effect at 3x the floor on these
    rigs, with the whole vocabulary, is studies/diagnose_n_cables. The plant applies the offsets in its own
    tension law; the check is the moment ``J^T diag(k) d`` the offsets make at the logged poses (only three
    of the m offset directions move the platform at a pose), which a fit sized or ordered wrongly misses.
    """
    from csjm_opt.diagnose import diagnose
    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.model.kinematics import cable_terms
    from csjm_opt.testbed import inject, make_plant, simulate_experiment

    rig = co.Rig.from_toml(RIGS / rig_file)
    m = rig.n_cables
    plant = inject(make_plant(rig, None, 1.0, np.random.default_rng(0)), "drive_offsets", 3.0,
                   np.random.default_rng(1))                        # 0.9 mm per drive (sd)
    noise = InstrumentNoise.paper()
    log = simulate_experiment(rig, 4, np.random.default_rng(3), effect=plant, noise=noise)
    d = diagnose(rig, log, effects=["drive_offsets", "sensor_bias", "stiffness_scale"], noise=noise,
                 secondary=False, workers=1)
    assert d.selected == "drive_offsets"
    c = next(c for c in d.as_json()["candidates"] if c["effect"] == "drive_offsets")
    fitted = np.array([c["params"][f"drive_offset{i}_m"] for i in range(1, m + 1)]) + c["nuisance"]["dl_common_m"]
    _, J = cable_terms(log.R, rig.platform_holes_A_m, rig.base_holes_B_m)
    k = np.asarray(rig.cable_stiffness_N_per_m)

    def moments(offsets_m):
        return np.einsum("nmi,m->ni", J, k * offsets_m)

    truth = np.asarray(plant.drive_offsets_m)
    assert np.sqrt(np.mean(moments(fitted - truth) ** 2)) < 0.15 * np.sqrt(np.mean(moments(truth) ** 2))
    # the same offsets on the cables in reverse order are far off (the check can tell the cables apart)
    assert np.sqrt(np.mean(moments(fitted[::-1] - truth) ** 2)) > 0.5 * np.sqrt(np.mean(moments(truth) ** 2))


def test_codegen_plans_like_python(chain, tmp_path):
    from csjm_opt.codegen import load

    rig_path, _ = chain
    rig = co.Rig.from_toml(rig_path)
    assert cli.main(["codegen", "--rig", rig_path, "-o", str(tmp_path / "c")]) == 0
    lib = load(tmp_path / "c")
    assert lib.n_cables == rig.n_cables
    rng = np.random.default_rng(0)
    for _ in range(20):
        R = co.so3.exp(rng.normal(size=3) * 0.1)
        tau = rng.normal(size=3) * 0.1
        assert np.max(np.abs(lib.plan_tensions(R, tau).tensions_N - co.plan_tensions(rig, R, tau).tensions_N)) <= 1e-9


def test_exported_mjcf_settles_at_the_planned_pose(chain, tmp_path):
    rig_path, _ = chain
    rig = co.Rig.from_toml(rig_path)
    R_plan, tau = co.so3.exp([0.08, -0.05, 0.04]), np.array([0.1, -0.05, 0.02])
    assert cli.main(["export-mjcf", "--rig", rig_path, "--rotvec", "0.08", "-0.05", "0.04", "--tau", "0.1", "-0.05",
                     "0.02", "-o", str(tmp_path / "rig.xml")]) == 0
    m = mujoco.MjModel.from_xml_path(str(tmp_path / "rig.xml"))
    assert m.ntendon == rig.n_cables
    xml = export_mjcf(rig, R_plan, tau, joint_damping_Nms_per_rad=0.3, timestep_s=2e-3)
    m = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, data, 0)
    mujoco.mj_integratePos(m, data.qpos, np.array([0.03, 0.0, -0.02]), 1.0)     # nudged away
    for _ in range(4000):
        mujoco.mj_step(m, data)
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, data.qpos)
    assert co.so3.angle_between(R.reshape(3, 3), R_plan) < 1e-9


def test_sweep_over_the_cable_count(tmp_path, capsys):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('[sweep]\nmethod = "grid"\n\n[base]\nplatform_radius_m = 0.058\nbase_radius_m = 0.075\n'
                     'platform_gamma_deg = 10.0\nbase_gamma_deg = 50.0\n\n[parameters.n_cables]\nvalues = [4, 6, 8]\n\n'
                     '[sampling]\norientations = 40\nmax_tilt_deg = 20.0\nmax_torsion_deg = 10.0\nseed = 0\n')
    capsys.readouterr()
    assert cli.main(["sweep", str(sweep), "--out", str(tmp_path / "out.jsonl"), "--json", "-"]) == 0
    designs = json.loads(capsys.readouterr().out)["designs"]
    assert sorted(int(d["params"]["n_cables"]) for d in designs) == [4, 6, 8]
    # more cables on the same circles hold more: the workspace never shrinks as pairs are added
    by_m = {int(d["params"]["n_cables"]): d for d in designs}
    assert by_m[8]["workspace_fraction"] >= by_m[4]["workspace_fraction"]
    assert by_m[8]["min_stiffness_Nm_per_rad"] > by_m[6]["min_stiffness_Nm_per_rad"]
