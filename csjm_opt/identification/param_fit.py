"""Physical-parameter identification over a whole measurement log.

Parameters: cable-plus-drive stiffness (one shared ``k`` or one per cable)
and rest-length offsets ``dl`` (m) per drive, so the actual rest length is the
commanded ``l + dl`` (a pretension offset: ``dT = -k dl``). They are fitted by
nonlinear least squares on the equilibrium (moment) residuals at the measured
poses, which is fast and needs no forward statics::

    r_i = J(R_i)^T T_i + tau_load_i,   T_i = k (c(R_i) - l_i - dl)   (38), docs/conventions.md

weighted by the F/T uncertainty when an instrument model is given. The
covariance of the parameters is ``s^2 (A^T A)^-1`` from the Jacobian ``A`` at
the optimum (``s^2 = 1`` with known instrument weights, else the residual
variance). The fitted model is then checked where it matters: the poses it
predicts by forward statics (:func:`csjm_opt.model.statics.solve_equilibrium`),
on rows it has not seen.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from .. import so3
from ..errors import IllConditionedData, InvalidInput, NoEquilibrium, SolverError
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.numeric import Model
from ..model.rig import Rig
from ..model.statics import solve_equilibrium


@dataclasses.dataclass(frozen=True, eq=False)
class ParameterFit:
    """Fitted physical parameters with their covariance."""

    rig: Rig                        # the rig with the fitted stiffness
    names: tuple[str, ...]
    values: np.ndarray              # (p,)
    cov: np.ndarray                 # (p, p)
    rest_length_offsets_m: np.ndarray  # (m,) dl
    residual_rms_Nm: float          # rms moment residual per axis at the optimum
    initial_residual_rms_Nm: float
    condition: float                # condition number of the (scaled) Jacobian
    n_rows: int

    @property
    def std(self) -> np.ndarray:
        """(p,) standard deviations of the fitted parameters, in the order of ``names``."""
        return np.sqrt(np.diag(self.cov))

    def summary(self) -> dict[str, Any]:
        """The fit as a JSON-able dict.

        Returns
        -------
        dict
            Fitted parameters with standard deviations, residual RMS and condition.
        """
        return {"parameters": {n: {"value": float(v), "std": float(s)}
                               for n, v, s in zip(self.names, self.values, self.std)},
                "residual_rms_Nm": self.residual_rms_Nm, "initial_residual_rms_Nm": self.initial_residual_rms_Nm,
                "condition": self.condition, "n_rows": self.n_rows}

    def predict(self, log: MeasurementLog, R_init: np.ndarray | None = None, model: Model | None = None) -> np.ndarray:
        """Equilibrium orientations of the fitted model for the log's rest lengths and loads.

        Parameters
        ----------
        log : MeasurementLog
            Rows to predict.
        R_init : ndarray, shape (n, 3, 3), optional
            Starting pose of each forward-statics solve (default: the row's measured pose).
        model : Model, optional
            A numeric model of the fitted rig to reuse.

        Returns
        -------
        ndarray, shape (n, 3, 3)
            Predicted orientations of {A} in {B}.

        Raises
        ------
        NoEquilibrium
            If the fitted model has no equilibrium for a row.
        """
        if model is None or model.rig is not self.rig:   # the model must carry the fitted stiffness
            model = Model(self.rig)
        starts = log.R if R_init is None else R_init
        out = np.empty((len(log), 3, 3))
        for i in range(len(log)):
            try:
                eq = solve_equilibrium(self.rig, log.rest_lengths_m[i] + self.rest_length_offsets_m,
                                       log.tau_ext_A_Nm[i], R_init=starts[i], model=model)
            except NoEquilibrium as exc:
                raise NoEquilibrium(f"row {i} (sample {int(log.sample[i])}): {exc}", exc.reason,
                                    exc.residual_Nm) from exc
            out[i] = eq.R
        return out

    def pose_errors_rad(self, log: MeasurementLog, model: Model | None = None) -> np.ndarray:
        """Pose error of the fitted model per row: ``||log(R_pred^T R_meas)||``.

        Parameters
        ----------
        log : MeasurementLog
            Rows to check.
        model : Model, optional
            A numeric model of the fitted rig to reuse.

        Returns
        -------
        ndarray, shape (n,)
            Errors (rad).
        """
        return so3.angle_between(self.predict(log, model=model), log.R)


def _unpack(theta: np.ndarray, shared: bool, offsets: bool, k0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    m = k0.shape[0]
    nk = 1 if shared else m
    k = np.full(m, theta[0]) if shared else theta[:m]
    dl = theta[nk:nk + m] if offsets else np.zeros(m)
    return k, dl


def fit_parameters(log: MeasurementLog, rig: Rig, *, shared_stiffness: bool = False,
                   rest_length_offsets: bool = True, noise: InstrumentNoise | None = None,
                   model: Model | None = None) -> ParameterFit:
    """Fit the cable stiffness (shared or per cable) and rest-length offsets to a whole log.

    Moment residuals at the measured poses, ``J(R_i)^T T_i + tau_load_i`` with
    ``T_i = k (c(R_i) - l_i - dl)``, are minimised by least squares; standard deviations come
    from the Jacobian.

    Parameters
    ----------
    log : MeasurementLog
        The measurements (all cycles).
    rig : Rig
        The nominal rig (geometry and starting values).
    shared_stiffness : bool, optional
        One stiffness for all cables instead of one per cable.
    rest_length_offsets : bool, optional
        Also fit one rest-length offset per cable (m).
    noise : InstrumentNoise, optional
        Weights the residuals by the instrument uncertainties.
    model : Model, optional
        A numeric model of ``rig`` to reuse.

    Returns
    -------
    ParameterFit
        Fitted values with standard deviations; ``predict`` and ``pose_errors_rad`` give the poses
        the fitted model predicts.

    Raises
    ------
    IllConditionedData
        If the log has too few rows for the parameters or does not determine them.
    SolverError
        If the least-squares solver fails.
    """
    model = model or Model(rig)
    R = log.R
    n = len(log)
    J = model.jacobian(R)                                   # (n, m, 3)
    c = model.cable_lengths(R)                              # (n, m)
    tau_load = log.tau_ext_A_Nm + model.weight_moment(R)    # (n, 3)
    l = log.rest_lengths_m
    w = (1.0 / np.asarray(noise.tau_sigma_Nm)) if noise is not None and min(noise.tau_sigma_Nm) > 0 else np.ones(3)
    k0 = np.asarray(rig.cable_stiffness_N_per_m, float)
    m = rig.n_cables
    log.check_cables(m)
    names = (("k",) if shared_stiffness else tuple(f"k{i}" for i in range(1, m + 1)))
    names += tuple(f"dl{i}" for i in range(1, m + 1)) if rest_length_offsets else ()
    theta0 = np.r_[[k0.mean()] if shared_stiffness else k0, np.zeros(m if rest_length_offsets else 0)]
    if 3 * n <= len(theta0):
        raise IllConditionedData(f"{n} rows ({3 * n} equations) cannot determine {len(theta0)} parameters",
                                 float("inf"), 3 * n)

    def residual(theta: np.ndarray) -> np.ndarray:
        k, dl = _unpack(theta, shared_stiffness, rest_length_offsets, k0)
        T = k * np.maximum(c - l - dl, 0.0)
        return ((np.einsum("nsi,ns->ni", J, T) + tau_load) * w).ravel()

    def jacobian(theta: np.ndarray) -> np.ndarray:
        k, dl = _unpack(theta, shared_stiffness, rest_length_offsets, k0)
        stretch = c - l - dl
        taut = stretch > 0
        dk = J * (np.where(taut, stretch, 0.0))[:, :, None]           # (n, m, 3): d r / d k_s
        cols = [dk.sum(axis=1)[:, :, None] if shared_stiffness else dk.transpose(0, 2, 1)]
        if rest_length_offsets:
            cols.append((-J * (k * taut)[:, :, None]).transpose(0, 2, 1))  # d r / d dl_s
        A = np.concatenate(cols, axis=2) * w[None, :, None]            # (n, 3, p)
        return A.reshape(3 * n, -1)

    lower = np.r_[np.full(1 if shared_stiffness else m, 1e-6), np.full(m if rest_length_offsets else 0, -np.inf)]
    x_scale = np.r_[np.full(1 if shared_stiffness else m, max(k0.mean(), 1.0)),
                    np.full(m if rest_length_offsets else 0, 1e-3)]
    r0 = residual(theta0)
    sol = least_squares(residual, theta0, jac=jacobian, bounds=(lower, np.inf), x_scale=x_scale,
                        xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=200)
    if not sol.success and sol.status <= 0:
        raise SolverError(f"parameter fit did not converge: {sol.message}", "scipy.least_squares")
    A = jacobian(sol.x)
    scale = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    s = np.linalg.svd(A / scale, compute_uv=False)
    cond = float(s[0] / s[-1]) if s[-1] > 0 else float("inf")
    if not np.isfinite(cond) or cond > 1e10:
        raise IllConditionedData(f"the log does not determine the parameters {list(names)}: condition "
                                 f"{cond:.3g} (vary poses and rest lengths across cycles)", cond)
    dof = 3 * n - len(theta0)
    s2 = 1.0 if noise is not None else float(np.sum(sol.fun ** 2) / dof)
    cov = np.linalg.inv((A / scale).T @ (A / scale)) / np.outer(scale, scale) * s2
    k, dl = _unpack(sol.x, shared_stiffness, rest_length_offsets, k0)
    rms = float(np.sqrt(np.mean((sol.fun.reshape(n, 3) / w) ** 2)))
    rms0 = float(np.sqrt(np.mean((r0.reshape(n, 3) / w) ** 2)))
    return ParameterFit(rig.replace(cable_stiffness_N_per_m=k), names, sol.x, cov, dl, rms, rms0, cond, n)


def check_fit(fit: ParameterFit, log: MeasurementLog) -> dict[str, float]:
    """Held-out check of a parameter fit: predicted against measured poses on ``log``.

    Parameters
    ----------
    fit : ParameterFit
        From :func:`fit_parameters` (on other rows).
    log : MeasurementLog
        Held-out rows.

    Returns
    -------
    dict
        ``{"rms_rad": ..., "max_rad": ...}`` of the pose error by forward statics.

    Raises
    ------
    InvalidInput
        If ``log`` is empty.
    NoEquilibrium
        If the fitted model has no equilibrium for a row.
    """
    if len(log) == 0:
        raise InvalidInput("empty held-out log", "log")
    e = fit.pose_errors_rad(log)
    return {"heldout_rms_rad": float(np.sqrt(np.mean(e ** 2))), "heldout_max_rad": float(e.max()),
            "n_rows": len(log)}
