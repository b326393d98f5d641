"""Figures of a diagnosis report: where the model misses, and how much the selected effect closes.

Each function draws into ``fig`` (a new figure when ``None``) and returns it;
saving is the caller's one line (:func:`csjm_opt.report.diagnosis.report.write_report`
saves them as PNG next to the page).
"""

from __future__ import annotations

import numpy as np

from ... import _plotting as plots
from ...diagnose import Diagnosis


def residual_map(d: Diagnosis, fig=None):
    """Held-out residual over the pose, before (nominal model) and after (selected effect): two panels.

    Parameters
    ----------
    d : Diagnosis
        The diagnosis to draw.
    fig : matplotlib Figure, optional
        Figure to draw into (a new one when ``None``).

    Returns
    -------
    matplotlib Figure
        The figure drawn.
    """
    fig = fig if fig is not None else plots.figure().figure(figsize=(10, 4.2), layout="constrained")
    t = d.heldout_table
    x, y = t.tilt_rad * np.cos(t.azimuth_rad), t.tilt_rad * np.sin(t.azimuth_rad)
    before = 1e3 * np.linalg.norm(t.zeta_rad, axis=1)
    after = 1e3 * np.linalg.norm(d.selected_score.heldout_zeta_rad, axis=1)
    vmax = float(np.percentile(before, 98)) or 1.0
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    for ax, val, title in ((axes[0], before, "nominal model (rig file)"),
                           (axes[1], after, f"selected: {d.selected}")):
        sc = ax.scatter(x, y, c=val, s=18, cmap="viridis", vmin=0, vmax=vmax)
        ax.set_title(f"{title}: RMS {np.sqrt(np.mean(val ** 2)):.2f} mrad", fontsize=9)
        ax.set_xlabel("tilt cos(azimuth) (rad)")
        ax.set_aspect("equal")
    axes[0].set_ylabel("tilt sin(azimuth) (rad)")
    fig.colorbar(sc, ax=axes, label="||log(R_pred^T R_meas)|| (mrad)")
    fig.suptitle("Held-out residual over the pose (colour: size of the residual)")
    return fig


def hysteresis_loops(d: Diagnosis, fig=None, n_cycles: int = 4):
    """Residual against the load along each cycle's main direction, for the first ``n_cycles`` held-out cycles.

    Parameters
    ----------
    d : Diagnosis
        The diagnosis to draw.
    fig : matplotlib Figure, optional
        Figure to draw into (a new one when ``None``).
    n_cycles : int
        Number of cycles drawn, one panel each.

    Returns
    -------
    matplotlib Figure
        The figure drawn.
    """
    t = d.heldout_table
    ids = list(dict.fromkeys(t.cycle.tolist()))[:n_cycles]
    n = max(len(ids), 1)
    fig = fig if fig is not None else plots.figure().figure(figsize=(3.2 * n, 3.4), layout="constrained")
    axes = fig.subplots(1, n, squeeze=False, sharey=True)
    after = d.selected_score.heldout_zeta_rad
    for ax, c in zip(axes[0], ids):
        idx = np.flatnonzero(t.cycle == c)
        tau = t.rows.tau_meas_A_Nm[idx]
        direction = tau[np.argmax(np.linalg.norm(tau - tau[0], axis=1))] - tau[0]
        u = direction / (np.linalg.norm(direction) or 1.0)
        s = (tau - tau[0]) @ u
        # residual along the main axis of the before-residuals of this cycle
        zb = t.zeta_rad[idx]
        _, _, Vt = np.linalg.svd(zb - zb.mean(axis=0))
        v = Vt[0]
        ax.plot(s, 1e3 * zb @ v, "o-", label="nominal")
        ax.plot(s, 1e3 * after[idx] @ v, "s--", label=d.selected)
        ax.set_title(f"cycle {c}")
        ax.set_xlabel("load along main direction (N m)", fontsize=8)
    axes[0][0].set_ylabel("residual along its main axis (mrad)")
    axes[0][0].legend(fontsize=8, loc="best")
    fig.suptitle("Hysteresis: residual against the load along each cycle's main direction, loading and "
                 "unloading branches")
    return fig


def candidate_errors(d: Diagnosis, ax=None):
    """Held-out RMS error of every candidate model against the noise floor (selected in green).

    Parameters
    ----------
    d : Diagnosis
        The diagnosis to draw.
    ax : matplotlib Axes, optional
        Axes to draw into (a new figure when ``None``).

    Returns
    -------
    matplotlib Axes
        The axes drawn.
    """
    names = ["nominal", "nominal_refit"] + list(d.candidates)
    vals = [d.nominal_heldout_rms_rad, d.baseline.heldout_rms_rad] + [c.heldout_rms_rad for c in d.candidates.values()]
    colors = ["grey", "silver"] + ["tab:green" if n == d.selected else "tab:blue" for n in d.candidates]
    if ax is None:
        ax = plots.figure().figure(figsize=(8, 3.6), layout="constrained").subplots()
    ax.bar(range(len(names)), 1e3 * np.asarray(vals), color=colors)
    ax.axhline(1e3 * d.noise_floor_rad, color="k", ls=":", label=f"noise floor {1e3 * d.noise_floor_rad:.2f} mrad")
    ax.set_xticks(range(len(names)), names, rotation=30, ha="right")
    ax.set_ylabel("held-out RMS (mrad)")
    ax.set_xlabel("candidate model")
    ax.set_title("Held-out error of each candidate model (green: selected)")
    ax.legend(loc="best")
    return ax


def before_after(d: Diagnosis, fig=None):
    """Held-out residual before and after the selected effect: RMS per axis of {A}, and its distribution.

    Parameters
    ----------
    d : Diagnosis
        The diagnosis to draw.
    fig : matplotlib Figure, optional
        Figure to draw into (a new one when ``None``).

    Returns
    -------
    matplotlib Figure
        The figure drawn.
    """
    fig = fig if fig is not None else plots.figure().figure(figsize=(9, 3.4), layout="constrained")
    zb, za = d.heldout_table.zeta_rad, d.selected_score.heldout_zeta_rad
    axes = fig.subplots(1, 2)
    w = 0.38
    axes[0].bar(np.arange(3) - w / 2, 1e3 * np.sqrt(np.mean(zb ** 2, axis=0)), w, label="before")
    axes[0].bar(np.arange(3) + w / 2, 1e3 * np.sqrt(np.mean(za ** 2, axis=0)), w, label="after")
    axes[0].set_xticks(range(3), ["x", "y", "z"])
    axes[0].set_ylabel("RMS residual per axis of {A} (mrad)")
    axes[0].set_xlabel("axis of {A}")
    axes[0].set_title("per axis")
    axes[0].legend(loc="best")
    bins = np.linspace(0, 1e3 * max(np.linalg.norm(zb, axis=1).max(), 1e-6), 30)
    axes[1].hist(1e3 * np.linalg.norm(zb, axis=1), bins, alpha=0.6, label="before")
    axes[1].hist(1e3 * np.linalg.norm(za, axis=1), bins, alpha=0.6, label="after")
    axes[1].set_xlabel("||residual|| (mrad)")
    axes[1].set_ylabel("held-out rows")
    axes[1].set_title("distribution")
    axes[1].legend(loc="best")
    fig.suptitle(f"Held-out residual before (nominal model) and after ({d.selected})")
    return fig

