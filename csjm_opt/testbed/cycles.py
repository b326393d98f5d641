"""Design of synthetic load cycles around reference poses (what an experimenter commands).

A cycle: pick a reference pose ``R_ref`` (tilt, azimuth, twist) and a
pre-load ``tau0``; plan tensions there with the *nominal* rig
(:func:`csjm_opt.planning.planner.plan_tensions`) and command the matching rest
lengths (:func:`csjm_opt.model.statics.rest_lengths_for`); then apply the external
moment ``tau0 + alpha dtau`` for ``alpha`` stepping up to 1 and back down to
0 (order matters under friction). Designs whose nominal response would slacken
a cable or leave the tension range are redrawn.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import so3
from ..errors import CsjmError
from ..model.numeric import Model
from ..model.rig import Rig
from ..model.statics import rest_lengths_for, solve_equilibrium
from ..planning.planner import plan_tensions


@dataclasses.dataclass(frozen=True, eq=False)
class CycleDesign:
    """One commanded load cycle."""

    R_ref: np.ndarray            # (3, 3) reference pose
    tau0_A_Nm: np.ndarray        # (3,) pre-load
    dtau_A_Nm: np.ndarray        # (3,) load increment at the top of the cycle
    alphas: np.ndarray           # (m,) fractions of dtau, up then down
    rest_lengths_m: np.ndarray   # (m,)

    @property
    def tau_ext_A_Nm(self) -> np.ndarray:
        """(m, 3) external moments of the cycle's rows, in time order."""
        return self.tau0_A_Nm + self.alphas[:, None] * self.dtau_A_Nm


def up_down(steps: int) -> np.ndarray:
    """``0, 1/steps, ..., 1, ..., 1/steps, 0``."""
    up = np.linspace(0.0, 1.0, steps + 1)
    return np.concatenate([up, up[-2::-1]])


def design_cycles(rig: Rig, n_cycles: int, rng: np.random.Generator, steps: int = 4,
                  max_tilt_rad: float = 0.35, max_twist_rad: float = 0.2,
                  preload_Nm: tuple[float, float] = (0.0, 1.5), load_Nm: tuple[float, float] = (1.5, 3.0),
                  max_tries: int = 50) -> list[CycleDesign]:
    """``n_cycles`` feasible cycles (nominal model: taut cables within bounds everywhere)."""
    model = Model(rig)
    alphas = up_down(steps)
    cycles: list[CycleDesign] = []
    for _ in range(n_cycles):
        for _attempt in range(max_tries):
            design = _draw(rig, model, rng, alphas, max_tilt_rad, max_twist_rad, preload_Nm, load_Nm)
            if design is not None:
                cycles.append(design)
                break
        else:
            raise CsjmError(f"could not design a feasible cycle in {max_tries} tries")
    return cycles


def _draw(rig, model, rng, alphas, max_tilt, max_twist, preload, load) -> CycleDesign | None:
    tilt, az = rng.uniform(0.05, max_tilt), rng.uniform(0, 2 * np.pi)
    R_ref = (so3.exp(tilt * np.array([np.cos(az), np.sin(az), 0.0]))
             @ so3.exp([0, 0, rng.uniform(-max_twist, max_twist)]))
    tau0 = _random_unit(rng) * rng.uniform(*preload)
    dtau = _random_unit(rng) * rng.uniform(*load)
    try:
        plan = plan_tensions(rig, R_ref, tau0, model=model)
        l = rest_lengths_for(rig, R_ref, plan.tensions_N, model=model)
        R = R_ref
        for a in alphas[: (len(alphas) + 1) // 2]:
            eq = solve_equilibrium(rig, l, tau0 + a * dtau, R_init=R, model=model)
            R = eq.R
            if eq.tensions_N.min() < 0.5 * rig.t_min_N or eq.tensions_N.max() > rig.t_max_N:
                return None
    except CsjmError:
        return None
    return CycleDesign(R_ref, tau0, dtau, alphas, l)


def _random_unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)
