"""The speed work on the diagnosis changes no result: reused fits, remembered band positions, worker processes.

Each shortcut is compared with the direct computation it replaces (a fresh fit, a fresh play operator,
a fresh balance and tangent, a serial diagnosis).
"""

from __future__ import annotations

import numpy as np
import pytest

from csjm_opt.diagnose import diagnose
from csjm_opt.diagnose.data.residuals import compute_residuals
from csjm_opt.diagnose.effects import make_effect
from csjm_opt.diagnose.effects.friction import band_position
from csjm_opt.diagnose.fitting.augmented import AugmentedModel
from csjm_opt.diagnose.fitting.gauss_newton import _linearised, data_jacobian, fit_model
from csjm_opt.diagnose.fitting.pool import map_ordered, resolve_workers
from csjm_opt.diagnose.selection.scoring import score
from csjm_opt.errors import InvalidInput
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.testbed import simulate_experiment


@pytest.fixture(scope="module")
def coulomb_log(rig):
    return simulate_experiment(rig, 2, np.random.default_rng(5), effect="coulomb_friction", severity=4.0,
                               noise=InstrumentNoise.paper(), steps=3)


def _square(k: int, x: int) -> int:
    return k * x * x


def test_map_ordered_returns_results_in_item_order_on_workers():
    ticks = []
    items = list(range(7))
    assert map_ordered(_square, (3,), items, 2, ticks.append) == [3 * x * x for x in items]
    assert sum(ticks) == len(items)


def _started(x: int) -> tuple[int, float]:
    import time
    t = time.monotonic()
    time.sleep(0.2)
    return x, t


def test_map_ordered_starts_the_costliest_calls_first_and_keeps_item_order():
    """On two workers the two costliest items start before any other; results stay in item order."""
    items = list(range(6))
    out = map_ordered(_started, (), items, 2, cost=lambda x: x)
    assert [x for x, _ in out] == items
    start = {x: t for x, t in out}
    assert max(start[4], start[5]) < min(start[x] for x in range(4))


def test_workers_below_one_are_refused():
    with pytest.raises(InvalidInput, match="workers"):
        resolve_workers(0)
    assert resolve_workers(None) >= 1


def test_parallel_diagnosis_equals_serial(rig, coulomb_log):
    """Law: the fits are independent and deterministic, so the worker processes change no number."""
    kw = {"effects": ["friction", "sensor_bias", "mass_com"]}
    serial = diagnose(rig, coulomb_log, workers=1, **kw)
    parallel = diagnose(rig, coulomb_log, workers=2, **kw)
    assert parallel.as_json() == serial.as_json()
    assert serial.pair_scores, "no pair was fitted: the test would not exercise the pair pool"
    assert serial.verdict.selected != "none", "no verdict: the trend probes (on the workers too) did not run"
    for k, sc in serial.pair_scores.items():
        assert parallel.pair_scores[k].fit.rss == sc.fit.rss
        np.testing.assert_array_equal(parallel.pair_scores[k].heldout_zeta_rad, sc.heldout_zeta_rad)


def test_a_reused_fit_scores_as_a_fresh_one(rig, coulomb_log):
    """The variant's fit handed to ``score`` gives what ``score`` fitting on its own gives."""
    table = compute_residuals(rig, coulomb_log)
    folds = [np.flatnonzero(table.cycle == c) for c in np.unique(table.cycle)]
    model = AugmentedModel(rig, [make_effect("sensor_bias", rig), make_effect("friction", rig, law="coulomb")])
    fresh = score(model, table, None, folds)
    reused = score(model, table, None, folds, fit=fit_model(model, table))
    assert reused.fit.rss == fresh.fit.rss
    np.testing.assert_array_equal(reused.heldout_zeta_rad, fresh.heldout_zeta_rad)


def test_remembered_band_positions_equal_fresh_ones(rig, coulomb_log):
    table = compute_residuals(rig, coulomb_log)
    fr = make_effect("friction", rig, law="coulomb")
    rng = np.random.default_rng(0)
    travels = [np.full((len(table), 6), 1e-4), rng.uniform(2e-5, 3e-4, (len(table), 6))]
    for _ in range(2):                             # the second round is answered from memory
        for t in travels:
            for s0 in (0.0, 0.3):
                np.testing.assert_array_equal(fr._band_position(table.rows, t, s0, 0.5),
                                              band_position(table.rows, t, s0, 0.5, True))
    other = compute_residuals(rig, coulomb_log).rows            # same values, another object: recomputed
    np.testing.assert_array_equal(fr._band_position(other, travels[1], 0.3, 0.5),
                                  band_position(other, travels[1], 0.3, 0.5, True))
    # a remembered result is a copy: changing what was returned changes nothing remembered
    s = fr._band_position(table.rows, travels[0], 0.0, 0.5)
    s[:] = 7.0
    np.testing.assert_array_equal(fr._band_position(table.rows, travels[0], 0.0, 0.5),
                                  band_position(table.rows, travels[0], 0.0, 0.5, True))


def test_jacobian_from_the_residuals_balance_and_tangent_equals_a_fresh_one(rig, coulomb_log):
    table = compute_residuals(rig, coulomb_log)
    model = AugmentedModel(rig, [make_effect("friction", rig, law="capstan")])
    theta = model.x0() + np.r_[1e-5, np.full(6, 0.05), 0.0, 0.2]
    _, g0, G = _linearised(model, table, theta)
    np.testing.assert_array_equal(data_jacobian(model, table, theta, (g0, G)), data_jacobian(model, table, theta))


def _default_in_worker(_: int) -> int:
    from csjm_opt.diagnose.fitting.pool import default_workers

    return default_workers()


def test_a_pool_worker_fits_serially_by_default():
    """A study's worker process diagnoses on one core (its pool spreads the logs over the cores)."""
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(1) as ex:
        assert ex.submit(_default_in_worker, 0).result() == 1


def test_soft_clip_equals_its_formula_to_the_last_bit():
    """The shortcut of the softplus (its linear tail not evaluated) changes no bit of the rounded clip."""
    from numba import njit

    from csjm_opt.diagnose.effects.friction import _soft_clip

    @njit
    def formula(x, w):                      # the formula in full, compiled as the package's is
        a, b = (x + 1.0) / w, (x - 1.0) / w
        sp_a = a + np.log1p(np.exp(-a)) if a > 0 else np.log1p(np.exp(a))
        sp_b = b + np.log1p(np.exp(-b)) if b > 0 else np.log1p(np.exp(b))
        return -1.0 + w * sp_a - w * sp_b

    rng = np.random.default_rng(3)
    for w in (0.02 / 8, 0.02, 0.3):
        xs = np.r_[rng.uniform(-3, 3, 4000), rng.normal(1, 5 * w, 2000), rng.normal(-1, 5 * w, 2000),
                   -1 + w * np.linspace(35, 45, 500), 1 + w * np.linspace(35, 45, 500)]
        got = np.array([_soft_clip(float(x), w) for x in xs])
        want = np.array([formula(float(x), w) for x in xs])
        np.testing.assert_array_equal(got, want)


def _fail_on_three(x: int) -> int:
    if x == 3:
        raise ValueError("three")
    return x


def test_an_error_in_a_worker_reaches_the_caller():
    with pytest.raises(ValueError, match="three"):
        map_ordered(_fail_on_three, (), list(range(6)), 2)


def test_the_environment_sets_the_default_workers(monkeypatch):
    from csjm_opt.diagnose.fitting.pool import default_workers

    monkeypatch.setenv("CSJM_WORKERS", "3")
    assert default_workers() == 3
    monkeypatch.setenv("CSJM_WORKERS", "two")
    with pytest.raises(InvalidInput, match="CSJM_WORKERS"):
        default_workers()


def test_remembered_slide_direction_equals_a_fresh_one(rig, coulomb_log):
    """Joint friction keeps its last slide direction while the model hands back the same geometry."""
    import pickle

    table = compute_residuals(rig, coulomb_log)
    model = AugmentedModel(rig, [make_effect("joint_friction", rig)])
    theta = model.x0() + np.r_[1e-5, 0.02]
    g1, ev1 = model.evaluate(table.R_meas, table.rows, theta)
    g2, ev2 = model.evaluate(table.R_meas, table.rows, theta + np.r_[0.0, 0.01])   # same poses: remembered
    assert ev2.cable_jacobian is ev1.cable_jacobian
    fresh = AugmentedModel(rig, [make_effect("joint_friction", rig)])
    np.testing.assert_array_equal(g2, fresh.balance(table.R_meas, table.rows, theta + np.r_[0.0, 0.01]))
    np.testing.assert_array_equal(g1, fresh.balance(table.R_meas, table.rows, theta))
    assert "_last" not in pickle.loads(pickle.dumps(model.effects[0])).__dict__


def test_remembered_geometry_does_not_follow_a_changed_pose_array(rig, coulomb_log):
    """The last poses are a cache key: the caller's array changed in place afterwards is a new pose, not a hit."""
    table = compute_residuals(rig, coulomb_log)
    model = AugmentedModel(rig, [make_effect("mass_com", rig)])
    theta = model.x0()
    R = table.R_meas.copy()
    model.balance(R, table.rows, theta)
    R[:] = np.swapaxes(R, 1, 2)                              # another pose in the same array
    fresh = AugmentedModel(rig, [make_effect("mass_com", rig)])
    np.testing.assert_array_equal(model.balance(R, table.rows, theta), fresh.balance(R, table.rows, theta))


def test_two_logs_predicted_side_by_side_equal_each_alone(rig, coulomb_log):
    """predict_ramps steps the cycles of several logs at once: each log's poses and ramps are its own, bit for bit."""
    from csjm_opt.diagnose.fitting.augmented import with_entry
    from csjm_opt.diagnose.fitting.friction_ramp import predict_ramp, predict_ramps

    table = compute_residuals(rig, coulomb_log)
    other = compute_residuals(rig, simulate_experiment(rig, 3, np.random.default_rng(6), effect="coulomb_friction",
                                                       severity=4.0, noise=InstrumentNoise.paper(), steps=4))
    model = AugmentedModel(rig, [make_effect("friction", rig, None, law="coulomb", memory="carried")])
    theta = fit_model(model, table).theta
    parts = [(with_entry(model, t.rows, t.R_meas, theta), t.R_meas) for t in (table, other)]
    together = predict_ramps(model, parts, theta)
    for (rows, R), (sol, shape) in zip(parts, together):
        alone, alone_shape = predict_ramp(model, rows, theta, R)
        assert np.any(alone_shape != 0.0), "no ramp was predicted: the test checks nothing"
        np.testing.assert_array_equal(sol.R, alone.R)
        np.testing.assert_array_equal(sol.residual_Nm, alone.residual_Nm)
        np.testing.assert_array_equal(shape, alone_shape)
