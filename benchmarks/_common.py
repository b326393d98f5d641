"""Shared bits of the benchmark scripts: timing and the 'what a user would write' baselines."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np
from scipy.optimize import minimize


def median_time(fn: Callable[[], object], repeat: int = 30, warmup: int = 3) -> float:
    """Median wall time of ``fn()`` in seconds."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def numpy_jacobian(A: np.ndarray, B: np.ndarray, R: np.ndarray) -> np.ndarray:
    """J of (38) the way a user would write it: rows a_i x (R^T u_i)."""
    c = B - A @ R.T
    u = c / np.linalg.norm(c, axis=1, keepdims=True)
    return np.cross(A, u @ R)


def numpy_weight_moment(m: float, r: np.ndarray, g: np.ndarray, R: np.ndarray) -> np.ndarray:
    return m * np.cross(r, R.T @ g)


def slsqp_plan(rig, R: np.ndarray, tau_ext: np.ndarray) -> np.ndarray:
    """Baseline planner: numpy J plus scipy SLSQP on the same QP."""
    J = numpy_jacobian(rig.platform_holes_A_m, rig.base_holes_B_m, R)
    tau_load = tau_ext + numpy_weight_moment(rig.platform_mass_kg, rig.com_A_m, rig.gravity_B_m_per_s2, R)
    t_ref = rig.t_mid_N
    res = minimize(lambda t: 0.5 * np.sum((t - t_ref) ** 2), t_ref, jac=lambda t: t - t_ref,
                   constraints=[{"type": "eq", "fun": lambda t: J.T @ t + tau_load, "jac": lambda t: J.T}],
                   bounds=[(rig.t_min_N, rig.t_max_N)] * 6, method="SLSQP",
                   options={"ftol": 1e-12, "maxiter": 200})
    return res.x


def row(label: str, seconds: float, per: int = 1) -> str:
    rate = per / seconds if seconds > 0 else float("inf")
    return f"  {label:<46s} {seconds * 1e3:10.3f} ms   {rate:14,.0f} /s"
