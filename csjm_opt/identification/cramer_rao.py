"""The Cramér-Rao bound of K's six independent entries, errors in variables.

Measurement model of one cycle (row ``i``, reference pose ``R_ref`` fixed, ``zeta_i`` the true
body-frame displacement ``log(R_ref^T R_i)``)::

    tau_load_i = (I - 1/2 hat(zeta_i)) tau0 + S zeta_i + c(zeta_i) + e_tau_i      e_tau ~ N(0, Sigma_tau)
    z_i        = zeta_i + e_zeta_i                                               e_zeta ~ N(0, s^2 I)

with ``theta = (tau0, s)`` (load at the reference, the six entries of the symmetric ``K = S``,
order :data:`SYM_INDEX`) and ``c`` the curvature of the moment-rotation relation (known,
:mod:`csjm_opt.identification.curvature`). The true displacements are nuisance parameters.
Eliminating them (Schur complement of the joint information, Woodbury) leaves the exact
information of ``theta``::

    I(theta) = sum_i A_i^T V_i^-1 A_i,     V_i = Sigma_tau + s^2 (F_i - W_i)(F_i - W_i)^T

``A_i = d(mean)/d(theta)``, ``F_i = S + 1/2 hat(tau0) + dc/dzeta`` the slope of the relation and
``W_i`` the slope of the weight moment (added to the F/T reading at the measured pose, so its
noise enters with the tracker's). The bound of the six entries is the ``s`` block of
``I^-1``. Everything is per row, so the same code gives the bound of a measured log (at the
estimate) and of a planned experiment (at the predicted displacements).
"""

from __future__ import annotations

import numpy as np

from .. import so3

#: Order of K's six independent entries: K11, K22, K33, K12, K13, K23.
SYM_INDEX = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
#: Names of the six entries, in :data:`SYM_INDEX` order.
SYM_NAMES = ("K11", "K22", "K33", "K12", "K13", "K23")

_E = np.zeros((6, 3, 3))
for _m, (_i, _j) in enumerate(SYM_INDEX):
    _E[_m, _i, _j] = _E[_m, _j, _i] = 1.0


def sym_matrix(s: np.ndarray) -> np.ndarray:
    """The symmetric (3, 3) matrix of six entries in :data:`SYM_INDEX` order.

    Parameters
    ----------
    s : array (6,)
        K11, K22, K33, K12, K13, K23.

    Returns
    -------
    ndarray (3, 3)
    """
    return np.einsum("m,mij->ij", np.asarray(s, float), _E)


def sym_entries(K: np.ndarray) -> np.ndarray:
    """The six entries (:data:`SYM_INDEX` order) of the symmetric part of ``K``.

    Parameters
    ----------
    K : array (3, 3)

    Returns
    -------
    ndarray (6,)
    """
    Ks = 0.5 * (np.asarray(K, float) + np.asarray(K, float).T)
    return np.array([Ks[i, j] for i, j in SYM_INDEX])


def sym_to_full(cov6: np.ndarray) -> np.ndarray:
    """(9, 9) covariance of ``K.ravel()`` from the (6, 6) covariance of the six entries.

    Parameters
    ----------
    cov6 : array (6, 6)

    Returns
    -------
    ndarray (9, 9)
    """
    M = _E.reshape(6, 9).T
    return M @ cov6 @ M.T


def design_rows(zeta: np.ndarray) -> np.ndarray:
    """``A_i`` (n, 3, 9): derivative of the mean load moment by ``theta = (tau0, s)``.

    Parameters
    ----------
    zeta : array (n, 3)
        Displacements from the reference (rad, body frame).

    Returns
    -------
    ndarray (n, 3, 9)
    """
    zeta = np.asarray(zeta, float)
    A0 = np.eye(3)[None] - 0.5 * so3.hat(zeta)
    As = np.einsum("mij,nj->nim", _E, zeta)
    return np.concatenate([A0, As], axis=2)


def slopes(zeta: np.ndarray, tau0: np.ndarray, K: np.ndarray, dcurv: np.ndarray | None) -> np.ndarray:
    """``F_i`` (n, 3, 3): slope of the load moment in the displacement at each row.

    Parameters
    ----------
    zeta : array (n, 3)
    tau0 : array (3,)
        Load moment at the reference (N m, {A}).
    K : array (3, 3)
        Symmetric stiffness (N m/rad).
    dcurv : array (n, 3, 3) or None
        Slope of the curvature term (zero when None).

    Returns
    -------
    ndarray (n, 3, 3)
    """
    F = np.broadcast_to(np.asarray(K, float) + 0.5 * so3.hat(np.asarray(tau0, float)), (len(zeta), 3, 3))
    return F + dcurv if dcurv is not None else np.array(F)


def row_covariances(F: np.ndarray, W: np.ndarray | None, tau_cov: np.ndarray, angle_sigma_rad: float) -> np.ndarray:
    """Effective covariance ``V_i`` (n, 3, 3) of each row's moment residual.

    Parameters
    ----------
    F : array (n, 3, 3)
        Slopes of the relation (:func:`slopes`).
    W : array (n, 3, 3) or None
        Slopes of the weight moment in the displacement (added at the measured pose).
    tau_cov : array (3, 3)
        Covariance of the F/T moment (N^2 m^2).
    angle_sigma_rad : float
        Tracker orientation noise per axis (rad).

    Returns
    -------
    ndarray (n, 3, 3)
    """
    G = F - W if W is not None else F
    return np.asarray(tau_cov, float)[None] + angle_sigma_rad ** 2 * G @ np.swapaxes(G, 1, 2)


def information(zeta: np.ndarray, V: np.ndarray) -> np.ndarray:
    """Fisher information (9, 9) of ``theta = (tau0, s)``: ``sum A_i^T V_i^-1 A_i``.

    Parameters
    ----------
    zeta : array (n, 3)
    V : array (n, 3, 3)
        Row covariances (:func:`row_covariances`).

    Returns
    -------
    ndarray (9, 9)
    """
    A = design_rows(zeta)
    return np.einsum("nia,nij,njb->ab", A, np.linalg.inv(V), A)


def bound(info: np.ndarray) -> np.ndarray:
    """(6, 6) Cramér-Rao bound of the six entries of K from the (9, 9) information.

    Parameters
    ----------
    info : array (9, 9)

    Returns
    -------
    ndarray (6, 6)
        ``inf`` on the diagonal when the information is singular.
    """
    scale = np.sqrt(np.maximum(np.diag(info), 1e-300))
    try:
        inv = np.linalg.inv(info / np.outer(scale, scale)) / np.outer(scale, scale)
    except np.linalg.LinAlgError:
        return np.diag(np.full(6, np.inf))
    return 0.5 * (inv[3:, 3:] + inv[3:, 3:].T)


def crlb(zeta: np.ndarray, tau0: np.ndarray, K: np.ndarray, tau_cov: np.ndarray, angle_sigma_rad: float,
         dcurv: np.ndarray | None = None, W: np.ndarray | None = None) -> np.ndarray:
    """Cramér-Rao bound (6, 6) of K's six entries for one cycle's displacements.

    Parameters
    ----------
    zeta : array (n, 3)
        Displacements from the reference (rad), row 0 the reference itself (zeros).
    tau0 : array (3,)
        Load moment at the reference (N m, {A}).
    K : array (3, 3)
        Stiffness at the reference (symmetric, N m/rad).
    tau_cov : array (3, 3)
        F/T moment covariance (N^2 m^2).
    angle_sigma_rad : float
        Tracker orientation noise (rad per axis).
    dcurv : array (n, 3, 3), optional
        Slope of the curvature term at each row.
    W : array (n, 3, 3), optional
        Slope of the weight moment at each row.

    Returns
    -------
    ndarray (6, 6)
        Covariance bound, order :data:`SYM_NAMES` ((N m/rad)^2).
    """
    F = slopes(zeta, tau0, K, dcurv)
    return bound(information(zeta, row_covariances(F, W, tau_cov, angle_sigma_rad)))
