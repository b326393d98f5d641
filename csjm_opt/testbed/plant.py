"""The simulated "real" rig: the nominal rig with unmodelled effects injected.

Physics (independent of the diagnosis's fitting models where it can be):

* hole offsets and mass/centre of mass: a perturbed :class:`~csjm_opt.model.rig.Rig`;
* cable hardening: ``T = k e (1 + h e)``;
* friction at the base guide holes: each cable is split at its hole into a
  platform-side segment (fraction ``rho`` of the compliance) and a drive-side
  segment. While the cable sticks, the platform-side segment's unstretched
  length ``u`` is fixed, ``T_p = (k / rho)(c - u)``; it slips when
  ``T_p / T_d`` leaves ``[exp(-mu_beta), exp(+mu_beta)]`` (capstan law), and
  then ``T_p`` sits on the band's edge (a play operator: rate independent,
  path dependent). A cycle starts settled (``T_p = T_d``) unless
  ``friction_start`` says otherwise;
* link compliance: the loaded, tracked body is joined to the cable platform
  by a symmetric compliance ``C``, ``R_meas = R_cable exp(hat(C tau_m))``;
* sensor bias: the F/T reading is offset by a constant ``b`` in {A}.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .. import so3
from ..model import kinematics as kin
from ..model.rig import Rig

#: Width (N) of the rounding of the play operator's corners (keeps Newton's method happy).
SMOOTH_N = 0.02


def _softplus(z: np.ndarray, w: float) -> np.ndarray:
    return w * np.logaddexp(0.0, z / w)


def _smooth_clip(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, w: float) -> np.ndarray:
    """``clip(x, lo, hi)`` with corners rounded over about ``w``."""
    return lo + _softplus(x - lo, w) - _softplus(x - hi, w)


EFFECT_NAMES = ("hole_offsets", "friction", "cable_hardening", "link_compliance", "sensor_bias", "mass_com")


@dataclasses.dataclass(frozen=True, eq=False)
class Plant:
    """A rig with injected effects (all zero/identity = the nominal rig)."""

    rig: Rig                                   # true geometry, stiffness, mass, com
    hardening_per_m: float = 0.0
    friction_mu_beta: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(6))
    friction_platform_fraction: float = 0.1    # rho: compliance share of the platform-side segment
    friction_start: float = 0.0                # band position at a cycle's first row (0 settled, -1 pulled in)
    link_compliance_rad_per_Nm: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))
    sensor_bias_A_Nm: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    effects: tuple[str, ...] = ()

    @classmethod
    def nominal(cls, rig: Rig) -> "Plant":
        return cls(rig)

    # ------------------------------------------------------------ simulation
    def respond(self, rest_lengths_m: np.ndarray, tau_ext_A_Nm: np.ndarray, cycle: np.ndarray,
                R_init: np.ndarray) -> np.ndarray:
        """True poses of the measured body (n, 3, 3) for rows in time order (noise-free).

        Rows are stepped in order within each cycle (all cycles in parallel), so
        path-dependent effects see the history of their cycle.
        """
        n = len(cycle)
        starts = np.flatnonzero(np.r_[True, cycle[1:] != cycle[:-1]])
        ends = np.r_[starts[1:], n]
        R_out = np.empty((n, 3, 3))
        R_prev = np.array(R_init[starts], float)
        u_state = np.full((len(starts), 6), np.nan)           # stuck platform-side lengths
        tau_prev = np.array(tau_ext_A_Nm[starts], float)
        path = bool(np.any(self.friction_mu_beta > 0))
        for j in range(int((ends - starts).max())):
            live = np.flatnonzero(starts + j < ends)
            idx = starts[live] + j
            l, tau = rest_lengths_m[idx], tau_ext_A_Nm[idx]
            # path-dependent plants are loaded quasi-statically: the load moves
            # from the previous row's to this row's in small steps
            substeps = 8 if (path and j > 0) else 1
            R, u = R_prev[live], u_state[live]
            for q in range(1, substeps + 1):
                tau_q = tau_prev[live] + (tau - tau_prev[live]) * q / substeps

                def g(R, l=l, tau_q=tau_q, u=u):
                    return self._balance(R, l, tau_q, u)[0]

                sol = kin.solve_poses(g, R, tol_Nm=1e-10)
                if not np.all(sol.converged(1e-7)):
                    bad = idx[~sol.converged(1e-7)]
                    raise RuntimeError(f"plant has no equilibrium for rows {bad.tolist()}")
                R = sol.R
                _, u = self._balance(R, l, tau_q, u)
            u_state[live] = u
            R_prev[live] = R
            tau_prev[live] = tau
            R_out[idx] = R
        return R_out

    def measured_moment(self, tau_ext_A_Nm: np.ndarray) -> np.ndarray:
        """What a bias-free-but-for-``b`` F/T sensor reads (N m)."""
        return tau_ext_A_Nm + self.sensor_bias_A_Nm

    def _balance(self, R_m, l, tau_ext, u):
        rig = self.rig
        mr = rig.platform_mass_kg * np.asarray(rig.com_A_m)
        tau_m = tau_ext + kin.weight_moment(R_m, mr, np.asarray(rig.gravity_B_m_per_s2))
        E = so3.exp(tau_m @ self.link_compliance_rad_per_Nm)     # C symmetric
        R_c = R_m @ np.swapaxes(E, 1, 2)
        c, J = kin.cable_terms(R_c, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
        k = np.asarray(rig.cable_stiffness_N_per_m)
        e = c - l
        T_p = np.maximum(self._friction(c, l, e, k, u), 0.0)
        u_new = c - self.friction_platform_fraction * T_p / k
        T = T_p * (1.0 + self.hardening_per_m * np.maximum(e, 0.0))
        g = np.einsum("nij,ni->nj", J, T) + np.einsum("nij,nj->ni", E, tau_m)
        return g, u_new

    def _friction(self, c, l, e, k, u):
        T_free = k * e
        if not np.any(self.friction_mu_beta > 0):
            return T_free
        rho = self.friction_platform_fraction
        r = np.exp(self.friction_mu_beta)
        lo = k * e / (rho + (1 - rho) * r)        # r_- = 1/r
        hi = k * e / (rho + (1 - rho) / r)
        start = k * e * np.exp(self.friction_start * self.friction_mu_beta)   # first row: T_p = T_d r^s0
        stick = np.where(np.isnan(u), start, (k / rho) * (c - np.nan_to_num(u)))
        return _smooth_clip(stick, np.minimum(lo, hi), np.maximum(lo, hi), SMOOTH_N)
