"""Laplace approximation of a model's log marginal likelihood under its prior ranges.

Every parameter gets a proper prior from its plausible range ``(lo, hi)``
(:meth:`~csjm_opt.diagnose.effects.base.Effect.ranges`), the range being the prior's
central 95 % (+-2 sd): a Gaussian with mean the nominal value (0, clipped into the range)
and standard deviation a quarter of the range; where the nominal value sits on a bound the
parameter cannot cross (a friction band, a compliance's diagonal: the optimiser's bound
equals the range's end), a **half-normal** on the allowed side from that bound, with the
whole range as its 2 sd (sd half the range). A parameter without a finite range gets a
Gaussian of ten times its typical scale. Around
the fit, the whitened residual is linear in the parameters, ``r(x) = r0 + J (x - x0)``
(the fit's own Jacobian), and with noise variance ``sigma^2`` (the same for every
model of a diagnosis) the evidence of the linear-Gaussian model is exact::

    -2 log Z = min_x [ |r(x)|^2 / sigma^2 + |S^-1 (x - m)|^2 ] + log det(I + S J^T J S / sigma^2) + const

(exact for the linearised model; the linearisation, though, holds only near the fit: a parameter
whose step to the linearised posterior mode would exceed ``TRUST_PRIOR_SDS`` prior sds is held at its
fitted value and pays its prior density there. A friction fit that followed a flat direction to a
stick-travel factor of 1,300 (prior range 0-2: the friction term then acts as a per-cable stiffness,
a stand-in for hole offsets) was otherwise credited as if the factor could return to 0 at no cost.)
The second term is the Occam factor: a parameter the log determines well
(posterior much narrower than its prior) costs about ``log(prior sd / posterior sd)``,
one it cannot determine costs nothing, so a 36-parameter effect pays only for the
subspace the log identifies, and a 3-parameter effect that explains the same
residual is preferred.

A half-normal prior is the Gaussian one truncated at its mean and doubled, so its evidence is
the Gaussian evidence times ``2 P(x_i on the allowed side)`` under the Gaussian posterior; the
probability is taken from each bounded parameter's posterior marginal (their correlations
ignored). Against a full Gaussian of the same sd, a parameter the log puts well inside the
range gains ``log 2`` and one whose posterior straddles the bound less: a full Gaussian
spends half its mass on impossible values. This is the criterion that prices flexibility in the rule
(:mod:`csjm_opt.diagnose.selection.decision`), next to the held-out checks.
"""

from __future__ import annotations

import numpy as np
from scipy.special import log_ndtr

from ..data.residuals import ResidualTable
from .augmented import N_NUISANCE, AugmentedModel
from .gauss_newton import FitResult, linearisation

#: Prior sd of a parameter without a finite range, in units of its scale.
UNBOUNDED_SD_SCALES = 10.0
#: Largest step (in prior sds) of a parameter from its fitted value to the linearised posterior mode that the
#: evidence trusts; beyond it the parameter is held at its fitted value (the linearisation is local).
TRUST_PRIOR_SDS = 2.0
#: Prior sd of the nuisance (common pretension offset), m: drives zeroed to a fraction of a mm.
NUISANCE_SD_M = 1e-3


def prior_of(fit: FitResult) -> tuple[np.ndarray, np.ndarray]:
    """``(mean, sd)`` of the prior of every parameter of ``fit.model`` (SI units).

    Parameters
    ----------
    fit : FitResult

    Returns
    -------
    tuple of numpy.ndarray
        For a half-normal parameter (:func:`prior_sides`) the mean is its bound and the sd
        that of the half-normal.
    """
    return _prior(fit)[:2]


def prior_sides(fit: FitResult) -> np.ndarray:
    """Side of each parameter's half-normal prior: ``+1`` (above its bound), ``-1`` (below), 0 (Gaussian).

    A prior is half-normal when the nominal value (0 clipped into the plausible range) is an end of
    the range that the optimiser's bound forbids crossing (a friction band or a compliance's
    diagonal cannot be negative).

    Parameters
    ----------
    fit : FitResult

    Returns
    -------
    numpy.ndarray
    """
    return _prior(fit)[2]


def _prior(fit: FitResult) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    model = fit.model
    mean = [np.zeros(N_NUISANCE)]
    sd = [np.full(N_NUISANCE, NUISANCE_SD_M)]
    side = [np.zeros(N_NUISANCE)]
    for e in model.effects:
        rng = e.ranges()
        for name, scale, lb, ub in zip(e.param_names, e.scales, e.lower_bounds, e.upper_bounds):
            lo, hi = rng.get(name, (-np.inf, np.inf))
            if np.isfinite(lo) and np.isfinite(hi):
                mu = min(max(0.0, lo), hi)
                half = 1.0 if (mu == lo and lb == lo) else -1.0 if (mu == hi and ub == hi) else 0.0
                mean.append(np.array([mu]))
                sd.append(np.array([(hi - lo) / (2.0 if half else 4.0)]))
                side.append(np.array([half]))
            else:
                mean.append(np.zeros(1))
                sd.append(np.array([UNBOUNDED_SD_SCALES * scale]))
                side.append(np.zeros(1))
    return np.concatenate(mean), np.concatenate(sd), np.concatenate(side)


def log_evidence(fit: FitResult, noise_scale: float, at_fit: bool = False, trust: bool = True) -> float:
    """Laplace log marginal likelihood of ``fit``'s model (up to a constant shared by all models).

    Parameters
    ----------
    fit : FitResult
        A fitted model (carries its whitened Jacobian in scaled parameters).
    noise_scale : float
        Noise standard deviation in whitened units (the same for the models compared).
    at_fit : bool, optional
        Centre the approximation at the fitted parameters instead of the linearised posterior
        mode: the misfit the fit reached and the prior density there, with the same Occam factor.
        Never above the default (the linearised mode minimises the quadratic); the two agree
        when the fit is at that mode. Where they differ, the difference is misfit that only the
        linearisation promises (a Jacobian that is not the model's exact one, or a fit that stopped
        short): a comparison that must hold for the model as fitted uses this.
    trust : bool, optional
        Hold a parameter whose step would exceed ``TRUST_PRIOR_SDS`` prior sds at its value (default). False:
        the linearised model's evidence wherever its mode lies (a prediction from a point that is not a fit,
        :func:`predicted_evidence`, must not be held at its start).

    Returns
    -------
    float
    """
    if fit.evidence_fn is not None:
        return float(fit.evidence_fn(noise_scale))
    if fit.jac_x is None or fit.res_x is None:
        return float("nan")
    scales = fit.model.scales
    n = fit.n_obs
    J = fit.jac_x[:n]                          # d r / d x, x = theta / scales
    r0 = fit.res_x[:n]
    x0 = fit.theta / scales
    m, sd, side = _prior(fit)
    m, sd = m / scales, sd / scales
    s2 = float(noise_scale) ** 2
    # MAP of the linearised problem: (J^T J / s2 + S^-2) dx = -(J^T r0 / s2 + S^-2 (x0 - m))
    P = np.diag(1.0 / sd ** 2)
    A = J.T @ J / s2 + P
    b = J.T @ r0 / s2 + P @ (x0 - m)
    dx = np.zeros_like(x0) if at_fit else -np.linalg.solve(A, b)
    # the linearisation holds near the fit only: a parameter whose step would travel more than
    # TRUST_PRIOR_SDS prior sds (a flat direction the fit followed far out, where the prior says the
    # value is implausible) keeps its fitted value, and its prior density there is paid
    far = np.abs(dx) > TRUST_PRIOR_SDS * sd
    if trust and far.any():
        near = ~far
        dx = np.zeros_like(dx)
        if near.any():
            dx[near] = -np.linalg.solve(A[np.ix_(near, near)], b[near])
    r = r0 + J @ dx
    x = x0 + dx
    quad = float(r @ r / s2 + np.sum(((x - m) / sd) ** 2))
    if fit.residuals is not None and not at_fit and dx.any():
        # what the step promises, checked against the model: the Gauss-Newton Jacobian leaves out how a model
        # changes its own tangent, and along a direction the fit barely sees (stiffness scale against sensor
        # gain: the weight's share) it can promise a misfit the model never reaches (a pair 125 nats above its
        # single with the same residuals). Never more than the step promises; where the model's own cost falls
        # short of it, the approximation is centred where that cost is lower, the step's end or the fit
        lo, hi = fit.model.lower_bounds / scales, fit.model.upper_bounds / scales
        x_step = np.clip(x, lo, hi)
        r_step = fit.residuals(x_step * scales)
        centres = [(float(r0 @ r0 / s2 + np.sum(((x0 - m) / sd) ** 2)), x0),
                   (float(r_step @ r_step / s2 + np.sum(((x_step - m) / sd) ** 2)), x_step)]
        finite = [c for c in centres if np.isfinite(c[0])]
        if finite:                                  # (a fit without a finite cost keeps the step's value)
            q, xc = min(finite, key=lambda c: c[0])
            if q > quad:
                quad, x = q, xc
    M = np.eye(len(x)) + (sd[:, None] * (J.T @ J) * sd[None, :]) / s2
    sign, logdet = np.linalg.slogdet(M)
    # half-normal priors: the Gaussian evidence times 2 P(allowed side) under the posterior marginals
    h = np.flatnonzero(side)
    trunc = 0.0
    if h.size:
        post_sd = np.sqrt(np.maximum(np.diag(np.linalg.inv(A))[h], 1e-300))
        trunc = float(np.sum(np.log(2.0) + log_ndtr(side[h] * (x[h] - m[h]) / post_sd)))
    return float(-0.5 * quad - 0.5 * logdet + trunc)


def predicted_evidence(model: AugmentedModel, table: ResidualTable, theta: np.ndarray, noise_scale: float) -> float:
    """Log evidence of ``model`` predicted from ``theta``, a point that is not its fit (a score test).

    The model is linearised at ``theta`` and its linearised evidence taken (:func:`log_evidence`, every
    parameter free to travel to the linearised mode): what a fit from ``theta`` reaches where the model is
    linear near it. From a single effect's fit with a second effect at its nominal value, this is Rao's score
    (Lagrange multiplier) test of adding the second effect, priced by its Occam factor.

    Parameters
    ----------
    model : AugmentedModel
    table : ResidualTable
        The rows (training rows).
    theta : numpy.ndarray
        Full parameter vector (nuisance first), SI units.
    noise_scale : float
        Noise standard deviation in whitened units.

    Returns
    -------
    float
    """
    return log_evidence(linearisation(model, table, theta), noise_scale, trust=False)


def effective_parameters(fit: FitResult, noise_scale: float) -> float:
    """Number of parameters the log determines under the priors, ``sum lambda / (1 + lambda)``.

    ``lambda`` are the eigenvalues of ``S J^T J S / s^2`` (prior sds ``S``, whitened Jacobian ``J``):
    a direction the log pins down counts one, one it cannot see counts nothing. Over the noise, the
    expected log evidence of a model is its log evidence on the noise-free data minus
    ``(n - effective_parameters) / 2`` (the noise a model cannot follow), so this is what the study's
    identifiability oracle adds to a noise-free evidence.

    Parameters
    ----------
    fit : FitResult
    noise_scale : float

    Returns
    -------
    float
    """
    if fit.jac_x is None:
        return float("nan")
    J = fit.jac_x[:fit.n_obs]
    _, sd = prior_of(fit)
    sd = sd / fit.model.scales
    lam = np.linalg.eigvalsh((sd[:, None] * (J.T @ J) * sd[None, :]) / float(noise_scale) ** 2)
    lam = np.maximum(lam, 0.0)
    return float(np.sum(lam / (1.0 + lam)))
