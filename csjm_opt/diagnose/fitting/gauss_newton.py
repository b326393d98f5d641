"""Fit an augmented model on linearised, whitened pose residuals (Gauss-Newton).

Residual of row ``i``: ``W_i G_i(theta)^-1 g_i(theta)``: the balance ``g`` at
the measured pose mapped through the candidate's *own* tangent
``G = dg/dzeta`` (one Newton step: the pose the candidate predicts, to first
order) and whitened by the instrument noise (``W_i`` from :mod:`.residuals`).
The tangent must be the candidate's: with a fixed nominal tangent, a model
could shrink how moment *noise* enters ``g`` (e.g. softer cables plus a
negative series compliance) and win on noise, not on physics. Parameters are solved for in units of their typical
scale by ``scipy.optimize.least_squares``; parameters with a ridge prior add
rows ``theta_j / sd_j``. The result knows its covariance, its effective
number of parameters, the rank and condition of its Jacobian, and its BIC.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np
from scipy.optimize import least_squares

from ...errors import SolverError
from ..data.residuals import ResidualTable
from .augmented import N_NUISANCE, AugmentedModel, Rows

#: Condition number (parameters in units of their scale) above which a fit is reported ill-conditioned.
CONDITION_LIMIT = 1e4
#: A fit stops when a step lowers its cost by less than this share (``ftol`` of ``least_squares``). The cost is
#: half the whitened residual sum of squares, a few hundred near the noise floor: a step gaining 1e-6 of it
#: moves the evidence by under a thousandth of a nat. Friction along a loading path crawled on at smaller gains
#: for up to a hundred evaluations more (its evidence moves by a few nats between tolerances anyway: the path
#: is not smooth in the parameters); point models converge fast and lose under 1e-4 nats. On the 47 validation
#: logs, with 1e-6 instead of 1e-10, every verdict is the same and one warning went (a path pair 4.2 nats from
#: the verdict, near the 5-nat line); ``benchmarks/bench_diagnose.py`` gives the time saved.
FTOL = 1e-6
#: Evaluations of one ``least_squares`` run, and the runs again from its end when it used them all. A fit whose
#: cost is not smooth (dry friction along its loading path: the play operator's corners) shrinks its trust region
#: to a crawl: friction + mass/COM on a MuJoCo cable-hardening log stopped at 200 evaluations 50 nats (at unit
#: noise) above where a new run from its end arrived in 26 more.
MAX_NFEV = 200
RESTARTS = 2


@dataclasses.dataclass(frozen=True, eq=False)
class FitResult:
    """A fitted augmented model."""

    model: AugmentedModel
    theta: np.ndarray
    cov: np.ndarray            # (p, p) parameter covariance
    rss: float                 # sum of squared whitened data residuals
    n_obs: int                 # 3 * rows
    p_eff: float               # effective number of parameters (ridge-aware)
    rank: int                  # numerical rank of the data Jacobian
    condition: float           # condition number of the scaled data Jacobian
    zeta_lin_rad: np.ndarray   # (n, 3) linearised pose residuals at the fit
    jac_x: np.ndarray | None = None   # (3 n + priors, p) Jacobian of the scaled problem at the fit
    res_x: np.ndarray | None = None   # (3 n + priors,) its residuals
    free: np.ndarray | None = None    # (p,) parameters not at a bound
    rows: Rows | None = None          # the rows fitted (path-dependent models: the path their state followed)
    # a model whose likelihood is not a sum of squares (settled friction, :mod:`.friction_stick`): its own
    # Laplace log evidence at a noise scale, used by :func:`csjm_opt.diagnose.evidence.log_evidence`
    evidence_fn: Callable[[float], float] | None = None
    # the fit's own cost function, whitened data residuals (3 n,) at parameters theta (SI): what the evidence
    # checks a linearised step against (:func:`csjm_opt.diagnose.fitting.evidence.log_evidence`)
    residuals: Callable[[np.ndarray], np.ndarray] | None = None

    def refit_rows(self, keep: np.ndarray) -> np.ndarray:
        """Parameters fitted to rows ``keep`` only: one Gauss-Newton step from this fit.

        Exact for a linear problem, and the problem is linearised already (a whole refit
        moves the parameters by the same step to first order); used for the held-out folds.
        The step is the *difference* of the Gauss-Newton solutions on rows ``keep`` and on all
        rows: the stored Jacobian is the Gauss-Newton one (``W G^-1 dg/dx``, without the
        ``dG/dx`` term), so where a model changes its own tangent (stiffness scale, link
        compliance) and noise leaves ``g != 0`` the fit is not exactly its stationary point, and a
        plain step from it would travel to that point along a weakly determined direction (a
        whole-log step of half the stiffness scale was seen) instead of measuring what dropping
        the held-out rows changes.
        """
        if self.jac_x is None or self.res_x is None or self.free is None:
            raise SolverError("this fit carries no Jacobian for a fold refit", "diagnose")
        idx = self._problem_rows(keep)
        J, r = self.jac_x[idx][:, self.free], self.res_x[idx]
        Ja, ra = self.jac_x[:, self.free], self.res_x
        scales = self.model.scales
        dx = np.zeros(len(scales))
        dx[self.free] = np.linalg.lstsq(Ja, ra, rcond=None)[0] - np.linalg.lstsq(J, r, rcond=None)[0]
        x = np.clip(self.theta / scales + dx, self.model.lower_bounds / scales, self.model.upper_bounds / scales)
        return x * scales

    def prediction_cov(self, keep: np.ndarray | None, J_held: np.ndarray) -> np.ndarray:
        """Covariance of whitened linearised predictions from a fit to rows ``keep``.

        Per unit noise variance, the predictions ``J_held`` makes with parameters fitted to rows
        ``keep`` (``None``: all rows): ``J_h (J_k^T J_k)^+ J_h^T``.

        ``J_held`` has the columns of :attr:`jac_x` (scaled parameters); parameters at a bound are
        held fixed. A held-out residual of a correctly specified model is noise plus this.
        """
        if self.jac_x is None or self.free is None:
            raise SolverError("this fit carries no Jacobian for a prediction covariance", "diagnose")
        J = self.jac_x[:, self.free] if keep is None else self.jac_x[self._problem_rows(keep)][:, self.free]
        Jh = J_held[:, self.free]
        return Jh @ np.linalg.pinv(J.T @ J) @ Jh.T

    def held_rows_jacobian(self, held: np.ndarray) -> np.ndarray:
        """Rows of :attr:`jac_x` that belong to the data rows ``held`` (3 per row)."""
        assert self.jac_x is not None
        return self.jac_x[_components(held)]

    def _problem_rows(self, keep: np.ndarray) -> np.ndarray:
        """Rows of :attr:`jac_x` / :attr:`res_x` of a fit to data rows ``keep``: theirs and the priors'."""
        assert self.jac_x is not None
        return np.r_[_components(keep), np.arange(self.n_obs, len(self.jac_x))]

    @property
    def sigma2(self) -> float:
        """Residual variance per whitened observation, ``RSS / (N - p_eff)``.

        Returns
        -------
        float
            The noise-scale estimate squared (dimensionless, whitened units).
        """
        return self.rss / max(self.n_obs - self.p_eff, 1.0)

    @property
    def bic(self) -> float:
        """Gaussian BIC with unknown noise scale: ``N ln(RSS/N) + p_eff ln N``."""
        N = self.n_obs
        return float(N * np.log(self.rss / N) + self.p_eff * np.log(N))

    @property
    def stderr(self) -> np.ndarray:
        """Standard errors of the parameters, from the diagonal of ``cov``.

        Returns
        -------
        numpy.ndarray
            Shape (p,), in the units of each parameter (negative variances clipped to 0).
        """
        return np.sqrt(np.maximum(np.diag(self.cov), 0.0))

    @property
    def identifiable(self) -> bool:
        """Whether the data determine every parameter.

        Returns
        -------
        bool
            True if the Jacobian has full rank and its condition number is below ``CONDITION_LIMIT``.
        """
        return bool(self.rank == self.model.n_params and self.condition < CONDITION_LIMIT)

    def params(self, effect_only: bool = True) -> dict[str, float]:
        """Fitted parameter values by name.

        Parameters
        ----------
        effect_only : bool, optional
            Leave out the nuisance parameters (``dl_common_m``); default True.

        Returns
        -------
        dict of str to float
            Parameter name (with units) -> fitted value (SI).
        """
        names = self.model.param_names
        start = N_NUISANCE if effect_only else 0
        return {n: float(v) for n, v in zip(names[start:], self.theta[start:])}

    def param_sd(self, effect_only: bool = True) -> dict[str, float]:
        """Standard errors of the fitted parameters by name.

        Parameters
        ----------
        effect_only : bool, optional
            Leave out the nuisance parameters (``dl_common_m``); default True.

        Returns
        -------
        dict of str to float
            Parameter name (with units) -> standard error (same units).
        """
        names = self.model.param_names
        start = N_NUISANCE if effect_only else 0
        return {n: float(v) for n, v in zip(names[start:], self.stderr[start:])}


def fit_model(model: AugmentedModel, table: ResidualTable, theta0: np.ndarray | None = None) -> FitResult:
    """Fit ``model`` to the rows of ``table`` (all rows are training rows)."""
    scales = model.scales
    prior = model.prior_sd
    has_prior = np.isfinite(prior)
    W = table.whiten
    # linearised residuals, balance and tangent at the last points evaluated: the optimiser asks for the
    # Jacobian where it has just evaluated the residuals (both start from the same g and G), and the result
    # is built at a point evaluated before; each is computed once (bit for bit what a new evaluation gives)
    last: dict[bytes, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}

    def linearised(theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        key = theta.tobytes()
        if key not in last:
            last[key] = _linearised(model, table, theta)
            while len(last) > 4:
                last.pop(next(iter(last)))
        return last[key]

    def data_res(x: np.ndarray) -> np.ndarray:
        return np.einsum("nij,nj->ni", W, linearised(x * scales)[0]).ravel()

    def res(x: np.ndarray) -> np.ndarray:
        r = data_res(x)
        if has_prior.any():
            r = np.concatenate([r, (x * scales)[has_prior] / prior[has_prior]])
        return r

    def jac(x: np.ndarray) -> np.ndarray:
        theta = x * scales
        Jd = data_jacobian(model, table, theta, linearised(theta)[1:])
        if has_prior.any():
            P = np.zeros((int(has_prior.sum()), len(x)))
            P[np.arange(P.shape[0]), np.flatnonzero(has_prior)] = scales[has_prior] / prior[has_prior]
            Jd = np.vstack([Jd, P])
        return Jd

    lb, ub = model.lower_bounds / scales, model.upper_bounds / scales
    starts = model.starts() if theta0 is None else [np.asarray(theta0)]

    def run(x0: np.ndarray):
        return least_squares(res, x0, jac=jac, bounds=(lb, ub), method="trf",
                             x_scale=1.0, xtol=1e-10, ftol=FTOL, gtol=1e-10, max_nfev=MAX_NFEV)

    def solve(x0: np.ndarray):
        sol = run(x0)
        for _ in range(RESTARTS):       # out of evaluations: again from its end, with a fresh trust region
            if sol.status != 0:
                break
            again = run(sol.x)
            if not again.cost < sol.cost:
                break
            sol = again
        return sol

    sol = None
    for start in starts:     # best of the starts (more than one only where an effect asks for it)
        x0 = np.clip(start / scales, lb, ub)
        trial = solve(x0)
        if _stuck(trial, x0, lb, ub):
            # a start on a bound (a friction band, a compliance's diagonal at 0) whose gradient points out of it
            # cuts the first step to the start's 1e-10 offset from the bound: the step gains nothing, FTOL ends the
            # fit where it began, and the other parameters never move (joint friction + cable hardening stayed
            # at the nominal model, its misfit above the null model's). Once more from one scale inside the bound
            low, high = x0 <= lb, x0 >= ub
            inside = x0.copy()
            inside[low] = np.minimum(lb[low] + 1.0, 0.5 * (lb[low] + ub[low]))
            inside[high] = np.maximum(ub[high] - 1.0, 0.5 * (lb[high] + ub[high]))
            again = solve(inside)
            if again.cost < trial.cost:
                trial = again
        if sol is None or trial.cost < sol.cost:
            sol = trial
    assert sol is not None
    x = sol.x
    Jfull = sol.jac
    Jd = Jfull[:3 * len(table)]
    rd = data_res(x)
    rss = float(rd @ rd)
    N = rd.size
    # effective parameters: trace of the hat matrix of the data rows; active bounds drop out
    free = ~(((x <= lb + 1e-9) & np.isfinite(lb)) | ((x >= ub - 1e-9) & np.isfinite(ub)))
    JtJ = Jfull[:, free].T @ Jfull[:, free]
    JtJ_inv = np.linalg.pinv(JtJ)
    p_eff = float(np.trace(Jd[:, free] @ JtJ_inv @ Jd[:, free].T))
    s = np.linalg.svd(Jd, compute_uv=False)
    rank = int(np.sum(s > s[0] * 1e-9)) if s.size else 0
    cond = float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")
    sigma2 = rss / max(N - p_eff, 1.0)
    cov_x = np.zeros((len(x), len(x)))
    cov_x[np.ix_(free, free)] = JtJ_inv * sigma2
    cov = cov_x * np.outer(scales, scales)
    theta = x * scales
    zeta = linearised(theta)[0]
    return FitResult(model, theta, cov, rss, N, p_eff, rank, cond, zeta, Jfull, res(x), free, table.rows,
                     residuals=WhitenedResiduals(model, table))


#: A fit that did not leave its start although its free parameters promise this much (nats at unit noise) is stuck.
STUCK_NATS = 0.5


def _stuck(sol, x0: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> bool:
    """Whether ``least_squares`` ended where it began, at a start on a bound, with a gain left on the table.

    The gain is what the Gauss-Newton step of the parameters off their bounds promises,
    ``g_f^T (J_f^T J_f)^+ g_f / 2`` (half the whitened cost: nats at unit noise).
    """
    on_bound = (x0 <= lb) | (x0 >= ub)
    if not on_bound.any() or np.max(np.abs(sol.x - x0)) > 1e-6:
        return False
    free = (sol.x > lb + 1e-6) & (sol.x < ub - 1e-6)
    if not free.any():
        return False
    J, g = sol.jac[:, free], sol.grad[free]
    return bool(0.5 * g @ np.linalg.lstsq(J.T @ J, g, rcond=None)[0] > STUCK_NATS)


class WhitenedResiduals:
    """``theta -> W zeta_lin(theta)`` flattened (3 n,): :func:`fit_model`'s data residuals, picklable.

    A fit carries it so that its evidence can check what a linearised step from the fit promises against
    the model itself (the Gauss-Newton Jacobian leaves out how a model changes its own tangent).
    """

    def __init__(self, model: AugmentedModel, table: ResidualTable):
        self.model, self.table = model, table

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """The whitened linearised pose residuals (3 n,) at ``theta`` (SI units, nuisance first)."""
        zeta = _linearised(self.model, self.table, np.asarray(theta, float))[0]
        return np.einsum("nij,nj->ni", self.table.whiten, zeta).ravel()


def linearisation(model: AugmentedModel, table: ResidualTable, theta: np.ndarray) -> FitResult:
    """``model`` linearised at ``theta`` without fitting it: its whitened residuals and Jacobian there.

    A :class:`FitResult` whose fit statistics are those of the point (no covariance), for a
    prediction of what a fit from ``theta`` would reach (:func:`.evidence.predicted_evidence`).
    ``theta`` is clipped into the bounds.
    """
    theta = np.clip(np.asarray(theta, float), model.lower_bounds, model.upper_bounds)
    zeta, g0, G = _linearised(model, table, theta)
    r = np.einsum("nij,nj->ni", table.whiten, zeta).ravel()
    J = data_jacobian(model, table, theta, (g0, G))
    p = len(theta)
    return FitResult(model, theta, np.full((p, p), np.nan), float(r @ r), r.size, float("nan"), 0, float("nan"),
                     zeta, J, r, np.ones(p, bool), table.rows)


def objective(model: AugmentedModel, table: ResidualTable, theta: np.ndarray) -> float:
    """The cost :func:`fit_model` minimises, at ``theta``: whitened linearised residuals plus priors.

    Parameters
    ----------
    model : AugmentedModel
    table : ResidualTable
        The rows the cost is taken over.
    theta : numpy.ndarray
        Full parameter vector (SI units).

    Returns
    -------
    float
        ``|W zeta_lin|^2 + sum (theta_j / sd_j)^2`` over the parameters with a prior.
    """
    r = np.einsum("nij,nj->ni", table.whiten, linearised_zeta(model, table, theta))
    prior = model.prior_sd
    has = np.isfinite(prior)
    return float(np.sum(r ** 2) + np.sum((np.asarray(theta)[has] / prior[has]) ** 2))


def _components(rows: np.ndarray) -> np.ndarray:
    """Indices of the 3 residual components of each data row in ``rows`` (rows are row-major)."""
    return (3 * np.asarray(rows)[:, None] + np.arange(3)).ravel()


def data_jacobian(model: AugmentedModel, table: ResidualTable, theta: np.ndarray,
                  at: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Gauss-Newton Jacobian ``W G^-1 dg/dx`` (3 n, p) in units of the parameters' scales.

    (The ``dG/dx G^-1 g`` term vanishes at a perfect fit.) Its Gram matrix is the
    Fisher information of the scaled parameters under whitened noise. ``at``: the balance ``g``
    and its pose tangent ``G`` at ``theta`` when the caller has them (from :func:`linearised_zeta`
    at the same ``theta``), else they are evaluated here.

    ``dg/dx`` is exact (forward mode, one evaluation) for the parameters
    :meth:`~.augmented.AugmentedModel.exact_params` names (the common offset, loads, rest lengths, tension
    laws, further moments, and hole positions and the link's twist where every pose and geometry hook
    carries its tangent); the rest (registration, a guide's exit point) by forward differences, one
    evaluation each.
    """
    scales = model.scales
    rows, R_meas = table.rows, table.R_meas
    theta = np.asarray(theta, float)
    x = theta / scales

    def g(R: np.ndarray, th: np.ndarray = theta) -> np.ndarray:
        return model.balance(R, rows, th)

    g0, G = (g(R_meas), None) if at is None else at
    WGinv = table.whiten @ _safe_inv(model.tangent(R_meas, rows, theta, g0, h=1e-6) if G is None else G)
    Jd = np.empty((g0.size, len(x)))
    exact = np.flatnonzero(model.exact_params(rows))
    if exact.size:
        dg = model.balance_derivative(R_meas, rows, theta, exact)[1] * scales[exact]
        Jd[:, exact] = (WGinv @ dg).reshape(g0.size, exact.size)
    for j in np.setdiff1d(np.arange(len(x)), exact):
        step = 1e-6 * max(1.0, abs(x[j]))
        th = theta.copy()
        th[j] += step * scales[j]
        Jd[:, j] = np.einsum("nij,nj->ni", WGinv, (g(R_meas, th) - g0) / step).ravel()
    return Jd


def linearised_zeta(model: AugmentedModel, table: ResidualTable, theta: np.ndarray) -> np.ndarray:
    """``G^-1 g`` (n, 3): the pose residual ``log(R_pred^T R_meas)`` to first order (rad).

    (``g(R_meas exp(d)) ~ g + G d = 0`` gives ``R_pred = R_meas exp(-G^-1 g)``.)
    """
    return _linearised(model, table, theta)[0]


def _linearised(model: AugmentedModel, table: ResidualTable,
                theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`linearised_zeta`, and the balance ``g`` (n, 3) and tangent ``G`` (n, 3, 3) it came from."""
    def g(R: np.ndarray) -> np.ndarray:
        return model.balance(R, table.rows, theta)

    g0 = g(table.R_meas)
    G = model.tangent(table.R_meas, table.rows, theta, g0, h=1e-6)
    zeta = np.einsum("nij,nj->ni", _safe_inv(G), g0)
    # a parameter trial that leaves a row without a tangent (all cables slack) costs 1 rad, not a crash
    return np.where(np.isfinite(zeta), np.clip(zeta, -1.0, 1.0), 1.0), g0, G


def _safe_inv(G: np.ndarray) -> np.ndarray:
    """Batched inverse; singular or non-finite rows get a pseudo-inverse (or zeros)."""
    G = np.where(np.isfinite(G), G, 0.0)
    try:
        return np.linalg.inv(G)
    except np.linalg.LinAlgError:
        return np.linalg.pinv(G)
