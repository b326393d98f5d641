"""The workspace boundary of a design drawn on the rig: how far the platform tilts, per azimuth.

:func:`tilt_boundary_deg` finds, per azimuth of the tilt axis, the largest tilt (no torsion) up to
which the planner holds the platform's weight plus every test load (``load_Nm`` about each of
``load_directions`` horizontal axes of {A}) with K positive definite: scanned in steps, then
bisected. :func:`workspace_traces` draws a boundary (that one, or a certified range ``tilt <= s x
max_tilt``) as the ring the platform's centre traces at the boundary tilt.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..design.sampling import tilt_torsion_rotations
from ..errors import CsjmError
from ..model.joint_stiffness import stiffness
from ..model.rig import Rig
from ..planning.planner import plan_tensions

__all__ = ["tilt_boundary_deg", "workspace_traces"]


def _test_loads(load_Nm: float, n_dirs: int) -> np.ndarray:
    if load_Nm <= 0:
        return np.zeros((1, 3))
    a = np.linspace(0.0, 2 * np.pi, n_dirs, endpoint=False)
    return np.vstack([np.zeros(3), load_Nm * np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)])


def _holds(rig: Rig, R: np.ndarray, loads: np.ndarray) -> bool:
    for tau in loads:
        try:
            T = plan_tensions(rig, R, tau).tensions_N
            if np.linalg.eigvalsh(stiffness(rig, R, T))[0] <= 0:
                return False
        except CsjmError:
            return False
    return True


def tilt_boundary_deg(rig: Rig, azimuths_deg: ArrayLike, load_Nm: float = 0.0, load_directions: int = 4,
                      max_tilt_deg: float = 60.0, step_deg: float = 5.0, tol_deg: float = 0.25) -> np.ndarray:
    """Largest tilt (deg) held per azimuth: weight plus every test load held, K positive definite.

    Parameters
    ----------
    rig : Rig
    azimuths_deg : (k,) array
        Azimuths of the tilt axis (deg).
    load_Nm : float
        Size of the test moments (N m, in {A}); 0 tests the weight alone.
    load_directions : int
        Horizontal directions of the test moments.
    max_tilt_deg, step_deg, tol_deg : float
        Largest tilt tried, scan step and bisection tolerance (deg).

    Returns
    -------
    (k,) array
        The boundary tilt per azimuth (0 if even upright fails, ``max_tilt_deg`` if never reached).
    """
    loads = _test_loads(float(load_Nm), int(load_directions))
    out = []
    for phi in np.radians(np.asarray(azimuths_deg, float)):
        def ok(theta_deg: float, phi: float = phi) -> bool:
            R = tilt_torsion_rotations(np.radians([theta_deg]), np.array([phi]), np.zeros(1))[0]
            return _holds(rig, R, loads)

        if not ok(0.0):
            out.append(0.0)
            continue
        lo = 0.0
        while lo + step_deg <= max_tilt_deg and ok(lo + step_deg):
            lo += step_deg
        hi = min(lo + step_deg, max_tilt_deg)
        if hi == lo or ok(hi):
            out.append(hi)
            continue
        while hi - lo > tol_deg:
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if ok(mid) else (lo, mid)
        out.append(lo)
    return np.asarray(out)


def workspace_traces(rig: Rig, azimuths_deg: ArrayLike, tilts_deg: ArrayLike, label: str,
                     scene: str = "scene", color: str = "#8250df") -> list[dict]:
    """The ring the platform's centre traces at the boundary tilt of each azimuth (plotly traces).

    Parameters
    ----------
    rig : Rig
    azimuths_deg, tilts_deg : (k,) arrays
        Boundary tilt per azimuth (deg); the ring is closed.
    label : str
        Text at the ring.
    scene : str
        Plotly scene id.
    color : str

    Returns
    -------
    list of dict
    """
    az = np.radians(np.asarray(azimuths_deg, float))
    tilt = np.radians(np.broadcast_to(np.asarray(tilts_deg, float), az.shape))
    centre_A = np.array([0.0, 0.0, float(np.mean(rig.platform_holes_A_m[:, 2]))])
    Rs = tilt_torsion_rotations(tilt, az, np.zeros_like(az))
    pts = np.vstack([Rs @ centre_A, (Rs @ centre_A)[:1]])
    k = int(np.argmax(pts[:-1, 0] - pts[:-1, 1]))
    return [{"type": "scatter3d", "mode": "lines+markers", "x": pts[:, 0].round(6).tolist(),
             "y": pts[:, 1].round(6).tolist(), "z": pts[:, 2].round(6).tolist(),
             "line": {"color": color, "width": 5}, "marker": {"size": 2, "color": color},
             "name": label, "hoverinfo": "name", "showlegend": False, "scene": scene},
            {"type": "scatter3d", "mode": "text", "x": [float(pts[k, 0])], "y": [float(pts[k, 1])],
             "z": [float(pts[k, 2]) + 0.01], "text": [label], "textfont": {"color": color, "size": 11},
             "hoverinfo": "skip", "showlegend": False, "scene": scene, "name": label}]
