"""The shaping part of ``csjm demo``: shape K at a paper pose, reachable set, short closed loop.

Also holds :func:`soft_stiff_targets`, shared with ``studies/soft_stiff_switch.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from .. import so3
from ..control.closed_loop import plot_closed_loop, plot_closed_loop_stiffness, simulate
from .._plotting import save
from ..control.controllers import StiffnessShapingController
from .._fileio import atomic_write_json
from ..control.load_profiles import Constant, Sinusoid, Step
from ..model.numeric import Model
from ..shaping.reachable import _lp, plot_reachable_set, reachable_set
from ..model.rig import Rig
from ..shaping.shaper import shape_stiffness, stiffness_basis
from .._validate import as_rotation

#: Table 3's original pose R0 with erratum 3 applied (element (3,2) = -0.300).
PAPER_R0 = np.array([[0.992, -0.060, -0.111], [0.090, 0.952, 0.292], [0.088, -0.300, 0.950]])
#: A moderate external moment for the demo (N m, in {A}).
DEMO_TAU_EXT = np.array([0.2, -0.5, 0.1])


def soft_stiff_targets(rig: Rig, R: np.ndarray, tau_ext: np.ndarray, direction: npt.ArrayLike = (1.0, 0.0, 0.0),
                       margin: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """Two reachable targets (N m/rad) at ``R`` under ``tau_ext``: softest and stiffest along ``direction``.

    Each is K at feasible tensions: those minimising (maximising) the
    directional stiffness ``u^T K u`` (an exact LP, :mod:`csjm_opt.shaping.reachable`),
    pulled ``margin`` of the way toward the mid-range plan so that they are
    not on the boundary of the feasible set.
    """
    from ..planning.planner import plan_tensions

    basis = stiffness_basis(rig, R)
    tau_load = tau_ext + basis.tau_weight_A_Nm
    u = np.asarray(direction, float) / np.linalg.norm(direction)
    g = np.einsum("j,ijk,k->i", u, basis.G, u)
    T_mid = plan_tensions(rig, R, tau_ext).tensions_N
    T_soft = _lp(g, basis.J, tau_load, rig.t_min_N, rig.t_max_N)
    T_stiff = _lp(-g, basis.J, tau_load, rig.t_min_N, rig.t_max_N)
    return (basis.K((1 - margin) * T_soft + margin * T_mid), basis.K((1 - margin) * T_stiff + margin * T_mid))


def run_demo(rig: Rig, out_dir: Path, R: np.ndarray | None = None, tau_ext: np.ndarray | None = None,
             duration_s: float = 0.3, dt_s: float = 1e-3) -> dict:
    """Shaping example, reachable-set figure and a short closed loop; returns a JSON-able summary."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    R = as_rotation(PAPER_R0 if R is None else R)
    tau = DEMO_TAU_EXT if tau_ext is None else np.asarray(tau_ext, float)
    model = Model(rig)

    # 1. shaping: a reachable target (from feasible tensions) and an unreachable isotropic one
    K_soft, K_stiff = soft_stiff_targets(rig, R, tau)
    reach = shape_stiffness(rig, R, tau, K_stiff, model=model)
    rs = reachable_set(rig, R, tau, n_samples=1500)
    iso = 1.15 * rs.eigen_ranges[2, 1] * np.eye(3)           # stiffer than any eigenvalue can be
    unreach = shape_stiffness(rig, R, tau, iso, model=model)

    # 2. reachable set figure, with the two shaped results marked
    ax_eig, _ = plot_reachable_set(rs, rig.t_min_N, rig.t_max_N, {"shaped (reachable target)": reach.K,
                                                                   "shaped (isotropic target)": unreach.K})
    fig_reach = save(ax_eig.figure, out_dir / "reachable_set.png")

    # 3. closed loop: hold R, step + sinusoidal disturbance about x, soft/stiff (about x) switching at half time
    half = duration_s / 2
    target = lambda t: K_soft if t < half else K_stiff                         # noqa: E731
    load = (Constant(tau) + Step(0.2 * duration_s, np.array([0.15, 0.0, 0.0]))
            + Sinusoid(np.array([0.05, 0.0, 0.0]), 10.0))
    ctrl = StiffnessShapingController(rig, R, target)
    log = simulate(rig, ctrl, load, duration_s, dt_s)
    figs = [save(plot_closed_loop(log, rig.t_min_N, rig.t_max_N)[0].figure, out_dir / "closed_loop.png"),
            save(plot_closed_loop_stiffness(log)[0].figure, out_dir / "closed_loop_K.png")]
    summ = log.summary()

    summary = {
        "pose_rotvec_rad": so3.log(R).tolist(),
        "tau_ext_Nm": tau.tolist(),
        "reachable_target_residual_Nm_per_rad": reach.residual,
        "reachable_target_exact": reach.exact,
        "soft_Kxx_Nm_per_rad": float(K_soft[0, 0]),
        "stiff_Kxx_Nm_per_rad": float(K_stiff[0, 0]),
        "isotropic_target_Nm_per_rad": float(iso[0, 0]),
        "isotropic_target_residual_Nm_per_rad": unreach.residual,
        "isotropic_target_exact": unreach.exact,
        "isotropic_active_bounds": ", ".join(unreach.active_bounds) or "none",
        "eigen_ranges_Nm_per_rad": rs.eigen_ranges.tolist(),
        "closed_loop_steps": summ["steps"],
        "closed_loop_max_pose_error_rad": summ["max_pose_error_rad"],
        "closed_loop_final_pose_error_rad": summ["final_pose_error_rad"],
        "closed_loop_final_stiffness_error_Nm_per_rad": summ["final_stiffness_error_Nm_per_rad"],
        "closed_loop_median_step_us": 1e6 * summ["median_step_time_s"],
        "shaping": {"reachable": reach.as_dict(), "isotropic": unreach.as_dict()},
        "reachable_set": rs.as_dict(),
        "closed_loop": summ,
        "figures": [p.relative_to(out_dir).as_posix() for p in [fig_reach, *figs]],
    }
    atomic_write_json(out_dir / "shaping_summary.json", summary)
    return summary
