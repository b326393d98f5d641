"""Physical-parameter fit: recover per-cable stiffness and rest-length offsets, predict unseen poses."""

import numpy as np
import pytest

from csjm_opt.errors import IllConditionedData
from csjm_opt.identification.param_fit import check_fit, fit_parameters
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.testbed.scripted import add_noise, load_directions, simulate_log

K_TRUE = np.array([4300.0, 4700.0, 4500.0, 4900.0, 4400.0, 4800.0])
DL_TRUE = np.array([0.4, -0.3, 0.2, 0.0, -0.5, 0.3]) * 1e-3


def make_log(rig, n_cycles, seed, n_loads=8):
    """Log of the TRUE rig; commanded rest lengths are the true ones minus DL_TRUE."""
    true_rig = rig.replace(cable_stiffness_N_per_m=K_TRUE)
    rng = np.random.default_rng(seed)
    cycles = [(rng.normal(size=3) * 0.12, rng.normal(size=3) * 0.3, load_directions(n_loads, rng) * 0.8)
              for _ in range(n_cycles)]
    log, _ = simulate_log(true_rig, cycles)
    return MeasurementLog.from_arrays(log.cycle, log.rest_lengths_m - DL_TRUE, log.tau_ext_A_Nm, log.R)


@pytest.fixture(scope="module")
def train_test(rig):
    return make_log(rig, 4, 0), make_log(rig, 2, 1, n_loads=5)


def test_recovers_per_cable_stiffness_and_offsets(rig, train_test):
    train, test = train_test
    fit = fit_parameters(train, rig)
    np.testing.assert_allclose(fit.rig.cable_stiffness_N_per_m, K_TRUE, rtol=1e-6)
    np.testing.assert_allclose(fit.rest_length_offsets_m, DL_TRUE, atol=1e-9)
    assert fit.residual_rms_Nm < 1e-8 < fit.initial_residual_rms_Nm
    # the fitted model predicts poses it has not seen (forward statics)
    assert check_fit(fit, test)["heldout_max_rad"] < 1e-7
    # while the nominal rig does not
    nominal = fit_parameters(train, rig, rest_length_offsets=False, shared_stiffness=True)
    assert check_fit(nominal, test)["heldout_rms_rad"] > 1e-3


def test_uncertainties_with_instrument_noise(rig, train_test):
    train, test = train_test
    noise = InstrumentNoise.paper()
    z = []
    for seed in range(6):
        noisy = add_noise(train, noise, np.random.default_rng(seed))
        fit = fit_parameters(noisy, rig, noise=noise)
        truth = np.r_[K_TRUE, DL_TRUE]
        z.append((fit.values - truth) / fit.std)
    z = np.array(z)
    assert np.all(np.abs(z) < 5)
    assert 0.3 < np.sqrt(np.mean(z ** 2)) < 2.0
    assert set(fit.summary()["parameters"]) == {*(f"k{i}" for i in range(1, 7)), *(f"dl{i}" for i in range(1, 7))}


def test_too_few_rows(rig, train_test):
    train, _ = train_test
    with pytest.raises(IllConditionedData):
        fit_parameters(train.subset(np.arange(3)), rig)
