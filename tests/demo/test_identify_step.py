"""run_demo: identification, held-out verification and parameter fit on a simulated noisy log."""

import json

import numpy as np

from csjm_opt.demo.identify_step import run_demo
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed.scripted import add_noise, load_directions, simulate_log


def test_run_demo_summary(rig, model, tmp_path):
    rng = np.random.default_rng(0)
    cycles = [(rng.normal(size=3) * 0.1, rng.normal(size=3) * 0.3, load_directions(24, rng) * 0.8)
              for _ in range(3)]
    log, refs = simulate_log(rig, cycles, model)
    noisy = add_noise(log, InstrumentNoise.paper(), rng)
    summary = run_demo(rig, noisy, tmp_path / "out")
    json.dumps(summary)
    assert [c["cycle"] for c in summary["cycles"]] == [0, 1, 2]
    for c, ref in zip(summary["cycles"], refs):
        K = np.array(c["K"])
        assert np.max(np.abs(K - ref.K)) < 6 * np.max(c["K_std"]) + 0.05
    v = summary["verification"]
    assert v["K_D"]["rms_rad"] < 0.01 and v["K"]["rms_rad"] < 0.01
    assert summary["param_fit"]["heldout_rms_rad"] < 0.01
    for f in summary["files"]:
        assert (tmp_path / "out").joinpath(f).exists()
