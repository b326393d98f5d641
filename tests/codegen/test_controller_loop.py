"""The generated C in use: the MuJoCo closed loop, the example program and its Makefile, the
sanitizers on bad input, and the `csjm codegen` command."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.cli import main
from csjm_opt.codegen import CTensionPlanningController, find_compiler, generate_c, load
from csjm_opt.codegen.build import CORE_SOURCES
from csjm_opt.control import simulate
from csjm_opt.control.controllers import TensionPlanningController
from csjm_opt.control.load_profiles import Step
from csjm_opt.control.plants import MujocoPlant
from csjm_opt.errors import InvalidInput
from csjm_opt.planning import plan_tensions_batch
from tests.codegen.test_generate import paper_folder

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler (cc or $CC) on this machine")


@pytest.fixture(scope="module")
def paper_dir(tmp_path_factory):
    return paper_folder(tmp_path_factory)


def test_mujoco_closed_loop_with_the_c_library_tracks_as_python(paper_dir):
    """A held pose under a load step in MuJoCo: the controller calling C (warm-started) gives the
    Python controller's pose error at every step to 1e-9 rad."""
    rig = co.paper_rig()
    R_hold = so3.exp([0.08, -0.05, 0.1])
    load_step = Step(0.1, [0.3, -0.2, 0.1])
    logs = {}
    for name, ctrl in [("python", TensionPlanningController(rig, R_hold)),
                       ("c", CTensionPlanningController(rig, load(paper_dir), R_hold))]:
        logs[name] = simulate(rig, ctrl, load_step, 0.3, plant=MujocoPlant(rig, joint_damping_Nms_per_rad=0.3))
    e_py, e_c = logs["python"].pose_error_rad, logs["c"].pose_error_rad
    assert e_py.max() > 1e-4                                  # the step does move the platform
    assert np.abs(e_c - e_py).max() <= 1e-9
    assert np.nanmax(np.abs(logs["c"].tensions_cmd_N - logs["python"].tensions_cmd_N)) <= 1e-9


def test_controller_refuses_a_library_of_another_rig(paper_dir):
    other = co.paper_rig(cable_stiffness_N_per_m=3000.0)
    with pytest.raises(InvalidInput, match="another rig"):
        CTensionPlanningController(other, load(paper_dir), np.eye(3))


@pytest.mark.skipif(shutil.which("make") is None, reason="no make on this machine")
def test_makefile_builds_the_example_and_its_1khz_loop_matches_python(paper_dir, tmp_path):
    """`make` (with -Werror) builds the static and shared libraries and the example; the example's
    tensions over the sample trajectory equal the Python planner's."""
    work = tmp_path / "gen"
    shutil.copytree(paper_dir, work)
    subprocess.run(["make", "-s", "-C", str(work), "all", "run"], check=True, capture_output=True, text=True)
    for f in ("libcsjm.a", "libcsjm.so", "csjm_example", "tensions.csv"):
        assert (work / f).is_file()
    traj = np.loadtxt(work / "trajectory.csv", delimiter=",", skiprows=1)
    out = np.loadtxt(work / "tensions.csv", delimiter=",", skiprows=1)
    assert out.shape[0] == traj.shape[0] and np.all(out[:, 1] == 0)
    Rs = Rotation.from_quat(traj[:, [2, 3, 4, 1]]).as_matrix()       # scipy: (x, y, z, w)
    ref = plan_tensions_batch(co.paper_rig(), Rs, traj[:, 5:8])
    assert np.abs(out[:, 2:8] - ref.tensions_N).max() <= 1e-9
    assert np.abs(out[:, 8:14] - ref.rest_lengths_m).max() <= 1e-12
    if shutil.which("nm"):   # the library needs nothing but libm: no allocation, no I/O
        undefined = subprocess.run(["nm", "-u", str(work / "libcsjm.a")], capture_output=True, text=True).stdout
        defined = subprocess.run(["nm", "--defined-only", str(work / "libcsjm.a")], capture_output=True,
                                 text=True).stdout
        own = {ln.split()[-1] for ln in defined.splitlines() if len(ln.split()) == 3}
        external = {ln.split()[-1] for ln in undefined.splitlines() if ln.strip().startswith("U")} - own
        assert external <= {"sqrt", "fabs"}, external


DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "csjm.h"

static int fails = 0;
#define EXPECT(cond) do { if (!(cond)) { printf("FAILED line %d: %s\n", __LINE__, #cond); ++fails; } } while (0)

int main(void)
{
    double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, R[9], tau[3] = {0.1, -0.2, 0.05}, K[9], c[6], J[18], w[3];
    double T[6] = {50, 60, 70, 80, 90, 100}, l[6], nan = NAN, inf = INFINITY;
    double q_unit[4] = {0.9, 0.3, -0.2, 0.1}, q_bad[4] = {2, 0, 0, 0}, q_zero[4] = {0, 0, 0, 0};
    double q_nan[4] = {nan, 0, 0, 1}, big[3] = {1e300, -1e300, 1e300}, tref_nan[6] = {1, 2, 3, nan, 5, 6};
    csjm_plan plan;
    csjm_warm_start warm;
    int i, s;
    memset(&warm, 0xff, sizeof warm);               /* garbage warm start: must be tolerated */
    for (i = 0; i < 4; ++i) q_unit[i] /= sqrt(0.81 + 0.09 + 0.04 + 0.01);
    EXPECT(csjm_plan_tensions_R(I, tau, NULL, 0, &warm, &plan) == CSJM_SOLVED);
    EXPECT(csjm_plan_tensions_q(q_unit, tau, NULL, 0, NULL, &plan) == CSJM_SOLVED);
    memcpy(R, I, sizeof R); R[0] = nan;
    EXPECT(csjm_plan_tensions_R(R, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    R[0] = inf;
    EXPECT(csjm_plan_tensions_R(R, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    memcpy(R, I, sizeof R); R[8] = -1.0;            /* a reflection */
    EXPECT(csjm_plan_tensions_R(R, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    memcpy(R, I, sizeof R); R[1] = 0.5;             /* far from a rotation */
    EXPECT(csjm_plan_tensions_R(R, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    tau[1] = nan;
    EXPECT(csjm_plan_tensions_R(I, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    tau[1] = -0.2;
    EXPECT(csjm_plan_tensions_R(I, tau, tref_nan, 0, NULL, &plan) == CSJM_BAD_INPUT);
    EXPECT(csjm_plan_tensions_q(q_bad, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    EXPECT(csjm_plan_tensions_q(q_zero, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    EXPECT(csjm_plan_tensions_q(q_nan, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    EXPECT(csjm_plan_tensions_q(NULL, tau, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    EXPECT(csjm_plan_tensions_R(I, NULL, NULL, 0, NULL, &plan) == CSJM_BAD_INPUT);
    EXPECT(csjm_plan_tensions_R(I, tau, NULL, 0, NULL, NULL) == CSJM_BAD_INPUT);
    s = csjm_plan_tensions_R(I, big, NULL, 0, NULL, &plan);          /* absurd but finite load */
    EXPECT(s == CSJM_INFEASIBLE);
    s = csjm_plan_tensions_R(I, tau, NULL, -5, NULL, &plan);         /* odd iteration caps */
    EXPECT(s == CSJM_SOLVED);
    s = csjm_plan_tensions_R(I, tau, NULL, 1 << 30, NULL, &plan);
    EXPECT(s == CSJM_SOLVED || s == CSJM_ITERATION_CAP);
    s = csjm_plan_tensions_R(I, big, NULL, 1 + CSJM_NO_FALLBACK, NULL, &plan);
    EXPECT(s == CSJM_ITERATION_CAP);
    EXPECT(csjm_stiffness_R(I, T, K) == CSJM_SOLVED);
    EXPECT(csjm_stiffness_q(q_bad, T, K) == CSJM_BAD_INPUT);
    T[3] = nan;
    EXPECT(csjm_stiffness_R(I, T, K) == CSJM_BAD_INPUT);
    EXPECT(csjm_rest_lengths_R(I, T, l) == CSJM_BAD_INPUT);
    EXPECT(csjm_pose_terms_q(q_nan, c, J, w) == CSJM_BAD_INPUT);
    EXPECT(csjm_pose_terms_R(I, c, J, w) == CSJM_SOLVED);
    EXPECT(csjm_rotation_from_quaternion(q_bad, R) == CSJM_BAD_INPUT);
    printf("%d failed\n", fails);
    return fails != 0;
}
"""


def test_bad_input_gives_a_status_under_the_sanitizers(paper_dir, tmp_path):
    """NaN, infinities, non-unit quaternions, reflections, NULL pointers, garbage warm starts, absurd
    loads and iteration caps: each call returns its documented status, with AddressSanitizer and
    UndefinedBehaviorSanitizer finding nothing (any report aborts the program)."""
    (tmp_path / "driver.c").write_text(DRIVER)
    exe = tmp_path / "driver"
    cmd = [find_compiler(), "-std=c99", "-Wall", "-Wextra", "-Werror", "-O1", "-g", "-fno-omit-frame-pointer",
           "-fsanitize=address,undefined", "-fno-sanitize-recover=all", f"-I{paper_dir}", str(tmp_path / "driver.c"),
           *[str(paper_dir / s) for s in CORE_SOURCES], "-o", str(exe), "-lm"]
    build = subprocess.run(cmd, capture_output=True, text=True)
    if build.returncode != 0 and ("asan" in build.stderr or "ubsan" in build.stderr):
        pytest.skip(f"the compiler has no sanitizer runtime: {build.stderr.strip().splitlines()[-1]}")
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, env={"ASAN_OPTIONS": "detect_leaks=1"})
    assert run.returncode == 0, run.stdout + run.stderr
    assert "0 failed" in run.stdout and "runtime error" not in run.stderr and "Sanitizer" not in run.stderr


def test_cli_writes_and_builds(tmp_path, capsys):
    out = tmp_path / "gen"
    assert main(["codegen", "-o", str(out), "--build", "--json", str(tmp_path / "s.json")]) == 0
    summary = json.loads((tmp_path / "s.json").read_text())
    assert {"csjm.h", "csjm_model.c", "csjm_rig.h", "Makefile", "example.c"} <= set(summary["files"])
    assert summary["library"] and len(list(out.glob("libcsjm_py-*.so"))) == 1
    assert "#define CSJM_T_MAX_N 150" in (out / "csjm_rig.h").read_text()
    assert "malloc" not in "".join((out / f).read_text() for f in ("csjm_api.c", "csjm_qp.c", "csjm_model.c"))
    first = load(out)
    other = co.paper_rig().replace(t_max_N=120.0)       # regenerated in the same process: the new code loads
    generate_c(other, out)
    second = load(out)
    assert (first.t_max_N, second.t_max_N) == (150.0, 120.0) and len(list(out.glob("libcsjm_py-*.so"))) == 1
    assert second.plan_tensions(np.eye(3), [1.0, 0.0, 0.0]).tensions_N.max() <= 120.0


@pytest.mark.parametrize("args", [["--rig", "no_such_rig.toml"], ["-o", "FILE/sub"], ["-o", "FILE"]])
def test_cli_bad_input_is_one_line_and_exit_2(args, tmp_path, capsys):
    (tmp_path / "FILE").write_text("not a folder")
    argv = ["codegen"] + [a.replace("FILE", str(tmp_path / "FILE")).replace("no_such", str(tmp_path / "no_such"))
                          for a in args]
    if "-o" not in argv:
        argv += ["-o", str(tmp_path / "gen")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("csjm: error:")
    assert not (tmp_path / "gen").exists()
