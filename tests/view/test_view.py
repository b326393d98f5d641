"""csjm_opt.view without a browser: the numbers, the figure's geometry, the command, the report pages.

References are independent of the page code: the planner and ``co.stiffness`` called here, the
planner's ``InfeasibleLoad.distance_Nm``, eigenvalues by numpy, and parameters injected by the test.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import view
from csjm_opt.view.traces import ELLIPSOID_FRACTION, panel_scale, state_traces

MAX_BYTES = 3_000_000


def _page_data(page) -> dict:
    m = re.search(r'<script type="application/json" id="csjm-data">(.*?)</script>', page.html, re.S)
    return json.loads(m.group(1).replace("<\\/", "</"))


def test_state_numbers_are_the_apis(rig):
    R, tau = co.so3.exp([0.2, -0.1, 0.05]), np.array([0.3, -0.4, 0.1])
    s = view.rig_state(rig, R, tau)
    T = co.plan_tensions(rig, R, tau).tensions
    np.testing.assert_allclose(s.tensions_N, T, atol=1e-9)
    np.testing.assert_allclose(s.eigenvalues_Nm_per_rad, np.linalg.eigvalsh(co.stiffness(rig, R, T)), atol=1e-9)
    assert s.feasible and s.message.startswith("Held")


def test_infeasible_load_names_the_cables_at_bounds(rig):
    R, tau = co.so3.exp([0.3, 0.1, 0.0]), np.array([20.0, 0.0, 0.0])
    with pytest.raises(co.InfeasibleLoad) as info:
        co.plan_tensions(rig, R, tau)
    s = view.rig_state(rig, R, tau)
    assert not s.feasible and s.K is None
    assert s.residual_Nm == pytest.approx(info.value.distance_Nm, rel=1e-6)
    T = s.tensions_N
    assert np.all(T >= rig.t_min_N - 1e-9) and np.all(T <= rig.t_max_N + 1e-9)
    at = {i for i, t in enumerate(T) if min(abs(t - rig.t_min_N), abs(t - rig.t_max_N)) < 1e-6}
    assert set(s.at_bounds) == at and at
    for i in at:
        assert f"{i + 1} (t_m" in s.message


def test_compliance_ellipsoid_axes_are_in_the_ratio_of_the_eigenvalues(rig):
    R = co.so3.exp([0.0, 0.35, 0.0])
    s = view.rig_state(rig, R, np.zeros(3))
    surf = next(t for t in state_traces(s, panel_scale([s])) if t["type"] == "surface")
    pts = np.stack([np.array(surf[k], float) for k in "xyz"], axis=-1).reshape(-1, 3)
    w, V = np.linalg.eigh(co.stiffness(rig, R, co.plan_tensions(rig, R).tensions))
    extent = np.abs(pts @ (R @ V)).max(axis=0)           # semi-axis along each eigenvector, in {B}
    np.testing.assert_allclose(extent / extent[0], w[0] / w, rtol=2e-3)   # axes ~ 1/lambda: soft = long
    radius = np.linalg.norm(rig.platform_holes_A_m[:, :2], axis=1).max()
    assert extent[0] == pytest.approx(ELLIPSOID_FRACTION * radius, rel=2e-3)


def test_page_frames_hold_every_cable_and_hole_label(rig):
    page = view.pose_view(rig, [0.1, 0.2, 0.0], [0.2, 0.0, 0.1], n_steps=3)
    assert len(page) <= MAX_BYTES and "http://" not in page.html and "https://" not in page.html
    data = _page_data(page)
    assert len(data["frames"]) == 3 and data["initial"] == 2
    m = len(rig.platform_holes_A_m)
    for f in data["frames"]:
        labels = [t["text"] for t in f["traces"] if t.get("mode") == "text" and t["name"].endswith("holes")]
        assert labels == [[f"A{i}" for i in range(1, m + 1)], [f"B{i}" for i in range(1, m + 1)]]
        assert len(re.findall(r'data-q="tension"', f["numbers"])) == m


@pytest.mark.parametrize("rig_file", ["eight_cable.toml", "four_cable.toml"])
def test_other_cable_counts_display(rig_file):
    """Rigs of 8 and 4 cables: m comes from the rig, never a literal 6."""
    rig_m = co.load_rig(Path(__file__).resolve().parents[2] / "rigs" / rig_file)
    m = rig_m.n_cables
    page = view.pose_view(rig_m, [0.05, 0.0, 0.0], n_steps=2)
    f = _page_data(page)["frames"][-1]
    assert len(re.findall(r'data-q="tension"', f["numbers"])) == m
    assert any(t.get("text") == [f"A{i}" for i in range(1, m + 1)] for t in f["traces"])


def test_designs_side_by_side_with_their_rings():
    from csjm_opt.design.geometry import design_rig

    rigs = [design_rig({"platform_radius_m": 0.058, "platform_gamma_deg": g}) for g in (9.9, 60.0)]
    page = view.designs_view(rigs, ["a", "b"], certified_tilt_deg=[12.0, 20.0])
    data = _page_data(page)
    assert {t["scene"] for t in data["frames"][0]["traces"]} == {"scene", "scene2"}
    rings = [t for t in data["frames"][0]["traces"] if t["name"].startswith("certified tilt")
             and t["mode"] == "lines+markers"]
    for ring, tilt in zip(rings, (12.0, 20.0)):    # the ring is the platform centre at that tilt
        p = np.stack([np.array(ring[k], float) for k in "xyz"], axis=1)
        h = float(np.mean(rigs[0].platform_holes_A_m[:, 2]))
        np.testing.assert_allclose(np.degrees(np.arccos(p[:, 2] / h)), tilt, atol=1e-3)


def test_tilt_boundary_is_where_the_planner_stops_holding(rig):
    az = np.array([0.0, 90.0])
    tilt = view.tilt_boundary_deg(rig, az, load_Nm=1.0, tol_deg=0.05)
    from csjm_opt.design.sampling import tilt_torsion_rotations

    loads = [np.zeros(3)] + [np.array([np.cos(a), np.sin(a), 0.0]) for a in np.radians([0, 90, 180, 270])]
    for a, t in zip(az, tilt):
        if t >= 60.0:
            continue
        inside, outside = (tilt_torsion_rotations(np.radians([x]), np.radians([a]), np.zeros(1))[0]
                           for x in (t - 0.01, t + 0.1))
        for tau in loads:
            co.plan_tensions(rig, inside, tau)                     # held just inside
        failed = 0
        for tau in loads:
            try:
                T = co.plan_tensions(rig, outside, tau).tensions
                failed += np.linalg.eigvalsh(co.stiffness(rig, outside, T))[0] <= 0
            except co.CsjmError:
                failed += 1
        assert failed >= 1                                          # not held just outside


def test_diagnosis_view_draws_injected_offsets_and_sticking_cables(rig):
    page = view.diagnosis_view(rig, "hole_offsets", {"dA3_x_m": 0.003, "dA3_y_m": 0.004, "dB5_z_m": -0.0015})
    text = json.dumps(_page_data(page))
    assert "A3: 5.0 mm" in text and "B5: 1.5 mm" in text        # |(3, 4)| = 5 mm
    page = view.diagnosis_view(rig, "friction", {"mu_beta_2": 0.04, "mu_beta_4": 0.03, "mu_beta_1": 0.001,
                                                 "stick_travel_factor": 0.3})
    assert page.note.endswith(": 2, 4")


def test_cli_view(tmp_path, rig, capsys):
    from csjm_opt.cli import main

    out, js = tmp_path / "v.html", tmp_path / "v.json"
    args = ["view", "--rotvec", "0.3", "0.1", "0", "--tau", "20", "0", "0", "--steps", "2", "-o", str(out),
            "--json", str(js)]
    assert main(args) == 0                               # a pose the rig cannot hold still renders
    assert "NOT held" in capsys.readouterr().out and out.stat().st_size <= MAX_BYTES
    assert oct(out.stat().st_mode & 0o777) == "0o644"
    frames = json.loads(js.read_text())["frames"]
    last, first = frames[-1]["panels"][0], frames[0]["panels"][0]
    assert not last["feasible"] and last["at_bounds"]
    np.testing.assert_allclose(first["tensions_N"], co.plan_tensions(rig, np.eye(3)).tensions, atol=1e-9)
    assert main(["view", "--rig", str(tmp_path / "missing.toml"), "-o", str(tmp_path / "x.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "missing.toml" in err and not (tmp_path / "x.html").exists()


def test_cli_view_of_a_logs_cycles(tmp_path, rig):
    from csjm_opt.cli import main
    from csjm_opt.testbed.identification import simulate_identification_experiment

    log_path, js = tmp_path / "log.csv", tmp_path / "v.json"
    simulate_identification_experiment(rig, 2, np.random.default_rng(3), loads_per_cycle=4).to_csv(log_path)
    log = co.MeasurementLog.from_csv(log_path)
    assert main(["view", "--log", str(log_path), "-o", str(tmp_path / "v.html"), "--json", str(js)]) == 0
    frames = json.loads(js.read_text())["frames"]
    assert len(frames) == len(log.cycle_ids)
    for c, f in zip(log.cycle_ids, frames):
        rows = log.cycle_rows(c)
        k = rows[np.argmax(np.linalg.norm(log.tau_ext_A_Nm[rows], axis=1))]   # the cycle's most loaded row
        panel = f["panels"][0]
        np.testing.assert_allclose(panel["rotvec"], log.rotvec_rad[k], atol=1e-12)
        np.testing.assert_allclose(panel["tau_ext"], log.tau_ext_A_Nm[k], atol=1e-12)
        T = co.plan_tensions(rig, log.R[k], log.tau_ext_A_Nm[k]).tensions
        np.testing.assert_allclose(panel["tensions_N"], T, atol=1e-9)
