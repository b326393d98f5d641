"""MJCF export (model/mjcf.py, cli/export_mjcf.py) and the rig's [dynamics] section (model/dynamics.py)."""

from __future__ import annotations

import json

import mujoco
import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.cli.app import main
from csjm_opt.model.dynamics import Dynamics, estimate_inertia, rig_dynamics
from csjm_opt.model.mjcf import quat_wxyz, rig_to_mjcf
from csjm_opt.planning import export_mjcf

R_EXPORT = so3.exp([0.1, -0.2, 0.15])
TAU_EXPORT = np.array([0.2, 0.1, -0.1])


def _load(xml):
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    return m, d


def _R(d):
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, d.qpos)
    return R.reshape(3, 3)


def test_quaternion_convention():
    """(w, x, y, z) with w >= 0, as MuJoCo reads it back; also near 180 degrees."""
    for w in ([0.3, -0.2, 0.5], [0.0, 0.0, 0.0], [np.pi - 1e-3, 0, 0], [0, 2.0, 2.0]):
        R = so3.exp(w)
        q = quat_wxyz(R)
        M = np.zeros(9)
        mujoco.mju_quat2Mat(M, q)
        assert np.allclose(M.reshape(3, 3), R, atol=1e-12) and q[0] >= 0


@pytest.mark.parametrize("actuation", ["spring", "winch", "tension"])
def test_export_is_an_equilibrium_in_mujoco(rig, actuation):
    """The keyframe of every actuation mode is a static equilibrium at the planned pose."""
    m, d = _load(export_mjcf(rig, R_EXPORT, TAU_EXPORT, actuation=actuation))
    assert np.allclose(_R(d), R_EXPORT, atol=1e-12)
    assert np.abs(d.qfrc_smooth).max() < 1e-10
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(m.nu)]
    assert names[-3:] == ["load_x", "load_y", "load_z"]
    T = co.plan_tensions(rig, R_EXPORT, TAU_EXPORT).tensions_N
    if actuation == "winch":       # pull-only, capped at t_max: actuator forces are minus the tensions
        assert np.allclose(-d.actuator_force[:6], T, atol=1e-8)
        assert np.allclose(m.actuator_forcerange[:6], [[-rig.t_max_N, 0.0]] * 6)
    if actuation == "tension":
        assert np.allclose(m.actuator_ctrlrange[:6], [[rig.t_min_N, rig.t_max_N]] * 6)


def test_winch_settles_like_the_springs(rig):
    """Winch actuation (forcerange clamp) and dead-band springs settle at the same pose from a nudge."""
    poses = []
    for actuation in ("spring", "winch"):
        m, d = _load(export_mjcf(rig, R_EXPORT, TAU_EXPORT, actuation=actuation, joint_damping_Nms_per_rad=0.3,
                                 timestep_s=2e-3))
        mujoco.mj_integratePos(m, d.qpos, np.array([0.03, 0.0, -0.02]), 1.0)
        for _ in range(3000):
            mujoco.mj_step(m, d)
        poses.append(_R(d))
    assert all(np.linalg.norm(so3.log(R_EXPORT.T @ R)) < 1e-9 for R in poses)


def test_dead_band_is_pull_only(rig):
    """A cable shorter than its rest length exerts nothing (MuJoCo two-value springlength)."""
    c = np.linalg.norm(rig.base_holes_B_m - rig.platform_holes_A_m, axis=1)
    m, d = _load(rig_to_mjcf(rig, c + 0.01))          # every cable slack by 10 mm at R = I
    d.qpos[:] = [1, 0, 0, 0]
    mujoco.mj_forward(m, d)
    assert np.allclose(d.qfrc_passive, 0.0)
    m, d = _load(rig_to_mjcf(rig, c - 0.001))         # every cable stretched by 1 mm: tension k * 1 mm
    J = co.Model(rig).jacobian(np.eye(3))
    assert np.allclose(d.qfrc_passive, J.T @ (rig.cable_stiffness_N_per_m * 0.001), atol=1e-12)


def test_cli_export(tmp_path, rig, capsys):
    out = tmp_path / "rig.xml"
    rig_file = tmp_path / "rig.toml"
    rig.to_toml(rig_file)
    assert main(["export-mjcf", "--rig", str(rig_file), "--rotvec", "0.1", "-0.2", "0.15", "--tau", "0.2", "0.1",
                 "-0.1", "-o", str(out), "--json", str(tmp_path / "s.json")]) == 0
    m, d = _load(out.read_text())
    assert np.allclose(_R(d), R_EXPORT, atol=1e-12) and np.abs(d.qfrc_smooth).max() < 1e-10
    assert json.loads((tmp_path / "s.json").read_text())["actuation"] == "spring"
    before = rig_file.read_text()
    assert main(["export-mjcf", "--rig", str(rig_file), "-o", str(rig_file)]) == 2
    assert rig_file.read_text() == before
    assert "refusing to overwrite" in capsys.readouterr().err
    assert main(["export-mjcf", "--rotvec", "0", "0", "3.0", "--tau", "50", "0", "0", "-o", str(out)]) == 2


def test_dynamics_section_round_trip_and_defaults(rig, tmp_path):
    dyn = rig_dynamics(rig)                                    # defaults: disc of the hole circle
    r = np.linalg.norm(rig.platform_holes_A_m[0, :2])
    assert np.allclose(np.diag(dyn.inertia_com_A_kgm2), [rig.platform_mass_kg * r * r / 4] * 2
                       + [rig.platform_mass_kg * r * r / 2])
    I_O = dyn.inertia_about_O_A_kgm2(rig.platform_mass_kg, rig.com_A_m)
    assert np.isclose(I_O[0, 0], dyn.inertia_com_A_kgm2[0, 0] + rig.platform_mass_kg * 0.081 ** 2)
    full = np.array([[2e-3, 1e-4, 0], [1e-4, 2e-3, 0], [0, 0, 3e-3]])
    rig2 = rig.replace(dynamics=Dynamics(full, 0.05, [1, 2, 3, 4, 5, 6]))
    path = tmp_path / "r.toml"
    rig2.to_toml(path)
    back = co.Rig.from_toml(path).dynamics
    assert np.allclose(back.inertia_com_A_kgm2, full) and back.joint_damping_Nms_per_rad == 0.05
    assert np.allclose(back.cable_damping_Ns_per_m, [1, 2, 3, 4, 5, 6])
    assert co.Rig.from_toml(rig.to_toml(tmp_path / "plain.toml") and tmp_path / "plain.toml").dynamics is None
    assert np.allclose(estimate_inertia(1.0, [[0.1, 0, 0]] * 6), np.diag([0.0025, 0.0025, 0.005]))


@pytest.mark.parametrize("table, key", [({"inertia": [1, 2]}, "dynamics.inertia"),
                                        ({"inertia": [1, 1, 5]}, "dynamics.inertia"),
                                        ({"inertia": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]}, "dynamics.inertia"),
                                        ({"joint_damping": -1}, "dynamics.joint_damping"),
                                        ({"cable_damping": [1, 2]}, "dynamics.cable_damping"),
                                        ({"mass": 1}, "dynamics.mass")])
def test_dynamics_section_errors_name_the_key(rig, table, key):
    data = rig.as_dict()
    data["dynamics"] = table
    with pytest.raises(co.RigFileError) as err:
        co.Rig.from_dict(data)
    assert err.value.key == key
