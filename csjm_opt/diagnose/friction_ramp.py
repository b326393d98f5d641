"""The path between two rows: cable motion along a quasi-static ramp of the inputs, for dry friction.

A rig is moved from one row to the next by ramping its inputs (the load, and between cycles the
rest lengths) while the platform follows quasi-statically. A dry-friction state is a play
operator of each cable's motion, and a play operator remembers the *extremes* of its input, not
only its end points: when a cable's length reverses during the ramp (it draws out, then back in,
as the platform swings from one reference pose to the next), the state it leaves differs from
the state one step from the previous row's length to this row's would leave. Between load cycles
such reversals reach millimetres (tens of stick travels), so a one-step model gets the state at a
cycle's first row wrong on some cables, and a fit compensates with unphysical parameters.

:func:`ramp_shape` computes, once per log, the shape of each cable's motion along the ramp from
the nominal model's equilibria at ``RAMP_SUBSTEPS`` evenly spaced inputs between the two rows
(linear in the rest lengths and the measured moment, as a lab ramps its drives and loads). The
friction model then moves each cable along ``dc / S + shape_q`` (:func:`ramp_steps`): the row's
own length change (measured, or predicted by the fitted model) spread evenly, plus the ramp's
deviation from a straight line. The row end points are the fitted model's; only the curvature
between them comes from the nominal model (friction moves the poses by a fraction of a
milliradian, the reversals come from the geometry of the swing).
"""

from __future__ import annotations

import numpy as np

from ..model import kinematics as kin
from ..model.rig import Rig

#: Evenly spaced inputs along each ramp between two rows (resolves one reversal of a cable's motion).
RAMP_SUBSTEPS = 8


def ramp_shape(rig: Rig, rest_prev_m: np.ndarray, tau_prev_A_Nm: np.ndarray, R_prev: np.ndarray,
               rest_m: np.ndarray, tau_A_Nm: np.ndarray, R: np.ndarray,
               substeps: int = RAMP_SUBSTEPS) -> np.ndarray:
    """Deviation (n, S, 6) of each cable's steps along the ramp into each row from even steps (m).

    Parameters
    ----------
    rig : Rig
        The nominal rig (its frictionless equilibria trace the ramp).
    rest_prev_m, tau_prev_A_Nm : numpy.ndarray
        Inputs of the row before each row (n, 6) and (n, 3): where the ramp starts.
    R_prev : numpy.ndarray
        Poses (n, 3, 3) at the previous rows (starting guesses of the equilibria).
    rest_m, tau_A_Nm : numpy.ndarray
        Inputs of the rows (n, 6) and (n, 3): where the ramp ends.
    R : numpy.ndarray
        Poses (n, 3, 3) at the rows (unused but for rows whose ramp does not converge).
    substeps : int, optional
        Number of steps ``S`` along each ramp.

    Returns
    -------
    numpy.ndarray
        ``d_q - mean_q d_q`` (n, S, 6), ``d_q`` the change of each cable's nominal equilibrium
        length over step ``q``; it sums to zero over the steps. Rows whose ramp has no converged
        nominal equilibrium get zeros (a straight path, one even step).
    """
    from .augmented import AugmentedModel, Rows       # the nominal balance (same layer)

    model = AugmentedModel(rig)
    theta = model.x0()
    A = np.asarray(rig.platform_holes_A_m, float)
    B = np.asarray(rig.base_holes_B_m, float)
    n = len(rest_m)
    cycle = np.arange(n)
    lengths = np.empty((substeps + 1, n, 6))
    ok = np.ones(n, bool)
    R_q = np.array(R_prev, float)
    for q in range(substeps + 1):
        f = q / substeps
        rows = Rows(rest_prev_m + f * (rest_m - rest_prev_m), tau_prev_A_Nm + f * (tau_A_Nm - tau_prev_A_Nm),
                    cycle, np.zeros((n, 6)))
        sol = kin.solve_poses(lambda Rx, rows=rows: model.balance(Rx, rows, theta), R_q)  # type: ignore[misc]
        good = sol.converged(1e-6) & np.all(np.isfinite(sol.R.reshape(n, -1)), axis=1)
        ok &= good
        R_q = np.where(good[:, None, None], sol.R, R_q if q else np.asarray(R, float))
        lengths[q], _ = kin.cable_terms(R_q, A, B)
    d = np.swapaxes(np.diff(lengths, axis=0), 0, 1)            # (n, S, 6)
    d = d - d.mean(axis=1, keepdims=True)
    d[~ok] = 0.0
    return d


def ramp_steps(dc_m: np.ndarray, shape_m: np.ndarray | None) -> np.ndarray:
    """Each cable's steps (n, S, 6) along the ramp into each row, for row changes ``dc_m`` (n, 6).

    Parameters
    ----------
    dc_m : numpy.ndarray
        Change of each cable's length since the previous row (m).
    shape_m : numpy.ndarray or None
        The ramp's deviation from even steps (:func:`ramp_shape`); None for one step.

    Returns
    -------
    numpy.ndarray
        ``dc / S + shape`` (sums to ``dc`` over the steps); ``dc[:, None]`` without a shape.
    """
    if shape_m is None:
        return dc_m[:, None, :]
    return dc_m[:, None, :] / shape_m.shape[1] + shape_m


def log_ramp_shape(rig: Rig, rest_m: np.ndarray, tau_A_Nm: np.ndarray, R: np.ndarray) -> np.ndarray:
    """:func:`ramp_shape` for a log's rows in time order (each ramp from the log's previous row).

    Parameters
    ----------
    rig : Rig
        The nominal rig.
    rest_m, tau_A_Nm : numpy.ndarray
        The rows' rest lengths (n, 6) and measured moments (n, 3), in time order.
    R : numpy.ndarray
        Poses (n, 3, 3) near the rows' equilibria (measured or predicted).

    Returns
    -------
    numpy.ndarray
        (n, S, 6); zeros on the first row.
    """
    rest_m, tau_A_Nm, R = (np.asarray(a, float) for a in (rest_m, tau_A_Nm, R))
    prev = np.r_[0, np.arange(len(rest_m) - 1)]
    return ramp_shape(rig, rest_m[prev], tau_A_Nm[prev], R[prev], rest_m, tau_A_Nm, R)
