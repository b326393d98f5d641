"""The creep and drum-slip probes' warnings on such rigs, and their silence on friction (issue 31).

The creeping and slipping logs are made by the package's forward statics (``co.solve_equilibrium``), not
by the diagnosis's model: row by row, each cable's rest length grows by ``lambda / k_i`` times its solved
tension (creep), or by ``c_slip`` times its solved tension's excess over a threshold after the row settles
(slip), restarting every cycle. The friction log comes from the testbed's plant.
"""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt.diagnose import diagnose
from csjm_opt.measurement.instruments import InstrumentNoise
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.testbed.simulate import simulate_experiment

CREEP_PER_ROW = 0.01
#: the candidates a creeping or slipping log is taken for (friction's path, tension laws): the probes are fitted
#: beside any verdict, so a few keep the tests fast
FEW = ["friction", "cable_hardening", "stiffness_scale", "sensor_bias", "joint_friction"]


def _creeping_log(rig, lam, n_cycles, seed):
    rng = np.random.default_rng(seed)
    proto = simulate_experiment(rig, n_cycles, rng, noise=InstrumentNoise.none())
    l, tau, cyc, R0 = proto.rest_lengths_m, proto.tau_ext_A_Nm, np.asarray(proto.cycle), proto.R
    k = np.asarray(rig.cable_stiffness_N_per_m)
    R = np.empty_like(R0)
    grown = np.zeros(l.shape[1])
    for i in range(len(l)):
        if i == 0 or cyc[i] != cyc[i - 1]:
            grown = np.zeros(l.shape[1])          # re-tensioned between cycles
        T = co.solve_equilibrium(rig, l[i] + grown, tau[i], R_init=R0[i]).tensions_N
        for _ in range(3):                        # the row's own creep: a fixed point of its tension
            eq = co.solve_equilibrium(rig, l[i] + grown + lam / k * T, tau[i], R_init=R0[i])
            T = eq.tensions_N
        grown = grown + lam / k * T
        R[i] = eq.R
    tau_m, R_m = InstrumentNoise.paper().sample(tau, R, rng)
    return MeasurementLog.from_arrays(cyc, l, tau_m, R_m)


def test_a_creeping_rig_is_warned_about_and_its_rate_found(rig):
    d = diagnose(rig, _creeping_log(rig, CREEP_PER_ROW, 6, 3), effects=FEW, secondary=False, workers=1)
    creep = d.verdict.creep
    assert d.selected != "none" and creep is not None
    assert creep["percent_per_row"] == pytest.approx(100 * CREEP_PER_ROW, rel=0.2)
    assert any("trends with time (sample order within each cycle)" in w for w in d.verdict.warnings)


def _slipping_log(rig, share, quantile, n_cycles, seed):
    rng = np.random.default_rng(seed)
    proto = simulate_experiment(rig, n_cycles, rng, noise=InstrumentNoise.none())
    l, tau, cyc, R0 = proto.rest_lengths_m, proto.tau_ext_A_Nm, np.asarray(proto.cycle), proto.R
    k = np.asarray(rig.cable_stiffness_N_per_m)
    T_nominal = np.array([co.solve_equilibrium(rig, li, ti, R_init=Ri).tensions_N for li, ti, Ri in zip(l, tau, R0)])
    threshold = float(np.quantile(T_nominal, quantile))
    R = np.empty_like(R0)
    slipped = np.zeros(l.shape[1])
    for i in range(len(l)):
        if i == 0 or cyc[i] != cyc[i - 1]:
            slipped = np.zeros(l.shape[1])        # the drives re-home between cycles
        eq = co.solve_equilibrium(rig, l[i] + slipped, tau[i], R_init=R0[i])
        R[i] = eq.R
        slipped = slipped + share / k * np.maximum(eq.tensions_N - threshold, 0.0)   # after the row settles
    tau_m, R_m = InstrumentNoise.paper().sample(tau, R, rng)
    return MeasurementLog.from_arrays(cyc, l, tau_m, R_m), threshold


def test_a_slipping_rig_is_warned_about_and_its_threshold_found(rig):
    log, threshold = _slipping_log(rig, 0.5, 0.8, 6, 5)
    d = diagnose(rig, log, effects=FEW, secondary=False, workers=1)
    slip = d.verdict.drum_slip
    assert d.selected != "none" and slip is not None
    assert slip["slip_threshold_N"] == pytest.approx(threshold, rel=0.25)
    assert any("cables slipping on their drums" in w for w in d.verdict.warnings)


def test_friction_is_not_taken_for_creep_or_slip(rig):
    log = simulate_experiment(rig, 6, np.random.default_rng(4), effect="friction", severity=3.0)
    d = diagnose(rig, log, secondary=False, workers=1)
    assert d.selected == "friction"
    assert d.verdict.creep is None and d.verdict.drum_slip is None
    assert not any("sample order within each cycle" in w for w in d.verdict.warnings)
