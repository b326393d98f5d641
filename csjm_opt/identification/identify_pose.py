"""Identify K at one reference pose from one cycle's orientations and loads (Section III, (46)-(50)).

For one load cycle (rows in time order, the first row is the reference)::

    dzeta_i = log(R_ref^T R_i)                        body frame, (46)
    tau_load_i = tau_ext_i + tau_weight(R_i)          total load (55)-(56), in {A}
    K_D ~ dtau_load / dzeta                           (48a), estimated by (49)
    K = K_D + K_L,  K_L = -1/2 hat(tau_load_ref)      (47), corrected (errata 1-2)

The default estimate is ``K_ml`` (``StiffnessEstimate.estimator``): maximum likelihood with
the tracker and F/T noise and the curvature of the moment-rotation relation from the rig model,
with the Cramér-Rao bound of its six entries (:mod:`csjm_opt.identification.ml_estimator`,
:mod:`csjm_opt.identification.cramer_rao`). For comparison, three more estimates are returned
together in :class:`StiffnessEstimate`:

* ``K_D_paper`` / ``K_paper``: the paper's literal ``Psi Omega^+`` on
  differences to the reference row (49)-(50), with the corrected ``K_L``.
* ``K_D`` / ``K``: affine least squares ``tau_load_i = c + K_D dzeta_i
  [+ terms of degree 2..order]`` over all rows, so the reference row's noise
  is not copied into every difference; ``K_L`` uses the fitted ``c``. With an
  :class:`~csjm_opt.measurement.instruments.InstrumentNoise`, the normal matrix is
  corrected for the known orientation noise in ``dzeta`` (errors-in-variables,
  corrected least squares) and the covariance uses the instrument model.
* ``K_sym``: the symmetric-constrained estimate. K is symmetric (37), so
  ``K_D - K_D^T = hat(tau0)`` with ``tau0`` the load at the reference; with
  ``K_D = S + 1/2 hat(tau0)`` the model ``tau_load_i = (I - 1/2 hat(dzeta_i))
  tau0 + S dzeta_i`` is linear in ``(tau0, S)`` and ``K_sym = S`` is fitted by
  generalised least squares, weighted by the row covariance
  ``Sigma_tau + sigma_angle^2 K_D K_D^T`` (effective variance).

Confidence intervals are analytic (Student t on the residual covariance, or
normal on the instrument covariance) and optionally a pairs bootstrap.

Refusal rule (what cannot be identified is not returned): a cycle is refused
with :class:`~csjm_opt.errors.IllConditionedData` when its displacements do
not span three directions (rank < 3 or condition > ``max_condition``), or when
the estimate is not determined to :data:`MAX_RELATIVE_HALF_WIDTH`: the largest
confidence half-width of any entry of K, relative to ``||K||_2`` (the largest
singular value of K), exceeds 0.2. The error carries ``direction``, the
weakest direction of the centred load moments in {A} (smallest right singular
vector): loads with a moment component along it supply what is missing.
``allow_ill_conditioned=True`` returns the estimate anyway (rank 3 needed),
marked ``ill_conditioned``.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy import stats

from .. import so3
from .._limits import MAX_BOOTSTRAP
from .._validate import as_array, as_rotations
from ..errors import IllConditionedData, InvalidInput
from ..measurement.instruments import InstrumentNoise
from ..model.numeric import Model
from .cramer_rao import sym_to_full
from .curvature import model_curvature, weight_slopes
from .estimate import StiffnessEstimate, relative_half_width
from .ml_estimator import fit_ml
from .refusal import (
    MAX_CONDITION,
    MAX_RELATIVE_HALF_WIDTH,
    _check_rows,
    _missing,
    excitation,
    weakest_load_direction,
)
from .stiffness_fits import (
    affine_fit,
    bootstrap_interval,
    n_parameters,
    paper_estimate,
    symmetric_fit,
)


# --------------------------------------------------------------- estimators
@functools.lru_cache(maxsize=256)
def _quantile(ci_level: float, dof: int) -> float:
    """Two-sided quantile: Student t with ``dof`` degrees of freedom, normal for ``dof = 0`` (cached)."""
    a = 0.5 + ci_level / 2
    return float(stats.norm.ppf(a) if dof == 0 else stats.t.ppf(a, dof))


def identify_stiffness(R: np.ndarray, tau_ext_A_Nm: np.ndarray, model: Model | None = None,
                       tau_weight_A_Nm: np.ndarray | None = None, *, noise: InstrumentNoise | None = None,
                       order: int = 1, ci_level: float = 0.95, bootstrap: int = 0,
                       rng: np.random.Generator | None = None, max_condition: float = MAX_CONDITION,
                       cycle: int | None = None, allow_ill_conditioned: bool = False,
                       rest_lengths_m: np.ndarray | None = None, curvature: str = "model",
                       tracker_sigma_rad: float | None = None) -> StiffnessEstimate:
    """Identify K at ``R[0]`` from one cycle's orientations (n, 3, 3) and external moments (n, 3).

    Parameters
    ----------
    R : array (n, 3, 3)
        Measured orientations of {A} in {B}; row 0 is the reference.
    tau_ext_A_Nm : array (n, 3)
        External moments about O in {A} (N m), platform weight excluded.
    model : Model, optional
        Gives the weight moment at each measured pose when ``tau_weight_A_Nm`` is not given.
    tau_weight_A_Nm : array (n, 3), optional
        Weight moments (zeros for a weightless platform).
    noise : InstrumentNoise, optional
        Instrument model: errors-in-variables correction and normal intervals.
    order : {1, 2, 3}
        Degree of the fit in dzeta.
    ci_level : float
        Confidence level in (0, 1).
    bootstrap : int
        Pairs-bootstrap resamples, 0 to :data:`~csjm_opt._limits.MAX_BOOTSTRAP`.
    rng : numpy.random.Generator, optional
        Bootstrap generator.
    max_condition : float
        Largest accepted condition number of the displacements (>= 1; ``inf``: no limit).
    cycle : int, optional
        Cycle id stored in the result.
    allow_ill_conditioned : bool
        Return an estimate that fails the precision rule (or the condition
        limit) anyway, marked ``ill_conditioned``; rank-deficient data still raise.

    Returns
    -------
    StiffnessEstimate

    Raises
    ------
    InvalidInput
        Bad shapes, values or options.
    IllConditionedData
        The cycle does not determine K (module docstring: rank, condition,
        relative precision); ``direction`` is the weakest load direction in {A}.
    """
    R = as_rotations(R, "R")
    n = R.shape[0]
    tau_ext = as_array(tau_ext_A_Nm, (n, 3), "tau_ext")
    if curvature not in ("model", "none"):
        raise InvalidInput(f"curvature: expected 'model' or 'none', got {curvature!r}", "curvature")
    if tau_weight_A_Nm is None:
        if model is None:
            raise InvalidInput("give a model (for the weight moment) or tau_weight_A_Nm", "model")
        tau_weight_A_Nm = model.weight_moment(R)
    if order not in (1, 2, 3):
        raise InvalidInput(f"order: expected 1, 2 or 3, got {order!r}", "order")
    if isinstance(bootstrap, bool) or not isinstance(bootstrap, (int, np.integer)) \
            or not 0 <= bootstrap <= MAX_BOOTSTRAP:
        raise InvalidInput(f"bootstrap: expected an integer in [0, {MAX_BOOTSTRAP}], got {bootstrap!r}", "bootstrap")
    if not (isinstance(ci_level, (int, float)) and 0 < ci_level < 1):
        raise InvalidInput(f"ci_level: expected a number in (0, 1), got {ci_level!r}", "ci_level")
    if not (isinstance(max_condition, (int, float)) and 1 <= max_condition):
        raise InvalidInput(f"max_condition: expected a number >= 1 (inf: no limit), got {max_condition!r}",
                           "max_condition")
    tau_load = tau_ext + as_array(tau_weight_A_Nm, (n, 3), "tau_weight")
    dzeta = so3.log(np.swapaxes(R[0], -1, -2)[None] @ R)
    p = n_parameters(order)
    _check_rows(n, p)
    u, _ = weakest_load_direction(tau_load)
    ill = False
    try:
        cond, s = excitation(dzeta, noise, max_condition)
    except IllConditionedData as exc:
        if not allow_ill_conditioned or exc.rank is None or exc.rank < 3:
            raise IllConditionedData(f"{exc}; {_missing(u)}", exc.condition, exc.rank, u) from exc
        cond, ill = exc.condition, True
        s = np.linalg.svd(dzeta - dzeta.mean(axis=0), compute_uv=False)[:3]

    K_D_paper = paper_estimate(dzeta, tau_load)
    fit = affine_fit(dzeta, tau_load, order, noise)
    sym = symmetric_fit(dzeta, tau_load, order, fit["Sigma"])
    if noise is not None:
        q = _quantile(ci_level, 0)
        Y_std = np.sqrt(np.asarray(noise.tau_sigma_Nm) ** 2
                        + noise.angle_sigma_rad ** 2 * np.sum(fit["K_D"] ** 2, axis=1))
        chi2 = float(np.sum((fit["resid"] / Y_std) ** 2) / (3 * (n - p)))
    else:
        q = _quantile(ci_level, n - p)
        chi2 = float("nan")
    if tracker_sigma_rad is None:
        tracker_sigma_rad = InstrumentNoise.paper().angle_sigma_rad
    ml, curv_used = _fit_ml(dzeta, tau_load, R, model, rest_lengths_m, noise, curvature, tracker_sigma_rad)
    ml_quantile = _quantile(ci_level, 0 if noise is not None else max(ml.dof, 1))
    # K is determined when either estimate determines it: the linear fit (its residual-based interval
    # grows with unmodelled curvature) or K_ml (its bound, curvature subtracted, noise as stated)
    half_lin = q * np.sqrt(np.maximum(np.diag(fit["cov_K"]), 0.0))
    half_ml = ml_quantile * np.sqrt(np.maximum(np.diag(sym_to_full(ml.crlb6)), 0.0))
    rel_lin, rel_ml = relative_half_width(half_lin, fit["K"]), relative_half_width(half_ml, ml.K)
    half, scale, rel = ((half_lin, float(np.linalg.norm(fit["K"], 2)), rel_lin) if rel_lin <= rel_ml
                        else (half_ml, float(np.linalg.norm(ml.K, 2)), rel_ml))
    if not rel <= MAX_RELATIVE_HALF_WIDTH:
        if not allow_ill_conditioned:
            raise IllConditionedData(
                f"K is not determined to {MAX_RELATIVE_HALF_WIDTH:.0%}: {int(round(ci_level * 100))} % "
                f"half-widths up to {half.max():.3g} N m/rad against ||K|| = {scale:.3g} N m/rad "
                f"({rel:.0%}); {_missing(u)}", cond, 3, u)
        ill = True
    boot = None
    if bootstrap:
        boot = bootstrap_interval(dzeta, tau_load, order, noise, bootstrap, ci_level,
                                  rng or np.random.default_rng(0))
    return StiffnessEstimate(
        cycle=cycle, n_rows=n, order=order, R_ref=R[0], tau_load_ref_A_Nm=fit["c"],
        K_D=fit["K_D"], K_L=-0.5 * so3.hat(fit["c"]), K=fit["K"], K_sym=sym["K"],
        K_D_paper=K_D_paper, K_paper=K_D_paper - 0.5 * so3.hat(tau_load[0]),
        cov_K=fit["cov_K"], cov_K_sym=sym["cov_K"], ci_level=ci_level, ci_quantile=q,
        condition=cond, singular_values_rad=s,
        residual_rms_Nm=float(np.sqrt(np.mean(np.sum(fit["resid"] ** 2, axis=1)))),
        chi2_per_dof=chi2, bootstrap_K_ci=boot, design_condition=float(fit["design_condition"]),
        weakest_load_direction_A=u, ill_conditioned=ill,
        K_ml=ml.K, crlb6=ml.crlb6, cov6_ml=ml.cov6,
        ml_quantile=ml_quantile,
        curvature=curv_used, noise_estimated=ml.noise_estimated)


def _fit_ml(dzeta, tau_load, R, model, rest_lengths_m, noise, curvature, tracker_sigma_rad):
    """K_ml of the cycle: the curvature from the rig model when it and the rest lengths are known."""
    W = weight_slopes(model, R, dzeta) if model is not None else None
    if curvature == "model" and model is not None and rest_lengths_m is not None:
        l = as_array(rest_lengths_m, (model.A.shape[0],), "rest_lengths_m")
        c, dc = model_curvature(model, R[0], l, dzeta)
        return fit_ml(dzeta, tau_load, noise, c, dc, W, tracker_sigma_rad=tracker_sigma_rad), "model"
    return fit_ml(dzeta, tau_load, noise, None, None, W, tracker_sigma_rad=tracker_sigma_rad), "none"
