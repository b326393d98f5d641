"""The example scripts run as a user would run them, and their outputs hold the laws they show.

Each script is started with ``sys.executable examples/x.py OUT_DIR`` from a directory outside
the repository, with no PYTHONPATH from the test run (the package is found as installed, or
through the repository root the test adds), and must write its outputs into OUT_DIR only.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted(p.name for p in (ROOT / "examples").glob("*.py"))


def run_example(name: str, out: Path) -> str:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["PYTHONPATH"] = str(ROOT)          # as an editable install would; nothing else
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / name), str(out)], cwd=out.parent,
                          env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def test_every_example_is_tested():
    assert EXAMPLES == ["design_sweep_small.py", "identify_from_log.py", "plan_and_stiffness.py",
                        "shape_stiffness.py"]


def test_plan_and_stiffness(tmp_path, rig):
    out = tmp_path / "out"
    run_example("plan_and_stiffness.py", out)
    s = json.loads((out / "plan_and_stiffness.json").read_text())
    T, K = np.array(s["tensions_N"]), np.array(s["K_Nm_per_rad"])
    assert np.all(T >= rig.t_min_N - 1e-9) and np.all(T <= rig.t_max_N + 1e-9)
    assert s["equilibrium_residual_Nm"] < 1e-8
    np.testing.assert_allclose(K, K.T, atol=1e-9)                  # the energy Hessian is symmetric
    assert min(s["eigenvalues_Nm_per_rad"]) > 0                    # and positive definite (stable pose)
    assert s["forward_statics_pose_error_rad"] < 1e-8              # its rest lengths hold the same pose
    assert (out / "tensions.png").stat().st_size > 1000
    assert sorted(p.name for p in out.iterdir()) == ["plan_and_stiffness.json", "tensions.png"]


def test_identify_from_log(tmp_path):
    out = tmp_path / "out"
    run_example("identify_from_log.py", out)
    s = json.loads((out / "identification.json").read_text())
    assert len(s["cycles"]) == 2
    for c in s["cycles"]:
        K = np.array(c["K"])
        assert c["condition"] < 10                                 # a designed multi-direction cycle
        assert np.all(np.linalg.eigvalsh(0.5 * (K + K.T)) > 0)
    assert s["heldout_rms_rad"] < 0.01                             # a few mrad: the tracker noise
    assert (out / "log.csv").read_text().startswith("sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz")
    assert (out / "convergence.png").stat().st_size > 1000


def test_shape_stiffness(tmp_path):
    out = tmp_path / "out"
    run_example("shape_stiffness.py", out)
    s = json.loads((out / "shaping.json").read_text())
    K_planned, K_target, K_shaped = (np.array(s[k]) for k in ("K_planned", "K_target", "K_shaped"))
    # shaping moves K toward the target, and the achieved K lies in the reachable eigenvalue ranges
    assert np.linalg.norm(K_shaped - K_target) < np.linalg.norm(K_planned - K_target)
    lam = np.linalg.eigvalsh(0.5 * (K_shaped + K_shaped.T))
    ranges = np.array(s["eigen_ranges_Nm_per_rad"])
    assert np.all(lam[[0, 2]] >= ranges[[0, 2], 0] - 1e-6) and np.all(lam[[0, 2]] <= ranges[[0, 2], 1] + 1e-6)
    assert (out / "reachable_set.png").stat().st_size > 1000


def test_design_sweep_small_resumes(tmp_path):
    out = tmp_path / "out"
    first = run_example("design_sweep_small.py", out)
    lines = (out / "results.jsonl").read_text().splitlines()
    assert len(lines) == 4 and first.count("workspace fraction") == 4
    fractions = [float(x.split("workspace fraction ")[1].split(",")[0]) for x in first.splitlines()
                 if "workspace fraction" in x]
    assert all(0 < f <= 1 for f in fractions)
    second = run_example("design_sweep_small.py", out)              # resumes: nothing recomputed
    assert (out / "results.jsonl").read_text().splitlines() == lines
    assert second == first


@pytest.mark.parametrize("name", EXAMPLES)
def test_example_has_usage_docstring(name):
    text = (ROOT / "examples" / name).read_text()
    assert text.startswith('"""') and f"python examples/{name}" in text
