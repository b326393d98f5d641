"""MuJoCo as the testbed's plant: the same effects, realised in the engine's model.

:class:`MujocoTestbedPlant` wraps a :class:`~csjm_opt.testbed.plant.TestbedPlant` (the
effect parameters drawn by :func:`~csjm_opt.testbed.injection.inject`, so both
plants share effect names, parameters and random draws) and answers the same
calls (``respond``, ``measured_moment``, ``measured_pose``). The engine model is
:func:`~csjm_opt.testbed.mujoco.model.plant_mjcf`; what MuJoCo computes:

* hole offsets, mass/COM, stiffness scale: the true rig's sites, inertial and
  tendon springs;
* Coulomb friction at the guides: tendon ``frictionloss`` (MuJoCo's friction
  acts on the tendon length: the platform-side segment is rigid, ``rho = 0``);
  the capstan law: ``frictionloss = mu_beta_i T_i``, updated every step;
* joint friction: the ball joint's ``frictionloss`` (per axis of {A});
* cable hardening: the extra tension ``k h e^2`` of each taut cable through
  the tendon's Jacobian (``qfrc_applied``, every step);
* link compliance: the ``tool`` body on a ball joint, spring ``C^{-1}`` on its
  rotation vector (``qfrc_applied``); the load, the weight and the measured
  pose are the tool's;
* drum slip: rest lengths lengthened after each row (re-homed every cycle);
* sensor bias, drift and tracker registration: on the readings, as the
  quasi-static plant. A finite guide radius is not available here.

Settling a row: the rest lengths and the load move from the previous row's
to this row's over ``ramp_s`` (``friction_ramp_s`` on a plant with friction; heavy
damping, implicit integration), then the engine runs until the joint speed is below
``speed_tol_rad_per_s``. Without friction the pose is then polished by Newton's
method on MuJoCo's own net force to round-off; with friction it is certified
by :func:`~csjm_opt.testbed.static_certificate.certify_static` (friction forces within
their bounds hold it), and MuJoCo's noslip iterations stop the soft friction
from creeping. With ``persistent`` (the plant's setting, default) a cycle
starts where the previous one settled; otherwise each cycle starts from its
``R_init``, settled without friction first (a relaxed start). The wait for rest is
bounded by ``max_settle_s`` of simulated time (at most ``(cycle_ramp_s + max_settle_s) /
timestep`` engine steps a row); a row that is not at rest by then is certified as it stands
(held by friction within its bounds and the damping force of its remaining speed) and
flagged (:attr:`MujocoRow.settled`), or refused (:class:`~csjm_opt.errors.NoEquilibrium`).

Not to be confused with :class:`csjm_opt.control.plants.MujocoPlant`: that one is the
*closed loop's* plant, the nominal rig stepped in real time under a controller's commands
(inertia, winch rate limits, no injected effects, no settling). This one *settles* every
row of a log statically, with effects injected, to make diagnosis logs; both build their
engine model with :func:`csjm_opt.model.mjcf.rig_to_mjcf`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from ...errors import InvalidInput
from ...model.dynamics import rig_dynamics
from ..plant import LOADINGS, TestbedPlant
from ..static_certificate import FrictionCertificate

#: The plants a study or ``csjm simulate`` can use.
PLANTS = ("quasi-static", "mujoco")
#: Effects of the quasi-static testbed the MuJoCo plant cannot realise.
MUJOCO_UNSUPPORTED = ("guide_radius",)


@dataclasses.dataclass(frozen=True)
class MujocoRow:
    """How one row settled on the MuJoCo plant.

    Attributes
    ----------
    R_tool : (3, 3) array
        Pose of the measured body (the tool; the platform without a link).
    R_platform : (3, 3) array
        Pose of the cable platform.
    tensions_N : (m,) array
        Spring tensions (hardening included, friction excluded).
    certificate : FrictionCertificate or None
        The friction LP (``None`` without friction: polished to round-off).
    seconds_simulated : float
    speed_rad_per_s : float
        Joint speed left when the row was recorded (0 for a polished frictionless row; a slow
        creep of a row on the verge of slipping otherwise, its damping force in the certificate).
    settled : bool
        Whether the row came to rest (speed below ``speed_tol_rad_per_s``) within ``max_settle_s``
        of simulated time; a row that did not is still certified (held by friction within its
        bounds plus the damping force at the speed left) but flagged here. Frictionless rows are
        polished to an exact equilibrium (always ``True``).
    """

    R_tool: np.ndarray
    R_platform: np.ndarray
    tensions_N: np.ndarray
    certificate: FrictionCertificate | None
    seconds_simulated: float
    speed_rad_per_s: float = 0.0
    settled: bool = True


@dataclasses.dataclass(frozen=True, eq=False)
class MujocoTestbedPlant:
    """A :class:`TestbedPlant` realised in MuJoCo (see the module doc).

    Attributes
    ----------
    plant : TestbedPlant
        The effects (true rig, friction, hardening, link, readings).
    ramp_s, max_settle_s : float
        Time over which a row's inputs move (frictionless plant); longest wait for rest.
    friction_ramp_s : float
        Time over which a row's inputs move on a plant with friction. MuJoCo's tendon
        friction (noslip) does not reach its bound on a tendon that slides slowly: on a fast
        ramp the platform slides on past the quasi-static stop, and the settled pose depends on
        the ramp's speed (about 1 mrad between 0.3 s and 30 s ramps on a 3x-floor friction
        log, seven times the tracker noise). At 10 s the poses are within 0.01 mrad of a 30 s
        ramp's: the rows are quasi-static, as a real rig's dry friction makes them
        (docs/guide/mujoco.md).
    cycle_ramp_s : float
        Time over which the inputs move to a new cycle's first row on a plant with
        friction (large moves: slow enough to stay quasi-static; 20 s is within 0.01 mrad
        of 60 s).
    speed_tol_rad_per_s : float
        Joint speed below which the engine has settled.
    rest_travel_tol_rad : float
        With friction, a row is also at rest when the quasi-static travel left (the joints'
        damping force at the current speed over the tangent stiffness) is below this (default
        0: off). MuJoCo's soft friction lets a row on the verge of slipping creep on at 1e-6 to
        1e-4 rad/s for seconds (noslip reduces, does not remove it), far beyond that travel:
        without this test such a row waits the full ``max_settle_s``. At 1e-5 such rows stop
        4-6x sooner, but a row stopped so creeps on by a few 1e-6 rad in the next row
        (``benchmarks/bench_mujoco_plant.py --travel-tol``; docs/guide/diagnosis.md).
    noslip_iterations : int
        MuJoCo's noslip solver iterations (0: soft friction creeps).
    noslip_tolerance : float
        Its tolerance (MuJoCo's default 1e-6 leaves a stuck tendon creeping at ~2e-6 rad/s).
    loading : {"ramp", "step"}
        How a row's load reaches the rig. ``"ramp"`` (default): the inputs move over
        ``friction_ramp_s`` (quasi-static, the friction state follows a play operator). ``"step"``:
        as a lab hangs a weight, the row's load (and any change of its rest lengths within a
        cycle) is applied at once and the rig comes to rest under its own dynamics (the joints'
        damping of :func:`critical_damping`, friction sliding then sticking wherever the motion
        stops); the rest lengths of a new cycle still move over ``cycle_ramp_s`` (the drives),
        under the previous row's load, before the new load is hung.
    static_friction_ratio : float
        Static over sliding friction (>= 1; default 1: one bound). A friction element (a cable's
        tendon, the ball joint's axes) that moves slower than ``STICK_SPEED_M_PER_S`` (tendon) or
        ``STICK_SPEED_RAD_PER_S`` (joint) holds up to this times its sliding bound; once it breaks
        loose it slides at its sliding bound until it slows down again (updated every engine step).
        A settled row is certified against the static bounds.
    """

    plant: TestbedPlant
    ramp_s: float = 0.3
    max_settle_s: float = 6.0
    speed_tol_rad_per_s: float = 1e-6
    rest_travel_tol_rad: float = 0.0
    cycle_ramp_s: float = 20.0
    friction_ramp_s: float = 10.0
    noslip_iterations: int = 1000
    noslip_tolerance: float = 1e-12
    loading: str = "ramp"
    static_friction_ratio: float = 1.0

    def __post_init__(self) -> None:
        if self.plant.guide_radius_m > 0:
            raise InvalidInput("the MuJoCo plant has no guide radius (quasi-static plant only)", "effect")
        if self.loading not in LOADINGS:
            raise InvalidInput(f"unknown loading {self.loading!r}; expected one of {', '.join(LOADINGS)}", "loading")
        if not (np.isfinite(self.static_friction_ratio) and self.static_friction_ratio >= 1.0):
            raise InvalidInput(f"static_friction_ratio must be a number >= 1 (got {self.static_friction_ratio})",
                               "static_friction_ratio")

    @property
    def rig(self):
        """The plant's *true* rig (:attr:`TestbedPlant.rig`)."""
        return self.plant.rig

    @property
    def effects(self) -> tuple[str, ...]:
        """Names of the injected effects."""
        return self.plant.effects

    @property
    def frictional_plant(self) -> bool:
        """Whether the plant has friction (cable or joint)."""
        return self.plant.has_friction

    @property
    def persistent(self) -> bool:
        """Whether cycles start where the previous one settled."""
        return self.plant.persistent

    def measured_moment(self, tau_ext_A_Nm: np.ndarray) -> np.ndarray:
        """F/T reading without noise (as :meth:`TestbedPlant.measured_moment`).

        Parameters
        ----------
        tau_ext_A_Nm : (n, 3) or (3,) array

        Returns
        -------
        ndarray
        """
        return self.plant.measured_moment(tau_ext_A_Nm)

    def measured_pose(self, R_true: np.ndarray) -> np.ndarray:
        """Tracker reading without noise (as :meth:`TestbedPlant.measured_pose`).

        Parameters
        ----------
        R_true : (n, 3, 3) array

        Returns
        -------
        ndarray
        """
        return self.plant.measured_pose(R_true)

    def respond(self, rest_lengths_m: np.ndarray, tau_ext_A_Nm: np.ndarray, cycle: np.ndarray,
                R_init: np.ndarray, load_first_moment_A_kgm: np.ndarray | None = None,
                progress: Callable[[int], object] | None = None) -> np.ndarray:
        """True poses of the measured body (n, 3, 3), rows in time order (as :meth:`TestbedPlant.respond`).

        Parameters
        ----------
        rest_lengths_m : (n, m) array
        tau_ext_A_Nm : (n, 3) array
        cycle : (n,) int array
        R_init : (n, 3, 3) array
            Start poses; used at the log's first row (and each cycle's without persistence).
        load_first_moment_A_kgm : (n, 3) array, optional
            Dead weights on the tool, ``mass * point`` in {A} (as :meth:`TestbedPlant.respond`).
        progress : callable, optional
            Called with the number of rows just settled (e.g. ``tqdm.update``).

        Returns
        -------
        (n, 3, 3) array

        Raises
        ------
        NoEquilibrium
            A row does not settle (or the friction LP cannot certify it).
        """
        rows = self.respond_rows(rest_lengths_m, tau_ext_A_Nm, cycle, R_init, load_first_moment_A_kgm, progress)
        return np.stack([r.R_tool for r in rows])

    def respond_rows(self, rest_lengths_m: np.ndarray, tau_ext_A_Nm: np.ndarray, cycle: np.ndarray,
                     R_init: np.ndarray, load_first_moment_A_kgm: np.ndarray | None = None,
                     progress: Callable[[int], object] | None = None) -> list[MujocoRow]:
        """Like :meth:`respond`, with each row's platform pose, tensions and friction certificate.

        Parameters
        ----------
        rest_lengths_m, tau_ext_A_Nm, cycle, R_init, load_first_moment_A_kgm, progress
            As :meth:`respond`.

        Returns
        -------
        list of MujocoRow

        Raises
        ------
        NoEquilibrium
            A row does not settle (or the friction LP cannot certify it).
        """
        from .engine import Engine

        l_all = np.asarray(rest_lengths_m, float)
        if self.plant.drive_offsets_m is not None:   # what the drives realise for what was commanded
            l_all = l_all + np.asarray(self.plant.drive_offsets_m, float)
        tau_all = np.asarray(tau_ext_A_Nm, float)
        cycle = np.asarray(cycle)
        mr_all = (np.zeros((len(cycle), 3)) if load_first_moment_A_kgm is None
                  else np.asarray(load_first_moment_A_kgm, float).reshape(len(cycle), 3))
        engine = Engine(self, l_all[0])
        rows: list[MujocoRow] = []
        slip = np.zeros(self.rig.n_cables)
        for i in range(len(cycle)):
            first = i == 0 or cycle[i] != cycle[i - 1]
            if first:
                slip[:] = 0.0
            if i == 0 or (first and not self.persistent):
                engine.relaxed_start(np.asarray(R_init[i], float), l_all[i], tau_all[i], mr_all[i])
            elif self.loading == "step":
                if first:      # the drives move to the new cycle's rest lengths under the load hung before
                    engine.ramp(l_all[i] + slip, engine.tau, engine.mr,
                                self.cycle_ramp_s if self.frictional_plant else None)
                engine.set_inputs(l_all[i] + slip, tau_all[i], mr_all[i])    # the load hung at once
            else:
                seconds = (self.cycle_ramp_s if first else self.friction_ramp_s) if self.frictional_plant else None
                engine.ramp(l_all[i] + slip, tau_all[i], mr_all[i], seconds)
            row = engine.settle(i)
            rows.append(row)
            if progress is not None:
                progress(1)
            p = self.plant
            if np.isfinite(p.drum_slip_threshold_N) and p.drum_slip_compliance_m_per_N > 0:
                slip += np.maximum(row.tensions_N - p.drum_slip_threshold_N, 0.0) * p.drum_slip_compliance_m_per_N
        return rows



def as_mujoco(plant: TestbedPlant, **options) -> MujocoTestbedPlant:
    """The same plant realised in MuJoCo.

    Parameters
    ----------
    plant : TestbedPlant
    **options
        :class:`MujocoTestbedPlant` settings (``ramp_s``, ``noslip_iterations``, ...); ``loading`` and
        ``static_friction_ratio`` default to the plant's own.

    Returns
    -------
    MujocoTestbedPlant

    Raises
    ------
    InvalidInput
        An effect MuJoCo cannot realise (guide radius).
    """
    options.setdefault("loading", plant.loading)
    options.setdefault("static_friction_ratio", plant.static_friction_ratio)
    return MujocoTestbedPlant(plant, **options)


def critical_damping(plant: TestbedPlant) -> float:
    """A ball-joint damping (N m s/rad) near critical for the rig's cable stiffness and inertia.

    Parameters
    ----------
    plant : TestbedPlant

    Returns
    -------
    float
    """
    rig = plant.rig
    K = float(np.sum(np.asarray(rig.cable_stiffness_N_per_m) * np.sum(np.asarray(rig.platform_holes_A_m) ** 2, 1)))
    I_max = float(np.linalg.eigvalsh(rig_dynamics(rig).inertia_com_A_kgm2).max())
    return 2.0 * np.sqrt(K * I_max)
