"""Shared builders for the tests."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")   # the tests write figures to files only (the library never picks a backend)
# pytest-xdist already runs the tests on every core: a diagnosis runs its fits serially here
# (tests that check the parallel path pass ``workers=`` explicitly).
os.environ.setdefault("CSJM_WORKERS", "1")

import csjm_opt as co  # noqa: E402

#: Code that compiles (and caches, numba ``cache=True``) the compiled kernels, split in two
#: halves that compile in parallel; see :func:`pytest_configure`.
_WARM_UP = (
    "import csjm_opt as co, numpy as np\n"
    "rig = co.paper_rig(); R = co.so3.exp([0.1, 0.0, 0.0])\n"
    "co.plan_tensions(rig, R, [0.1, 0.0, 0.0]); co.plan_tensions_batch(rig, np.stack([R, R]))\n"
    "Rs = co.so3.random_rotations(5000, np.random.default_rng(0), max_angle=0.2)\n"  # parallel kernels
    "co.stiffness_batch(rig, Rs, co.plan_tensions_batch(rig, Rs).tensions_N)\n"
    "from csjm_opt.design.feasibility import wrench_margin_Nm\n"
    "wrench_margin_Nm(co.Model(rig).jacobian(Rs[:2]), np.zeros((2, 3)), 5.0, 150.0)\n",
    "import csjm_opt as co, numpy as np\n"
    "from csjm_opt.control.closed_loop import simulate\n"
    "from csjm_opt.control.controllers import StiffnessShapingController\n"
    "from csjm_opt.control.load_profiles import Constant\n"
    "rig = co.paper_rig(); R = co.so3.exp([0.1, 0.0, 0.0])\n"
    "p = co.plan_tensions(rig, R)\n"
    "co.solve_equilibrium(rig, co.rest_lengths_for(rig, R, p.tensions_N), R_init=R)\n"
    "K = co.stiffness(rig, R, p.tensions_N)\n"
    "simulate(rig, StiffnessShapingController(rig, R, K), Constant(np.zeros(3)), 0.002, 1e-3)\n"
    "co.MeasurementLog.from_text('sample,cycle,l1,l2,l3,l4,l5,l6,tau_x,tau_y,tau_z,rx,ry,rz\\n'\n"
    "                            '0,0,.1,.1,.1,.1,.1,.1,0,0,0,0,0,0\\n1,0,.1,.1,.1,.1,.1,.1,0.5,0,0,1e-3,0,0\\n')\n",
)


def pytest_configure(config: pytest.Config) -> None:
    """Compile the numba kernels once, before the xdist workers start.

    On a fresh clone every worker (and every ``csjm`` subprocess a CLI test starts) would
    otherwise compile the same kernels itself; compiled here, in two parallel processes,
    they are loaded from numba's cache by everyone else. A no-op in the workers, and cheap
    when the cache is already warm. Failures are left to the tests to report.
    """
    if hasattr(config, "workerinput") or os.environ.get("CSJM_NO_WARM_UP"):
        return
    root = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [root, os.environ.get("PYTHONPATH")])))
    procs = [subprocess.Popen([sys.executable, "-c", code], cwd=root, env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for code in _WARM_UP]
    for proc in procs:
        proc.wait()

#: Table 3's original pose R0 with errata item 3 applied (element (3,2) = -0.300).
R0_CORRECTED = np.array([[0.992, -0.060, -0.111],
                         [0.090, 0.952, 0.292],
                         [0.088, -0.300, 0.950]])
#: Table 3's pre-load (total load on the platform, N m, in {A}).
TAU0_TABLE3 = np.array([-0.06, -3.08, 1.07])


@pytest.fixture(scope="session")
def rig() -> co.Rig:
    return co.paper_rig()


@pytest.fixture(scope="session")
def model(rig) -> co.Model:
    return co.Model(rig)


def cable_energy(rig: co.Rig, R: np.ndarray, rest_lengths: np.ndarray) -> float:
    """Phi = sum 1/2 k (c - l)^2 over taut cables, written from scratch (no package code)."""
    A = np.asarray(rig.platform_holes_A_m)
    B = np.asarray(rig.base_holes_B_m)
    c = np.linalg.norm(B - A @ R.T, axis=1)
    stretch = np.maximum(c - rest_lengths, 0.0)
    return float(0.5 * np.sum(rig.cable_stiffness_N_per_m * stretch**2))


def rodrigues(w: np.ndarray) -> np.ndarray:
    """exp(hat(w)) written from scratch for the tests (w not tiny)."""
    th = np.linalg.norm(w)
    if th < 1e-12:
        return np.eye(3)
    k = w / th
    Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * Kx + (1 - np.cos(th)) * Kx @ Kx


def fd_hessian(f, h: float = 1e-4) -> np.ndarray:
    """Central finite-difference Hessian of f(zeta) at zeta = 0 (3x3, symmetric by construction)."""
    E = np.eye(3)
    H = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            H[i, j] = (f(h * E[i] + h * E[j]) - f(h * E[i] - h * E[j])
                       - f(-h * E[i] + h * E[j]) + f(-h * E[i] - h * E[j])) / (4 * h * h)
    return H


def fd_gradient(f, h: float = 1e-6) -> np.ndarray:
    E = np.eye(3)
    return np.array([(f(h * E[i]) - f(-h * E[i])) / (2 * h) for i in range(3)])
