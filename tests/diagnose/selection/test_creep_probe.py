"""The creep probe's warning on a creeping rig, and its silence on friction (issue 31: time-dependent faults).

The creeping log is made by the package's forward statics (``co.solve_equilibrium``), not by the
diagnosis's model: row by row, each cable's rest length grows by ``lambda / k_i`` times its solved
tension, restarting every cycle. The friction log comes from the testbed's plant.
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
    d = diagnose(rig, _creeping_log(rig, CREEP_PER_ROW, 6, 3), secondary=False, workers=1)
    creep = d.verdict.creep
    assert d.selected != "none" and creep is not None
    assert creep["percent_per_row"] == pytest.approx(100 * CREEP_PER_ROW, rel=0.2)
    assert any("trends with time (sample order within each cycle)" in w for w in d.verdict.warnings)


def test_friction_is_not_taken_for_creep(rig):
    log = simulate_experiment(rig, 6, np.random.default_rng(4), effect="friction", severity=3.0)
    d = diagnose(rig, log, secondary=False, workers=1)
    assert d.selected == "friction"
    assert d.verdict.creep is None
    assert not any("sample order within each cycle" in w for w in d.verdict.warnings)
