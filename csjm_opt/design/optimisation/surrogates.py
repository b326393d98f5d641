"""Smooth twins of the sweep's two front metrics (workspace fraction, minimum stiffness), in CasADi.

The sweep (:mod:`csjm_opt.design.metrics`) scores a design on its own sample
orientations R_i (``[sampling]``):

* ``workspace_fraction`` = mean over i of [every load holdable at R_i], the
  exact zonotope test of :mod:`csjm_opt.design.feasibility`: the wrench margin
  ``m_i = min_k min_p (h w_p - |n_p . (w_k - c)|)`` over the m (m - 1) / 2 facet normals
  ``n_p = g_a x g_b`` (unit) of the moment zonotope and the loads k;
* ``min_stiffness_Nm_per_rad`` = min over the feasible i of the smallest
  eigenvalue of K at the planner's tensions of load 0.

Both are non-smooth (a count; a minimum over a set that changes with the
design). Their twins here are smooth and tend to them as the widths go to 0:

* ``F = mean_i sigmoid(m~_i / FEASIBLE_WIDTH_NM)``, ``m~_i`` the same margin
  with the minima as soft minima (width :data:`MARGIN_SOFTMIN_NM`) and ``|x|``
  as ``sqrt(x^2 + eps^2)``;
* ``S = -tau log(sum_i sigma_i exp(-lambda_i / tau) / sum_i sigma_i)``, the
  soft minimum of ``lambda_i`` weighted by ``sigma_i`` (tau =
  :data:`STIFFNESS_SOFTMIN`): a held pose counts fully, a pose on the edge
  (``sigma = 1/2``) as if ``tau ln 2`` stiffer, a pose not held not at all;
  ``lambda_i`` is the smallest eigenvalue (closed form for a symmetric 3 x 3
  matrix) of K at the least-squares tensions of load 0, which are the
  planner's wherever they lie inside the tension box.

J, K and the weight moment are :mod:`csjm_opt.model.casadi_model`; the holes
:func:`~csjm_opt.design.optimisation.symbols.holes_sym`. The surrogate is only a
guide for the search: every design it returns is scored by the sweep's own
evaluator (:func:`csjm_opt.design.design_evaluation.evaluate_design`).
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import casadi as ca
import numpy as np

from ...model.casadi_model import build_functions
from ..evaluation_settings import EvaluationSettings
from ..sampling import tilt_torsion_angles
from .settings import OptimiseSettings
from .symbols import design_sym

#: Width (N m) of the sigmoid that turns a wrench margin into "held": a margin of 2 widths counts 0.88.
FEASIBLE_WIDTH_NM = 0.05
#: Width (N m) of the soft minimum over facets and loads (bias at most width x ln(105) = 0.047 N m).
MARGIN_SOFTMIN_NM = 0.01
#: Width (N m/rad) of the soft minimum of the stiffness over poses (it lies between the minimum and the
#: weighted mean; a wider one is smoother: poses entering the set move it gradually).
STIFFNESS_SOFTMIN = 0.1
_ABS_EPS = 1e-9


def _softmin(values: Any, width: float) -> Any:
    lo = ca.mmin(values)
    return lo - width * ca.log(ca.sum1(ca.exp(-(values - lo) / width)))


def _smallest_eigenvalue(K: Any) -> Any:
    """Smallest eigenvalue of a symmetric 3 x 3 matrix (trigonometric closed form)."""
    q = ca.trace(K) / 3
    p1 = K[0, 1] ** 2 + K[0, 2] ** 2 + K[1, 2] ** 2
    p2 = (K[0, 0] - q) ** 2 + (K[1, 1] - q) ** 2 + (K[2, 2] - q) ** 2 + 2 * p1
    p = ca.sqrt(p2 / 6 + 1e-18)
    r = ca.det((K - q * ca.DM.eye(3)) / p) / 2
    phi = ca.acos(ca.fmin(ca.fmax(r, -1 + 1e-12), 1 - 1e-12)) / 3
    return q + 2 * p * ca.cos(phi + 2 * math.pi / 3)


def _pose_function(n_loads: int, n_cables: int = 6) -> Any:
    """Soft wrench margin and smallest eigenvalue of K at one pose (m = ``n_cables``), as a CasADi function."""
    c = n_cables
    A, B, R = ca.SX.sym("A", 3, c), ca.SX.sym("B", 3, c), ca.SX.sym("R", 3, 3)
    rig, loads = ca.SX.sym("rig", 8), ca.SX.sym("load", 3, n_loads)
    f = build_functions(c)
    k, t_min, t_max, mass, com_z = rig[0], rig[1], rig[2], rig[3], rig[4]
    J = f["jacobian"](R, A, B)
    tau_w = f["weight_moment"](R, mass, ca.vertcat(0, 0, com_z), rig[5:8])[0]
    h, t_mid = 0.5 * (t_max - t_min), 0.5 * (t_min + t_max)
    centre = t_mid * ca.sum1(J).T
    slacks = []
    for a, b in itertools.combinations(range(c), 2):
        n = ca.cross(J[a, :].T, J[b, :].T)
        unit = n / ca.sqrt(ca.sumsqr(n) + 1e-30)
        width = sum(ca.sqrt((J[i, :] @ unit) ** 2 + _ABS_EPS ** 2) for i in range(c) if i not in (a, b))
        for kk in range(n_loads):
            off = unit.T @ (-(loads[:, kk] + tau_w) - centre)
            slacks.append(h * width - ca.sqrt(off ** 2 + _ABS_EPS ** 2))
    margin = _softmin(ca.vertcat(*slacks), MARGIN_SOFTMIN_NM)
    T0 = t_mid + J @ ca.solve(J.T @ J, -(loads[:, 0] + tau_w) - J.T @ (t_mid * ca.DM.ones(c)))
    K = f["stiffness"](R, T0, k * ca.DM.ones(c), A, B)
    return ca.Function("sweep_pose", [A, B, rig, R, loads], [margin, _smallest_eigenvalue(K)])


def sweep_surrogate(settings: OptimiseSettings, evaluation: EvaluationSettings) -> ca.Function:
    """``u -> (F, S)``: the smooth workspace fraction and minimum stiffness on the sweep's own samples.

    Parameters
    ----------
    settings : OptimiseSettings
        Optimised variables and their bounds (``u`` in [0, 1] maps onto them), base design, gravity.
    evaluation : EvaluationSettings
        The sweep's evaluator settings (sample orientations, loads).

    Returns
    -------
    casadi.Function
        Input ``u`` (n variables, scaled to their bounds); outputs ``F`` (fraction, 0..1), ``S``
        (N m/rad), the per-pose margins ``m`` (N m) and eigenvalues ``lam`` (N m/rad).
    """
    names = settings.names
    u = ca.MX.sym("u", len(names))
    p, A, B, rig = design_sym(settings, u)
    Rs = evaluation.sampling.rotations()
    loads = np.asarray(evaluation.loads.taus_ext_A_Nm, float)
    pose = _pose_function(loads.shape[0], A.size2()).map(Rs.shape[0], "serial")
    margin, lam = pose(A, B, rig, ca.DM(np.concatenate(list(Rs), axis=1)), ca.DM(loads.T))
    held = 1.0 / (1.0 + ca.exp(-margin / FEASIBLE_WIDTH_NM))
    F = ca.sum2(held) / Rs.shape[0]
    lo = ca.mmin(lam)     # shift only (exact): keeps the exponentials in range
    weights = held * ca.exp(-(lam - lo) / STIFFNESS_SOFTMIN)
    S = lo - STIFFNESS_SOFTMIN * ca.log(ca.sum2(weights) / (ca.sum2(held) + 1e-300) + 1e-300)
    return ca.Function("sweep_surrogate", [u], [F, S, margin.T, lam.T], ["u"], ["F", "S", "m", "lam"])


def sample_angles_deg(evaluation: EvaluationSettings) -> np.ndarray:
    """Tilt, azimuth, torsion (deg) of the sweep's sample orientations, (n, 3).

    Parameters
    ----------
    evaluation : EvaluationSettings

    Returns
    -------
    ndarray
    """
    return np.degrees(np.column_stack(tilt_torsion_angles(evaluation.sampling.rotations())))
