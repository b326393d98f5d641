"""Rows of a further experiment appended to a log (``csjm diagnose ... --extra MORE.csv``).

The extra rows must come from the same rig: at their measured poses the rig file's
cables must be taut and within reach of the tension range on most rows (a log from
another rig, with other rest lengths, shows slack or wildly stretched cables). Their
cycles are renumbered to follow the log's, in the order given (they were run after it:
a friction state carries on from the log's last row, and the held-out scoring deals
them to folds as cycles of their own). A cycle id that comes back after other rows is
a new cycle (rows of one cycle are consecutive): the cables were moved in between.
"""

from __future__ import annotations

import numpy as np

from ...errors import InvalidInput
from ...measurement.logfile import MeasurementLog
from ...model import kinematics as kin
from ...model.rig import Rig
from .residuals import compute_residuals

#: Largest share of rows whose nominal tensions at the measured pose are implausible.
MAX_BAD_SHARE = 0.25
#: The extra rows' nominal pose residual may exceed the log's (or 10 mrad) by at most this factor.
RESIDUAL_FACTOR = 5.0
#: Nominal tension beyond this multiple of ``t_max`` (or a slack below ``-t_max``) is implausible.
TENSION_FACTOR = 3.0


def check_rows_belong(rig: Rig, log: MeasurementLog, what: str) -> None:
    """Raise unless the log's rest lengths fit the rig at the measured poses.

    Parameters
    ----------
    rig : Rig
    log : MeasurementLog
    what : str
        Name of the log in the message (e.g. the file).

    Raises
    ------
    InvalidInput
        More than ``MAX_BAD_SHARE`` of the rows have a cable far slack or far over ``t_max``.
    """
    c, _ = kin.cable_terms(log.R, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    T = np.asarray(rig.cable_stiffness_N_per_m) * (c - log.rest_lengths_m)
    bad = np.any((T < -rig.t_max_N) | (T > TENSION_FACTOR * rig.t_max_N), axis=1)
    if bad.mean() > MAX_BAD_SHARE:
        i = int(np.flatnonzero(bad)[0])
        raise InvalidInput(f"{what}: {bad.sum()} of {len(bad)} rows do not fit this rig (e.g. sample "
                           f"{int(log.sample[i])}: nominal tensions "
                           f"{np.round(T[i], 1).tolist()} N at the measured pose, range [{rig.t_min_N:g}, "
                           f"{rig.t_max_N:g}] N); is it a log of another rig?", "extra")


def check_same_rig(rig: Rig, log: MeasurementLog, extra: MeasurementLog, what: str) -> None:
    """Raise when the nominal model misses the extra rows far more than it misses the log's.

    Parameters
    ----------
    rig : Rig
    log, extra : MeasurementLog
    what : str
        Name of the extra log in the message.

    Raises
    ------
    InvalidInput
        The extra rows' nominal pose residual RMS exceeds ``RESIDUAL_FACTOR`` x max(the log's, 10 mrad):
        the same unmodelled effects cannot make that difference, another rig can.
    """
    own = compute_residuals(rig, log).rms_rad
    theirs = compute_residuals(rig, extra).rms_rad
    if not theirs <= RESIDUAL_FACTOR * max(own, 0.01):
        raise InvalidInput(f"{what}: the rig file's model misses its poses by {1e3 * theirs:.0f} mrad RMS against "
                           f"{1e3 * own:.0f} mrad on the log; is it a log of another rig?", "extra")


def append_log(rig: Rig, log: MeasurementLog, extra: MeasurementLog, what: str = "extra log") -> MeasurementLog:
    """``log`` followed by ``extra`` (its cycles numbered after the log's, in time order).

    Parameters
    ----------
    rig : Rig
    log, extra : MeasurementLog
    what : str, optional
        Name of the extra log in messages.

    Returns
    -------
    MeasurementLog

    Raises
    ------
    InvalidInput
        ``extra`` does not belong to ``rig`` (:func:`check_rows_belong`, :func:`check_same_rig`).
    """
    check_rows_belong(rig, extra, what)
    check_same_rig(rig, log, extra, what)
    c = np.asarray(extra.cycle)
    runs = np.cumsum(np.r_[True, c[1:] != c[:-1]]) - 1       # cycles in time order (rows consecutive)
    cyc = np.r_[np.asarray(log.cycle), int(np.max(log.cycle)) + 1 + runs]
    return MeasurementLog.from_arrays(cyc, np.r_[log.rest_lengths_m, extra.rest_lengths_m],
                                      np.r_[log.tau_ext_A_Nm, extra.tau_ext_A_Nm],
                                      np.concatenate([log.R, extra.R]))
