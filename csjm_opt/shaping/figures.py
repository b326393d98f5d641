"""Figures of stiffness shaping: the reachable set at a pose and load."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .reachable import ReachableSet, directional_range

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def plot_reachable_set(rs: ReachableSet, t_min_N: float, t_max_N: float,
                       K_marks: dict[str, np.ndarray] | None = None, n_directions: int = 72, *,
                       fig: Figure | None = None) -> tuple[Axes, Axes]:
    """Eigenvalue ranges (left) and directional stiffness range in the {A} x-y plane (right, polar).

    Parameters
    ----------
    rs : ReachableSet
        From :func:`reachable_set`.
    t_min_N, t_max_N : float
        Tension bounds (N) of the rig, for the directional ranges.
    K_marks : dict of str to ndarray (3, 3), optional
        Stiffness matrices (N m/rad) to mark, by label (e.g. shaped results).
    n_directions : int, optional
        Number of directions in the x-y plane for the polar plot.
    fig : matplotlib.figure.Figure, optional
        Empty figure to draw the two panels in; a new one is made when omitted.

    Returns
    -------
    tuple of matplotlib.axes.Axes
        The eigenvalue axes and the polar axes.
    """
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(12, 4.4), layout="constrained")
    ax = fig.add_subplot(1, 2, 1)
    for i in range(3):
        lo, hi = rs.eigen_ranges[i]
        ax.plot([lo, hi], [i, i], lw=8, color="C0", alpha=0.35, solid_capstyle="butt")
        if len(rs.sample_eigenvalues):
            ys = i + 0.15 * (np.random.default_rng(i).random(len(rs.sample_eigenvalues)) - 0.5)
            ax.scatter(rs.sample_eigenvalues[:, i], ys, s=2, color="C0", alpha=0.3)
        ax.text(hi, i + 0.22, f"[{lo:.2f}, {hi:.2f}]  ({rs.eigen_method[i][0]}/{rs.eigen_method[i][1]})",
                ha="right", fontsize=7)
    for j, (name, K) in enumerate((K_marks or {}).items()):
        lam = np.linalg.eigvalsh(0.5 * (K + K.T))
        ax.scatter(lam, range(3), marker="x|+"[j % 3], s=60, color=f"C{j + 1}", label=name, zorder=3)
    ax.set_ylim(-0.5, 2.7)
    ax.set_yticks(range(3), [r"$\lambda_1$", r"$\lambda_2$", r"$\lambda_3$"])
    ax.set_xlabel("stiffness eigenvalue (N m/rad)")
    ax.set_title("reachable eigenvalues of K")
    if K_marks:
        ax.legend(fontsize=7, loc="lower right")
    ax2: Any = fig.add_subplot(1, 2, 2, projection="polar")
    phi = np.linspace(0, 2 * np.pi, n_directions + 1)
    dirs = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    rng_ = directional_range(rs.basis, rs.tau_load_A_Nm, dirs[:-1], t_min_N, t_max_N)
    rng_ = np.vstack([rng_, rng_[:1]])
    ax2.fill_between(phi, rng_[:, 0], rng_[:, 1], alpha=0.35, color="C0", label="reachable")
    ax2.plot(phi, rng_[:, 0], color="C0", lw=0.8)
    ax2.plot(phi, rng_[:, 1], color="C0", lw=0.8)
    for j, (name, K) in enumerate((K_marks or {}).items()):
        ax2.plot(phi, np.einsum("ni,ij,nj->n", dirs, K, dirs), color=f"C{j + 1}", lw=1.2, label=name)
    ax2.set_rmin(0.0)
    ax2.set_title(r"$u^T K u$ for $u$ in the {A} x-y plane (N m/rad)", fontsize=9)
    ax2.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.08, 1.0))
    return ax, ax2

