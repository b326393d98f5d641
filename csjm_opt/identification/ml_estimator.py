"""K_ml: maximum likelihood of the symmetric stiffness, both noises, curvature from the rig model.

The model and the information are those of :mod:`csjm_opt.identification.cramer_rao`. With the true
displacements profiled out, the likelihood of ``theta = (tau0, s)`` is (to first order in the
tracker noise, which is 3e-4 rad against 0.07 rad displacements) the effective-variance
generalised least squares::

    min_theta  sum_i r_i^T V_i(theta)^-1 r_i,    r_i = tau_load_i - c(z_i) - A(z_i) theta

solved by iterating the weights ``V_i`` (three passes reach round-off). With the weights fixed,
the noise in the measured displacements also dilutes the slope (by ``s^2 / var(zeta)``, up to
0.3 % for stiff rigs with small turns: small against one log's noise but a clear bias over
hundreds of logs); its expectation is subtracted from the normal equations (corrected least
squares, with the stated tracker noise, or an assumed one when the noise is estimated), which
makes the estimate consistent.

Noise: stated (an :class:`~csjm_opt.measurement.instruments.InstrumentNoise`) or, when not
given, estimated from the data as one constant 3x3 row covariance (the residual covariance,
``3 n - 9`` degrees of freedom; intervals then use Student t).

Three covariances are returned for the six entries:

* ``crlb``: the inverse information at the estimate with the stated (or estimated) noise, the
  Cramér-Rao bound of the design; it is also the covariance the intervals use;
* ``cov``: the estimate's own covariance, the sandwich ``I^-1 (sum A^T V^-1 r r^T V^-1 A) I^-1``
  from its residuals (robust to a wrong noise statement);
* ``efficiency = trace(crlb) / trace(cov)``: about 1 when the noise model and the curvature hold.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..measurement.instruments import InstrumentNoise
from .cramer_rao import bound, design_rows, information, row_covariances, slopes, sym_matrix

#: Weight iterations of the effective-variance fit.
ML_ITERATIONS = 4


@dataclasses.dataclass(frozen=True, eq=False)
class MLFit:
    """The maximum-likelihood fit of one cycle."""

    K: np.ndarray            # (3, 3) symmetric, N m/rad
    tau0_A_Nm: np.ndarray    # (3,) load moment at the reference
    crlb6: np.ndarray        # (6, 6) bound (inverse information) of the six entries
    cov6: np.ndarray         # (6, 6) sandwich covariance of the estimate
    resid: np.ndarray        # (n, 3) residuals (N m)
    tau_cov: np.ndarray      # (3, 3) F/T covariance used (stated or, with angle noise 0, estimated)
    noise_estimated: bool
    dof: int                 # 3 n - 9
    chi2_per_dof: float      # against the row covariances used

    @property
    def efficiency(self) -> float:
        """``trace(crlb) / trace(cov)`` (1 when the estimate's scatter is the bound's)."""
        t = float(np.trace(self.cov6))
        return float(np.trace(self.crlb6) / t) if t > 0 else float("nan")


def fit_ml(zeta: np.ndarray, tau_load: np.ndarray, noise: InstrumentNoise | None = None,
           curv: np.ndarray | None = None, dcurv: np.ndarray | None = None,
           W: np.ndarray | None = None, iterations: int = ML_ITERATIONS,
           tracker_sigma_rad: float | None = None) -> MLFit:
    """Maximum-likelihood (effective-variance) fit of ``theta = (tau0, s)`` for one cycle.

    Parameters
    ----------
    zeta : array (n, 3)
        Measured displacements from the reference (rad, body frame).
    tau_load : array (n, 3)
        Measured total load moments in {A} (F/T plus the weight at the measured pose, N m).
    noise : InstrumentNoise, optional
        Stated instrument noise; estimated from the residuals when None.
    curv, dcurv : arrays (n, 3) and (n, 3, 3), optional
        Curvature of the relation and its slope (:func:`~csjm_opt.identification.curvature.model_curvature`);
        none (linear relation) when not given.
    W : array (n, 3, 3), optional
        Slope of the weight moment at each row.
    iterations : int
        Weight iterations.
    tracker_sigma_rad : float, optional
        With ``noise=None``: the tracker noise assumed for the dilution correction (the row
        covariance is still estimated from the residuals; the tracker noise alone cannot be told
        apart from the F/T noise there). None: no correction.

    Returns
    -------
    MLFit
    """
    zeta, tau_load = np.asarray(zeta, float), np.asarray(tau_load, float)
    n = len(zeta)
    y = tau_load - curv if curv is not None else tau_load
    A = design_rows(zeta)
    V = np.repeat(np.eye(3)[None], n, 0)
    estimated = noise is None
    G = (W if W is not None else 0.0) - (dcurv if dcurv is not None else 0.0)
    for it in range(iterations + 1):
        Vi = np.linalg.inv(V)
        info = np.einsum("nia,nij,njb->ab", A, Vi, A)
        rhs = np.einsum("nia,nij,nj->a", A, Vi, y)
        sigma = noise.angle_sigma_rad if noise is not None else (tracker_sigma_rad or 0.0)
        if sigma > 0:
            dN, dr = _dilution(Vi, G, sigma)
            info, rhs = info - dN, rhs - dr
        theta = _solve(info, rhs)
        tau0, K = theta[:3], sym_matrix(theta[3:])
        resid = y - np.einsum("nia,a->ni", A, theta)
        if it == iterations:
            break
        if estimated:
            tau_cov = resid.T @ resid / max(n - 3, 1)
            V = np.repeat(tau_cov[None], n, 0)
        else:
            assert noise is not None
            tau_cov = np.diag(np.asarray(noise.tau_sigma_Nm, float) ** 2)
            V = row_covariances(slopes(zeta, tau0, K, dcurv), W, tau_cov, noise.angle_sigma_rad)
    Vi = np.linalg.inv(V)
    info = information(zeta, V)
    inv = _inverse(info)
    g = np.einsum("nia,nij,nj->na", A, Vi, resid)
    dof = 3 * n - 9
    meat = g.T @ g * (3 * n / max(dof, 1))
    cov = inv @ meat @ inv
    chi2 = float(np.einsum("ni,nij,nj->", resid, Vi, resid) / max(dof, 1))
    return MLFit(K=K, tau0_A_Nm=tau0, crlb6=bound(info), cov6=0.5 * (cov[3:, 3:] + cov[3:, 3:].T), resid=resid,
                 tau_cov=tau_cov, noise_estimated=estimated, dof=dof, chi2_per_dof=chi2)


def _dilution(Vi: np.ndarray, G: np.ndarray | float, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Expected contribution of the tracker noise ``e`` to the normal equations (corrected least squares).

    ``A(z) = A(zeta) + sum_k e_k B_k`` and the residual carries ``G e`` (``G = W - dc``), so
    ``E[A^T V^-1 A]`` gains ``s^2 sum_k B_k^T V^-1 B_k`` and ``E[A^T V^-1 y]`` gains
    ``s^2 sum_k B_k^T V^-1 G u_k``; subtracting both removes the regression dilution.
    """
    B = design_rows(np.eye(3))
    B[:, :, :3] -= np.eye(3)[None]                          # B_k = dA/dz_k
    dN = sigma ** 2 * np.einsum("kia,nij,kjb->ab", B, Vi, B)
    Gn = np.broadcast_to(G, Vi.shape) if np.ndim(G) else np.zeros_like(Vi)
    dr = sigma ** 2 * np.einsum("kia,nij,njk->a", B, Vi, Gn)
    return dN, dr


def _solve(info: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    s = np.sqrt(np.maximum(np.diag(info), 1e-300))
    return np.linalg.lstsq(info / np.outer(s, s), rhs / s, rcond=None)[0] / s


def _inverse(info: np.ndarray) -> np.ndarray:
    s = np.sqrt(np.maximum(np.diag(info), 1e-300))
    return np.linalg.pinv(info / np.outer(s, s)) / np.outer(s, s)
