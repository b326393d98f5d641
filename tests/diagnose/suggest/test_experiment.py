"""--suggest and --extra: load sets, feasible candidate rows, the design, appended rows (issue 20)."""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.diagnose import diagnose
from csjm_opt.diagnose.data.extra import append_log, check_rows_belong
from csjm_opt.diagnose.suggest.dead_weights import DeadWeight, default_dead_weights, read_dead_weights
from csjm_opt.diagnose.suggest.experiment import (
    PROTOCOL_COLUMNS,
    candidate_cycles,
    protocol_text,
    suggest_experiment,
)
from csjm_opt.errors import InvalidInput
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.model import kinematics as kin
from csjm_opt.model.rig import paper_rig
from csjm_opt.testbed import random_rig, simulate_experiment


@pytest.fixture(scope="module")
def rig():
    return paper_rig()


def test_load_set_file_errors_name_the_key(tmp_path):
    p = tmp_path / "loads.toml"
    p.write_text('[[load]]\nname = "a"\nmass_kg = 0.2\npoint_A_m = [0.05, 0.0, 0.0]\n')
    (ld,) = read_dead_weights(p)
    assert ld.mass_kg == 0.2 and ld.point_A_m == (0.05, 0.0, 0.0)
    p.write_text('[[load]]\nmass_kg = -1\npoint_A_m = [0.05, 0.0, 0.0]\n')
    with pytest.raises(InvalidInput, match="mass_kg"):
        read_dead_weights(p)
    p.write_text('[[load]]\nmass_kg = 1\npoint_A_m = [0.05, 0.0]\n')
    with pytest.raises(InvalidInput, match="point_A_m"):
        read_dead_weights(p)
    p.write_text('[[load]]\nmass = 1\n')
    with pytest.raises(InvalidInput, match="unknown key"):
        read_dead_weights(p)


def test_load_moment_is_point_cross_weight(rig):
    """tau = p x (R^T m g): checked against the weight moment of a point mass the model computes."""
    ld = DeadWeight("x", 0.3, (0.04, -0.02, 0.01))
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    want = kin.weight_moment(R[None], 0.3 * np.array(ld.point_A_m), np.asarray(rig.gravity_B_m_per_s2))[0]
    np.testing.assert_allclose(ld.moment_A_Nm(R, rig.gravity_B_m_per_s2), want, atol=1e-12)


def test_candidate_rows_are_equilibria_within_tension_bounds(rig):
    """Every planned row balances (J^T T + tau_ext + tau_w = 0, T = k (c - l)) with tensions in bounds."""
    cands = candidate_cycles(rig, default_dead_weights(rig), np.random.default_rng(0), n=4)
    assert len(cands) == 4
    k = np.asarray(rig.cable_stiffness_N_per_m)
    mr = rig.platform_mass_kg * np.asarray(rig.com_A_m)
    for c in cands:
        assert c["loads"][0] is None and c["loads"][-1] is None and any(ld is not None for ld in c["loads"])
        lengths, J = kin.cable_terms(c["R"], np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
        T = k * (lengths - c["rest_lengths_m"])
        assert T.min() >= rig.t_min_N - 1e-6 and T.max() <= rig.t_max_N + 1e-6
        g = np.einsum("nij,ni->nj", J, T) + c["tau"] + kin.weight_moment(c["R"], mr, np.asarray(rig.gravity_B_m_per_s2))
        assert np.abs(g).max() < 1e-6


def test_a_load_set_the_rig_cannot_hold_is_refused(rig):
    with pytest.raises(InvalidInput, match="cannot hold"):
        candidate_cycles(rig, [DeadWeight("anvil", 500.0, (0.05, 0.0, 0.0))], np.random.default_rng(0), n=2,
                         max_tries=5)


def test_extra_rows_from_another_rig_are_refused(rig):
    log = simulate_experiment(rig, 2, np.random.default_rng(1), steps=2)
    other, _ = random_rig(np.random.default_rng([1234, 3]))
    foreign = simulate_experiment(other, 2, np.random.default_rng(2), steps=2)
    check_rows_belong(rig, log, "own")
    with pytest.raises(InvalidInput, match="another rig"):
        append_log(rig, log, foreign)
    both = append_log(rig, log, simulate_experiment(rig, 2, np.random.default_rng(3), steps=2))
    assert len(both) == 2 * len(log) and both.cycle_ids == [0, 1, 2, 3]


def test_suggestion_separates_lookalikes_within_the_row_budget(rig):
    """A constant moment and a tracker rotation look alike over small tilts; the suggested rows (larger
    tilts, hung weights) separate the two fits far more than the log does, within the budget."""
    log = simulate_experiment(rig, 3, np.random.default_rng(4), effect="sensor_bias", severity=2.0,
                              noise=InstrumentNoise.paper(), steps=2)
    d = diagnose(rig, log, effects=["sensor_bias", "tracker_registration"], secondary=False)
    s = suggest_experiment(rig, d, 20, seed=1)
    if s is None:           # the log told them apart after all: nothing to suggest
        assert not d.verdict.alternatives
        return
    assert len(s.cycle) <= 20 and len(np.unique(s.cycle)) >= 1 and s.cycle.min() > max(log.cycle)
    key = next(iter(s.separation_sd))
    assert s.separation_sd[key] > s.separation_before_sd[key]
    text = protocol_text(s).splitlines()
    assert text[0] == PROTOCOL_COLUMNS and len(text) == len(s.cycle) + 1
    cols = text[1].split(",")
    assert cols[8:14] == [""] * 6                                # measured columns left empty


def test_default_loads_reach_the_moment_the_log_applied(rig):
    """The heaviest default load exerts the given moment with its lever horizontal (|p x m g| = reach)."""
    reach = 2.4
    loads = default_dead_weights(rig, reach)
    g = np.asarray(rig.gravity_B_m_per_s2)
    top = max(np.linalg.norm(ld.moment_A_Nm(np.eye(3), g)) for ld in loads)
    assert top == pytest.approx(reach, rel=1e-9)
    assert {ld.mass_kg for ld in default_dead_weights(rig)} == {0.1, 0.2, 0.5}      # no moment given: the defaults


def test_extra_rows_are_cycles_of_their_own_in_time_order(rig):
    """The extra log's cycles follow the log's in the order they were run, whatever their ids."""
    log = simulate_experiment(rig, 2, np.random.default_rng(1), steps=1)
    more = simulate_experiment(rig, 3, np.random.default_rng(2), steps=1)
    ids = np.repeat([7, 3, 9], 3)                                 # run in this order
    more = type(more).from_arrays(ids, more.rest_lengths_m, more.tau_ext_A_Nm, more.R)
    both = append_log(rig, log, more)
    assert both.cycle[len(log):].tolist() == [2, 2, 2, 3, 3, 3, 4, 4, 4]
    np.testing.assert_array_equal(both.rest_lengths_m[len(log):], more.rest_lengths_m)


def test_suggested_rows_show_the_effect_not_only_the_lookalike_difference(rig):
    """On a short link-compliance log the two compliance explanations are near each other; the rows
    (simulated noise-free on the same plant after the log, dead weights) must still show the effect
    itself: the nominal model misses them by more than a noise floor (about 2 here, 1.5 on the log's own
    cycles; rows designed only to tell the two apart, with 0.1-0.5 kg weights, showed 0.3)."""
    noise = InstrumentNoise.paper()
    log = simulate_experiment(rig, 3, np.random.default_rng(5), effect="link_compliance", severity=1.0,
                              noise=noise, steps=2)
    d = diagnose(rig, log, effects=["link_compliance", "stiffness_scale"])
    s = suggest_experiment(rig, d, 30, seed=2)
    assert s is not None and s.hypotheses[-1] == "none" and len(s.cycle) <= 30
    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.testbed import simulate_protocol

    rows = simulate_protocol(rig, protocol_text(s), "link_compliance", 1.0, rng=np.random.default_rng(5),
                             noise=InstrumentNoise.none(), after=log)
    floor = compute_residuals(rig, log, noise).instrument_floor_rad
    assert compute_residuals(rig, rows, noise).rms_rad > floor


def test_a_cycle_a_hypothesis_puts_slack_in_the_rig_files_model_is_not_suggested(rig):
    """A cycle where one hypothesis predicts a pose at which a cable of the rig file's model is slack is not used.

    The candidate cycles' own poses are the nominal ones (every cable taut, ``candidate_cycles``); a hypothesis
    that turns a cycle's poses about {A}'s z axis until some cable is shorter than its rest length (checked from
    the cable lengths here, so the case is what it says) makes that cycle unusable. When no cycle is usable,
    all are.
    """
    from csjm_opt import so3
    from csjm_opt.diagnose.suggest.experiment import _usable

    holes = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    cands = candidate_cycles(rig, default_dead_weights(rig), np.random.default_rng(2), n=2)
    R = np.concatenate([c["R"] for c in cands])
    rest = np.concatenate([np.repeat(c["rest_lengths_m"][None], len(c["loads"]), 0) for c in cands])
    bounds = np.cumsum([0] + [len(c["loads"]) for c in cands])

    def slackened(cycles):
        """``R`` with the rows of ``cycles`` turned by the smallest angle that leaves a cable slack in each."""
        out = R.copy()
        for j in cycles:
            rows = slice(bounds[j], bounds[j + 1])
            for angle in np.linspace(0.01, 1.0, 100):
                out[rows] = so3.exp([0.0, 0.0, angle]) @ R[rows]
                if np.any(kin.cable_terms(out[rows], *holes)[0] < rest[rows]):
                    break
            assert np.any(kin.cable_terms(out[rows], *holes)[0] < rest[rows])
        return out

    assert np.all(kin.cable_terms(R, *holes)[0] > rest)
    assert list(_usable(rig, rest, [R], bounds)) == [True, True]
    assert list(_usable(rig, rest, [R, slackened([1])], bounds)) == [True, False]
    assert list(_usable(rig, rest, [slackened([0, 1])], bounds)) == [True, True]
