"""Candidate loads of an identification experiment, settled on the rig model, with their information.

Used by :mod:`csjm_opt.identification.experiment_design`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import so3
from ..errors import CsjmError
from ..measurement.instruments import InstrumentNoise
from ..model.numeric import Model
from ..model.rig import Rig
from ..model.statics import EquilibriumSolver, solve_equilibrium
from ..planning.planner import plan_tensions
from .cramer_rao import design_rows, row_covariances, slopes
from .curvature import model_curvature, weight_slopes
from .experiment_loads import ExperimentLoads


@dataclasses.dataclass(frozen=True, eq=False)
class Cycle:
    """Admissible loads at one reference pose and pretension, with each row's information."""

    R_ref: np.ndarray           # (3, 3) unloaded reference equilibrium
    rest_lengths_m: np.ndarray  # (m,)
    K: np.ndarray               # (3, 3) model stiffness at the reference
    ref_info: np.ndarray        # (9, 9) information of the reference row
    weight: np.ndarray          # (m,) N
    point: np.ndarray           # (m, 3) {A}
    direction: np.ndarray       # (m, 3) {B}
    info: np.ndarray            # (m, 9, 9)
    partner: np.ndarray         # (m,) index of the same load in the opposite direction, -1 if none


def admissible(rig: Rig, solver: EquilibriumSolver, l: np.ndarray, R_ref: np.ndarray,
               max_rotation_rad: float) -> np.ndarray | None:
    """The settled pose under the solver's dead weight, or None when it is not admissible.

    Admissible: a stable equilibrium near ``R_ref``, every tension in ``[t_min, t_max]``, a turn
    from ``R_ref`` of at most ``max_rotation_rad``.

    Parameters
    ----------
    rig : Rig
    solver : EquilibriumSolver
        With the load as its point force.
    l : array (m,)
    R_ref : array (3, 3)
    max_rotation_rad : float

    Returns
    -------
    ndarray (3, 3) or None
    """
    try:
        eq = solver.solve(l, np.zeros(3), R_ref)
    except CsjmError:
        return None
    T = eq.tensions_N
    if T.min() < rig.t_min_N or T.max() > rig.t_max_N:
        return None
    if np.linalg.norm(so3.log(R_ref.T @ eq.R)) > max_rotation_rad:
        return None
    return eq.R


def row_information(model: Model, R_ref: np.ndarray, l: np.ndarray, K: np.ndarray, tau0: np.ndarray,
                    zeta: np.ndarray, noise: InstrumentNoise) -> np.ndarray:
    """Information ``A_i^T V_i^-1 A_i`` (n, 9, 9) of rows at displacements ``zeta`` from ``R_ref``.

    Parameters
    ----------
    model : Model
    R_ref : array (3, 3)
    l : array (m,)
        Rest lengths.
    K : array (3, 3)
        Stiffness at the reference.
    tau0 : array (3,)
        Load moment at the reference.
    zeta : array (n, 3)
    noise : InstrumentNoise

    Returns
    -------
    ndarray (n, 9, 9)
    """
    _, dc = model_curvature(model, R_ref, l, zeta)
    W = weight_slopes(model, R_ref @ so3.exp(zeta), zeta)
    V = row_covariances(slopes(zeta, tau0, K, dc), W, np.diag(np.asarray(noise.tau_sigma_Nm) ** 2),
                        noise.angle_sigma_rad)
    A = design_rows(zeta)
    return np.einsum("nia,nij,njb->nab", A, np.linalg.inv(V), A)


def cycle_for(rig: Rig, model: Model, R_pose: np.ndarray, pretension_N: float, loads: ExperimentLoads,
              noise: InstrumentNoise) -> Cycle | None:
    """Settle every load of ``loads`` at one pose and pretension (None if the reference fails).

    Parameters
    ----------
    rig : Rig
    model : Model
    R_pose : array (3, 3)
        Pose the pretension is planned at.
    pretension_N : float
        Reference tension of the planner.
    loads : ExperimentLoads
    noise : InstrumentNoise

    Returns
    -------
    Cycle or None
    """
    try:
        t_ref = np.full(rig.n_cables, pretension_N)
        l = plan_tensions(rig, R_pose, np.zeros(3), t_ref_N=t_ref, model=model).rest_lengths_m
        ref = solve_equilibrium(rig, l, R_init=R_pose, model=model)
    except CsjmError:
        return None
    if ref.tensions_N.min() < rig.t_min_N or ref.tensions_N.max() > rig.t_max_N:
        return None
    nd = len(loads.directions_B)
    neg = np.array([int(np.argmin(np.linalg.norm(loads.directions_B + d, axis=1))) for d in loads.directions_B])
    key: dict[tuple[int, int, int], int] = {}
    poses: list[np.ndarray] = []
    w_: list[float] = []
    p_: list[np.ndarray] = []
    d_: list[np.ndarray] = []
    for wi, w in enumerate(loads.weights_N):
        for pi, p in enumerate(loads.points_A_m):
            for di, d in enumerate(loads.directions_B):
                R = admissible(rig, EquilibriumSolver(rig, [(w * d, p)]), l, ref.R, loads.max_rotation_rad)
                if R is None:
                    continue
                key[(wi, pi, di)] = len(poses)
                poses.append(R)
                w_.append(float(w))
                p_.append(p)
                d_.append(d)
    tau0 = model.weight_moment(ref.R)
    ref_info = row_information(model, ref.R, l, ref.K, tau0, np.zeros((1, 3)), noise)[0]
    if not poses:
        return Cycle(ref.R, l, ref.K, ref_info, np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)),
                     np.zeros((0, 9, 9)), np.zeros(0, int))
    zeta = so3.log(ref.R.T @ np.array(poses))
    partner = np.array([key.get((wi, pi, int(neg[di])), -1) for (wi, pi, di) in key])
    assert nd == len(neg)
    return Cycle(ref.R, l, ref.K, ref_info, np.array(w_), np.array(p_), np.array(d_),
                 row_information(model, ref.R, l, ref.K, tau0, zeta, noise), partner)
