"""Shaping part of ``csjm demo`` (csjm_opt/demo_shaping.py) and the soft/stiff study script."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np

from csjm_opt._validate import as_rotation
from csjm_opt.demo.shaping_step import DEMO_TAU_EXT, PAPER_R0, run_demo, soft_stiff_targets
from csjm_opt.shaping.reachable import reachable_set


def test_soft_stiff_targets_are_reachable_and_ordered(rig):
    R = as_rotation(PAPER_R0)
    K_soft, K_stiff = soft_stiff_targets(rig, R, DEMO_TAU_EXT)
    rs = reachable_set(rig, R, DEMO_TAU_EXT, n_samples=0)
    lo, hi = rs.directional_range(np.array([[1.0, 0, 0]]), rig.t_min_N, rig.t_max_N)[0]
    assert lo <= K_soft[0, 0] < K_stiff[0, 0] <= hi
    assert K_stiff[0, 0] - K_soft[0, 0] > 0.5 * (hi - lo)


def test_run_demo_summary(rig, tmp_path):
    summary = run_demo(rig, tmp_path / "shaping", duration_s=0.04)
    json.dumps(summary)
    assert summary["reachable_target_exact"] is True and summary["isotropic_target_exact"] is False
    assert summary["reachable_target_residual_Nm_per_rad"] <= 1e-6
    assert summary["closed_loop_steps"] == 40
    for name in summary["figures"]:
        assert (tmp_path / "shaping" / name).stat().st_size > 5000
    assert (tmp_path / "shaping" / "shaping_summary.json").exists()


def test_study_script_runs(tmp_path):
    path = Path(__file__).resolve().parents[2] / "studies" / "soft_stiff_switch" / "soft_stiff_switch.py"
    spec = importlib.util.spec_from_file_location("soft_stiff_switch", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    assert mod.main(["--out", str(tmp_path), "--duration", "0.5", "--period", "0.25", "--no-noise"]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["deflection_ratio_soft_over_stiff"] > 1.5     # the soft phase yields more
    assert len(summary["figures"]) == 3
