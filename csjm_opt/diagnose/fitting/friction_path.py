"""The friction state along the model's own path: cable motion from predicted poses, not measured ones.

A dry-friction state (the play operator of :mod:`csjm_opt.diagnose.effects.friction`) is driven by the
motion of each cable. Where a cable sticks it hardly moves: with MuJoCo's rigid stick not at all, on a
real rig by the elastic travel of the band, tens of micrometres. The measured poses move it by their
noise (tens of micrometres of cable length), and a play operator driven by measured motion flips the
state of stuck cables at random, so the fit compensates with a longer stick travel and an unphysical
drive-side weight, and leaves a structured residual that the held-out cycles, predicted along the
model's own (noise-free) path, do not share.

:func:`on_predicted_path` therefore replaces a table's cable steps by those of the poses the model
predicts for every row (each cycle from the state the measured history leaves, as a held-out cycle is
predicted), and gives every row the shape of the ramp the model predicts into it
(:func:`csjm_opt.diagnose.fitting.friction_ramp.predict_ramp`: the quasi-static path between rows, where a
cable's motion may reverse): the training fit and the held-out prediction then see the same friction
physics. :func:`csjm_opt.diagnose.selection.scoring.score` refits a path-dependent model once on that path.
:func:`end_state` reads the state the log leaves on the same path (what a next experiment starts from).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...model.kinematics import PoseSolution
from ..data.residuals import ResidualTable
from .augmented import AugmentedModel, Rows, cable_steps, log_steps, with_entry
from .friction_ramp import predict_ramp


def on_predicted_path(model: AugmentedModel, table: ResidualTable, theta: np.ndarray) -> ResidualTable:
    """``table`` with the cable steps of the poses ``model`` predicts at ``theta`` (path-dependent models only).

    Parameters
    ----------
    model : AugmentedModel
        A fitted model; returned unchanged unless it is path dependent.
    table : ResidualTable
        The log's rows (measured poses, time order).
    theta : numpy.ndarray
        The model's parameters.

    Returns
    -------
    ResidualTable
        The same table whose ``rows`` carry the cable length changes (since the previous row of the
        log and of the cycle) along the predicted poses (each cable's length between its holes as the
        model places them, at the cable platform's pose: not the measured body's), and the shape of
        the predicted ramp into each row (``ramp_shape_m``); rows whose prediction did not converge
        keep their measured steps.
    """
    if not model.path_dependent:
        return table
    sol, shape = predict_ramp(model, with_entry(model, table.rows, table.R_meas, theta), theta, table.R_meas)
    return along(model, table, theta, sol, shape)


def along(model: AugmentedModel, table: ResidualTable, theta: np.ndarray, sol: PoseSolution,
          shape: np.ndarray) -> ResidualTable:
    """``table`` on the path of a prediction ``(sol, shape)`` of its rows (:func:`on_predicted_path`'s second half).

    ``(sol, shape)`` is :func:`~csjm_opt.diagnose.fitting.friction_ramp.predict_ramp` of the table's rows with
    their entries (:func:`~csjm_opt.diagnose.fitting.augmented.with_entry`) at ``theta``, made by the caller
    (e.g. beside another log's, :func:`~csjm_opt.diagnose.fitting.friction_ramp.predict_ramps`).
    """
    ok = np.all(np.isfinite(sol.R.reshape(len(table), -1)), axis=1) & sol.converged(1e-6)
    R = np.where(ok[:, None, None], sol.R, table.R_meas)
    # the cables' own lengths: at the cable platform's pose and the model's hole geometry (a link's twist,
    # a tracker registration and hole offsets all stand between the measured body and the cables)
    _, ev = model.evaluate(R, table.rows, theta)
    lengths = ev.lengths_m
    assert lengths is not None                           # set by every evaluation
    rows = dataclasses.replace(table.rows, log_steps_m=log_steps(lengths),
                               cable_steps_m=cable_steps(table.cycle, lengths), ramp_shape_m=shape)
    return dataclasses.replace(table, rows=rows)


def end_state(model: AugmentedModel, rows: Rows, R_meas: np.ndarray,
              theta: np.ndarray) -> tuple[np.ndarray, np.ndarray] | tuple[None, None]:
    """Path state and cable lengths (m,) the log leaves at its last row, on the path ``rows`` carry.

    ``rows`` are those the model was fitted on (:attr:`csjm_opt.diagnose.fitting.gauss_newton.FitResult.rows`: the
    measured steps, or the predicted path and ramps of :func:`on_predicted_path`), so the state a
    next experiment starts from is the fit's own.

    Parameters
    ----------
    model : AugmentedModel
        The fitted model.
    rows : Rows
        The rows it was fitted on.
    R_meas : numpy.ndarray
        Measured poses (n, 3, 3).
    theta : numpy.ndarray
        The fitted parameters.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray) or (None, None)
        The state and the cable lengths of the last row; ``(None, None)`` for a model without memory.
    """
    if not model.path_dependent:
        return None, None
    _, ev = model.evaluate(R_meas, rows, theta)          # the whole log in order, at the measured poses
    if ev.state_out is None or ev.lengths_m is None:
        return None, None
    return ev.state_out[-1], ev.lengths_m[-1]
