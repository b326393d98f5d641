"""Is this log from this rig? The equilibrium of a log's first rows checked with the rig file's cables.

A log holds, per row, the commanded rest lengths ``l``, the measured pose ``R`` and the
measured external moment ``tau_ext``. On the rig that made it, the cables' tensions
``T_i = k_i (c_i(R) - l_i)`` (0 when slack) balance the load::

    s J(R)^T T + tau_weight(R) + tau_ext = r,    r small        (in {A}, N m)

``s`` is one common stiffness factor, fitted by least squares and held to the diagnosis
vocabulary's plausible range [0.5, 2] (``stiffness_scale``), so that a rig file whose cable
stiffness is off by a factor is not refused here (the diagnosis names it). The residual is
expressed per row as the per-cable tension error that explains it,
``e = |r| / sum_i |J_i|`` (N): the moment ``r`` spread over all cables' lever arms.

A log from another rig (other holes, other lengths) needs tensions that are wrong by tens
of newtons on every row; the effects of the vocabulary at the sizes a lab meets need a few:
hole offsets of 1.5 mm (standard deviation per coordinate) on a 7000 N/m rig, Coulomb
friction of 3 N per cable, a 0.15 N m sensor bias or a 0.8 degree tracker registration give a
median ``e`` of at most 4.0 N, i.e. 0.85 mm of cable length (the 94 validation logs made
outside the project, ``studies/log_rig_check/``); logs of the other validation rigs read
with the paper rig need 6.4 N or more. The bound on the median over the first rows is
``TOL_LENGTH_M`` (1.25 mm of length on every cable, more than the worst in-vocabulary log
above) times the rig's mean cable stiffness, and at least ``TOL_FLOOR_N``.

What the check cannot see: a rig that differs from the log's by a common stiffness factor
together with a geometry change that such a factor absorbs (for example the paper rig and
the same rig with base holes 20 % further out and k = 7000 N/m balance each other's
logs within 1 mm); those logs pass, and the diagnosis reports the stiffness.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import LogRigMismatch
from ..model import cable_terms
from ..model.rig import Rig
from .logfile import MeasurementLog

__all__ = ["FIRST_ROWS", "LogRigFit", "TOL_FLOOR_N", "TOL_LENGTH_M", "check_log_rig", "log_rig_fit"]

#: Rows checked: the first three load cycles of the usual 11-row protocol.
FIRST_ROWS = 33
#: Equivalent cable-length error allowed (median over the rows), m.
TOL_LENGTH_M = 1.25e-3
#: Smallest allowed median per-cable tension error, N (noise and friction on soft rigs).
TOL_FLOOR_N = 5.0
#: Plausible range of the common stiffness factor (the vocabulary's ``stiffness_scale``).
SCALE_RANGE = (0.5, 2.0)


@dataclasses.dataclass(frozen=True)
class LogRigFit:
    """How well the rig balances a log's first rows.

    Attributes
    ----------
    rows : int
        Rows checked.
    stiffness_factor : float
        Fitted common cable stiffness factor, within ``SCALE_RANGE``.
    residual_N : numpy.ndarray
        Per-row tension error ``e`` (N), shape (rows,).
    slack_share : float
        Share of (row, cable) pairs with a slack cable at the measured pose.
    tolerance_N : float
        Bound on the median of ``residual_N``.
    """

    rows: int
    stiffness_factor: float
    residual_N: np.ndarray
    slack_share: float
    tolerance_N: float

    @property
    def median_N(self) -> float:
        """Median per-row tension error (N)."""
        return float(np.median(self.residual_N)) if self.rows else 0.0

    @property
    def ok(self) -> bool:
        """``True`` when the rig can have produced the rows."""
        return self.median_N <= self.tolerance_N


def log_rig_fit(rig: Rig, log: MeasurementLog, rows: int = FIRST_ROWS) -> LogRigFit:
    """The equilibrium of the first ``rows`` rows of ``log`` with ``rig``'s cables (module docstring).

    Parameters
    ----------
    rig : Rig
    log : MeasurementLog
    rows : int, optional
        How many rows from the start to check.

    Returns
    -------
    LogRigFit
    """
    n = min(int(rows), len(log))
    R = log.R[:n]
    A = np.asarray(rig.platform_holes_A_m, float)
    B = np.asarray(rig.base_holes_B_m, float)
    k = np.asarray(rig.cable_stiffness_N_per_m, float)
    c, _, J = cable_terms.geometry(R, A, B)
    stretch = c - log.rest_lengths_m[:n]
    T = np.maximum(k * stretch, 0.0)
    tau_cables = np.einsum("nij,ni->nj", J, T)
    tau_rest = (cable_terms.weight_moment(R, rig.platform_mass_kg * np.asarray(rig.com_A_m, float),
                                          np.asarray(rig.gravity_B_m_per_s2, float))
                + log.tau_ext_A_Nm[:n])
    denom = float(np.sum(tau_cables * tau_cables))
    s = -float(np.sum(tau_cables * tau_rest)) / denom if denom > 0 else 1.0
    s = float(np.clip(s, *SCALE_RANGE))
    lever_m = np.linalg.norm(J, axis=2).sum(axis=1)
    residual = np.linalg.norm(s * tau_cables + tau_rest, axis=1) / lever_m
    tol = max(TOL_FLOOR_N, TOL_LENGTH_M * float(np.mean(k)))
    return LogRigFit(rows=n, stiffness_factor=s, residual_N=residual,
                     slack_share=float(np.mean(stretch <= 0)) if n else 0.0, tolerance_N=tol)


def check_log_rig(rig: Rig, log: MeasurementLog, what: str | None = None, rows: int = FIRST_ROWS) -> LogRigFit:
    """Refuse a log that ``rig`` cannot have produced (its first rows out of equilibrium).

    Parameters
    ----------
    rig : Rig
    log : MeasurementLog
    what : str, optional
        Name of the log in the message (default: its source file).
    rows : int, optional
        How many rows from the start to check.

    Returns
    -------
    LogRigFit
        The fit, when the log passes.

    Raises
    ------
    LogRigMismatch
        The median per-cable tension error of the first rows exceeds the tolerance.
    """
    fit = log_rig_fit(rig, log, rows)
    if not fit.ok:
        name = what or log.source or "the log"
        raise LogRigMismatch(
            f"{name}: the rig file cannot have produced this log: its first {fit.rows} rows are out of "
            f"equilibrium with the rig's cables by {fit.median_N:.1f} N per cable (median; at most "
            f"{fit.tolerance_N:.1f} N from effects a rig can have); is it a log of another rig? Pass its "
            "rig file with --rig (or skip this check: --no-rig-check, check_rig=False)",
            log.source, fit.median_N, fit.tolerance_N)
    return fit
