"""The nominal moment balance augmented by effects, with nominal nuisance parameters.

For each row (rest lengths ``l``, measured moment ``tau_meas``, pose ``R_m``
of the measured body) the balance residual in N m is::

    g = J(R_c)^T T(e) + E (tau_ext + tau_w(R_m)),   e = c(R_c) - (l + dl)

with ``tau_ext = tau_meas`` and ``tau_w = (m r) x (R_m^T g_B)`` nominally,
``R_c = R_m`` and ``E = I`` unless an effect says otherwise (see
:mod:`csjm_opt.diagnose.effects.base`), and ``T = s k e`` for taut cables.
The nuisance parameters shared by every model (the nominal fit, so that the
baseline absorbs what it should) are ``log_k_scale`` (a common cable
stiffness scale ``s = exp(.)``) and ``dl_common_m`` (a common rest-length
offset: pretension error). Parameter vector: nuisance, then each effect's.
``g(R) = 0`` defines the model's predicted pose (:func:`predict_poses`).
"""

from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np

from ..rig import Rig
from . import kinematics as kin
from .effects import Effect

NUISANCE_NAMES = ("log_k_scale", "dl_common_m")
NUISANCE_SCALES = np.array([0.05, 2e-4])


@dataclasses.dataclass(frozen=True, eq=False)
class Rows:
    """Per-row inputs of the balance (the part of a log the model needs)."""

    rest_lengths_m: np.ndarray     # (n, 6)
    tau_meas_A_Nm: np.ndarray      # (n, 3)
    slip_sign: np.ndarray          # (n, 6) sliding direction of each cable (friction)

    def __len__(self) -> int:
        return self.rest_lengths_m.shape[0]

    def take(self, idx: np.ndarray) -> "Rows":
        return Rows(self.rest_lengths_m[idx], self.tau_meas_A_Nm[idx], self.slip_sign[idx])


@dataclasses.dataclass
class Evaluation:
    """Mutable working state of one evaluation of the balance (hooks edit it)."""

    A_m: np.ndarray
    B_m: np.ndarray
    first_moment_A_kgm: np.ndarray
    tau_ext_A_Nm: np.ndarray
    R_cable: np.ndarray
    link_rotation: np.ndarray
    slip_sign: np.ndarray
    tau_weight_A_Nm: np.ndarray | None = None


class AugmentedModel:
    """Nominal rig + nuisance parameters + a list of effects."""

    def __init__(self, rig: Rig, effects: Sequence[Effect] = ()):
        self.rig = rig
        self.effects = tuple(effects)
        self._A = np.asarray(rig.platform_holes_A_m, float)
        self._B = np.asarray(rig.base_holes_B_m, float)
        self._k = np.asarray(rig.cable_stiffness_N_per_m, float)
        self._mr = rig.platform_mass_kg * np.asarray(rig.com_A_m, float)
        self._g = np.asarray(rig.gravity_B_m_per_s2, float)
        sizes = [len(NUISANCE_NAMES)] + [e.n_params for e in self.effects]
        self._offsets = np.cumsum([0] + sizes)

    @property
    def name(self) -> str:
        return "+".join(e.name for e in self.effects) or "none"

    @property
    def param_names(self) -> tuple[str, ...]:
        return NUISANCE_NAMES + tuple(n for e in self.effects for n in e.param_names)

    @property
    def n_params(self) -> int:
        return int(self._offsets[-1])

    @property
    def scales(self) -> np.ndarray:
        return np.concatenate([NUISANCE_SCALES] + [e.scales for e in self.effects])

    @property
    def lower_bounds(self) -> np.ndarray:
        return np.concatenate([np.full(2, -np.inf)] + [e.lower_bounds for e in self.effects])

    @property
    def prior_sd(self) -> np.ndarray:
        """Ridge prior sd per parameter (inf = no prior)."""
        parts = [np.full(2, np.inf)]
        for e in self.effects:
            parts.append(np.full(e.n_params, np.inf) if e.prior_sd is None else e.prior_sd)
        return np.concatenate(parts)

    def x0(self) -> np.ndarray:
        return np.zeros(self.n_params)

    def effect_params(self, theta: np.ndarray) -> list[np.ndarray]:
        return [theta[self._offsets[i + 1]:self._offsets[i + 2]] for i in range(len(self.effects))]

    def balance(self, R_m: np.ndarray, rows: Rows, theta: np.ndarray) -> np.ndarray:
        """Moment balance residual ``g`` (n, 3) N m at measured-body poses ``R_m``."""
        theta = np.asarray(theta, float)
        n = len(rows)
        eye = np.broadcast_to(np.eye(3), (n, 3, 3))
        ev = Evaluation(self._A, self._B, self._mr, rows.tau_meas_A_Nm, R_m, eye, rows.slip_sign)
        params = self.effect_params(theta)
        for e, p in zip(self.effects, params):
            e.adjust_load(ev, p)
        ev.tau_weight_A_Nm = kin.weight_moment(R_m, ev.first_moment_A_kgm, self._g)
        for e, p in zip(self.effects, params):
            e.adjust_pose(ev, p)
        for e, p in zip(self.effects, params):
            e.adjust_geometry(ev, p)
        lengths, J = kin.cable_terms(ev.R_cable, ev.A_m, ev.B_m)
        stretch = lengths - (rows.rest_lengths_m + theta[1])
        T = np.exp(theta[0]) * self._k * np.maximum(stretch, 0.0)
        for e, p in zip(self.effects, params):
            T = e.adjust_tension(ev, stretch, T, p)
        tau_load = ev.tau_ext_A_Nm + ev.tau_weight_A_Nm
        return np.einsum("nij,ni->nj", J, T) + np.einsum("nij,nj->ni", ev.link_rotation, tau_load)

    def predict_poses(self, rows: Rows, theta: np.ndarray, R_init: np.ndarray) -> kin.PoseSolution:
        """Equilibrium poses of the measured body for each row (forward statics)."""
        return kin.solve_poses(lambda R: self.balance(R, rows, theta), R_init)


def slip_signs(cycle: np.ndarray, cable_lengths_m: np.ndarray, eps_m: float = 1e-7) -> np.ndarray:
    """Sliding direction of each cable per row: sign of the length change since the previous row
    of the same cycle (kept when the change is below ``eps_m``); 0 on a cycle's first row."""
    s = np.zeros_like(cable_lengths_m)
    for i in range(1, len(cycle)):
        if cycle[i] != cycle[i - 1]:
            continue
        d = cable_lengths_m[i] - cable_lengths_m[i - 1]
        s[i] = np.where(np.abs(d) > eps_m, np.sign(d), s[i - 1])
    return s
