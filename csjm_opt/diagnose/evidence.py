"""Laplace approximation of a model's log marginal likelihood under its prior ranges.

Every parameter gets a proper Gaussian prior from its plausible range ``(lo, hi)``
(:meth:`~csjm_opt.diagnose.effects.base.Effect.ranges`): mean the nominal value
(0, clipped into the range), standard deviation a quarter of the range (the range is
+-2 sd); a parameter without a finite range gets ten times its typical scale. Around
the fit, the whitened residual is linear in the parameters, ``r(x) = r0 + J (x - x0)``
(the fit's own Jacobian), and with noise variance ``sigma^2`` (the same for every
model of a diagnosis) the evidence of the linear-Gaussian model is exact::

    -2 log Z = min_x [ |r(x)|^2 / sigma^2 + |S^-1 (x - m)|^2 ] + log det(I + S J^T J S / sigma^2) + const

The second term is the Occam factor: a parameter the log determines well
(posterior much narrower than its prior) costs about ``log(prior sd / posterior sd)``,
one it cannot determine costs nothing, so a 36-parameter effect pays only for the
subspace the log identifies, and a 3-parameter effect that explains the same
residual is preferred. This is the criterion that prices flexibility in the rule
(:mod:`csjm_opt.diagnose.selection`), next to the held-out checks.
"""

from __future__ import annotations

import numpy as np

from .augmented import N_NUISANCE
from .fit import FitResult

#: Prior sd of a parameter without a finite range, in units of its scale.
UNBOUNDED_SD_SCALES = 10.0
#: Prior sd of the nuisance (common pretension offset), m: drives zeroed to a fraction of a mm.
NUISANCE_SD_M = 1e-3


def prior_of(fit: FitResult) -> tuple[np.ndarray, np.ndarray]:
    """``(mean, sd)`` of the Gaussian prior of every parameter of ``fit.model`` (SI units).

    Parameters
    ----------
    fit : FitResult

    Returns
    -------
    tuple of numpy.ndarray
    """
    model = fit.model
    mean = [np.zeros(N_NUISANCE)]
    sd = [np.full(N_NUISANCE, NUISANCE_SD_M)]
    for e in model.effects:
        rng = e.ranges()
        for name, scale in zip(e.param_names, e.scales):
            lo, hi = rng.get(name, (-np.inf, np.inf))
            if np.isfinite(lo) and np.isfinite(hi):
                mean.append(np.array([min(max(0.0, lo), hi)]))
                sd.append(np.array([(hi - lo) / 4.0]))
            else:
                mean.append(np.zeros(1))
                sd.append(np.array([UNBOUNDED_SD_SCALES * scale]))
    return np.concatenate(mean), np.concatenate(sd)


def log_evidence(fit: FitResult, noise_scale: float) -> float:
    """Laplace log marginal likelihood of ``fit``'s model (up to a constant shared by all models).

    Parameters
    ----------
    fit : FitResult
        A fitted model (carries its whitened Jacobian in scaled parameters).
    noise_scale : float
        Noise standard deviation in whitened units (the same for the models compared).

    Returns
    -------
    float
    """
    if fit.jac_x is None or fit.res_x is None:
        return float("nan")
    scales = fit.model.scales
    n = fit.n_obs
    J = fit.jac_x[:n]                          # d r / d x, x = theta / scales
    r0 = fit.res_x[:n]
    x0 = fit.theta / scales
    m, sd = prior_of(fit)
    m, sd = m / scales, sd / scales
    s2 = float(noise_scale) ** 2
    # MAP of the linearised problem: (J^T J / s2 + S^-2) dx = -(J^T r0 / s2 + S^-2 (x0 - m))
    P = np.diag(1.0 / sd ** 2)
    A = J.T @ J / s2 + P
    b = J.T @ r0 / s2 + P @ (x0 - m)
    dx = -np.linalg.solve(A, b)
    r = r0 + J @ dx
    x = x0 + dx
    quad = float(r @ r / s2 + np.sum(((x - m) / sd) ** 2))
    M = np.eye(len(x)) + (sd[:, None] * (J.T @ J) * sd[None, :]) / s2
    sign, logdet = np.linalg.slogdet(M)
    return float(-0.5 * quad - 0.5 * logdet)
