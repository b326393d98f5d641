"""Figures of the core quantities (tension bars, directional stiffness) and the one way figures are saved.

Plot functions draw into a figure or axes passed in (a new one when ``None``)
and return it; the caller saves with :func:`save` (atomic, then closed). The
backend is chosen by the caller (the CLI selects Agg in
:func:`csjm_opt.cli.app.main`).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from ._fileio import _file_mode


def figure():
    """``matplotlib.pyplot`` (imported on first use; the backend is the caller's choice)."""
    import matplotlib.pyplot as plt

    return plt


def save(fig, path: str | Path) -> Path:
    """Save atomically (temp file + rename) and close the figure.

    A figure with constrained layout already fits its labels and outside legends, so it is drawn once;
    any other figure is cropped to its content (``bbox_inches="tight"``, which draws it twice).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        PNG (or any format matplotlib writes) to create or replace.

    Returns
    -------
    Path
    """
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        constrained = isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine)
        fig.savefig(tmp, dpi=120, bbox_inches=None if constrained else "tight")
        os.chmod(tmp, _file_mode())                # mkstemp's 0600 would make the figure private
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
        figure().close(fig)
    return path


def rig_drawing(platform_holes_A_m: np.ndarray, base_holes_B_m: np.ndarray, title: str = "", fig=None):
    """The rig at its zero pose: holes, cables and the joint centre, in 3D and seen from above.

    Parameters
    ----------
    platform_holes_A_m, base_holes_B_m : ndarray, shape (m, 3)
        Hole positions (m); at the zero pose {A} and {B} coincide.
    title : str, optional
        Figure title.
    fig : matplotlib.figure.Figure, optional
        Figure to draw into (a new one when ``None``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = figure()
    fig = plt.figure(figsize=(10, 4.8), layout="constrained") if fig is None else fig
    A, B = np.asarray(platform_holes_A_m, float) * 1e3, np.asarray(base_holes_B_m, float) * 1e3
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    for ax, dims in ((ax3, 3), (ax2, 2)):
        for i in range(A.shape[0]):
            seg = np.array([A[i], B[i]])
            ax.plot(*seg[:, :dims].T, color=f"C{i % 10}", lw=1.5)
        ax.scatter(*A[:, :dims].T, color="k", marker="o", s=18, label="platform holes A_i")
        ax.scatter(*B[:, :dims].T, color="k", marker="s", s=18, label="base holes B_i")
        ax.scatter(*np.zeros(dims), color="r", marker="+", s=60, label="joint centre O")
    for i in range(A.shape[0]):
        ax2.annotate(f"A{i + 1}", A[i, :2], textcoords="offset points", xytext=(3, 3), fontsize=8)
        ax2.annotate(f"B{i + 1}", B[i, :2], textcoords="offset points", xytext=(3, -9), fontsize=8, color="0.4")
        ax3.text(*A[i], f"{i + 1}", fontsize=7)
    ax3.set_xlabel("x (mm)")
    ax3.set_ylabel("y (mm)")
    ax3.set_zlabel("z (mm)")
    ax2.set_xlabel("x (mm)")
    ax2.set_ylabel("y (mm)")
    ax2.set_aspect("equal")
    ax2.set_title("seen from above (+z), cable i joins A_i and B_i")
    ax2.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    if title:
        fig.suptitle(title)
    return fig


def tensions_and_ellipsoids(labels: list[str], tensions_N: np.ndarray, K: np.ndarray,
                            t_min_N: float, t_max_N: float, show: tuple[int, ...] | None = None, fig=None):
    """Tension bars per pose (top), K's directional stiffness at a few poses and K's eigenvalues (bottom).

    For a few poses, the directional stiffness ``u^T K u`` (N m/rad) for unit directions ``u`` in
    the three coordinate planes of {A}, drawn as polar curves beside the circle of the mean
    eigenvalue: an isotropic K is that circle, and a 1.4:1 anisotropy is a clearly flattened
    curve (3-D ellipsoids of such a K look like spheres).

    Parameters
    ----------
    labels : list of str
        One label per pose.
    tensions_N : (n, m) array
        Tensions per pose (N).
    K : (n, 3, 3) array
        Stiffness per pose (N m/rad).
    t_min_N, t_max_N : float
        Tension bounds drawn as dashed lines (N).
    show : tuple of int, optional
        Poses whose directional stiffness is drawn (first, middle and last by default).
    fig : matplotlib Figure, optional
        Figure to draw into (a new one when ``None``).

    Returns
    -------
    matplotlib Figure
        The figure drawn.
    """
    n = len(labels)
    show = tuple(show if show is not None else sorted({0, n // 2, n - 1}))
    if fig is None:
        fig = figure().figure(figsize=(14, 9), layout="constrained")
    grid = fig.add_gridspec(2, len(show) + 1, height_ratios=(1, 1.1), width_ratios=(1,) * len(show) + (1.3,))
    ax = fig.add_subplot(grid[0, :])
    m = tensions_N.shape[1]                                   # cables, from the data
    width = 0.8 / m
    for i in range(m):
        ax.bar(np.arange(n) + (i - (m - 1) / 2) * width, tensions_N[:, i], width, label=f"{i + 1}")
    ax.axhline(t_min_N, color="k", ls="--", lw=0.8)
    ax.axhline(t_max_N, color="k", ls="--", lw=0.8)
    ax.set_xticks(np.arange(n), labels, rotation=25, ha="right", fontsize=8)
    ax.set_ylabel("tension (N)")
    ax.set_title("Planned tensions per pose (dashed: t_min, t_max)")
    ax.set_xlabel("pose (tilt, azimuth of the tilt axis in deg)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.005, 1.0), title="cable")  # outside: no bar hidden
    theta = np.linspace(0.0, 2 * np.pi, 181)
    c, s_ = np.cos(theta), np.sin(theta)
    planes = (("x-y", 0, 1), ("y-z", 1, 2), ("z-x", 2, 0))
    lim = 1.08 * float(np.max(np.linalg.eigvalsh(K[list(show)])))
    for col, j in enumerate(show):
        w = np.linalg.eigvalsh(K[j])
        a2 = fig.add_subplot(grid[1, col])
        for name, p, q in planes:
            u = np.zeros((theta.size, 3))
            u[:, p], u[:, q] = c, s_
            k_dir = np.einsum("ni,ij,nj->n", u, K[j], u)      # directional stiffness u^T K u (N m/rad)
            a2.plot(k_dir * c, k_dir * s_, lw=1.6, label=f"{name} plane")
        mean = float(np.mean(w))
        a2.plot(mean * c, mean * s_, "k--", lw=0.8, label=f"mean eigenvalue {mean:.1f}")
        a2.set_xlim(-lim, lim)
        a2.set_ylim(-lim, lim)
        a2.set_aspect("equal")
        a2.set_title(f"{labels[j]}\neig {np.round(w, 1).tolist()} N m/rad, ratio {w.max() / w.min():.2f}:1",
                     fontsize=8)
        a2.set_xlabel("first axis of the plane (N m/rad)", fontsize=7)
        a2.set_ylabel("second axis (N m/rad)", fontsize=7)
        a2.tick_params(labelsize=6)
        if col == 0:
            a2.legend(fontsize=6, loc="best")
    ae = fig.add_subplot(grid[1, -1])
    eig = np.linalg.eigvalsh(K)
    for k in range(3):
        ae.plot(np.arange(n), eig[:, k], "o-", ms=3, label=f"eigenvalue {k + 1}")
    ae.set_xticks(np.arange(n), [str(i) for i in range(n)], fontsize=7)
    ae.set_xlabel("pose index (as above)")
    ae.yaxis.tick_right()
    ae.yaxis.set_label_position("right")
    ae.set_ylabel("eigenvalue of K (N m/rad)")
    ae.set_title("Eigenvalues of K per pose")
    ae.legend(fontsize=7, loc="best")
    fig.suptitle("Tensions and stiffness under the platform's weight (directional stiffness u^T K u, N m/rad)")
    return fig
