"""Identification refuses what it cannot identify (loads spanning a plane), naming the missing direction.

Logs come from the project's forward statics (``csjm_opt.testbed.scripted``) with the
paper's instrument noise. The missing direction is known by construction (the
normal of the plane the load increments span), so the check does not rely on
the code under test; the well-excited estimate is compared with the true K of
the simulated equilibrium.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from csjm_opt import cli
from csjm_opt.errors import IllConditionedData
from csjm_opt.identification.log_identification import identify_log
from csjm_opt.identification.refusal import MAX_RELATIVE_HALF_WIDTH
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed.scripted import add_noise, load_directions, simulate_log

ROTVEC_REF = np.array([0.1, -0.05, 0.02])
TAU_PRE = np.array([0.2, -0.5, 0.3])
NORMAL = np.array([1.0, 2.0, 2.0]) / 3.0           # the direction the planar loads never excite


def _plane_basis(n: np.ndarray) -> np.ndarray:
    u = np.cross(n, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    return np.stack([u, np.cross(n, u)])


@pytest.fixture(scope="module")
def logs(rig, model):
    rng = np.random.default_rng(3)
    full = load_directions(30, rng) * 1.5
    planar = rng.normal(size=(30, 2)) @ _plane_basis(NORMAL) * 1.0
    out = {}
    for name, inc in (("full", full), ("planar", planar)):
        log, refs = simulate_log(rig, [(ROTVEC_REF, TAU_PRE, inc)], model)
        out[name] = (add_noise(log, InstrumentNoise.paper(), np.random.default_rng(4)), refs[0])
    return out


def test_well_excited_cycle_is_identified(logs, rig, model):
    log, ref = logs["full"]
    (e,) = identify_log(log, rig, model=model)
    assert not e.ill_conditioned and e.relative_half_width < MAX_RELATIVE_HALF_WIDTH
    assert np.linalg.norm(e.K_sym - ref.K) / np.linalg.norm(ref.K) < 0.05


def test_planar_loads_are_refused_naming_the_plane_normal(logs, rig, model):
    log, _ = logs["planar"]
    with pytest.raises(IllConditionedData) as info:
        identify_log(log, rig, model=model)
    direction = info.value.direction
    assert direction is not None and abs(abs(direction @ NORMAL) - 1) < 0.05
    assert "moment component along" in str(info.value)


def test_allow_ill_conditioned_returns_a_marked_estimate(logs, rig, model):
    log, _ = logs["planar"]
    (e,) = identify_log(log, rig, model=model, allow_ill_conditioned=True)
    assert e.ill_conditioned and e.as_dict()["ill_conditioned"] is True
    assert abs(abs(e.weakest_load_direction_A @ NORMAL) - 1) < 0.05
    assert any(p.startswith("ill-conditioned") for p in e.problems())


def test_cli_exits_2_with_one_line_or_marks_the_estimate(logs, tmp_path, capsys):
    log, _ = logs["planar"]
    path = tmp_path / "planar.csv"
    log.to_csv(path)
    assert cli.main(["identify", str(path), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().split("\n")
    assert len(err) == 1 and "cycle 0" in err[0] and "moment component along" in err[0]
    out = tmp_path / "out.json"
    assert cli.main(["identify", str(path), "--allow-ill-conditioned", "--no-progress", "--json", str(out)]) == 0
    cycle = json.loads(out.read_text())["cycles"][0]
    assert cycle["ill_conditioned"] is True and cycle["relative_half_width"] > MAX_RELATIVE_HALF_WIDTH
