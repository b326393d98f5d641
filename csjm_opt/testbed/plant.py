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
  path dependent). A Coulomb law (a constant friction force ``F_i`` at the
  guide, as MuJoCo's tendon ``frictionloss``) bounds ``|T_p - T_d| <= F_i``
  instead: the band is ``T_p in [k e - (1 - rho) F_i, k e + (1 - rho) F_i]``
  (with both laws the two bands add). The log's first row starts settled
  (``T_p = T_d``) unless ``friction_start`` says otherwise; with
  ``persistent`` (the default, as in a real experiment: nobody relaxes the
  cables between cycles) every later cycle starts from the state where the
  previous one settled (pose and stuck segments), the rest lengths and the
  load moving to the new cycle's first row quasi-statically; without it
  every cycle starts settled;
* link compliance: the loaded, tracked body is joined to the cable platform
  by a symmetric compliance ``C``, ``R_meas = R_cable exp(hat(C tau_m))``;
* sensor bias: the F/T reading is offset by a constant ``b`` in {A};
* sensor gain: the F/T reading is the true moment times a gain per axis of {A}
  (``tau_meas = diag(g) tau + b``);
* drive offsets: each drive realises its commanded rest length plus a constant
  ``d_i`` (a homing error), ``l_true = l + d``;
* tracker registration: the tracker reports ``Q_B R Q_A`` (its frame rotated
  against {B}, the markers against {A});
* a common stiffness error: a :class:`Rig` with scaled stiffnesses;
* joint friction: a Coulomb friction moment ``|tau_f,j| <= M`` per axis of
  {A} at the ball joint (MuJoCo's ball-joint ``frictionloss``): the platform
  sticks to an anchor pose (stiffly, ``JOINT_STICK_NM_PER_RAD``) until the
  moment needed reaches ``M`` on an axis, then slips (a play operator, with
  memory like the cable friction).

How a row's load reaches the rig (:attr:`TestbedPlant.loading`): ``"ramp"`` (default) moves
the load (and the rest lengths) from one row's to the next in small quasi-static steps, the
friction state following the play operators above. ``"step"`` hangs each row's load at once,
as a lab hangs a weight: from the pose where the previous row settled, the platform moves along
an overdamped path under sliding friction and stops at the first point where friction within the
*static* bounds (``static_friction_ratio`` times the sliding ones) holds it
(:mod:`csjm_opt.testbed.step_settling`). There the friction elements are those of MuJoCo's
model (:meth:`TestbedPlant.frictionless_net`): each cable's friction force ``|f_i| <= F_i + mu_beta_i T_i``
acts on the tension the platform feels (a rigid platform-side segment, ``rho`` not used), the ball
joint's ``|tau_f,j| <= M`` on each axis of {A}; a new cycle's rest lengths still move in
``SUBSTEPS_NEW_CYCLE`` increments (the drives, each increment settled the same way) under the
previous row's load before the new load is hung.

Effects outside the diagnosis's vocabulary (to test that it says so):

* finite guide radius (``guide_radius``, an eyelet): each base guide is a ring of radius ``r`` in the base
  plane; the cable leaves it at the rim, on the side towards the platform
  hole, so the effective base hole moves with the cable's direction;
* thermal drift of the F/T sensor: the moment offset grows linearly with the
  row index (time) over the log, ``b(t) = drift * t``;
* drum slip: a cable slips on its drum when its tension exceeds a threshold
  ``T_s``, lengthening its rest length by ``(T - T_s) c_slip`` for the rest
  of the cycle (irreversible, accumulated row after row; the drives re-home
  between cycles, also with ``persistent``).
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable

import numpy as np

from .. import so3
from ..errors import InvalidInput, NoEquilibrium
from ..model import kinematics as kin
from ..model.rig import Rig
from .step_settling import settle_after_step

#: Width (N) of the rounding of the play operator's corners (keeps Newton's method happy).
SMOOTH_N = 0.002
#: Quasi-static steps from one row's load to the next (friction plants), and from a cycle's last row to
#: the next cycle's first (rest lengths and load) when cycles persist.
SUBSTEPS_ROW = 8
#: Stiffness of a stuck ball joint (N m/rad; joint friction) and the lever (m) turning SMOOTH_N into a moment.
JOINT_STICK_NM_PER_RAD = 1e4
JOINT_SMOOTH_M = 0.01
#: Finite-difference step (rad) of Newton's tangent for a row whose joint is about to slip. The stuck
#: joint's moment goes from sticking to its bound over ``SMOOTH_N * JOINT_SMOOTH_M / JOINT_STICK_NM_PER_RAD``
#: = 2e-9 rad of rotation; the default step (1e-7 rad) straddles that transition, the tangent is wrong
#: there and Newton stalls (about 5e-4 N m) on a slipping row. Coulomb friction cannot remove an
#: equilibrium the frictionless rig has, so a stalled row is solved again with a step inside it.
JOINT_TANGENT_STEP_RAD = 0.5 * SMOOTH_N * JOINT_SMOOTH_M / JOINT_STICK_NM_PER_RAD
SUBSTEPS_NEW_CYCLE = 16


def _softplus(z: np.ndarray, w: float) -> np.ndarray:
    return w * np.logaddexp(0.0, z / w)


def _smooth_clip(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, w: float) -> np.ndarray:
    """``clip(x, lo, hi)`` with corners rounded over about ``w``."""
    return lo + _softplus(x - lo, w) - _softplus(x - hi, w)


EFFECT_NAMES = ("hole_offsets", "friction", "cable_hardening", "link_compliance", "sensor_bias", "mass_com",
                "tracker_registration", "stiffness_scale", "drive_offsets", "sensor_gain", "joint_friction")
#: Further laws of a vocabulary effect the testbed can inject, and the vocabulary name a diagnosis should give.
VARIANT_NAMES = {"coulomb_friction": "friction"}
#: Effects the testbed simulates that the diagnosis has no model for.
OUTSIDE_NAMES = ("guide_radius", "sensor_drift", "drum_slip")
#: Old effect names still accepted (with a DeprecationWarning) -> their name now.
DEPRECATED_NAMES = {"eyelet_radius": "guide_radius"}
#: How a row's load reaches the rig (:attr:`TestbedPlant.loading`; the MuJoCo plant's too).
LOADINGS = ("ramp", "step")


@dataclasses.dataclass(frozen=True, eq=False)
class TestbedPlant:
    """A rig with injected effects (all zero/identity = the nominal rig)."""

    __test__ = False                           # a plant, not a pytest test class (its name starts with "Test")

    rig: Rig                                   # true geometry, stiffness, mass, com
    hardening_per_m: float = 0.0
    friction_mu_beta: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(6))
    friction_platform_fraction: float = 0.1    # rho: compliance share of the platform-side segment
    friction_start: float = 0.0                # band position at a cycle's first row (0 settled, -1 pulled in)
    friction_coulomb_N: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(6))   # F_i at the guide
    joint_friction_Nm: float = 0.0             # Coulomb friction moment of the ball joint, per axis of {A}
    link_compliance_rad_per_Nm: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))
    sensor_bias_A_Nm: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    sensor_gain_A: np.ndarray = dataclasses.field(default_factory=lambda: np.ones(3))   # reading / true, per axis
    drive_offsets_m: np.ndarray | None = None  # (m,) actual minus commanded rest length per drive (None: 0)
    tracker_rotation_B: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(3))   # Q_B
    marker_rotation_A: np.ndarray = dataclasses.field(default_factory=lambda: np.eye(3))    # Q_A
    guide_radius_m: float = 0.0
    sensor_drift_A_Nm_per_row: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    drum_slip_threshold_N: float = np.inf
    drum_slip_compliance_m_per_N: float = 0.0
    effects: tuple[str, ...] = ()
    persistent: bool = True                    # cycles start where the previous one settled
    loading: str = "ramp"                      # "ramp" (quasi-static play operators) or "step" (hung at once)
    static_friction_ratio: float = 1.0         # static over sliding friction bounds ("step" loading)

    def __post_init__(self) -> None:
        if self.loading not in LOADINGS:
            raise InvalidInput(f"unknown loading {self.loading!r}; expected one of {', '.join(LOADINGS)}", "loading")
        ratio = self.static_friction_ratio
        if not (isinstance(ratio, (int, float, np.floating, np.integer)) and np.isfinite(ratio) and ratio >= 1.0):
            raise InvalidInput(f"static_friction_ratio must be a finite number >= 1 (got {ratio!r})",
                               "static_friction_ratio")
        if ratio != 1.0 and self.loading != "step":
            raise InvalidInput("static_friction_ratio above 1 needs step loading on the quasi-static plant (its "
                               "ramped loads follow one friction band)", "static_friction_ratio")
        m = self.rig.n_cables                   # per-cable effects are sized by the rig
        for name in ("friction_mu_beta", "friction_coulomb_N"):
            value = np.asarray(getattr(self, name), float)
            if value.shape != (m,):
                if value.shape == (6,) and not value.any():     # the all-zero default
                    value = np.zeros(m)
                else:
                    raise InvalidInput(f"{name}: expected {m} values (one per cable), got shape {value.shape}",
                                       name)
                object.__setattr__(self, name, value)

    @classmethod
    def nominal(cls, rig: Rig) -> TestbedPlant:
        """The rig without effects.

        Parameters
        ----------
        rig : Rig

        Returns
        -------
        TestbedPlant
        """
        return cls(rig)

    @property
    def has_friction(self) -> bool:
        """Whether any cable has friction at its guide (the response is path dependent)."""
        return bool(np.any(self.friction_mu_beta > 0) or np.any(np.asarray(self.friction_coulomb_N) > 0)
                    or self.joint_friction_Nm > 0)

    # ------------------------------------------------------------ simulation
    def respond(self, rest_lengths_m: np.ndarray, tau_ext_A_Nm: np.ndarray, cycle: np.ndarray,
                R_init: np.ndarray, load_first_moment_A_kgm: np.ndarray | None = None,
                progress: Callable[[int], object] | None = None) -> np.ndarray:
        """True poses of the measured body (n, 3, 3) for rows in time order (noise-free).

        Path-dependent plants (friction, drum slip) step the rows in time order,
        the load (and, between cycles, the rest lengths) moving from one row's
        to the next in small steps. With :attr:`persistent` the whole log is one
        history (each cycle starts where the previous one settled); otherwise
        every cycle starts settled at ``R_init`` of its first row (cycles in
        parallel). Path-independent plants solve each row from ``R_init`` and the
        previous row of its cycle. With ``loading="step"`` each row's load is hung
        at once and the platform comes to rest under friction (the module doc);
        the log's first row (every cycle's without :attr:`persistent`) starts
        relaxed, at the frictionless equilibrium nearest ``R_init``. Without
        friction a step-loaded row comes to rest at its equilibrium, which is
        solved for directly (as with ramped loads).

        Parameters
        ----------
        rest_lengths_m : (n, m) array
        tau_ext_A_Nm : (n, 3) array
            True external moments in {A}.
        cycle : (n,) int array
            Cycle ids (rows of a cycle contiguous).
        R_init : (n, 3, 3) array
            Starting guesses; only each cycle's first row is used.
        load_first_moment_A_kgm : (n, 3) array, optional
            Dead weights hung on the measured body, ``mass * point`` in {A}
            (kg m): their moment ``(m p) x (R^T g)`` adds to ``tau_ext_A_Nm``.
        progress : callable, optional
            Called with the number of rows just settled (e.g. ``tqdm.update``).

        Returns
        -------
        (n, 3, 3) array

        Raises
        ------
        NoEquilibrium
            The plant has no equilibrium for some row.
        """
        rest_lengths_m = np.asarray(rest_lengths_m, float)
        if self.drive_offsets_m is not None:      # what the drives realise for what was commanded
            rest_lengths_m = rest_lengths_m + np.asarray(self.drive_offsets_m, float)
        tau_ext_A_Nm = np.asarray(tau_ext_A_Nm, float)
        cycle = np.asarray(cycle)
        n = len(cycle)
        mr_load = (np.zeros((n, 3)) if load_first_moment_A_kgm is None
                   else np.asarray(load_first_moment_A_kgm, float).reshape(n, 3))
        new_cycle = np.r_[True, cycle[1:] != cycle[:-1]]
        if self.loading == "step" and self.has_friction:    # without friction the path ends at the equilibrium
            return self._respond_step(rest_lengths_m, tau_ext_A_Nm, new_cycle, np.asarray(R_init, float), mr_load,
                                      progress)
        path = self.has_friction
        chain_one = self.persistent and path
        starts = np.array([0]) if chain_one else np.flatnonzero(new_cycle)
        ends = np.r_[starts[1:], n]
        R_out = np.empty((n, 3, 3))
        R_prev = np.array(R_init[starts], float)
        u_state = np.full((len(starts), self.rig.n_cables + 3), np.nan)   # stuck platform-side lengths, joint anchor
        tau_prev = np.array(tau_ext_A_Nm[starts], float)
        mr_prev = np.array(mr_load[starts], float)
        l_prev = np.array(rest_lengths_m[starts], float)
        slip = np.zeros((len(starts), self.rig.n_cables))   # drum slip so far in each cycle
        for j in range(int((ends - starts).max())):
            live = np.flatnonzero(starts + j < ends)
            idx = starts[live] + j
            if chain_one and new_cycle[idx[0]]:
                slip[:] = 0.0                       # the drives re-home between cycles
            l, tau, mr = rest_lengths_m[idx], tau_ext_A_Nm[idx], mr_load[idx]
            # path-dependent plants are loaded quasi-statically: the load (and
            # the rest lengths) move from the previous row's to this row's in small steps
            boundary = chain_one and bool(new_cycle[idx[0]])
            substeps = 1 if not (path and j > 0) else (SUBSTEPS_NEW_CYCLE if boundary else SUBSTEPS_ROW)
            R, u = R_prev[live], u_state[live]
            for q in range(1, substeps + 1):
                f = q / substeps
                tau_q = tau_prev[live] + (tau - tau_prev[live]) * f
                mr_q = mr_prev[live] + (mr - mr_prev[live]) * f
                l_q = l_prev[live] + (l - l_prev[live]) * f + (slip[live] if self._slipping else 0.0)

                def g(R, l=l_q, tau_q=tau_q, u=u, mr_q=mr_q):
                    return self._balance(R, l, tau_q, u, mr_q)[0]

                sol = kin.solve_poses(g, R, tol_Nm=1e-10)
                if not np.all(sol.converged(1e-7)) and self.joint_friction_Nm > 0:
                    sol = kin.solve_poses(g, R, tol_Nm=1e-10, tangent_step_rad=JOINT_TANGENT_STEP_RAD)
                if not np.all(sol.converged(1e-7)):
                    bad = idx[~sol.converged(1e-7)]
                    raise NoEquilibrium(f"plant has no equilibrium for rows {bad.tolist()}", "diverged",
                                        float(sol.residual_Nm.max()))
                R = sol.R
                _, u = self._balance(R, l_q, tau_q, u, mr_q, smooth_N=0.0)   # the state follows the exact play
            u_state[live] = u
            if self._slipping:       # after this row's equilibrium, over-tensioned cables slip
                k = np.asarray(self.rig.cable_stiffness_N_per_m)
                over = np.maximum(k * (self._lengths(R) - l - slip[live]) - self.drum_slip_threshold_N, 0.0)
                slip[live] += over * self.drum_slip_compliance_m_per_N
            R_prev[live] = R
            tau_prev[live] = tau
            mr_prev[live] = mr
            l_prev[live] = l
            R_out[idx] = R
            if progress is not None:
                progress(len(idx))
        return R_out

    @functools.cached_property
    def _has_link(self) -> bool:
        return bool(np.any(np.asarray(self.link_compliance_rad_per_Nm) != 0))

    @functools.cached_property
    def _cable_friction(self) -> bool:
        return bool(np.any(self.friction_mu_beta > 0) or np.any(np.asarray(self.friction_coulomb_N) > 0))

    @property
    def _slipping(self) -> bool:
        return bool(np.isfinite(self.drum_slip_threshold_N) and self.drum_slip_compliance_m_per_N > 0)

    def measured_moment(self, tau_ext_A_Nm: np.ndarray) -> np.ndarray:
        """What the F/T sensor reads without noise (N m): gain, bias, and drift over the rows (time order)."""
        tau = np.asarray(tau_ext_A_Nm, float)
        t = np.arange(len(tau))[:, None] if tau.ndim == 2 else 0.0       # rows in time order
        drift = t * np.asarray(self.sensor_drift_A_Nm_per_row)
        return tau * np.asarray(self.sensor_gain_A, float) + self.sensor_bias_A_Nm + drift

    def measured_pose(self, R_true: np.ndarray) -> np.ndarray:
        """What the tracker reports without noise: ``Q_B R Q_A``."""
        return self.tracker_rotation_B @ R_true @ self.marker_rotation_A

    def _base_holes(self, R_c: np.ndarray) -> np.ndarray:
        """Effective base holes (n, m, 3) or (m, 3): on the eyelet's rim, towards the platform hole."""
        B = np.asarray(self.rig.base_holes_B_m)
        if self.guide_radius_m <= 0:
            return B
        a_B = np.einsum("nij,kj->nki", R_c, np.asarray(self.rig.platform_holes_A_m))    # R a_i
        d = a_B - B
        d[..., 2] = 0.0
        return B + self.guide_radius_m * d / np.linalg.norm(d, axis=-1, keepdims=True)

    def _lengths(self, R_m: np.ndarray) -> np.ndarray:
        """Cable lengths at measured-body poses (the link's twist neglected; used for drum slip)."""
        c, _ = kin.cable_terms(R_m, np.asarray(self.rig.platform_holes_A_m), self._base_holes(R_m))
        return c

    def friction_bounds(self, tensions_N: np.ndarray) -> np.ndarray:
        """Sliding friction bounds of the friction elements: each cable's (N), then the ball joint's axes (N m).

        A cable's is ``F_i + mu_beta_i T_i`` (Coulomb plus the capstan law linearised at the
        tension, as MuJoCo's tendon ``frictionloss``), the joint's ``M`` on each axis of {A}. The
        static bounds are :attr:`static_friction_ratio` times these.

        Parameters
        ----------
        tensions_N : (..., m) array
            Cable tensions (elastic, friction excluded).

        Returns
        -------
        (..., m + 3) array
        """
        T = np.asarray(tensions_N, float)
        F = np.asarray(self.friction_coulomb_N, float) + np.asarray(self.friction_mu_beta, float) * T
        return np.concatenate([F, np.full(T.shape[:-1] + (3,), float(self.joint_friction_Nm))], axis=-1)

    def frictionless_net(self, R_m: np.ndarray, rest_lengths_m: np.ndarray, tau_ext_A_Nm: np.ndarray,
                         load_first_moment_A_kgm: np.ndarray | None = None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The net moment without friction, the friction elements' moment directions and their sliding bounds.

        The pose ``R_m`` is held under the inputs when friction forces ``f`` within their
        (static) bounds balance it: ``net + directions @ f = 0``
        (:func:`~csjm_opt.testbed.static_certificate.certify_static`). The elements are the
        cables (a unit friction force adds to the tension the platform feels: its column of
        ``J^T``) and the ball joint's axes of {A} (identity columns); rest lengths are the
        drives' (drive offsets included by the caller).

        Parameters
        ----------
        R_m : (n, 3, 3) array
            Poses of the measured body.
        rest_lengths_m : (n, m) or (m,) array
        tau_ext_A_Nm : (n, 3) or (3,) array
            External moments in {A} (on the measured body).
        load_first_moment_A_kgm : (n, 3) or (3,) array, optional
            Dead weights' ``mass * point`` in {A}.

        Returns
        -------
        net : (n, 3) array
            Frictionless net moment on the cable platform (N m): cable tensions (hardening included),
            weight, load.
        directions : (n, 3, m + 3) array
        bounds : (n, m + 3) array
            Sliding bounds (:meth:`friction_bounds`).
        """
        R_m = np.asarray(R_m, float)
        n = len(R_m)
        mr = np.zeros(3) if load_first_moment_A_kgm is None else np.asarray(load_first_moment_A_kgm, float)
        tau_m, E, _, c, J = self._loaded(R_m, np.broadcast_to(tau_ext_A_Nm, (n, 3)), np.broadcast_to(mr, (n, 3)))
        k = np.asarray(self.rig.cable_stiffness_N_per_m)
        e = c - np.asarray(rest_lengths_m, float)
        T = self._hardened(np.maximum(k * e, 0.0), e)
        net = self._moment(J, T, tau_m, E)
        directions = np.concatenate([np.swapaxes(J, 1, 2), np.broadcast_to(np.eye(3), (n, 3, 3))], axis=2)
        return net, directions, self.friction_bounds(T)

    def _respond_step(self, rest_lengths_m, tau_ext_A_Nm, new_cycle, R_init, mr_load, progress):
        """:meth:`respond` with every row's load hung at once (module doc; rest lengths with drive offsets)."""
        n = len(new_cycle)
        m = self.rig.n_cables
        R_out = np.empty((n, 3, 3))
        k = np.asarray(self.rig.cable_stiffness_N_per_m)
        slip = np.zeros(m)
        R = l_prev = tau_prev = mr_prev = None
        for i in range(n):
            if new_cycle[i]:
                slip[:] = 0.0                       # the drives re-home between cycles
            l = rest_lengths_m[i] + slip
            if R is None or (new_cycle[i] and not self.persistent):      # relaxed start: nothing stuck
                def g(Rs, l=l, tau=tau_ext_A_Nm[i], mr=mr_load[i]):
                    return self.frictionless_net(Rs, l, tau, mr)[0]

                sol = kin.solve_poses(g, R_init[i][None], tol_Nm=1e-10)
                if not np.all(sol.converged(1e-7)):
                    raise NoEquilibrium(f"plant has no equilibrium for row {i}", "diverged",
                                        float(sol.residual_Nm.max()))
                R = sol.R[0]
            else:
                if new_cycle[i]:    # the drives move to the new cycle's rest lengths under the load hung before
                    for q in range(1, SUBSTEPS_NEW_CYCLE + 1):
                        R = self._settle(R, l_prev + (l - l_prev) * q / SUBSTEPS_NEW_CYCLE, tau_prev, mr_prev, i)
                R = self._settle(R, l, tau_ext_A_Nm[i], mr_load[i], i)
            if self._slipping:       # after this row's rest, over-tensioned cables slip
                over = np.maximum(k * (self._lengths(R[None])[0] - l) - self.drum_slip_threshold_N, 0.0)
                slip += over * self.drum_slip_compliance_m_per_N
            R_out[i] = R
            l_prev, tau_prev, mr_prev = l, tau_ext_A_Nm[i], mr_load[i]
            if progress is not None:
                progress(1)
        return R_out

    def _settle(self, R, l, tau, mr, row):
        def net(Rs):
            return self.frictionless_net(Rs, l, tau, mr)

        try:
            return settle_after_step(net, R, self.static_friction_ratio).R
        except NoEquilibrium as exc:
            raise NoEquilibrium(f"row {row}: {exc}", exc.reason, exc.residual_Nm) from None

    def _loaded(self, R_m, tau_ext, mr_load):
        """Load moment, link rotation ``E`` (``None``: no link), platform pose, cable lengths and ``J`` at ``R_m``."""
        rig = self.rig
        mr = rig.platform_mass_kg * np.asarray(rig.com_A_m) + mr_load
        tau_m = tau_ext + kin.weight_moment(R_m, mr, np.asarray(rig.gravity_B_m_per_s2))
        if self._has_link:
            E = so3.exp(tau_m @ self.link_compliance_rad_per_Nm)     # C symmetric
            R_c = R_m @ np.swapaxes(E, 1, 2)
        else:
            E, R_c = None, R_m
        c, J = kin.cable_terms(R_c, np.asarray(rig.platform_holes_A_m), self._base_holes(R_c))
        return tau_m, E, R_c, c, J

    def _moment(self, J, T, tau_m, E):
        """Net moment on the cable platform of tensions ``T`` (platform side) and the load ``tau_m``."""
        return np.einsum("nij,ni->nj", J, T) + (tau_m if E is None else np.einsum("nij,nj->ni", E, tau_m))

    def _hardened(self, T_N, stretch_m):
        """Tensions ``T_N`` (N) of a linear cable under the hardening law: ``T (1 + h max(stretch, 0))``."""
        return T_N * (1.0 + self.hardening_per_m * np.maximum(stretch_m, 0.0))

    def _balance(self, R_m, l, tau_ext, u, mr_load, smooth_N=SMOOTH_N):
        tau_m, E, R_c, c, J = self._loaded(R_m, tau_ext, mr_load)
        k = np.asarray(self.rig.cable_stiffness_N_per_m)
        e = c - l
        m = self.rig.n_cables
        T_p = np.maximum(self._friction(c, l, e, k, u[:, :m], smooth_N), 0.0)
        u_new = np.empty_like(u)
        u_new[:, :m] = c - self.friction_platform_fraction * T_p / k
        T = self._hardened(T_p, e)
        g = self._moment(J, T, tau_m, E)
        if self.joint_friction_Nm > 0:     # per axis of {A}: stuck to an anchor pose, slips at the bound
            a = u[:, m:]
            z = so3.log(np.swapaxes(so3.exp(np.nan_to_num(a)), 1, 2) @ R_c)
            stick = np.where(np.isnan(a), 0.0, -JOINT_STICK_NM_PER_RAD * z)
            M = np.full_like(stick, self.joint_friction_Nm)
            w = smooth_N * JOINT_SMOOTH_M
            tau_f = _smooth_clip(stick, -M, M, w) if w > 0 else np.clip(stick, -M, M)
            g = g + tau_f
            u_new[:, m:] = so3.log(R_c @ so3.exp(tau_f / JOINT_STICK_NM_PER_RAD))
        else:
            u_new[:, m:] = np.nan
        return g, u_new

    def _friction(self, c, l, e, k, u, smooth_N):
        if not self._cable_friction:
            return k * e
        rho = self.friction_platform_fraction
        r = np.exp(self.friction_mu_beta)
        F = (1 - rho) * np.asarray(self.friction_coulomb_N, float)
        lo = k * e / (rho + (1 - rho) * r) - F      # r_- = 1/r
        hi = k * e / (rho + (1 - rho) / r) + F
        s0 = self.friction_start                    # first row: T_p = T_d r^s0 + s0 (1 - rho) F
        start = k * e * np.exp(s0 * self.friction_mu_beta) + s0 * F
        stick = np.where(np.isnan(u), start, (k / rho) * (c - np.nan_to_num(u)))
        lo, hi = np.minimum(lo, hi), np.maximum(lo, hi)
        return _smooth_clip(stick, lo, hi, smooth_N) if smooth_N > 0 else np.clip(stick, lo, hi)
