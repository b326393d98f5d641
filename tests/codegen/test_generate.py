"""Generated C planner (csjm_opt.codegen) against the Python planner, stiffness and model.

The C library is built with the system compiler (-std=c99 -Wall -Wextra -Werror -O2); every
check compares it with code it does not share: the Python planner (plan_tensions_batch and
plan_tensions, whose InfeasibleLoad carries the bounded-least-squares distance),
csjm_opt.stiffness, the numeric model and a finite-difference energy Hessian.
"""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import so3
from csjm_opt.codegen import INFEASIBLE, ITERATION_CAP, NO_FALLBACK, SOLVED, find_compiler, generate_c, load
from csjm_opt.errors import InfeasibleLoad, InvalidInput, NotARotation, SolverError
from csjm_opt.model.joint_stiffness import stiffness_batch
from csjm_opt.model.mjcf import quat_wxyz
from csjm_opt.planning import feasibility_distance_Nm, plan_tensions_batch
from csjm_opt.testbed.rigs import draw_rig
from tests.conftest import cable_energy, fd_hessian

pytestmark = pytest.mark.skipif(find_compiler() is None, reason="no C compiler (cc or $CC) on this machine")


def paper_folder(tmp_path_factory):
    """The paper rig's generated folder, shared by the codegen test modules of this session."""
    out = tmp_path_factory.getbasetemp() / "codegen_paper"
    if not (out / "csjm_rig.h").is_file():
        generate_c(co.paper_rig(), out)
    return out


@pytest.fixture(scope="module")
def paper_lib(tmp_path_factory):
    return load(paper_folder(tmp_path_factory))


def load_scale_Nm(rig) -> float:
    """A moment the rig can nearly hold: the tension range times the mean platform-hole radius."""
    return 0.5 * (rig.t_max_N - rig.t_min_N) * float(np.mean(np.linalg.norm(rig.platform_holes_A_m, axis=1)))


def random_cases(rig, n: int, n_big: int, rng, max_angle: float = 0.8):
    """Random poses and loads: ``n - n_big`` small loads, ``n_big`` large ones (many infeasible)."""
    Rs = so3.random_rotations(n, rng, max_angle=max_angle)
    taus = rng.normal(size=(n, 3))
    radius = np.where(np.arange(n) < n_big, 1.5, 0.3) * load_scale_Nm(rig)
    taus *= (radius * rng.random(n) ** (1 / 3) / np.linalg.norm(taus, axis=1))[:, None]
    return Rs, taus


def check_against_python(rig, lib, Rs, taus):
    """C (cold, one loop) against the Python planner on every row: same status, T, l, distance."""
    c = lib.plan_many(Rs, taus)
    assert set(np.unique(c.status)) <= {SOLVED, INFEASIBLE}
    ok = c.status == SOLVED
    py = plan_tensions_batch(rig, Rs[ok], taus[ok])   # raises InfeasibleLoad if C called a row solved wrongly
    assert np.abs(py.tensions_N - c.tensions_N[ok]).max() <= 1e-9
    assert np.abs(py.rest_lengths_m - c.rest_lengths_m[ok]).max() <= 1e-12
    for i in np.flatnonzero(~ok):                     # the Python planner must also refuse, at the same distance
        with pytest.raises(InfeasibleLoad) as exc:
            co.plan_tensions(rig, Rs[i], taus[i])
        assert exc.value.distance_Nm > 1e-8
        assert c.distance_Nm[i] == pytest.approx(exc.value.distance_Nm, rel=1e-9, abs=1e-12)
    return c


def test_plans_match_python_on_the_paper_rig(paper_lib):
    """10^4 random poses and loads (~0.5 % infeasible): same status, tensions to 1e-9 N, rest lengths
    to 1e-12 m, distance to 1e-9 relative (studies/codegen_equivalence/codegen_equivalence.py runs 10^5 and more)."""
    rig = co.paper_rig()
    Rs, taus = random_cases(rig, 10_000, 200, np.random.default_rng(0))
    c = check_against_python(rig, paper_lib, Rs, taus)
    assert 10 <= np.sum(c.status == INFEASIBLE) <= 150      # the infeasible branch is exercised
    assert np.any(c.iterations >= 3)                         # and the active set does change


@pytest.mark.parametrize("seed", [3, 11])
def test_plans_match_python_on_random_rigs(seed, tmp_path):
    rng = np.random.default_rng(seed)
    rig = draw_rig(rng)
    generate_c(rig, tmp_path)
    lib = load(tmp_path)
    Rs, taus = random_cases(rig, 2000, 80, rng, max_angle=0.5)
    c = check_against_python(rig, lib, Rs, taus)
    assert np.any(c.status == INFEASIBLE) and np.mean(c.status == SOLVED) > 0.9


def test_single_call_is_a_drop_in(paper_lib):
    """plan_tensions returns the Python API's TensionPlan, raises the same errors."""
    rig = co.paper_rig()
    R, tau = so3.exp([0.2, -0.1, 0.3]), np.array([0.4, -0.3, 0.2])
    plan, ref = paper_lib.plan_tensions(R, tau), co.plan_tensions(rig, R, tau)
    assert plan.is_valid() and plan.solver == "c"
    assert np.allclose(plan.tensions_N, ref.tensions_N, rtol=0, atol=1e-9)
    assert np.allclose(plan.J, ref.J, rtol=0, atol=1e-15)
    assert np.allclose(plan.tau_weight_A_Nm, ref.tau_weight_A_Nm, rtol=0, atol=1e-15)
    assert plan.active_bounds == ref.active_bounds
    big = np.array([20.0, -5.0, 3.0])
    with pytest.raises(InfeasibleLoad) as exc:
        paper_lib.plan_tensions(R, big)
    J = co.Model(rig).jacobian(R)
    assert exc.value.distance_Nm == pytest.approx(
        feasibility_distance_Nm(J, big + co.Model(rig).weight_moment(R), rig.t_min_N, rig.t_max_N), rel=1e-9)
    t_ref = np.linspace(40.0, 90.0, 6)
    assert np.allclose(paper_lib.plan_tensions(R, tau, t_ref).tensions_N,
                       co.plan_tensions(rig, R, tau, t_ref).tensions_N, rtol=0, atol=1e-9)


def test_bad_input_raises_the_package_errors(paper_lib):
    R = so3.exp([0.1, 0.2, 0.0])
    with pytest.raises(NotARotation):
        paper_lib.plan_tensions(2.0 * R)
    with pytest.raises(InvalidInput):
        paper_lib.plan_tensions(R, [np.nan, 0.0, 0.0])
    with pytest.raises(InvalidInput):
        paper_lib.plan_tensions(np.eye(4))
    with pytest.raises(InvalidInput):
        paper_lib.plan_tensions_q([1.0, 0.1, 0.0, 0.0])           # norm 1.005: not a unit quaternion
    with pytest.raises(InvalidInput):
        paper_lib.plan_tensions_q([np.nan, 0.0, 0.0, 1.0])


def test_near_rotations_are_projected_as_python_does(paper_lib):
    """A rotation off by 1e-6 is replaced by its polar factor (Python: SVD U V^T) in both."""
    rig = co.paper_rig()
    R = so3.exp([0.3, -0.2, 0.1]) + 1e-6 * np.random.default_rng(5).normal(size=(3, 3))
    plan, ref = paper_lib.plan_tensions(R, [0.1, 0.2, -0.1]), co.plan_tensions(rig, R, [0.1, 0.2, -0.1])
    assert np.allclose(plan.R, ref.R, rtol=0, atol=1e-15)
    assert np.allclose(plan.tensions_N, ref.tensions_N, rtol=0, atol=1e-9)


def test_quaternion_entry_points_agree_with_rotations(paper_lib):
    rng = np.random.default_rng(2)
    for R in so3.random_rotations(20, rng, max_angle=0.7):
        tau = 0.3 * rng.normal(size=3)
        a, b = paper_lib.plan_tensions_q(quat_wxyz(R), tau), paper_lib.plan_tensions(R, tau)
        assert np.allclose(a.tensions_N, b.tensions_N, rtol=0, atol=1e-9)


def test_pose_terms_match_the_model(paper_lib):
    model = co.Model(co.paper_rig())
    for R in so3.random_rotations(10, np.random.default_rng(4)):
        c, J, w = paper_lib.pose_terms(R)
        assert np.allclose(c, model.cable_lengths(R), rtol=0, atol=1e-15)
        assert np.allclose(J, model.jacobian(R), rtol=0, atol=1e-15)
        assert np.allclose(w, model.weight_moment(R), rtol=0, atol=1e-14)


def test_stiffness_matches_python_and_the_energy_hessian(paper_lib):
    """K (CasADi's generated C) against csjm_opt.stiffness on 2000 poses to 1e-9 relative, slack cables
    included, and against a finite-difference Hessian of the cable energy at one pose."""
    rig = co.paper_rig()
    rng = np.random.default_rng(6)
    Rs = so3.random_rotations(2000, rng, max_angle=0.8)
    T = rng.uniform(rig.t_min_N, rig.t_max_N, (2000, 6))
    T[::7, 2] = 0.0                       # a slack cable contributes nothing
    K_c = paper_lib.stiffness_many(Rs, T)
    K_py = stiffness_batch(rig, Rs, T, check_bounds=False)
    assert np.max(np.abs(K_c - K_py) / np.abs(K_py).max(axis=(1, 2))[:, None, None]) <= 1e-9
    R = so3.exp([0.2, 0.1, -0.15])
    T1 = T[1]
    rest = co.Model(rig).cable_lengths(R) - T1 / rig.cable_stiffness_N_per_m
    H = fd_hessian(lambda z: cable_energy(rig, R @ so3.exp(z), rest))
    assert np.allclose(paper_lib.stiffness(R, T1), H, rtol=1e-5, atol=1e-5 * np.abs(H).max())
    with pytest.raises(InvalidInput):
        paper_lib.stiffness(R, np.full(6, 1e4))     # outside the bounds, as csjm_opt.stiffness refuses


def smooth_trajectory(rig, dt_s: float, duration_s: float = 2.0):
    """A 0.5 Hz tilt-and-torsion with a load sweeping to 0.45 of the load scale (bounds become active)."""
    t = np.arange(0.0, duration_s, dt_s)
    s = np.sin(np.pi * t)
    Rs = so3.exp(np.c_[np.radians(15) * s, np.radians(-10) * np.sin(0.5 * np.pi * t), np.radians(20) * s])
    a = 0.45 * load_scale_Nm(rig)
    taus = a * np.c_[np.sin(2 * np.pi * 0.7 * t), np.cos(2 * np.pi * 0.4 * t), 0.3 * np.sin(2 * np.pi * 0.2 * t)]
    return Rs, taus


def test_warm_start_along_a_trajectory(paper_lib):
    """Warm-started along a smooth trajectory at 1 kHz: the same tensions as cold solves and as Python,
    mostly one iteration a step, and continuous: halving the step halves the largest change."""
    rig = co.paper_rig()
    Rs, taus = smooth_trajectory(rig, 1e-3)
    warm, cold = paper_lib.plan_many(Rs, taus, warm_start=True), paper_lib.plan_many(Rs, taus)
    assert np.all(warm.status == SOLVED) and np.all(cold.status == SOLVED)
    assert np.abs(warm.tensions_N - cold.tensions_N).max() <= 1e-9
    assert np.abs(warm.tensions_N - plan_tensions_batch(rig, Rs, taus).tensions_N).max() <= 1e-9
    at_bound = (np.abs(warm.tensions_N - rig.t_min_N) < 1e-9) | (np.abs(warm.tensions_N - rig.t_max_N) < 1e-9)
    assert np.any(at_bound.any(axis=1)) and np.any(at_bound[1:] != at_bound[:-1])   # the active set changes
    assert np.mean(warm.iterations == 1) > 0.95 and np.mean(warm.iterations) < np.mean(cold.iterations)
    step_1k = np.abs(np.diff(warm.tensions_N, axis=0)).max()
    Rs2, taus2 = smooth_trajectory(rig, 5e-4)
    step_2k = np.abs(np.diff(paper_lib.plan_many(Rs2, taus2, warm_start=True).tensions_N, axis=0)).max()
    assert 1.8 <= step_1k / step_2k <= 2.2                  # Lipschitz in time: no jumps


def test_exhaustive_fallback_and_the_iteration_cap(paper_lib):
    """With one active-set iteration allowed, the rows it does not settle are solved by the exhaustive
    KKT search to the Python planner's answer; with NO_FALLBACK they report the iteration cap instead."""
    rig = co.paper_rig()
    Rs, taus = random_cases(rig, 3000, 0, np.random.default_rng(8))
    keep = paper_lib.plan_many(Rs, taus).status == SOLVED
    Rs, taus = Rs[keep], taus[keep]
    one = paper_lib.plan_many(Rs, taus, max_iter=1)
    forced = one.fallback == 1
    assert forced.sum() > 100 and np.all(one.status == SOLVED)
    py = plan_tensions_batch(rig, Rs[forced], taus[forced])
    assert np.abs(one.tensions_N[forced] - py.tensions_N).max() <= 1e-9
    capped = paper_lib.plan_many(Rs, taus, max_iter=1 + NO_FALLBACK)
    assert np.all(capped.status[forced] == ITERATION_CAP) and np.all(capped.status[~forced] == SOLVED)
    with pytest.raises(SolverError):
        paper_lib.plan_tensions(Rs[forced][0], taus[forced][0], max_iter=1 + NO_FALLBACK)
