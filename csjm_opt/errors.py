"""One error family for csjm_opt.

Every error the library raises derives from :class:`CsjmError`; each class
names one condition and carries the data that explains it, so a caller can
react to the condition without parsing the message. The CLI turns any
``CsjmError`` into one line on stderr and exit status 2.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class CsjmError(Exception):
    """Base class of every error raised by csjm_opt."""


class InvalidInput(CsjmError, ValueError):
    """An argument has the wrong shape, type or value.

    ``name`` is the argument (or key) at fault.
    """

    def __init__(self, message: str, name: str | None = None):
        super().__init__(message)
        self.name = name


class NotARotation(InvalidInput):
    """A matrix given as a rotation is not one.

    ``orthogonality_error`` is ``||R^T R - I||_F``; ``det`` is ``det(R)``.
    """

    def __init__(self, message: str, orthogonality_error: float, det: float,
                 name: str | None = None):
        super().__init__(message, name)
        self.orthogonality_error = float(orthogonality_error)
        self.det = float(det)


class RigFileError(InvalidInput):
    """A rig description (TOML file or dict) is malformed.

    ``path`` is the file (or ``None`` for in-memory data), ``key`` the dotted
    key at fault, e.g. ``"cables.t_min"``.
    """

    def __init__(self, message: str, path: str | None = None, key: str | None = None):
        where = f"{path}: " if path else ""
        where += f"[{key}] " if key else ""
        super().__init__(where + message, key)
        self.path = path
        self.key = key


class DataFileError(InvalidInput):
    """A measurement log (CSV) is malformed. ``line`` is 1-based (header = 1)."""

    def __init__(self, message: str, path: str | None = None, line: int | None = None,
                 column: str | None = None):
        where = f"{path}" if path else "<data>"
        where += f":{line}" if line is not None else ""
        where += f" column '{column}'" if column else ""
        super().__init__(f"{where}: {message}", column)
        self.path = path
        self.line = line
        self.column = column


class InfeasibleLoad(CsjmError):
    """No tensions within ``[t_min, t_max]`` hold the load at the pose.

    ``distance_Nm`` is the smallest achievable equilibrium residual
    ``min ||J^T T + tau_load||`` over tensions within bounds: how far the
    load lies outside the wrench-feasible set.
    """

    def __init__(self, message: str, R: Any, tau_ext: Any, distance_Nm: float,
                 index: int | None = None):
        super().__init__(message)
        self.R = np.asarray(R)
        self.tau_ext = np.asarray(tau_ext)
        self.distance_Nm = float(distance_Nm)
        self.index = index


class SolverError(CsjmError):
    """A numerical back end (QP solver, CasADi) failed; ``backend`` names it."""

    def __init__(self, message: str, backend: str | None = None):
        super().__init__(message)
        self.backend = backend


class NoEquilibrium(CsjmError):
    """Forward statics found no stable equilibrium.

    ``residual_Nm`` is the best equilibrium residual reached, ``reason`` one of
    ``"diverged"``, ``"slack"``, ``"unstable"``.
    """

    def __init__(self, message: str, reason: str, residual_Nm: float = float("nan")):
        super().__init__(message)
        self.reason = reason
        self.residual_Nm = float(residual_Nm)


class IllConditionedData(CsjmError):
    """Measured excitation does not determine the estimate.

    ``condition`` is the condition number (``inf`` when rank deficient),
    ``rank`` the numerical rank of the excitation; ``direction`` (when known)
    the unit vector along which the excitation is weakest (for stiffness
    identification: of the load moments, in {A}), i.e. the direction a new
    experiment should load.
    """

    def __init__(self, message: str, condition: float, rank: int | None = None,
                 direction: Any = None):
        super().__init__(message)
        self.condition = float(condition)
        self.rank = rank
        self.direction = None if direction is None else np.asarray(direction, dtype=float)


class DesignError(InvalidInput):
    """A design (hole geometry) or a sweep description is invalid.

    ``key`` names the parameter or dotted TOML key at fault, ``path`` the file
    (``None`` for in-memory data).
    """

    def __init__(self, message: str, key: str | None = None, path: str | None = None):
        where = f"{path}: " if path else ""
        where += f"[{key}] " if key else ""
        super().__init__(where + message, key)
        self.key = key
        self.path = path


class LogRigMismatch(InvalidInput):
    """A measurement log the rig file cannot have produced (checked by its equilibrium).

    ``source`` names the log, ``residual_N`` the median per-cable tension error that the
    moment balance of its first rows needs with the rig's cables, ``tolerance_N`` the bound
    (:func:`csjm_opt.measurement.rig_fit.check_log_rig`).
    """

    def __init__(self, message: str, source: str | None, residual_N: float, tolerance_N: float):
        super().__init__(message, "rig")
        self.source = source
        self.residual_N = float(residual_N)
        self.tolerance_N = float(tolerance_N)


class UsageError(InvalidInput):
    """Bad command-line usage (unknown option, missing argument, bad value)."""


class InconsistentTensions(InvalidInput):
    """Tensions given to the stiffness are outside ``[t_min, t_max]`` or out of equilibrium.

    ``reason`` is ``"bounds"`` or ``"equilibrium"``; ``value`` the bound
    violation (N) or the equilibrium residual ``||J^T T + tau_load||`` (N m).
    """

    def __init__(self, message: str, reason: str, value: float):
        super().__init__(message, "tensions")
        self.reason = reason
        self.value = float(value)


class InfeasibleRequirement(CsjmError):
    """No design within the bounds meets an optimisation's requirements.

    ``constraint`` names the requirement that binds, ``angles_deg`` the
    orientation (tilt, azimuth, torsion in degrees) where it binds, or ``None``
    when it is not tied to one orientation.
    """

    def __init__(self, message: str, constraint: str, angles_deg: Any = None):
        super().__init__(message)
        self.constraint = constraint
        self.angles_deg = None if angles_deg is None else tuple(float(a) for a in angles_deg)
