"""Ready-made views: a path to one pose, a list of poses, a log's cycles, designs side by side.

Each returns a :class:`~csjm_opt.view.page.ViewPage` (write it with ``.write(path)``; in a
notebook it displays itself).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from .. import so3
from .._validate import as_vector3
from ..errors import InvalidInput
from ..measurement.logfile import MeasurementLog
from ..model.rig import Rig
from .page import ViewPage, view_page
from .state import rig_state

__all__ = ["designs_view", "log_view", "pose_view", "poses_view", "show"]


def _pose_label(rotvec: np.ndarray, tau: np.ndarray) -> str:
    tilt = np.rad2deg(np.linalg.norm(rotvec))
    return (f"rotvec {np.round(rotvec, 3).tolist()} rad ({tilt:.1f} deg), "
            f"load {np.round(tau, 3).tolist()} N m")


def poses_view(rig: Rig, Rs: ArrayLike, taus_A_Nm: ArrayLike | None = None, labels: Sequence[str] | None = None,
               title: str = "csjm view", initial: int = 0) -> ViewPage:
    """One rig at several poses and loads, one frame each (a slider moves between them).

    Parameters
    ----------
    rig : Rig
    Rs : (n, 3, 3) array
        Orientations of {A} in {B}.
    taus_A_Nm : (n, 3) array, optional
        External moments in {A} (N m), weight excluded (default zero).
    labels : sequence of str, optional
        One label per pose.
    title : str
    initial : int
        Frame shown first.

    Returns
    -------
    ViewPage

    Raises
    ------
    InvalidInput, NotARotation
        Bad shapes, non-finite numbers, not a rotation.
    """
    Rs = np.asarray(Rs, float)
    if Rs.ndim != 3 or Rs.shape[1:] != (3, 3) or len(Rs) == 0:
        raise InvalidInput(f"Rs: expected (n, 3, 3) with n >= 1, got {Rs.shape}", "Rs")
    taus = np.zeros((len(Rs), 3)) if taus_A_Nm is None else np.asarray(taus_A_Nm, float)
    if taus.shape != (len(Rs), 3):
        raise InvalidInput(f"taus: expected ({len(Rs)}, 3), got {taus.shape}", "taus")
    labels = list(labels) if labels is not None else [_pose_label(so3.log(R), t) for R, t in zip(Rs, taus)]
    frames = [[rig_state(rig, R, t, lab)] for R, t, lab in zip(Rs, taus, labels)]
    return view_page(frames, title, labels, panel_titles=["rig"], initial=initial)


def pose_view(rig: Rig, rotvec: ArrayLike = (0.0, 0.0, 0.0), tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0),
              n_steps: int = 5, title: str = "csjm view") -> ViewPage:
    """The rig along a straight path from upright and unloaded to one pose and load (shown first).

    Frame ``k`` of ``n_steps`` has rotation vector ``rotvec * k / (n_steps - 1)`` and load
    ``tau_ext * k / (n_steps - 1)``; the page opens on the last frame, the pose asked for.

    Parameters
    ----------
    rig : Rig
    rotvec : (3,) array
        Orientation of {A} in {B} as a rotation vector (rad).
    tau_ext_A_Nm : (3,) array
        External moment in {A} (N m), weight excluded.
    n_steps : int
        Frames on the path (>= 1).
    title : str

    Returns
    -------
    ViewPage

    Raises
    ------
    InvalidInput
        Bad shapes or non-finite numbers.
    """
    rv, tau = as_vector3(rotvec, "rotvec"), as_vector3(tau_ext_A_Nm, "tau_ext")
    n = max(int(n_steps), 1)
    s = np.linspace(0.0, 1.0, n) if n > 1 else np.ones(1)
    return poses_view(rig, so3.exp(s[:, None] * rv), s[:, None] * tau, title=title, initial=n - 1)


def log_view(rig: Rig, log: MeasurementLog, max_cycles: int = 40, title: str = "csjm view: a log's cycles") -> ViewPage:
    """One frame per load cycle of a measurement log: its most loaded row's measured pose and load.

    The tensions and K shown are the planner's for that pose and load (what the rig would need),
    not tensions measured on the rig.

    Parameters
    ----------
    rig : Rig
    log : MeasurementLog
    max_cycles : int
        At most this many cycles (the first ones).
    title : str

    Returns
    -------
    ViewPage
    """
    rows, labels = [], []
    for c in log.cycle_ids[:max_cycles]:
        r = log.cycle_rows(c)
        k = int(r[np.argmax(np.linalg.norm(log.tau_ext_A_Nm[r], axis=1))])
        rows.append(k)
        labels.append(f"cycle {c} (sample {int(log.sample[k])}): "
                      + _pose_label(log.rotvec_rad[k], log.tau_ext_A_Nm[k]))
    idx = np.asarray(rows, int)
    return poses_view(rig, so3.exp(log.rotvec_rad[idx]), log.tau_ext_A_Nm[idx], labels, title)


def designs_view(rigs: Sequence[Rig], labels: Sequence[str], rotvecs: ArrayLike | None = None,
                 title: str = "csjm view: designs side by side", workspace_load_Nm: float | None = None,
                 certified_tilt_deg: Sequence[float] | None = None, note: str = "") -> ViewPage:
    """Designs side by side (one panel each), at one or more common poses (the slider), unloaded.

    Parameters
    ----------
    rigs : sequence of Rig
    labels : sequence of str
        One per design (panel titles).
    rotvecs : (n, 3) array, optional
        Poses shared by every design (default: upright only).
    title : str
    workspace_load_Nm : float, optional
        Draw each design's tilt boundary (:func:`~csjm_opt.view.workspace.tilt_boundary_deg`: weight
        plus test moments of this size held, K positive definite) as a ring.
    certified_tilt_deg : sequence of float, optional
        Per design, a certified tilt range (deg, every azimuth), drawn as a ring.
    note : str
        A sentence under the title.

    Returns
    -------
    ViewPage
    """
    from .workspace import tilt_boundary_deg, workspace_traces

    rv = np.zeros((1, 3)) if rotvecs is None else np.atleast_2d(np.asarray(rotvecs, float))
    frames = [[rig_state(r, so3.exp(v), np.zeros(3), lab) for r, lab in zip(rigs, labels)] for v in rv]
    flabels = [f"pose rotvec {np.round(v, 3).tolist()} rad" for v in rv]
    extras: list[list[dict]] = [[] for _ in rigs]
    az = np.linspace(0.0, 360.0, 16, endpoint=False)
    for k, r in enumerate(rigs):
        if workspace_load_Nm is not None:
            tilt = tilt_boundary_deg(r, az, workspace_load_Nm)
            extras[k] += workspace_traces(r, az, tilt, f"tilt held ({tilt.min():.0f}-{tilt.max():.0f} deg)")
        if certified_tilt_deg is not None:
            t = float(certified_tilt_deg[k])
            extras[k] += workspace_traces(r, az, np.full(az.shape, t), f"certified tilt {t:.1f} deg",
                                          color="#1a7f37")
    return view_page(frames, title, flabels, panel_titles=list(labels), extras=extras, note=note)


def show(rig: Rig, rotvec: ArrayLike = (0.0, 0.0, 0.0), tau_ext_A_Nm: ArrayLike = (0.0, 0.0, 0.0),
         n_steps: int = 5) -> ViewPage:
    """The notebook widget: :func:`pose_view` (displays itself in a notebook, in an iframe).

    Parameters
    ----------
    rig : Rig
    rotvec : (3,) array
    tau_ext_A_Nm : (3,) array
    n_steps : int

    Returns
    -------
    ViewPage
    """
    return pose_view(rig, rotvec, tau_ext_A_Nm, n_steps)
