"""Bad input to the public functions of identification/, shaping/, measurement/, design/,
control/ and so3 raises the package's own errors (CsjmError), never a bare ValueError,
IndexError, LinAlgError or a backend's RuntimeError."""

from __future__ import annotations

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt import design as ds
from csjm_opt import identification as idf
from csjm_opt import measurement as ms
from csjm_opt import shaping as sh
from csjm_opt.control import load_profiles as lp
from csjm_opt.control import simulate
from csjm_opt.control.controllers import StiffnessShapingController, TensionPlanningController
from csjm_opt.errors import (
    CsjmError,
    DataFileError,
    DesignError,
    IllConditionedData,
    InfeasibleLoad,
    InvalidInput,
    NotARotation,
    RigFileError,
)

RIG = co.paper_rig()
EYE = np.eye(3)
NOT_A_ROTATION = np.diag([1.0, 1.0, 2.0])


def _log(n=3):
    return co.MeasurementLog.from_arrays([0] * n, [np.full(6, 0.15)] * n, np.zeros((n, 3)), np.zeros((n, 3)))


CASES = {
    # identification
    "identify: rows and loads disagree": (lambda m: co.identify_stiffness(EYE[None].repeat(4, 0), np.zeros((3, 3)), m),
                                          InvalidInput),
    "identify: non-finite load": (lambda m: co.identify_stiffness(EYE[None].repeat(5, 0), np.full((5, 3), np.nan), m),
                                  InvalidInput),
    "identify: no displacement": (lambda m: co.identify_stiffness(EYE[None].repeat(5, 0), np.zeros((5, 3)), m),
                                  IllConditionedData),
    "identify: not a rotation": (lambda m: co.identify_stiffness(np.stack([NOT_A_ROTATION] * 5), np.zeros((5, 3)), m),
                                 NotARotation),
    "identify_log: unknown cycle": (lambda m: co.identify_log(_log(), RIG, cycle=5, model=m), DataFileError),
    "predict_pose: singular K": (lambda m: idf.predict_pose(EYE, np.zeros((3, 3)), [1.0, 0.0, 0.0]), InvalidInput),
    "predict_pose: wrong increment": (lambda m: idf.predict_pose(EYE, EYE, [1.0, 0.0]), InvalidInput),
    "predict_pose_external: singular": (lambda m: idf.predict_pose_external(EYE, np.zeros((3, 3)), np.zeros(3),
                                                                            np.zeros(3), m), InvalidInput),
    "estimation_error: wrong shape": (lambda m: idf.estimation_error(EYE, np.ones((3, 2))), InvalidInput),
    # shaping
    "shape: non-finite target": (lambda m: co.shape_stiffness(RIG, EYE, np.zeros(3), np.full((3, 3), np.nan)),
                                 InvalidInput),
    "shape: unknown objective": (lambda m: co.shape_stiffness(RIG, EYE, np.zeros(3), EYE, objective="nope"),
                                 InvalidInput),
    "shape: infeasible load": (lambda m: co.shape_stiffness(RIG, EYE, [50.0, 0.0, 0.0], EYE), InfeasibleLoad),
    "shape: not a rotation": (lambda m: co.shape_stiffness(RIG, NOT_A_ROTATION, np.zeros(3), EYE), NotARotation),
    "reachable: negative samples": (lambda m: sh.reachable_set(RIG, EYE, np.zeros(3), n_samples=-1), InvalidInput),
    "reachable: infeasible load": (lambda m: sh.reachable_set(RIG, EYE, [50.0, 0.0, 0.0]), InfeasibleLoad),
    "directional range: zero direction": (lambda m: sh.directional_stiffness_range(RIG, EYE, np.zeros(3),
                                                                                   np.zeros((1, 3))), InvalidInput),
    # measurement
    "log: ragged arrays": (lambda m: co.MeasurementLog.from_arrays([0, 1], [np.ones(6)], np.zeros((1, 3)),
                                                                   np.zeros((1, 3))), CsjmError),
    "log: wrong header": (lambda m: co.MeasurementLog.from_text("a,b\n1,2\n"), DataFileError),
    "log: missing file": (lambda m: co.MeasurementLog.from_csv("/nonexistent/log.csv"), DataFileError),
    "log: subset out of range": (lambda m: _log(1).subset([5]), InvalidInput),
    "rigid fit: too few points": (lambda m: ms.fit_rigid_transform(np.zeros((2, 3)), np.zeros((2, 3))), CsjmError),
    "rigid fit: shapes differ": (lambda m: ms.fit_rigid_transform(np.zeros((4, 3)), np.zeros((3, 3))), CsjmError),
    "preprocess: empty text": (lambda m: ms.preprocess_text("", RIG), DataFileError),
    "preprocess: missing file": (lambda m: ms.preprocess_file("/nonexistent/raw.csv", RIG), DataFileError),
    # design
    "design: unknown parameter": (lambda m: ds.design_rig({"nope": 1.0}), DesignError),
    "design: non-finite parameter": (lambda m: ds.design_rig({"oo_a_m": float("nan")}), DesignError),
    "design: coincident holes": (lambda m: ds.check_holes(np.zeros((6, 3)), np.zeros((6, 3))), DesignError),
    "design: negative sampling": (lambda m: ds.OrientationSampling(-5), CsjmError),
    "sweep: unknown method": (lambda m: ds.SweepSpec.from_dict({"sweep": {"method": "nope"}}), DesignError),
    "sweep: missing file": (lambda m: ds.SweepSpec.from_toml("/nonexistent/sweep.toml"), CsjmError),
    "sweep: no workers": (lambda m: ds.run_sweep(None, "/nonexistent/x.jsonl", workers=0), DesignError),
    # control
    "simulate: negative step": (lambda m: simulate(RIG, TensionPlanningController(RIG, EYE), lp.Constant(np.zeros(3)),
                                                   0.01, -1.0), InvalidInput),
    "simulate: negative duration": (lambda m: simulate(RIG, TensionPlanningController(RIG, EYE),
                                                       lp.Constant(np.zeros(3)), -1.0, 1e-3), InvalidInput),
    "load profile: non-finite": (lambda m: lp.Step(0.0, [np.nan, 0.0, 0.0]), InvalidInput),
    "ramp: empty interval": (lambda m: lp.Ramp(1.0, 1.0, [0.0, 0.0, 1.0]), InvalidInput),
    "controller: not a rotation": (lambda m: TensionPlanningController(RIG, np.ones((3, 3))), NotARotation),
    "controller: wrong target": (lambda m: StiffnessShapingController(RIG, EYE, np.ones((2, 2))), InvalidInput),
    # model and so3 (the layers below)
    "rig: unknown field": (lambda m: RIG.replace(nope=1.0), InvalidInput),
    "rig: bounds crossed": (lambda m: RIG.replace(t_min_N=500.0), CsjmError),
    "rig: missing file": (lambda m: co.Rig.from_toml("/nonexistent/rig.toml"), RigFileError),
    "so3.exp: not numbers": (lambda m: co.so3.exp("abc"), InvalidInput),
    "so3.exp: wrong shape": (lambda m: co.so3.exp([1.0, 2.0]), InvalidInput),
    "so3.log: wrong shape": (lambda m: co.so3.log(np.ones((2, 2))), InvalidInput),
    "so3.hat: wrong shape": (lambda m: co.so3.hat([1.0, 2.0]), InvalidInput),
    "so3.random_rotations: negative n": (lambda m: co.so3.random_rotations(-1, np.random.default_rng(0)),
                                         InvalidInput),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_bad_input_raises_the_package_error(name, model):
    call, expected = CASES[name]
    with pytest.raises(CsjmError) as info:
        call(model)
    assert isinstance(info.value, expected), f"{type(info.value).__name__}: {info.value}"
    assert str(info.value)                                   # a message a person can read


def test_error_family_is_also_the_builtin_family_where_it_should_be():
    # code that catches ValueError for bad arguments keeps working
    assert issubclass(InvalidInput, ValueError) and issubclass(NotARotation, ValueError)
    for cls in (InfeasibleLoad, IllConditionedData, DesignError, DataFileError, RigFileError):
        assert issubclass(cls, CsjmError)
