"""Rigs of m = 4..12 cables: patterns, refusal at load, K, the planner and logs for any m.

Every check compares against something the code under test did not produce: hole
positions against the paper's hexagon construction, K against a finite-difference
Hessian of the cable energy (geometry recomputed here with scipy's rotations), the
planner against Clarabel (an interior-point QP solver) on a problem built here.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import qpsolvers
from scipy.spatial.transform import Rotation

import csjm_opt as co
from csjm_opt import cli
from csjm_opt.model import hexagon
from csjm_opt.model.hole_pattern import expand_pattern
from csjm_opt.model.rig import Rig

M_VALUES = (4, 5, 6, 8, 12)


def pattern_table(m: int) -> dict:
    """A working layout for any m: platform holes evenly spaced, base holes twisted alternately."""
    platform = np.arange(m) * 360.0 / m
    twist = 35.0 * np.where(np.arange(m) % 2 == 0, 1.0, -1.0)
    return {"count": m, "platform_radius": 0.06, "base_radius": 0.08, "platform_height": 0.08,
            "base_height": -0.08, "platform_angles_deg": platform.tolist(),
            "base_angles_deg": (platform + twist).tolist()}


def rig_data(m: int) -> dict:
    return {"geometry": {"pattern": pattern_table(m)},
            "cables": {"stiffness": [4600.0 + 50.0 * i for i in range(m)], "t_min": 5.0, "t_max": 150.0},
            "platform": {"mass": 0.45, "com": [0.0, 0.0, 0.081], "gravity": [0.0, 0.0, -9.81]}}


@pytest.fixture(scope="module", params=M_VALUES)
def rig(request) -> Rig:
    return Rig.from_dict(rig_data(request.param), path=f"rig{request.param}.toml")


# ------------------------------------------------------------------ rig files and patterns
def test_paper_hexagon_is_a_pair_pattern():
    """The paper's semi-regular hexagons, built from chords (hexagon.py), are pair patterns."""
    r_a, g_a = hexagon.circle_from_chords(*hexagon.PAPER_PLATFORM_CHORDS_M)
    r_b, g_b = hexagon.circle_from_chords(*hexagon.PAPER_BASE_CHORDS_M)
    A, B = expand_pattern({"count": 6, "platform_radius": r_a, "base_radius": r_b, "platform_height": 0.08,
                           "base_height": -0.08, "platform_pair_angle_deg": float(np.degrees(g_a)),
                           "base_pair_angle_deg": float(np.degrees(g_b))})
    paper = co.paper_rig()
    assert np.allclose(A, paper.platform_holes_A_m, atol=1e-12)
    assert np.allclose(B, paper.base_holes_B_m, atol=1e-12)


def test_pattern_keys_do_what_they_say():
    base = {"count": 4, "platform_radius": 0.05, "base_radius": 0.07, "platform_height": 0.08,
            "base_height": -0.08}
    A, B = expand_pattern(base)
    assert np.allclose(np.degrees(np.arctan2(A[:, 1], A[:, 0])) % 360, [0, 90, 180, 270])
    assert np.allclose(np.linalg.norm(B[:, :2], axis=1), 0.07)
    A2, B2 = expand_pattern({**base, "twist_deg": 30.0, "phase_deg": 10.0, "alternation": 0.01,
                             "connect_shift": 1})
    assert np.allclose(np.degrees(np.arctan2(A2[:, 1], A2[:, 0])) % 360, [10, 100, 190, 280])
    assert np.allclose(A2[:, 2], [0.085, 0.075, 0.085, 0.075])
    # cable i joins platform hole i and base hole i + 1: base hole 2 sits at 90 + 10 + 30 deg
    assert np.isclose(np.degrees(np.arctan2(B2[0, 1], B2[0, 0])), 130.0)


def test_rig_files_of_any_m_read_and_round_trip(rig, tmp_path):
    m = rig.n_cables
    assert rig.platform_holes_A_m.shape == (m, 3) and rig.cable_stiffness_N_per_m.shape == (m,)
    assert rig.t_mid_N.shape == (m,)
    path = tmp_path / "rig.toml"
    rig.to_toml(path)
    back = Rig.from_toml(path)
    assert np.array_equal(back.platform_holes_A_m, rig.platform_holes_A_m)
    assert np.array_equal(back.cable_stiffness_N_per_m, rig.cable_stiffness_N_per_m)


SHIPPED = {"four_cable.toml": 4, "five_cable.toml": 5, "paper.toml": 6, "eight_cable.toml": 8, "twelve_cable.toml": 12}


@pytest.mark.parametrize("name", list(SHIPPED))
def test_shipped_rigs(name):
    from pathlib import Path

    rig = Rig.from_toml(Path(__file__).resolve().parents[2] / "rigs" / name)
    assert rig.n_cables == SHIPPED[name]


def test_a_rig_without_tension_closure_is_refused():
    """All cables twisting the same way cannot hold a zero moment about z: refused at load."""
    data = rig_data(6)
    data["geometry"]["pattern"]["base_angles_deg"] = (np.arange(6) * 60.0 + 35.0).tolist()
    with pytest.raises(co.RigFileError, match="no tension closure") as info:
        Rig.from_dict(data, path="twisted.toml")
    assert info.value.key == "cables.t_max" and "twisted.toml" in str(info.value)
    Rig.from_dict(data, path="twisted.toml", check_closure=False)   # the geometry itself is valid


def test_the_stated_range_is_checked():
    """A rig that works at the zero pose but not at the tilts its file states is refused."""
    data = rig_data(4)
    data["cables"]["t_max"] = 12.0          # barely above t_min: the weight's moment at a tilt is too much
    data["platform"]["mass"] = 2.0
    Rig.from_dict(data)                      # the zero pose: the weight has no moment
    data["workspace"] = {"tilt_deg": 25.0}
    with pytest.raises(co.RigFileError, match="no tension closure.*tilts up to 25"):
        Rig.from_dict(data, path="tilt.toml")


@pytest.mark.parametrize("mutate, key, message", [
    (lambda d: d["cables"].__setitem__("stiffness", [4600.0] * 6), "cables.stiffness", r"shape \(5,\)"),
    (lambda d: d["geometry"]["pattern"].__setitem__("radius", 0.1), "geometry.pattern.radius", "unknown key"),
    (lambda d: d["geometry"]["pattern"].__setitem__("count", 3), "geometry.pattern.count", "4 <= count"),
    (lambda d: d["geometry"]["pattern"].__setitem__("platform_radius", [0.06] * 4), "geometry.pattern.platform_radius",
     "5 numbers"),
    (lambda d: d["geometry"]["pattern"].__setitem__("platform_pair_angle_deg", 5.0),
     "geometry.pattern.platform_pair_angle_deg", "not both"),
])
def test_bad_rigs_name_their_key(mutate, key, message):
    data = rig_data(5)
    mutate(data)
    with pytest.raises(co.RigFileError, match=message) as info:
        Rig.from_dict(data, path="bad.toml")
    assert info.value.key == key


def test_coincident_holes_are_refused():
    data = rig_data(5)
    angles = data["geometry"]["pattern"]["platform_angles_deg"]
    angles[1] = angles[0]
    with pytest.raises(co.RigFileError, match="apart"):
        Rig.from_dict(data, path="bad.toml")


# ------------------------------------------------------------------ K and the planner
def _lengths(rig: Rig, R: np.ndarray) -> np.ndarray:
    return np.linalg.norm(rig.base_holes_B_m - rig.platform_holes_A_m @ R.T, axis=1)


def _energy_hessian(rig: Rig, R: np.ndarray, tensions: np.ndarray, h: float) -> np.ndarray:
    """Central second differences of E(zeta) = sum 1/2 k (c(R exp(zeta)) - l)^2 at zeta = 0."""
    k = rig.cable_stiffness_N_per_m
    rest = _lengths(rig, R) - tensions / k

    def energy(zeta):
        c = _lengths(rig, R @ Rotation.from_rotvec(zeta).as_matrix())
        return 0.5 * np.sum(k * (c - rest) ** 2)

    H = np.empty((3, 3))
    e = np.eye(3) * h
    for i in range(3):
        for j in range(3):
            H[i, j] = (energy(e[i] + e[j]) - energy(e[i] - e[j]) - energy(-e[i] + e[j])
                       + energy(-e[i] - e[j])) / (4 * h * h)
    return H


def test_K_is_the_finite_difference_energy_hessian(rig):
    """K = Levi-Civita Hessian of the cable energy, to 1e-6 relative (Richardson-extrapolated FD)."""
    rng = np.random.default_rng(rig.n_cables)
    for _ in range(4):
        R = Rotation.from_rotvec(rng.normal(size=3) * 0.2).as_matrix()
        T = rng.uniform(10.0, 140.0, rig.n_cables)
        K = co.stiffness(rig, R, T)
        H1, H2 = _energy_hessian(rig, R, T, 2e-3), _energy_hessian(rig, R, T, 1e-3)
        H = (4 * H2 - H1) / 3
        assert np.linalg.norm(K - H) <= 1e-6 * np.linalg.norm(H)


def _independent_qp(rig: Rig, R: np.ndarray, tau: np.ndarray):
    m = rig.n_cables
    A, B = rig.platform_holes_A_m, rig.base_holes_B_m
    v = B - A @ R.T
    u_A = (v @ R) / np.linalg.norm(v, axis=1)[:, None]
    J = np.cross(A, u_A)
    tau_w = np.cross(rig.platform_mass_kg * rig.com_A_m, R.T @ rig.gravity_B_m_per_s2)
    t_ref = np.full(m, 0.5 * (rig.t_min_N + rig.t_max_N))
    problem = qpsolvers.Problem(np.eye(m), -t_ref, None, None, J.T, -(tau + tau_w), np.full(m, rig.t_min_N),
                                np.full(m, rig.t_max_N))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = qpsolvers.solve_problem(problem, solver="clarabel", tol_gap_abs=1e-13, tol_gap_rel=1e-13,
                                      tol_feas=1e-13, tol_ktratio=1e-10)
    return sol, t_ref


def test_planner_is_optimal_against_clarabel(rig):
    """Same status and objective within 1e-9 relative on random poses and loads (feasible and not)."""
    rng = np.random.default_rng(10 + rig.n_cables)
    n_feasible = n_infeasible = 0
    for _ in range(60):
        R = Rotation.from_rotvec(rng.normal(size=3) * 0.15).as_matrix()
        tau = rng.normal(size=3) * rng.choice([0.3, 10.0])
        sol, t_ref = _independent_qp(rig, R, tau)
        try:
            T = co.plan_tensions(rig, R, tau).tensions_N
        except co.InfeasibleLoad as exc:
            assert not sol.found or exc.distance_Nm < 1e-7
            n_infeasible += 1
            continue
        assert sol.found
        f, f_ref = 0.5 * np.sum((T - t_ref) ** 2), 0.5 * np.sum((sol.x - t_ref) ** 2)
        assert abs(f - f_ref) <= 1e-9 * max(f_ref, 1.0)
        n_feasible += 1
    assert n_feasible > 10 and n_infeasible > 3


def test_batch_equals_one_by_one(rig):
    rng = np.random.default_rng(1)
    Rs = co.so3.exp(rng.normal(size=(40, 3)) * 0.05)
    taus = rng.normal(size=(40, 3)) * 0.1
    batch = co.plan_tensions_batch(rig, Rs, taus)
    assert batch.tensions_N.shape == (40, rig.n_cables)
    for i in (0, 17, 39):
        assert np.allclose(batch.tensions_N[i], co.plan_tensions(rig, Rs[i], taus[i]).tensions_N, atol=1e-9)


def test_forward_statics_return_to_the_planned_pose(rig):
    R = co.so3.exp([0.08, -0.05, 0.03])
    plan = co.plan_tensions(rig, R, [0.1, -0.1, 0.05])
    eq = co.solve_equilibrium(rig, plan.rest_lengths_m, [0.1, -0.1, 0.05], R_init=np.eye(3))
    assert co.so3.angle_between(eq.R, R) < 1e-9
    assert np.allclose(eq.tensions_N, plan.tensions_N, atol=1e-6)


# ------------------------------------------------------------------ command line
def _write_rig(tmp_path, m: int, **changes) -> str:
    rig = Rig.from_dict(rig_data(m))
    path = tmp_path / f"rig{m}.toml"
    rig.to_toml(path)
    return str(path)


def test_cli_refuses_five_holes_with_six_stiffnesses(tmp_path, capsys):
    path = tmp_path / "rig5.toml"
    text = Rig.from_dict(rig_data(5)).to_toml()
    text = text.replace("stiffness = [", "stiffness = [4600.0, ")
    path.write_text(text)
    assert cli.main(["plan", "--rig", str(path), "--rotvec", "0", "0", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "cables.stiffness" in err[0]


def test_cli_refuses_an_unknown_pattern_key(tmp_path, capsys):
    path = tmp_path / "pattern.toml"
    path.write_text("[geometry.pattern]\ncount = 6\nplatform_radius = 0.06\nbase_radius = 0.08\n"
                    "platform_height = 0.08\nbase_height = -0.08\nspin_deg = 3\n"
                    "[cables]\nstiffness = [4600.0, 4600.0, 4600.0, 4600.0, 4600.0, 4600.0]\nt_min = 5.0\n"
                    "t_max = 150.0\n[platform]\nmass = 0.4\ncom = [0.0, 0.0, 0.08]\ngravity = [0.0, 0.0, -9.81]\n")
    assert cli.main(["rig", "show", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "geometry.pattern.spin_deg" in err[0]


def test_cli_refuses_a_log_of_another_cable_count(tmp_path, capsys):
    header = "sample,cycle," + ",".join(f"l{i}" for i in range(1, 9)) + ",tau_x,tau_y,tau_z,rx,ry,rz\n"
    rows = "".join(f"{i},0," + ",".join(["0.15"] * 8) + f",{0.1 * i},0,0,{0.001 * i},0,0\n" for i in range(4))
    log = tmp_path / "log8.csv"
    log.write_text(header + rows)
    assert cli.main(["identify", str(log)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(log) in err[0] and "'l8'" in err[0] and "6 cables" in err[0]


def test_rig_show_prints_holes_and_draws(tmp_path, capsys):
    path = _write_rig(tmp_path, 8)
    png = tmp_path / "rig.png"
    assert cli.main(["rig", "show", path, "-o", str(png)]) == 0
    out = capsys.readouterr().out
    assert "8 cables" in out and len([ln for ln in out.splitlines() if ln.strip()[:1].isdigit()]) == 8
    assert png.read_bytes()[:4] == b"\x89PNG" and (png.stat().st_mode & 0o777) == 0o644 & ~_umask()


def _umask() -> int:
    import os

    mask = os.umask(0)
    os.umask(mask)
    return mask


@pytest.mark.parametrize("m", [4, 8])
def test_logs_of_m_cables_round_trip(m):
    rng = np.random.default_rng(m)
    log = co.MeasurementLog.from_arrays(np.repeat([0, 1], 3), rng.uniform(0.1, 0.2, (6, m)),
                                        rng.normal(size=(6, 3)) * 0.1, rng.normal(size=(6, 3)) * 0.01)
    text = log.to_text()
    assert text.splitlines()[0].split(",")[2:2 + m] == [f"l{i}" for i in range(1, m + 1)]
    back = co.MeasurementLog.from_text(text)
    assert back.n_cables == m and np.array_equal(back.rest_lengths_m, log.rest_lengths_m)


# ------------------------------------------------------------------ generated C
_DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include "csjm.h"
/* stdin: n, then n rows R (9, row-major) tau (3); stdout per row: status, m tensions (default
 * iterations), m tensions (max_iter 1: the exhaustive fallback), K (9) at the planned tensions. */
int main(void)
{
    int n, r, i;
    csjm_warm_start warm = {{0}, {0}};
    if (scanf("%d", &n) != 1) return 2;
    for (r = 0; r < n; ++r) {
        double R[9], tau[3], K[9], nan_tau[3] = {NAN, 0.0, 0.0};
        csjm_plan a, b;
        int sa, sb;
        for (i = 0; i < 9; ++i) if (scanf("%lf", &R[i]) != 1) return 2;
        for (i = 0; i < 3; ++i) if (scanf("%lf", &tau[i]) != 1) return 2;
        sa = csjm_plan_tensions_R(R, tau, NULL, 0, &warm, &a);
        sb = csjm_plan_tensions_R(R, tau, NULL, 1, NULL, &b);
        if (csjm_plan_tensions_R(R, nan_tau, NULL, 0, NULL, &b) != CSJM_BAD_INPUT) return 3;
        sb = csjm_plan_tensions_R(R, tau, NULL, 1, NULL, &b);
        printf("%d %d", sa, sb);
        for (i = 0; i < CSJM_N_CABLES; ++i) printf(" %.17g", a.tensions_N[i]);
        for (i = 0; i < CSJM_N_CABLES; ++i) printf(" %.17g", b.tensions_N[i]);
        if (csjm_stiffness_R(R, a.tensions_N, K) != CSJM_SOLVED) return 4;
        for (i = 0; i < 9; ++i) printf(" %.17g", K[i]);
        printf("\n");
    }
    return 0;
}
"""


@pytest.mark.parametrize("m", [4, 8])
def test_generated_c_is_sanitizer_clean_and_agrees_with_python(m, tmp_path):
    """gcc -fsanitize=address,undefined: no report; tensions within 1e-9 N of Python, K to round-off."""
    import shutil
    import subprocess

    from csjm_opt.codegen import generate_c
    from csjm_opt.codegen.build import CORE_SOURCES

    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.skip("gcc not installed")
    rig = Rig.from_dict(rig_data(m))
    out = tmp_path / "c"
    generate_c(rig, out)
    (out / "driver.c").write_text(_DRIVER)
    exe = tmp_path / "driver"
    subprocess.run([gcc, "-std=c99", "-Wall", "-Wextra", "-Werror", "-O1", "-g", "-fsanitize=address,undefined",
                    "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", *(str(out / s) for s in CORE_SOURCES),
                    str(out / "driver.c"), "-o", str(exe), "-lm"], check=True, capture_output=True)
    rng = np.random.default_rng(m)
    Rs = Rotation.from_rotvec(rng.normal(size=(40, 3)) * 0.15).as_matrix()
    taus = rng.normal(size=(40, 3)) * 0.3
    stdin = f"{len(Rs)}\n" + "".join(" ".join(f"{v:.17g}" for v in (*R.ravel(), *t)) + "\n"
                                     for R, t in zip(Rs, taus, strict=True))
    proc = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True, check=False)
    assert proc.returncode == 0 and "runtime error" not in proc.stderr and "Sanitizer" not in proc.stderr, \
        proc.stderr[:2000]
    rows = [np.array(line.split(), float) for line in proc.stdout.splitlines()]
    assert len(rows) == len(Rs)
    for row, R, tau in zip(rows, Rs, taus, strict=True):
        status = int(row[0])
        try:
            plan = co.plan_tensions(rig, R, tau)
        except co.InfeasibleLoad:
            assert status == 1
            continue
        assert status == 0 and int(row[1]) == 0
        assert np.max(np.abs(row[2:2 + m] - plan.tensions_N)) <= 1e-9
        assert np.max(np.abs(row[2 + m:2 + 2 * m] - plan.tensions_N)) <= 1e-9     # exhaustive fallback
        K = co.stiffness(rig, R, plan.tensions_N)
        assert np.allclose(row[2 + 2 * m:].reshape(3, 3), K, rtol=1e-12, atol=1e-9)
