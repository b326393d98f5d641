"""The numba-free single plan of ``csjm plan`` against Clarabel and against the compiled planner.

Clarabel (an interior-point QP solver) solves a problem built here from scipy's rotations
(tests/model/test_n_cables.py); the compiled planner is a second implementation of the same
method. Rigs of 4 to 12 cables from their pattern.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import csjm_opt as co
from csjm_opt.model.rig import Rig
from csjm_opt.planning.one_shot import plan_tensions_uncompiled, solve_active_set
from tests.model.test_n_cables import M_VALUES, _independent_qp, rig_data

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("m", M_VALUES)
def test_uncompiled_plan_is_optimal_and_equals_the_compiled_one(m):
    rig = Rig.from_dict(rig_data(m), path=f"rig{m}.toml")
    rng = np.random.default_rng(100 + m)
    n_feasible = n_settled = n_active = n_infeasible = 0
    for _ in range(80):
        R = Rotation.from_rotvec(rng.normal(size=3) * 0.15).as_matrix()
        tau = rng.normal(size=3) * rng.choice([0.3, 3.0, 10.0])
        sol, t_ref = _independent_qp(rig, R, tau)
        try:
            compiled = co.plan_tensions(rig, R, tau)
        except co.InfeasibleLoad:
            with pytest.raises(co.InfeasibleLoad):
                plan_tensions_uncompiled(rig, R, tau)
            n_infeasible += 1
            continue
        plan = plan_tensions_uncompiled(rig, R, tau)
        n_feasible += 1
        assert plan.is_valid()
        assert np.allclose(plan.tensions_N, compiled.tensions_N, rtol=0, atol=1e-9)
        assert np.allclose(plan.rest_lengths_m, compiled.rest_lengths_m, rtol=0, atol=1e-12)
        f, f_ref = 0.5 * np.sum((plan.tensions_N - t_ref) ** 2), 0.5 * np.sum((sol.x - t_ref) ** 2)
        assert sol.found and abs(f - f_ref) <= 1e-9 * max(f_ref, 1.0)
        # the NumPy method itself settled (the hand-over to the compiled planner is for the rest)
        J = plan.J
        T = solve_active_set(J, -plan.tau_load_A_Nm, t_ref, rig.t_min_N, rig.t_max_N)
        if T is not None:
            n_settled += 1
            n_active += bool(plan.active_bounds)
            assert np.allclose(T, compiled.tensions_N, rtol=0, atol=1e-9)
    assert n_settled >= 0.9 * n_feasible and n_active >= 3 and n_infeasible >= 1


def test_uncompiled_plan_takes_a_reference_tension_and_validates_like_the_compiled_one():
    rig = co.paper_rig()
    R = co.so3.exp(np.array([0.1, -0.05, 0.0]))
    for t_ref in (40.0, np.linspace(30, 90, 6)):
        assert np.allclose(plan_tensions_uncompiled(rig, R, [0.2, 0, 0], t_ref).tensions_N,
                           co.plan_tensions(rig, R, [0.2, 0, 0], t_ref_N=t_ref).tensions_N, atol=1e-9)
    with pytest.raises(co.CsjmError, match="rotation"):
        plan_tensions_uncompiled(rig, 2.0 * R)
    with pytest.raises(co.CsjmError, match="tau_ext"):
        plan_tensions_uncompiled(rig, R, [np.nan, 0, 0])


def test_csjm_plan_loads_no_numerical_library_beyond_numpy():
    code = ("import sys; from csjm_opt.cli import main; assert main(['plan', '--rotvec', '0.1', '-0.05', '0']) == 0; "
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'numba', 'scipy', 'casadi', 'qpsolvers', "
            "'matplotlib', 'mujoco', 'dask'}))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert res.stdout.strip().splitlines()[-1] == "[]"
