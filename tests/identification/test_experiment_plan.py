"""Experiment design: admissible rows (checked on the testbed plant), the selection against brute
force, the protocol format, and ``csjm plan-experiment``."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.cli.app import main
from csjm_opt.errors import DataFileError, DesignError
from csjm_opt.identification.experiment_design import (
    _criterion,
    _select,
    paper_protocol,
    plan_experiment,
    predict_bound,
)
from csjm_opt.identification.experiment_loads import ExperimentLoads, sphere_directions
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.measurement.protocol import Protocol
from csjm_opt.model import kinematics as kin
from csjm_opt.model.rig import paper_rig
from csjm_opt.testbed.plant import TestbedPlant
from csjm_opt.testbed.protocol_runner import settle_protocol

RIG = paper_rig()


@pytest.fixture(scope="module")
def plans():
    loads = ExperimentLoads.default(RIG)
    loads = ExperimentLoads(loads.weights_N, loads.points_A_m, sphere_directions(16), loads.pretensions_N, 0.15)
    plan = plan_experiment(RIG, 24, loads)
    paper = paper_protocol(RIG, 24, np.random.default_rng(0), loads=loads)
    return loads, plan, paper


def test_planned_rows_hold_on_the_testbed_plant(plans):
    loads, plan, _ = plans
    R, _ = settle_protocol(TestbedPlant(RIG), plan.protocol)
    c, _ = kin.cable_terms(R, np.asarray(RIG.platform_holes_A_m), np.asarray(RIG.base_holes_B_m))
    T = np.asarray(RIG.cable_stiffness_N_per_m) * (c - plan.protocol.rest_lengths_m)
    assert T.min() >= RIG.t_min_N - 1e-6 and T.max() <= RIG.t_max_N + 1e-6
    turn = np.linalg.norm(so3.log(np.swapaxes(R[:1], 1, 2) @ R), axis=1)
    assert turn.max() <= loads.max_rotation_rad + 1e-9
    # +- pairs: consecutive loaded rows share weight and point and have opposite directions
    d = plan.protocol.direction_B[1:]
    assert np.allclose(d[0::2], -d[1::2])


def test_planned_bound_is_at_least_twice_narrower_and_reproducible(plans, tmp_path):
    _, plan, paper = plans
    ratio = paper.ci_half_width().mean() / plan.ci_half_width().mean()
    assert ratio >= 2.0
    path = tmp_path / "p.csv"
    plan.protocol.to_csv(path)
    again = predict_bound(RIG, Protocol.from_csv(path))[0][0]      # re-settled from the file
    assert np.allclose(again, plan.crlb6[0], rtol=1e-5)


def test_selection_matches_brute_force():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(8, 3, 9))
    units = np.einsum("nia,nib->nab", X, X)
    base = 1e-3 * np.eye(9)
    chosen = _select(base, units, np.ones(8, int), 4, "A", pairs=False)
    best = min(_criterion(base + units[list(c)].sum(0), "A")
               for c in itertools.combinations_with_replacement(range(8), 4))
    got = _criterion(base + units[chosen].sum(0), "A")
    assert got <= best * 1.05          # greedy + exchange within 5 % of the optimum


def test_protocol_format_round_trip_and_errors(plans, tmp_path):
    _, plan, _ = plans
    text = plan.protocol.to_text()
    header, first = text.splitlines()[:2]
    assert header.startswith("sample,cycle,l1,") and header.endswith("point_x,point_y,point_z")
    assert ",,,,,," in first                                          # measured columns empty
    back = Protocol.from_text(text)
    assert np.allclose(back.force_B_N, plan.protocol.force_B_N)
    bad = text.replace(text.splitlines()[2].split(",")[15], "0.5", 1)
    with pytest.raises(DataFileError, match="p.csv:3"):
        Protocol.from_text(bad, "p.csv")


def test_impossible_designs_are_refused(tmp_path, capsys):
    with pytest.raises(DesignError):
        plan_experiment(RIG, 2)
    loads = tmp_path / "heavy.toml"
    loads.write_text("weights_N = [5000.0]\ndirections = 8\npretensions_N = [25.0]\n")
    assert main(["plan-experiment", "--budget", "10", "--loads", str(loads), "-o", str(tmp_path / "p.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot" in err[0]
    loads.write_text("weigths_N = [5.0]\n")
    assert main(["plan-experiment", "--budget", "10", "--loads", str(loads), "-o", str(tmp_path / "p.csv")]) == 2
    assert "weigths_N" in capsys.readouterr().err


def test_cli_writes_protocol_and_json(tmp_path):
    loads = tmp_path / "l.toml"
    loads.write_text("directions = 12\npretensions_N = [25.0, 60.0]\n")
    out = tmp_path / "p.csv"
    assert main(["plan-experiment", "--budget", "9", "--loads", str(loads), "-o", str(out), "--json",
                 str(tmp_path / "o.json")]) == 0
    res = json.loads((tmp_path / "o.json").read_text())
    assert len(Protocol.from_csv(out)) == 10
    assert len(res["planned"]["ci95_half_width"][0]) == 6 and res["narrower_by"] > 1.0
    assert InstrumentNoise.paper().angle_sigma_rad > 0


def test_a_selection_that_does_not_determine_k_scores_inf():
    """Singular or numerically singular information (round-off inverse of any sign) is never the best."""
    rng = np.random.default_rng(1)
    X = rng.normal(size=(20, 9))
    full = X.T @ X
    low = X[:, :5].T @ X[:, :5]
    singular = np.zeros((9, 9))
    singular[:5, :5] = low
    nearly = X[:4].T @ X[:4] + 1e-14 * np.eye(9)        # rank 4 plus round-off
    values = _criterion(np.stack([full, singular, nearly]), "A")
    # the well-posed one: trace of the K block of the inverse, by a linear solve
    assert values[0] == pytest.approx(np.trace(np.linalg.solve(full, np.eye(9))[3:, 3:]), rel=1e-9)
    assert np.isinf(values[1]) and values[1] > 0 and np.isinf(values[2]) and values[2] > 0
    assert np.isinf(_criterion(nearly, "D")) and np.isfinite(_criterion(full, "D"))


@pytest.mark.parametrize("budget", [3, 4, 5])
def test_a_small_budget_is_planned_and_beats_the_paper_protocol(budget):
    """Fewer than three +- pairs cannot turn the platform about three axes: single loads, a finite bound."""
    loads = ExperimentLoads.default(RIG)
    loads = ExperimentLoads(loads.weights_N, loads.points_A_m, sphere_directions(16), (25.0, 60.0), 0.15)
    plan = plan_experiment(RIG, budget, loads)
    assert len(plan.protocol) == budget + 1
    # the bound re-settled from the protocol's loads (not the selection's information)
    again = predict_bound(RIG, plan.protocol)[0][0]
    assert np.all(np.linalg.eigvalsh(again) > 0)
    paper = paper_protocol(RIG, budget, np.random.default_rng(0), loads=loads)
    assert np.trace(again) < np.trace(paper.crlb6[0])


def test_a_singular_selection_is_a_design_error(monkeypatch, tmp_path, capsys):
    """An information matrix numpy cannot invert is the library's DesignError (the CLI: one line, exit 2)."""
    import csjm_opt.identification.experiment_design as design

    def singular(*args):
        np.linalg.inv(np.zeros((6, 6)))          # numpy's own failure on a singular matrix

    monkeypatch.setattr(design, "_design_at", singular)
    with pytest.raises(DesignError, match="cannot determine K"):
        plan_experiment(RIG, 6)
    out = tmp_path / "p.csv"
    assert main(["plan-experiment", "--budget", "6", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot determine K" in err[0] and not out.exists()
