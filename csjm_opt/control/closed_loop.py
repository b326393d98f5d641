"""Controller-in-the-loop simulation of a CSJM under a load profile.

Each step ``k`` (time ``t_k = k dt``):

1. **read**: the measured pose, angular velocity and external moment, the true
   ones plus optional :class:`~csjm_opt.measurement.instruments.InstrumentNoise`
   (pose noise as ``R exp(hat(n))``, ``n ~ N(0, sigma^2 I)``; moment noise per
   axis). The measured moment includes the moments of the plant's dead-weight
   point forces (an F/T sensor under the platform sees them), not its own weight;
2. **control**: ``command = controller(observation)``;
3. **command**: the drives take the command's rest lengths (or tensions);
4. **simulate**: the plant advances to ``t_{k+1}`` (:mod:`csjm_opt.control.plants`):
   by default the quasi-static :class:`~csjm_opt.control.plants.QuasiStaticPlant`
   (``plant_rig``, the controller's rig by default, settles at the equilibrium
   for those rest lengths under the load at ``t_{k+1}``; no dynamics), or any
   plant passed as ``plant``, e.g. :class:`~csjm_opt.control.plants.MujocoPlant`
   (inertia, damping, winch limits).

The :class:`ClosedLoopLog` holds the time series (true and measured pose,
pose error to the controller's reference, commanded and actual tensions,
achieved K of the plant against the target, wall time per step) and
:func:`plot_closed_loop` draws them.
"""

from __future__ import annotations

import dataclasses
import time
from typing import TYPE_CHECKING, Sequence

import numpy as np

from .. import so3
from ..errors import CsjmError, InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..model.rig import Rig
from ..model.statics import PointForce
from .controllers.base import Controller, Observation
from .load_profiles import LoadProfile
from .plants import Plant, QuasiStaticPlant

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


@dataclasses.dataclass(frozen=True, eq=False)
class ClosedLoopLog:
    """Time series of one run; index 0 is the initial state."""

    t_s: np.ndarray              # (n,)
    R: np.ndarray                # (n, 3, 3) true pose
    R_meas: np.ndarray           # (n, 3, 3) measured pose (what the controller read at t_k)
    R_ref: np.ndarray            # (n, 3, 3) controller's reference
    tau_ext_A_Nm: np.ndarray     # (n, 3) true external moment
    tensions_cmd_N: np.ndarray   # (n, m) tensions the controller planned (nan at 0)
    tensions_N: np.ndarray       # (n, m) actual tensions of the plant
    K: np.ndarray                # (n, 3, 3) achieved cable stiffness of the plant
    K_target: np.ndarray         # (n, 3, 3) target (nan when the controller sets none)
    step_time_s: np.ndarray      # (n,) wall time of read + control + command + simulate (nan at 0)
    step_cpu_s: np.ndarray       # (n,) the same as thread CPU time (excludes preemption by other processes)
    omega_A_rad_s: np.ndarray | None = None   # (n, 3) true angular velocity in {A} (zero when quasi-static)

    @property
    def pose_error_rad(self) -> np.ndarray:
        """``||log(R_ref^T R)||`` per sample (rad)."""
        return np.linalg.norm(so3.log(np.swapaxes(self.R_ref, 1, 2) @ self.R), axis=-1)

    @property
    def stiffness_error(self) -> np.ndarray:
        """``||K - K_target||_F`` per sample (N m/rad; nan without target)."""
        return np.linalg.norm((self.K - self.K_target).reshape(len(self.t_s), 9), axis=1)

    def summary(self) -> dict:
        """JSON-able summary of the run."""
        dt = self.step_time_s[1:]
        err = self.pose_error_rad
        return {"steps": int(len(self.t_s) - 1), "duration_s": float(self.t_s[-1] - self.t_s[0]),
                "max_pose_error_rad": float(np.max(err)), "final_pose_error_rad": float(err[-1]),
                "final_stiffness_error_Nm_per_rad": float(self.stiffness_error[-1]),
                "min_tension_N": float(np.min(self.tensions_N)), "max_tension_N": float(np.max(self.tensions_N)),
                "median_step_time_s": float(np.median(dt)) if len(dt) else float("nan"),
                "median_step_cpu_s": float(np.median(self.step_cpu_s[1:])) if len(dt) else float("nan")}


def simulate(rig: Rig, controller: Controller, load: LoadProfile, duration_s: float, dt_s: float = 1e-3,
             R_init: np.ndarray | None = None, noise: InstrumentNoise | None = None,
             rng: np.random.Generator | None = None, plant_rig: Rig | None = None,
             point_forces: Sequence[PointForce] = (), reset: bool = True,
             progress: bool | None = None, plant: Plant | None = None,
             omega_init_A_rad_s: np.ndarray | None = None) -> ClosedLoopLog:
    """Run ``controller`` on the simulated rig for ``duration_s`` with step ``dt_s`` (see module doc).

    Parameters
    ----------
    rig : Rig
        The controller's rig (and the default plant's).
    controller : Controller
    load : callable
        Load profile ``t -> (3,)`` N m, fixed in {A} (or in the frame ``plant.load_fixed_in``).
    duration_s, dt_s : float
        Run length and control period (s).
    R_init : (3, 3) array, optional
        Initial pose (default: the controller's reference at 0).
    noise, rng
        Instrument noise and its random generator.
    plant_rig, point_forces
        Rig and dead weights of the default quasi-static plant (not with ``plant``).
    reset : bool
        Reset the controller first.
    progress : bool, optional
        tqdm bar on stderr (default: only for runs over 20000 steps on a terminal).
    plant : Plant, optional
        The simulated rig (default :class:`~csjm_opt.control.plants.QuasiStaticPlant`).
    omega_init_A_rad_s : (3,) array, optional
        Initial angular velocity in {A} (plants with inertia only).

    Returns
    -------
    ClosedLoopLog

    Raises
    ------
    InvalidInput
        Non-positive durations, or ``point_forces``/``plant_rig`` together with ``plant``.
    CsjmError
        From the controller or the plant, with the simulation time prefixed.
    """
    import sys

    from tqdm import tqdm

    if not (dt_s > 0 and duration_s > 0):
        raise InvalidInput(f"expected duration_s > 0 and dt_s > 0, got {duration_s}, {dt_s}", "dt_s")
    n = int(round(duration_s / dt_s))
    if plant is None:
        plant = QuasiStaticPlant(plant_rig or rig, point_forces=list(point_forces))
    elif len(point_forces) or plant_rig is not None:
        raise InvalidInput("point_forces and plant_rig configure the default plant; not with plant=",
                           "plant")
    noise = noise or InstrumentNoise.none()
    rng = rng or np.random.default_rng(0)
    sigma_tau = np.asarray(noise.tau_sigma_Nm, float)
    tau_noise = bool(np.any(sigma_tau > 0))
    if reset:
        controller.reset()
    R = np.array(controller.reference(0.0) if R_init is None else R_init, float)
    state = plant.reset(R, omega_init_A_rad_s, load)

    t = np.arange(n + 1) * dt_s
    m_plant = getattr(plant, "rig", plant_rig or rig).n_cables
    out = {name: np.full((n + 1,) + shape, np.nan) for name, shape in
           [("R", (3, 3)), ("R_meas", (3, 3)), ("R_ref", (3, 3)), ("tau", (3,)), ("T_cmd", (rig.n_cables,)),
            ("T", (m_plant,)), ("K", (3, 3)), ("K_target", (3, 3)), ("dt", ()), ("cpu", ()), ("omega", (3,))]}
    out["R"][0], out["tau"][0], out["R_ref"][0] = R, state.tau_ext_A_Nm, controller.reference(0.0)
    out["omega"][0] = state.omega_A_rad_s
    if progress is None:
        progress = n > 20000 and sys.stderr.isatty()
    for k in tqdm(range(n), desc="closed loop", unit="step", disable=not progress, file=sys.stderr):
        t0, c0 = time.perf_counter(), time.thread_time()
        # 1. read
        tau_meas = plant.measured_load_A(R, state.tau_ext_A_Nm)
        R_meas = R
        if noise.angle_sigma_rad > 0:
            R_meas = R @ so3.exp(noise.angle_sigma_rad * rng.standard_normal(3))
        if tau_noise:
            tau_meas = tau_meas + sigma_tau * rng.standard_normal(3)
        # 2. control, 3. command
        try:
            cmd = controller(Observation(float(t[k]), R_meas, tau_meas, state.omega_A_rad_s.copy()))
            # 4. simulate
            state = plant.step(cmd, load, float(t[k]), float(t[k + 1]))
        except CsjmError as exc:
            _at_time(exc, float(t[k]))
            raise
        R = state.R
        out["dt"][k + 1] = time.perf_counter() - t0
        out["cpu"][k + 1] = time.thread_time() - c0
        out["R"][k + 1], out["R_meas"][k], out["tau"][k + 1] = R, R_meas, state.tau_ext_A_Nm
        out["omega"][k + 1] = state.omega_A_rad_s
        out["R_ref"][k + 1] = controller.reference(float(t[k + 1]))
        out["T_cmd"][k + 1], out["T"][k + 1], out["K"][k + 1] = cmd.tensions_N, state.tensions_N, state.K
        if cmd.K_target is not None:
            out["K_target"][k + 1] = cmd.K_target
    out["R_meas"][n] = R
    out["T"][0], out["K"][0] = out["T"][min(1, n)], out["K"][min(1, n)]
    return ClosedLoopLog(t, out["R"], out["R_meas"], out["R_ref"], out["tau"], out["T_cmd"], out["T"],
                         out["K"], out["K_target"], out["dt"], out["cpu"], out["omega"])


def _at_time(exc: CsjmError, t_s: float) -> CsjmError:
    """Prefix the simulation time to an error's message (same class, same data)."""
    exc.args = (f"at t = {t_s:.4f} s: {exc.args[0] if exc.args else exc}",) + tuple(exc.args[1:])
    return exc


def plot_closed_loop(log: ClosedLoopLog, t_min_N: float | None = None, t_max_N: float | None = None, *,
                     fig: Figure | None = None) -> tuple[Axes, Axes, Axes]:
    """Pose error, external moment and tensions against time, one panel each.

    Parameters
    ----------
    log : ClosedLoopLog
        From :func:`simulate`.
    t_min_N, t_max_N : float, optional
        Tension bounds (N) drawn as dotted lines.
    fig : matplotlib.figure.Figure, optional
        Empty figure to draw the three panels in; a new one is made when omitted.

    Returns
    -------
    tuple of matplotlib.axes.Axes
        The pose-error, moment and tension axes (shared time axis).
    """
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(8, 7.5), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    t = log.t_s
    axes[0].semilogy(t, np.maximum(1e3 * log.pose_error_rad, 1e-10), color="C3")
    axes[0].set_ylabel("pose error (mrad, floor 1e-10)")
    axes[1].plot(t, log.tau_ext_A_Nm, label=[r"$\tau_x$", r"$\tau_y$", r"$\tau_z$"])
    axes[1].set_ylabel("external moment (N m)")
    axes[1].legend(fontsize=7, ncol=3)
    axes[2].plot(t, log.tensions_N, lw=1.0)
    for bound in (t_min_N, t_max_N):
        if bound is not None:
            axes[2].axhline(bound, color="k", ls=":", lw=0.8)
    axes[2].set_ylabel("tensions (N)")
    axes[2].set_xlabel("time (s)")
    return axes[0], axes[1], axes[2]


def plot_closed_loop_stiffness(log: ClosedLoopLog, *, fig: Figure | None = None) -> tuple[Axes, Axes]:
    """Achieved against target stiffness: eigenvalues of K (left) and ``||K - K_target||_F`` (right).

    Parameters
    ----------
    log : ClosedLoopLog
        From :func:`simulate`; ``K_target`` is NaN where the controller sets none.
    fig : matplotlib.figure.Figure, optional
        Empty figure to draw the two panels in; a new one is made when omitted.

    Returns
    -------
    tuple of matplotlib.axes.Axes
        The eigenvalue axes and the error axes.
    """
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(10, 3.8), layout="constrained")
    axes = fig.subplots(1, 2)
    t = log.t_s
    lam = np.linalg.eigvalsh(log.K)
    has_target = np.all(np.isfinite(log.K_target.reshape(len(t), 9)), axis=1)
    lam_t = np.full_like(lam, np.nan)
    if np.any(has_target):
        Kt = log.K_target[has_target]
        lam_t[has_target] = np.linalg.eigvalsh(0.5 * (Kt + np.swapaxes(Kt, 1, 2)))
    for i in range(3):
        axes[0].plot(t, lam[:, i], color=f"C{i}", label=rf"achieved $\lambda_{i + 1}$")
        axes[0].plot(t, lam_t[:, i], color=f"C{i}", ls="--", lw=1.0, label=rf"target $\lambda_{i + 1}$")
    axes[0].set_ylabel("eigenvalues of K (N m/rad)")
    axes[0].set_xlabel("time (s)")
    axes[0].legend(fontsize=6, ncol=2)
    axes[1].plot(t, log.stiffness_error, color="C3")
    axes[1].set_ylabel(r"$||K - K_{target}||_F$ (N m/rad)")
    axes[1].set_xlabel("time (s)")
    return axes[0], axes[1]
