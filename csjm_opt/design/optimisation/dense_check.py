"""Dense certification of an optimised design: every requirement re-checked where the optimiser never looked.

The design is evaluated with the sweep's kernels (the exact zonotope feasibility test of
:mod:`csjm_opt.design.feasibility`, the model's J and K) and by
:mod:`csjm_opt.design.clearance`, on a Halton set of orientations of its
required range drawn with another seed than the optimiser's, then on the
orientations a pattern search reaches from the worst samples of each
requirement (tilt, azimuth and torsion moved within the range, steps halved).
Each requirement has a slack per orientation (>= 0 holds):

* ``tension``: the least-squares (closest to mid-range) tensions of the
  stiffness load within ``[t_min + margin, t_max - margin]`` (N). Where they
  are, they are the planner's tensions (no bound active), so the stiffness
  below is the one the planner and the sweep see; a design whose planner must
  push a tension onto a bound to hold the stiffness load fails here;
* ``stiffness``: smallest eigenvalue of K at those tensions minus the required value (N m/rad);
* ``load k``: wrench margin of load k in the tension box shrunk by the margin
  (N m; >= 0 iff some tensions in that box hold it);
* ``cable distance``, ``link clearance`` (m) and ``exit angle`` (deg).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from ...model.numeric import Model
from ...model.rig import Rig
from ..clearance import pose_interference
from ..feasibility import wrench_margin_Nm
from ..sampling import OrientationSampling, tilt_torsion_rotations
from .settings import Requirements

#: Tolerance of each slack (its units): round-off, not a design margin.
TOLERANCES = {"tension": 1e-6, "stiffness": 1e-6, "load": 1e-6, "cable distance": 1e-9,
              "link clearance": 1e-9, "exit angle": 1e-6, "shaping": 1e-6}
#: Worst samples per requirement refined by the local search, its rounds and first steps (deg).
LOCAL_SEEDS = 4
LOCAL_ROUNDS = 10
LOCAL_STEPS_DEG = (2.0, 10.0, 2.0)


@dataclasses.dataclass(frozen=True)
class Check:
    """Worst slack of each requirement over the dense set and the local search, and where."""

    worst: dict[str, tuple[float, tuple[float, float, float]]]   # name -> (slack, (tilt, azimuth, torsion) deg)
    failing: np.ndarray                                         # (k, 3) angles (rad) of failing orientations
    orientations: int                                           # orientations evaluated

    @property
    def ok(self) -> bool:
        """Whether every requirement holds everywhere checked."""
        return all(v[0] >= -TOLERANCES[_kind(k)] for k, v in self.worst.items())

    def as_dict(self) -> dict[str, Any]:
        """JSON-able: per requirement its worst slack and the orientation (deg).

        Returns
        -------
        dict
        """
        return {k: {"slack": v[0], "tilt_deg": v[1][0], "azimuth_deg": v[1][1], "torsion_deg": v[1][2]}
                for k, v in self.worst.items()}


def _deg(a: np.ndarray) -> tuple[float, float, float]:
    return float(math.degrees(a[0])), float(math.degrees(a[1])), float(math.degrees(a[2]))


def _kind(name: str) -> str:
    return "load" if name.startswith("load ") else name


def slacks(rig: Rig, angles: np.ndarray, req: Requirements, stiffness_Nm_per_rad: float,
           margin_N: float, model: Model | None = None) -> dict[str, np.ndarray]:
    """Slack of every requirement at each orientation (see the module docstring).

    Parameters
    ----------
    rig : Rig
        The design (with its link).
    angles : ndarray, shape (n, 3)
        Tilt, azimuth, torsion (rad).
    req : Requirements
        Loads, clearances, exit-angle limit.
    stiffness_Nm_per_rad : float
        Required smallest eigenvalue of K.
    margin_N : float
        Required tension margin.
    model : Model, optional
        Numeric model of ``rig`` to reuse.

    Returns
    -------
    dict of str to ndarray, shape (n,)
    """
    model = model or Model(rig)
    Rs = tilt_torsion_rotations(angles[:, 0], angles[:, 1], angles[:, 2])
    loads = np.asarray(req.loads, float)
    J = model.jacobian(Rs)
    tau_w = model.weight_moment(Rs)
    # the planner's tensions of the stiffness load where no tension is at a bound: least squares from mid-range
    t_mid = rig.t_mid_N
    w0 = -(loads[0] + tau_w) - np.einsum("nij,i->nj", J, t_mid)
    JtJ = np.einsum("nij,nik->njk", J, J)
    T = t_mid + np.einsum("nij,nj->ni", J, np.linalg.solve(JtJ, w0[..., None])[..., 0])
    tension = np.minimum(T - rig.t_min_N - margin_N, rig.t_max_N - margin_N - T).min(axis=1)
    eig = np.linalg.eigvalsh(model.stiffness(Rs, T))
    out = {"tension": tension, "stiffness": eig[:, 0] - stiffness_Nm_per_rad}
    for k in range(1, loads.shape[0]):
        out[f"load {k + 1}"] = wrench_margin_Nm(J, loads[k] + tau_w, rig.t_min_N + margin_N,
                                                rig.t_max_N - margin_N)
    pi = pose_interference(rig, Rs)
    out["cable distance"] = pi.cable_distance_m.min(axis=1) - req.min_cable_distance_m
    out["link clearance"] = pi.link_clearance_m.min(axis=1) - req.min_link_clearance_m
    out["exit angle"] = req.max_exit_angle_deg - pi.exit_angle_deg.max(axis=(1, 2))
    return out


def certify(rig: Rig, req: Requirements, scale: float, stiffness_Nm_per_rad: float, margin_N: float,
            n: int = 10000, seed: int = 0) -> Check:
    """Check a design on ``n`` dense orientations of its range plus a local search from the worst.

    Parameters
    ----------
    rig : Rig
        The design.
    req : Requirements
        Range (tilt, torsion; multiplied by ``scale``), loads, clearances.
    scale : float
        Range scale certified.
    stiffness_Nm_per_rad, margin_N : float
        Required smallest eigenvalue and tension margin.
    n : int
        Dense orientations (Halton, ``seed``).
    seed : int
        Seed of the dense set (use another than the optimiser's).

    Returns
    -------
    Check
    """
    model = Model(rig)
    max_tilt, max_tors = math.radians(req.max_tilt_deg) * scale, math.radians(req.max_torsion_deg) * scale
    s = OrientationSampling(n, math.degrees(max_tilt), math.degrees(max_tors), seed=seed)
    angles = np.vstack([np.zeros((1, 3)), np.column_stack(s.angles())])
    sl = slacks(rig, angles, req, stiffness_Nm_per_rad, margin_N, model)
    worst: dict[str, tuple[float, np.ndarray]] = {}
    seeds = []
    for name, v in sl.items():
        idx = np.argsort(v)[:LOCAL_SEEDS]
        seeds.append(angles[idx])
        worst[name] = (float(v[idx[0]]), angles[idx[0]])
    extra = _local_search(rig, model, np.vstack(seeds), req, stiffness_Nm_per_rad, margin_N, max_tilt, max_tors)
    count = angles.shape[0] + extra[2]
    sl2 = slacks(rig, extra[0], req, stiffness_Nm_per_rad, margin_N, model)
    failing = []
    for name, vals in sl2.items():
        i = int(np.argmin(vals))
        if vals[i] < worst[name][0]:
            worst[name] = (float(vals[i]), extra[0][i])
    for name, (w, a) in worst.items():
        if w < -TOLERANCES[_kind(name)]:
            bad_dense = angles[sl[name] < -TOLERANCES[_kind(name)]]
            failing.append(a[None])
            failing.append(bad_dense[np.argsort(sl[name][sl[name] < -TOLERANCES[_kind(name)]])[:4]])
    fail = np.unique(np.vstack(failing), axis=0) if failing else np.zeros((0, 3))
    return Check(worst={k: (w, _deg(a)) for k, (w, a) in worst.items()},
                 failing=fail, orientations=count)


def _local_search(rig: Rig, model: Model, start: np.ndarray, req: Requirements, lam: float, mu: float,
                  max_tilt: float, max_tors: float) -> tuple[np.ndarray, np.ndarray, int]:
    """Pattern search lowering each requirement's slack from ``start`` (batched); returns angles found."""
    names = list(slacks(rig, start[:1], req, lam, mu, model))
    per = start.shape[0] // len(names)
    x = start.copy()
    own = np.repeat(np.arange(len(names)), per)          # which requirement each seed lowers
    step = np.radians(np.array(LOCAL_STEPS_DEG))
    count = 0
    lo = np.array([0.0, -np.inf, -max_tors])
    hi = np.array([max_tilt, np.inf, max_tors])

    def value(a: np.ndarray, who: np.ndarray) -> np.ndarray:
        sl = slacks(rig, a, req, lam, mu, model)
        return np.stack([sl[n] for n in names])[who, np.arange(a.shape[0])]

    f = value(x, own)
    count += x.shape[0]
    moves = np.vstack([np.eye(3), -np.eye(3)])
    for _ in range(LOCAL_ROUNDS):
        cand = np.clip(x[:, None, :] + moves[None] * step, lo, hi).reshape(-1, 3)
        fc = value(cand, np.repeat(own, 6)).reshape(-1, 6)
        count += cand.shape[0]
        best = np.argmin(fc, axis=1)
        better = fc[np.arange(len(x)), best] < f
        x = np.where(better[:, None], cand.reshape(-1, 6, 3)[np.arange(len(x)), best], x)
        f = np.where(better, fc[np.arange(len(x)), best], f)
        step = step * 0.5
    return x, f, count
