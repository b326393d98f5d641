"""Per-design metrics over sampled orientations: workspace, stiffness, margins, shaping range.

Definitions (all over the orientations of an :class:`OrientationSampling`):

* A pose is **feasible** when every load of the load set can be held with
  tensions in ``[t_min, t_max]``: ``tau_load = tau_ext + tau_weight(R)``
  lies in the available moment set (exact zonotope test,
  :mod:`csjm_opt.design.feasibility`).
* ``workspace_fraction``: feasible poses / sampled poses (the fraction of the
  sampled tilt/torsion region, Haar measure).
* ``tilt_cone_deg``: largest tilt such that every sample with a smaller tilt
  (any azimuth, any sampled torsion) is feasible; ``max_tilt_deg`` when all are.
  The infeasible samples of smallest tilt are refined by bisection along
  their tilt ray (azimuth, torsion fixed) to the feasibility boundary.
* Stiffness at a feasible pose is K (load convention of docs/conventions.md) with the
  planner's tensions (closest to mid-range, :func:`csjm_opt.planning.planner`'s QP,
  solved by the batched exact active-set method) for the *stiffness load*,
  the first load of the set. ``min_stiffness_Nm_per_rad`` is the smallest
  eigenvalue of K over feasible poses; ``max_condition`` the largest
  ``lambda_max / lambda_min``; ``min_torsion_stiffness_Nm_per_rad`` the
  smallest ``K_zz`` (about the platform axis z_A); ``min_bending_stiffness``
  the smallest eigenvalue of the x-y block; medians likewise.
  ``stable_fraction``: feasible poses with K positive definite.
* ``min_tension_margin_N`` / ``median_tension_margin_N``: smallest / median
  over feasible poses of ``min(T - t_min, t_max - T)`` of those planned
  tensions; ``median_wrench_margin_Nm``: median over feasible poses of the
  smallest distance of any load of the set to the boundary of the available
  moment set (capacity margin, N m). (Minima of margins go to 0 whenever the
  workspace is not the whole region, so medians are reported.)
* ``home_*``: the same at the home pose R = I (feasible, smallest eigenvalue
  of K, tension margin, wrench margin).
* Shaping range: at ``shaping_poses`` feasible poses (the first ones in
  sample order, spread over the region by the low-discrepancy sequence) the
  exact min and max of the directional stiffness ``u^T K u`` over all
  tensions holding the stiffness load, for u = x, y (bending) and z
  (torsion) of {A}; reported as medians over those poses
  (:mod:`csjm_opt.design.shaping_range`).
* Interference (:mod:`csjm_opt.design.clearance`) over the feasible
  poses: ``min_cable_distance_m`` between any two cables,
  ``min_link_clearance_m`` from any cable to the link (the rig's, or the
  documented default), ``max_exit_angle_deg`` of any cable against its hole's
  axis. A sweep may make them a validity rule (``[metrics]``
  ``min_cable_distance_m`` / ``min_link_clearance_m`` / ``max_exit_angle_deg``).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from ..errors import DesignError, InfeasibleLoad
from ..model.numeric import Model
from ..model.rig import Rig
from ..planning import active_set as active_set
from ..planning.planner import plan_tensions
from . import feasibility, shaping_range
from .clearance import interference
from .sampling import OrientationSampling, tilt_torsion_angles, tilt_torsion_rotations

#: Infeasible samples refined by bisection for the tilt cone, and bisection steps
#: (2^-8 of the sample's tilt: 0.18 deg at 45 deg).
CONE_RAYS = 64
CONE_BISECTIONS = 8


@dataclasses.dataclass(frozen=True, eq=False)
class DesignLoads:
    """External moments (N m, in {A}, weight excluded) a feasible pose must hold; row 0 is the stiffness load."""

    taus_ext_A_Nm: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((1, 3)))

    def __post_init__(self) -> None:
        arr = np.array(self.taus_ext_A_Nm, dtype=float, ndmin=2)
        if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] < 1:
            raise DesignError(f"expected rows of [tx, ty, tz], got shape {arr.shape}", "loads.tau_ext")
        if not np.all(np.isfinite(arr)):
            raise DesignError("expected finite numbers", "loads.tau_ext")
        arr.setflags(write=False)
        object.__setattr__(self, "taus_ext_A_Nm", arr)


@dataclasses.dataclass(frozen=True)
class MetricOptions:
    """Tolerances and effort of :func:`evaluate`."""

    shaping_poses: int = 16
    feasibility_tol_Nm: float = 1e-9

    def __post_init__(self) -> None:
        if isinstance(self.shaping_poses, bool) or not isinstance(self.shaping_poses, int) \
                or self.shaping_poses < 0:
            raise DesignError(f"expected an integer >= 0, got {self.shaping_poses!r}", "shaping_poses")
        if not self.feasibility_tol_Nm >= 0:
            raise DesignError(f"expected >= 0, got {self.feasibility_tol_Nm}", "feasibility_tol_Nm")


@dataclasses.dataclass(frozen=True, eq=False)
class PoseMetrics:
    """Per-orientation arrays behind :class:`DesignMetrics` (n = number of samples)."""

    R: np.ndarray                   # (n, 3, 3)
    tilt_rad: np.ndarray            # (n,)
    feasible: np.ndarray            # (n,) bool, all loads held
    wrench_margin_Nm: np.ndarray    # (n, m) per load
    tensions_N: np.ndarray          # (n, m) planned for the stiffness load (valid where feasible)
    K: np.ndarray                   # (n, 3, 3) at those tensions
    eig_Nm_per_rad: np.ndarray      # (n, 3) ascending
    fallbacks: int                  # feasible rows the active-set method did not settle


@dataclasses.dataclass(frozen=True)
class DesignMetrics:
    """Scalar metrics of one design (defined in :mod:`csjm_opt.design.metrics`); NaN when undefined."""

    n_orientations: int
    workspace_fraction: float
    tilt_cone_deg: float
    min_stiffness_Nm_per_rad: float
    median_min_stiffness_Nm_per_rad: float
    max_condition: float
    median_condition: float
    min_torsion_stiffness_Nm_per_rad: float
    median_torsion_stiffness_Nm_per_rad: float
    min_bending_stiffness_Nm_per_rad: float
    median_bending_stiffness_Nm_per_rad: float
    stable_fraction: float
    min_tension_margin_N: float
    median_tension_margin_N: float
    median_wrench_margin_Nm: float
    home_feasible: bool
    home_min_stiffness_Nm_per_rad: float
    home_tension_margin_N: float
    home_wrench_margin_Nm: float
    shaping_range_Nm_per_rad: dict[str, tuple[float, float]]
    planner_fallbacks: int
    seconds: float
    #: Interference over the feasible orientations (csjm_opt.design.clearance); NaN without any.
    min_cable_distance_m: float = math.nan
    min_link_clearance_m: float = math.nan
    max_exit_angle_deg: float = math.nan

    def as_dict(self) -> dict[str, Any]:
        """The metrics as a JSON-able dict (the ``metrics`` of a sweep record).

        Returns
        -------
        dict
        """
        return {k: _json_safe(v) for k, v in dataclasses.asdict(self).items()}


def _json_safe(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    return value


def evaluate_poses(rig: Rig, Rs: np.ndarray, loads: DesignLoads = DesignLoads(),
                   options: MetricOptions = MetricOptions(), model: Model | None = None) -> PoseMetrics:
    """Feasibility, planned tensions and K at every given orientation.

    Parameters
    ----------
    rig : Rig
        The design.
    Rs : ndarray, shape (n, 3, 3)
        Orientations of {A} in {B}.
    loads : DesignLoads, optional
        External moments (N m in {A}).
    options : MetricOptions, optional
        Feasibility tolerance.
    model : Model, optional
        A numeric model of ``rig`` to reuse.

    Returns
    -------
    PoseMetrics
        Per pose: feasible or not, tensions under the first load, K and its eigenvalues, margins.
    """
    model = model or Model(rig)
    J = model.jacobian(Rs)
    tau_w = model.weight_moment(Rs)
    tau_load = loads.taus_ext_A_Nm[None, :, :] + tau_w[:, None, :]          # (n, m, 3)
    margin = feasibility.wrench_margin_Nm(J, tau_load, rig.t_min_N, rig.t_max_N)
    ok = np.all(margin >= -options.feasibility_tol_Nm, axis=1)
    # Tensions only where the load set can be held (infeasible rows never settle).
    rows = np.flatnonzero(ok)
    t_ref = np.broadcast_to(rig.t_mid_N, (rows.size, rig.n_cables))
    res = active_set.solve(np.swapaxes(J[rows], 1, 2), -tau_load[rows, 0], np.ascontiguousarray(t_ref),
                           rig.t_min_N, rig.t_max_N)
    T = np.tile(rig.t_mid_N, (Rs.shape[0], 1))
    T[rows] = res.t
    unsettled = rows[~res.converged]
    for i in unsettled:  # rare: the exact feasibility verdict says yes, ask the general planner
        try:
            T[i] = plan_tensions(rig, Rs[i], loads.taus_ext_A_Nm[0], model=model).tensions_N
        except InfeasibleLoad:  # inside the tolerance band of the zonotope test only
            ok[i] = False
    K = model.stiffness(Rs, T)
    return PoseMetrics(R=Rs, tilt_rad=tilt_torsion_angles(Rs)[0], feasible=ok, wrench_margin_Nm=margin,
                       tensions_N=T, K=K, eig_Nm_per_rad=np.linalg.eigvalsh(K),
                       fallbacks=int(unsettled.size))


def evaluate(rig: Rig, sampling: OrientationSampling = OrientationSampling(),
             loads: DesignLoads = DesignLoads(), options: MetricOptions = MetricOptions(),
             model: Model | None = None) -> DesignMetrics:
    """All scalar metrics of one design over sampled orientations (see the module docstring).

    Parameters
    ----------
    rig : Rig
        The design.
    sampling : OrientationSampling, optional
        Orientations to evaluate (tilt and torsion ranges, count, seed).
    loads : DesignLoads, optional
        External moments (N m in {A}); a pose is feasible when every load can be held; the first
        load is the one the stiffness is computed under.
    options : MetricOptions, optional
        Number of shaping poses, feasibility tolerance.
    model : Model, optional
        A numeric model of ``rig`` to reuse.

    Returns
    -------
    DesignMetrics
        Workspace fraction, tilt cone, stiffness (minimum and median smallest eigenvalue,
        condition, torsion and bending), tension and wrench margins, shaping range.
    """
    start = time.perf_counter()
    model = model or Model(rig)
    pm = evaluate_poses(rig, sampling.rotations(), loads, options, model)
    ok = pm.feasible
    n = ok.size
    cone = _tilt_cone_deg(rig, model, sampling, ok, loads, options)
    eig, K = pm.eig_Nm_per_rad[ok], pm.K[ok]
    lam_min = eig[:, 0]
    cond = np.where(lam_min > 0, eig[:, -1] / np.where(lam_min > 0, lam_min, 1.0), np.inf)
    torsion = K[:, 2, 2]
    bending = np.linalg.eigvalsh(K[:, :2, :2])[:, 0] if K.size else np.empty(0)
    T = pm.tensions_N[ok]
    tension_margin = np.minimum(T - rig.t_min_N, rig.t_max_N - T).min(axis=1) if T.size else T
    shaping = _shaping(rig, model, pm, loads, options.shaping_poses)
    home = evaluate_poses(rig, np.eye(3)[None], loads, options, model)
    t_home = home.tensions_N[0]
    clash = interference(rig, pm.R[ok]) if np.any(ok) else None
    home_tension_margin = float(min(np.min(t_home - rig.t_min_N), np.min(rig.t_max_N - t_home))) \
        if home.feasible[0] else math.nan
    return DesignMetrics(
        n_orientations=n, workspace_fraction=float(ok.mean()), tilt_cone_deg=float(cone),
        min_stiffness_Nm_per_rad=_stat(np.min, lam_min),
        median_min_stiffness_Nm_per_rad=_stat(np.median, lam_min),
        max_condition=_stat(np.max, cond), median_condition=_stat(np.median, cond),
        min_torsion_stiffness_Nm_per_rad=_stat(np.min, torsion),
        median_torsion_stiffness_Nm_per_rad=_stat(np.median, torsion),
        min_bending_stiffness_Nm_per_rad=_stat(np.min, bending),
        median_bending_stiffness_Nm_per_rad=_stat(np.median, bending),
        stable_fraction=_stat(np.mean, lam_min > 0) if lam_min.size else math.nan,
        min_tension_margin_N=_stat(np.min, tension_margin),
        median_tension_margin_N=_stat(np.median, tension_margin),
        median_wrench_margin_Nm=_stat(np.median, pm.wrench_margin_Nm[ok].min(axis=1)),
        home_feasible=bool(home.feasible[0]),
        home_min_stiffness_Nm_per_rad=float(home.eig_Nm_per_rad[0, 0]) if home.feasible[0] else math.nan,
        home_tension_margin_N=home_tension_margin,
        home_wrench_margin_Nm=float(home.wrench_margin_Nm[0].min()),
        shaping_range_Nm_per_rad=shaping, planner_fallbacks=pm.fallbacks,
        seconds=time.perf_counter() - start,
        min_cable_distance_m=clash.min_cable_distance_m if clash else math.nan,
        min_link_clearance_m=clash.min_link_clearance_m if clash else math.nan,
        max_exit_angle_deg=clash.max_exit_angle_deg if clash else math.nan)


def _tilt_cone_deg(rig: Rig, model: Model, sampling: OrientationSampling, ok: np.ndarray,
                   loads: DesignLoads, options: MetricOptions) -> float:
    """Largest tilt below which every sampled azimuth/torsion is feasible (deg).

    The infeasible samples of smallest tilt (up to ``CONE_RAYS``) are moved
    along their own tilt ray (azimuth and torsion fixed) by bisection to the
    feasibility boundary, so the estimate depends on the sampling density in
    azimuth and torsion only, not in tilt.
    """
    if np.all(ok):
        return float(sampling.max_tilt_deg)
    tilt, azimuth, torsion = sampling.angles()
    bad = np.flatnonzero(~ok)
    bad = bad[np.argsort(tilt[bad])[:CONE_RAYS]]
    bad = np.resize(bad, CONE_RAYS)  # fixed batch size for the cached CasADi maps
    lo, hi = np.zeros(bad.size), tilt[bad].copy()
    # boundary in [lo, hi]: hi infeasible; lo = 0 feasible unless shown otherwise
    at_zero = _feasible_at(rig, model, lo, azimuth[bad], torsion[bad], loads, options)
    hi = np.where(at_zero, hi, 0.0)
    for _ in range(CONE_BISECTIONS):
        mid = 0.5 * (lo + hi)
        good = _feasible_at(rig, model, mid, azimuth[bad], torsion[bad], loads, options)
        lo, hi = np.where(good, mid, lo), np.where(good, hi, mid)
    return math.degrees(float(hi.min()))


def _feasible_at(rig: Rig, model: Model, tilt: np.ndarray, azimuth: np.ndarray, torsion: np.ndarray,
                 loads: DesignLoads, options: MetricOptions) -> np.ndarray:
    Rs = tilt_torsion_rotations(tilt, azimuth, torsion)
    tau_load = loads.taus_ext_A_Nm[None, :, :] + model.weight_moment(Rs)[:, None, :]
    margin = feasibility.wrench_margin_Nm(model.jacobian(Rs), tau_load, rig.t_min_N, rig.t_max_N)
    return np.all(margin >= -options.feasibility_tol_Nm, axis=1)


def stiffness_affine_parts(model: Model, Rs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``K(T) = K0 + sum_i T_i K_i`` at each pose (all cables taut): K0 (n, 3, 3), K_i (n, 6, 3, 3)."""
    return model.stiffness_basis(Rs)


def _shaping(rig: Rig, model: Model, pm: PoseMetrics, loads: DesignLoads,
             count: int) -> dict[str, tuple[float, float]]:
    idx = np.flatnonzero(pm.feasible)[:count]
    if count == 0 or idx.size == 0:
        return {axis: (math.nan, math.nan) for axis in shaping_range.AXES}
    idx = np.resize(idx, count)  # fixed batch size: CasADi maps are cached per size
    Rs = pm.R[idx]
    K0, Ki = stiffness_affine_parts(model, Rs)
    J = model.jacobian(Rs)
    tau_load = loads.taus_ext_A_Nm[0] + model.weight_moment(Rs)
    lo, hi = shaping_range.directional_stiffness_range(
        J, tau_load, K0, Ki, rig.t_min_N, rig.t_max_N, np.array(list(shaping_range.AXES.values())))
    return {axis: (float(np.nanmedian(lo[:, d])), float(np.nanmedian(hi[:, d])))
            for d, axis in enumerate(shaping_range.AXES)}


def _stat(fn: Any, values: np.ndarray) -> float:
    return float(fn(values)) if np.size(values) else math.nan
