"""The path between two rows: cable motion along a quasi-static ramp of the inputs, for dry friction.

A rig is moved from one row to the next by ramping its inputs (the load, and between cycles the
rest lengths) while the platform follows quasi-statically. A dry-friction state is a play
operator of each cable's motion, and a play operator remembers the *extremes* of its input, not
only its end points: when a cable's length reverses during the ramp (it draws out, then back in,
as the platform swings from one reference pose to the next, or as its neighbours break loose and
the platform jumps), the state it leaves differs from the state one step from the previous row's
length to this row's would leave. Between load cycles such reversals reach millimetres (tens of
stick travels), so a one-step model gets the state at a cycle's first row wrong on some cables,
and a fit compensates with unphysical parameters.

:func:`predict_ramp` predicts the poses of a path-dependent model along the ramp into every row,
in ``RAMP_SUBSTEPS`` evenly spaced inputs (linear in the rest lengths and the measured moment, as a
lab ramps its drives and loads), each from the state the previous one left: the friction model's
own quasi-static response, stick and slip included. It returns the *shape* of each cable's motion
along each ramp (its steps' deviation from even steps); a fit then moves each cable along
``dc / S + shape_q`` (:func:`ramp_steps`): the row's own length change (measured, or predicted)
spread evenly, plus the ramp's shape. The shape is computed at given parameters and held fixed
while they are refitted (:func:`csjm_opt.diagnose.fitting.friction_path.on_predicted_path`).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Sequence

import numpy as np

from ... import so3
from ...model import kinematics as kin

if TYPE_CHECKING:      # (augmented imports the effects, which import ramp_steps from here)
    from .augmented import Rows

#: Evenly spaced inputs along each ramp between two rows (resolves one reversal of a cable's motion).
RAMP_SUBSTEPS = 8
#: Equilibria solved along a ramp within a cycle (a load step; the path between them is interpolated):
#: the platform swings between cycles, within a cycle only the load moves.
ROW_SUBSTEPS = 2
#: Balance tolerance (N m) of the equilibria inside a ramp (the row's own is solved to the default).
INNER_TOL_NM = 1e-7


def predict_ramp(model, rows, theta: np.ndarray, R_init: np.ndarray, substeps: int = RAMP_SUBSTEPS,
                 row_substeps: int = ROW_SUBSTEPS) -> tuple[kin.PoseSolution, np.ndarray]:
    """Poses a path-dependent model predicts for every row, stepped along the ramps, and the ramps' shape.

    Rows are stepped in order within their cycle (all cycles at once); a cycle's first row ramps
    from the log's previous row, from the state the measured history leaves there
    (``rows.entry_state``, :func:`csjm_opt.diagnose.fitting.augmented.with_entry`); a row without
    history starts at the model's first-row state, without a ramp.

    Parameters
    ----------
    model : AugmentedModel
        A path-dependent model.
    rows : Rows
        The rows in time order (with their entry states for carried memory).
    theta : numpy.ndarray
        The model's parameters.
    R_init : numpy.ndarray
        Poses (n, 3, 3) near the rows' equilibria (the measured ones); a cycle's first ramp starts
        at the measured pose of the log's previous row (``rows.entry_R``).
    substeps : int, optional
        Number of steps ``S`` along each ramp (equilibria solved along the ramp into a cycle).
    row_substeps : int, optional
        Equilibria solved along a ramp within a cycle (a divisor of ``S``; the points between
        them are interpolated linearly).

    Returns
    -------
    (PoseSolution, numpy.ndarray)
        The predicted poses at the rows (residuals of the last step), and the shape (n, S, m) of
        each cable's motion along the ramp into each row (:func:`ramp_shape_of`; zero where
        a step did not converge, and on rows without history).
    """
    n = len(rows)
    R_init = np.asarray(R_init, float)
    l_all, tau_all = np.asarray(rows.rest_lengths_m, float), np.asarray(rows.tau_meas_A_Nm, float)
    pos = rows.positions
    R_out, res = R_init.copy(), np.zeros(n)
    m = l_all.shape[1]
    state, lengths = np.full((n, m), np.nan), np.full((n, m), np.nan)
    path = np.zeros((n, substeps + 1, m))
    ok, no_ramp = np.ones(n, bool), np.zeros(n, bool)
    it = 0
    for j in range(int(pos.max(initial=0)) + 1):
        idx = np.flatnonzero(pos == j)
        if j == 0:              # from the log's row before the cycle, as the measured history left it
            has = all(a is not None for a in (rows.entry_state, rows.entry_lengths_m, rows.entry_rest_m,
                                              rows.entry_tau_A_Nm, rows.entry_R))
            nan = np.full((len(idx), m), np.nan)
            s_q = rows.entry_state[idx] if has else nan                     # type: ignore[index]
            c_q = rows.entry_lengths_m[idx] if has else nan                 # type: ignore[index]
            l_p = rows.entry_rest_m[idx] if has else nan                    # type: ignore[index]
            t_p = rows.entry_tau_A_Nm[idx] if has else nan[:, :3]           # type: ignore[index]
            R_q = rows.entry_R[idx] if has else R_init[idx]                 # type: ignore[index]
        else:
            s_q, c_q, R_q = state[idx - 1], lengths[idx - 1], R_out[idx - 1]
            l_p, t_p = l_all[idx - 1], tau_all[idx - 1]
        fresh = (np.isnan(c_q).any(axis=1) | np.isnan(l_p).any(axis=1) | np.isnan(t_p).any(axis=1)
                 | np.isnan(R_q).any(axis=(1, 2)))    # no history: the row itself, at the first-row state
        l0 = np.where(fresh[:, None], l_all[idx], l_p)
        t0 = np.where(fresh[:, None], tau_all[idx], t_p)
        R_q = np.where(fresh[:, None, None], R_init[idx], R_q)
        c_q = np.where(fresh[:, None], np.nan, c_q)
        no_ramp[idx] = fresh
        every = 1 if j == 0 else max(substeps // row_substeps, 1)
        dl = (l_all[idx] - l0) * (every / substeps)
        path[idx, 0] = np.nan_to_num(c_q)
        base = rows.take(idx)
        R_last = R_q
        for q in range(every, substeps + 1, every):
            f = q / substeps
            sub = dataclasses.replace(base, rest_lengths_m=l0 + f * (l_all[idx] - l0),
                                      tau_meas_A_Nm=t0 + f * (tau_all[idx] - t0), rest_steps_m=dl,
                                      log_steps_m=None, state_prev=np.nan_to_num(s_q), lengths_prev_m=c_q,
                                      ramp_shape_m=None)
            # start from the pose extrapolated along the last step's rotation (equal input steps)
            guess = R_q @ so3.exp(so3.log(np.swapaxes(R_last, 1, 2) @ R_q)) if q > every else R_q
            R_last = R_q
            sol = kin.solve_poses(lambda R, sub=sub: model.balance(R, sub, theta), guess,  # type: ignore[misc]
                                  tol_Nm=1e-10 if q == substeps else INNER_TOL_NM,
                                  tangent_fn=lambda R, g0, sub=sub: model.tangent(R, sub, theta, g0))  # type: ignore[misc]
            _, ev = model.evaluate(sol.R, sub, theta)
            ok[idx] &= sol.converged(1e-6)
            R_q = sol.R
            s_q = ev.state_out if ev.state_out is not None else np.zeros((len(idx), m))
            c_q = np.where(fresh[:, None], np.nan, ev.lengths_m)
            for h in range(1, every + 1):          # interpolated points between the solved ones
                path[idx, q - every + h] = path[idx, q - every] + (h / every) * (ev.lengths_m - path[idx, q - every])
            it = max(it, sol.iterations)
            res[idx] = sol.residual_Nm
        R_out[idx], state[idx], lengths[idx] = R_q, s_q, path[idx, substeps]
    shape = ramp_shape_of(path)
    shape[~ok | no_ramp | ~np.isfinite(shape).all(axis=(1, 2))] = 0.0
    return kin.PoseSolution(R_out, res, it), shape


def predict_ramps(model, parts: Sequence[tuple[Rows, np.ndarray]],
                  theta: np.ndarray) -> list[tuple[kin.PoseSolution, np.ndarray]]:
    """:func:`predict_ramp` of several logs' rows ``(rows, R_init)`` at the same parameters, in one pass.

    The cycles of every part are stepped side by side: a cycle's ramps depend on its own rows and entry only,
    and each row's equilibria are solved row by row (:func:`csjm_opt.model.kinematics.solve_poses`), so each
    part gets the numbers it gets alone (the solutions' ``iterations`` is the pass's largest) for one pass's
    overhead: the steps of a prediction are many small batches, and their cost hardly grows with the rows.

    Parameters
    ----------
    model : AugmentedModel
        A path-dependent model.
    parts : sequence of (Rows, numpy.ndarray)
        Each log's rows in time order (with their entry states, :func:`csjm_opt.diagnose.fitting.augmented.
        with_entry`) and poses near their equilibria.
    theta : numpy.ndarray
        The model's parameters.

    Returns
    -------
    list of (PoseSolution, numpy.ndarray)
        Per part, as :func:`predict_ramp` returns.
    """
    sizes = np.cumsum([0] + [len(r) for r, _ in parts])
    sol, shape = predict_ramp(model, _side_by_side([r for r, _ in parts]), theta,
                              np.concatenate([np.asarray(R, float) for _, R in parts]))
    return [(kin.PoseSolution(sol.R[a:b], sol.residual_Nm[a:b], sol.iterations), shape[a:b])
            for a, b in zip(sizes[:-1], sizes[1:])]


def _side_by_side(parts: Sequence[Rows]) -> Rows:
    """The rows of ``parts`` as one log of distinct cycles, with what :func:`predict_ramp` reads of them.

    Inputs, cycles (renumbered after each other), measured steps and entries (NaN where a part has none: a
    row without history, as :func:`predict_ramp` treats a missing entry); the rest is set along the ramps.
    """
    from .augmented import Rows

    cycles, start = [], 0
    for r in parts:
        first = np.r_[True, r.cycle[1:] != r.cycle[:-1]]
        cycles.append(start + np.cumsum(first) - 1)
        start = int(cycles[-1][-1]) + 1 if len(r) else start

    def joined(name: str, tail: tuple[int, ...]) -> np.ndarray | None:
        got = [getattr(r, name) for r in parts]
        if all(g is None for g in got):
            return None
        return np.concatenate([np.full((len(r),) + tail, np.nan) if g is None else np.asarray(g, float)
                               for r, g in zip(parts, got)])

    m = np.shape(parts[0].rest_lengths_m)[1]
    return Rows(np.concatenate([r.rest_lengths_m for r in parts]), np.concatenate([r.tau_meas_A_Nm for r in parts]),
                np.concatenate(cycles), np.concatenate([r.cable_steps_m for r in parts]),
                entry_state=joined("entry_state", (m,)), entry_lengths_m=joined("entry_lengths_m", (m,)),
                entry_rest_m=joined("entry_rest_m", (m,)), entry_tau_A_Nm=joined("entry_tau_A_Nm", (3,)),
                entry_R=joined("entry_R", (3, 3)))


def ramp_shape_of(path_m: np.ndarray) -> np.ndarray:
    """Deviation (n, S, m) of each cable's steps along ramps ``path_m`` (n, S + 1, m) from even steps (m).

    Parameters
    ----------
    path_m : numpy.ndarray
        Each cable's length at the ``S + 1`` points of each row's ramp (m).

    Returns
    -------
    numpy.ndarray
        ``d_q - mean_q d_q`` (sums to zero over the steps), ``d_q`` the change over step ``q``.
    """
    d = np.diff(path_m, axis=1)
    return d - d.mean(axis=1, keepdims=True)


def ramp_steps(dc_m: np.ndarray, shape_m: np.ndarray | None) -> np.ndarray:
    """Each cable's steps (n, S, m) along the ramp into each row, for row changes ``dc_m`` (n, m).

    Parameters
    ----------
    dc_m : numpy.ndarray
        Change of each cable's length since the previous row (m).
    shape_m : numpy.ndarray or None
        The ramp's deviation from even steps (:func:`predict_ramp`); None for one step.

    Returns
    -------
    numpy.ndarray
        ``dc / S + shape`` (sums to ``dc`` over the steps); ``dc[:, None]`` without a shape.
    """
    if shape_m is None:
        return dc_m[:, None, :]
    return dc_m[:, None, :] / shape_m.shape[1] + shape_m
