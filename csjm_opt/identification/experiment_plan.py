"""A planned (or drawn) identification experiment, the paper's protocol, and the bound of any protocol.

:func:`paper_protocol` draws the paper's protocol for comparison: one pose, 25 N pretension,
loads of U(3, 15) N in random directions at the four default points, redrawn until admissible.
:func:`predict_bound` settles a protocol's rows on the rig model and returns the predicted
Cramér-Rao bound per cycle.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import so3
from ..errors import CsjmError, DesignError
from ..measurement.instruments import InstrumentNoise
from ..measurement.protocol import Protocol
from ..model.numeric import Model
from ..model.rig import Rig
from ..model.statics import EquilibriumSolver, solve_equilibrium
from ..planning.planner import plan_tensions
from .candidate_loads import admissible, row_information
from .cramer_rao import bound
from .experiment_loads import ExperimentLoads


@dataclasses.dataclass(frozen=True, eq=False)
class ExperimentPlan:
    """A planned (or drawn) identification experiment and its predicted precision."""

    protocol: Protocol
    crlb6: list[np.ndarray]          # per cycle (pose): (6, 6) predicted bound of K's entries
    K_model: list[np.ndarray]        # per cycle: model K at the reference
    pretension_N: list[float]        # per cycle: chosen reference tension
    rotvec_ref: list[np.ndarray]     # per cycle: predicted reference pose
    budget: int

    def ci_half_width(self, level: float = 0.95) -> np.ndarray:
        """(cycles, 6) predicted interval half-widths of K's entries (normal quantile).

        Parameters
        ----------
        level : float, optional

        Returns
        -------
        ndarray
        """
        from scipy import stats

        q = float(stats.norm.ppf(0.5 + level / 2))
        return np.array([q * np.sqrt(np.diag(c)) for c in self.crlb6])

    def as_dict(self) -> dict:
        """JSON-able summary.

        Returns
        -------
        dict
        """
        return {"budget": self.budget, "rows": len(self.protocol), "pretension_N": self.pretension_N,
                "rotvec_ref": [r.tolist() for r in self.rotvec_ref],
                "K_model": [K.tolist() for K in self.K_model],
                "crlb_std": [np.sqrt(np.diag(c)).tolist() for c in self.crlb6],
                "ci95_half_width": self.ci_half_width().tolist()}


def paper_protocol(rig: Rig, budget: int, rng: np.random.Generator, pose: np.ndarray | None = None,
                   pretension_N: float = 25.0, weights_N: tuple[float, float] = (3.0, 15.0),
                   loads: ExperimentLoads | None = None, noise: InstrumentNoise | None = None,
                   model: Model | None = None, max_draws: int = 100) -> ExperimentPlan:
    """The paper's protocol: one pose, 25 N pretension, U(3, 15) N loads in random directions.

    Parameters
    ----------
    rig : Rig
    budget : int
        Loads (the reference row comes on top).
    rng : numpy.random.Generator
    pose : array (3,), optional
        Reference pose (rotation vector; identity by default).
    pretension_N : float
        Reference tension (clipped into the rig's range).
    weights_N : (float, float)
        Range of the uniformly drawn weights.
    loads : ExperimentLoads, optional
        Attachment points and the tracker range (default :meth:`ExperimentLoads.default`).
    noise : InstrumentNoise, optional
    model : Model, optional
    max_draws : int
        Draws per load before giving up.

    Returns
    -------
    ExperimentPlan

    Raises
    ------
    DesignError
        No admissible load in ``max_draws`` draws.
    """
    loads = loads or ExperimentLoads.default(rig)
    noise = noise or InstrumentNoise.paper()
    model = model or Model(rig)
    R = so3.exp(np.zeros(3) if pose is None else np.asarray(pose, float))
    t = float(np.clip(pretension_N, rig.t_min_N, rig.t_max_N))
    l = plan_tensions(rig, R, np.zeros(3), t_ref_N=np.full(rig.n_cables, t), model=model).rest_lengths_m
    try:
        ref = solve_equilibrium(rig, l, R_init=R, model=model)
    except CsjmError as exc:
        raise DesignError(f"the paper protocol's reference does not settle: {exc}", "pretension") from exc
    w, d, p = [], [], []
    for _ in range(budget):
        for _ in range(max_draws):
            wi = rng.uniform(*weights_N)
            di = rng.normal(size=3)
            di /= np.linalg.norm(di)
            pi = loads.points_A_m[rng.integers(len(loads.points_A_m))]
            if admissible(rig, EquilibriumSolver(rig, [(wi * di, pi)]), l, ref.R, loads.max_rotation_rad) is not None:
                break
        else:
            raise DesignError(f"no admissible paper-protocol load in {max_draws} draws", "loads")
        w.append(wi)
        d.append(di)
        p.append(pi)
    n = budget + 1
    proto = Protocol(np.zeros(n, int), np.repeat(l[None], n, 0), np.r_[0.0, w],
                     np.vstack([np.zeros(3), d]), np.vstack([np.zeros(3), p]))
    crlb6, K = predict_bound(rig, proto, noise, model)[0]
    return ExperimentPlan(proto, [crlb6], [K], [t], [so3.log(ref.R)], budget)


def predict_bound(rig: Rig, protocol: Protocol, noise: InstrumentNoise | None = None,
                  model: Model | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Predicted bound (6, 6) and model K per cycle of a protocol, settled on the rig model.

    Parameters
    ----------
    rig : Rig
    protocol : Protocol
    noise : InstrumentNoise, optional
    model : Model, optional

    Returns
    -------
    list of (ndarray (6, 6), ndarray (3, 3))

    Raises
    ------
    DesignError
        A row's load is not admissible on the model.
    """
    noise = noise or InstrumentNoise.paper()
    model = model or Model(rig)
    out = []
    for c in np.unique(protocol.cycle):
        rows = np.flatnonzero(protocol.cycle == c)
        l = protocol.rest_lengths_m[rows[0]]
        ref = solve_equilibrium(rig, l, R_init=np.eye(3), model=model)
        Rs = []
        for i in rows[1:]:
            R = admissible(rig, EquilibriumSolver(rig, [(protocol.force_B_N[i], protocol.point_A_m[i])]), l, ref.R,
                           np.inf)
            if R is None:
                raise DesignError(f"protocol row {i}: the rig model cannot hold this load", "protocol")
            Rs.append(R)
        zeta = np.vstack([np.zeros(3), so3.log(ref.R.T @ np.array(Rs))])
        info = row_information(model, ref.R, l, ref.K, model.weight_moment(ref.R), zeta, noise).sum(0)
        out.append((bound(info), ref.K))
    return out
