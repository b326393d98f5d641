"""Frame changes of the preprocessing: point-set fit, wrench to {A}, weight moment in {A}.

Rigid fit of point sets (erratum 6), wrench moved to {A} (55), weight moment
in {A} (56).
"""

from __future__ import annotations

import numpy as np

from .._validate import as_array
from ..errors import IllConditionedData, InvalidInput
from ..model.cable_terms import weight_moment
from ..model.rig import Rig


def fit_rigid_transform(P_src: np.ndarray, P_dst: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Least-squares rigid transform between two point sets (Kabsch/Umeyama, no scale).

    Replaces the 4 x 4 inverse of the paper's (52), exact only for noise-free points (erratum 6).

    Parameters
    ----------
    P_src : array_like, shape (n, 3)
        Points in the source frame (n >= 3, not collinear).
    P_dst : array_like, shape (n, 3)
        The same points measured in the destination frame.

    Returns
    -------
    R : ndarray, shape (3, 3)
        Rotation with ``P_dst ~ P_src R^T + p``.
    p : ndarray, shape (3,)
        Translation.
    rms_m : float
        RMS residual of the fit.

    Raises
    ------
    InvalidInput
        If the shapes differ or a value is not finite.
    IllConditionedData
        If there are fewer than 3 points or they are collinear.
    """
    P_src, P_dst = as_array(P_src, (None, 3), "P_src"), as_array(P_dst, (None, 3), "P_dst")
    if P_src.shape != P_dst.shape:
        raise InvalidInput(f"P_src {P_src.shape} and P_dst {P_dst.shape}: expected the same points", "P_dst")
    if len(P_src) < 3:
        raise IllConditionedData(f"a rigid fit needs at least 3 points, got {len(P_src)}", float("inf"), len(P_src))
    a, b = P_src.mean(axis=0), P_dst.mean(axis=0)
    A, B = P_src - a, P_dst - b
    s = np.linalg.svd(A, compute_uv=False)
    if s[1] <= 1e-9 * max(s[0], 1e-300):
        raise IllConditionedData("points for the rigid fit are collinear", float("inf"), 1)
    U, _, Vt = np.linalg.svd(B.T @ A)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    R = U @ D @ Vt
    p = b - R @ a
    rms = float(np.sqrt(np.mean(np.sum((P_src @ R.T + p - P_dst) ** 2, axis=1))))
    return R, p, rms


def wrench_to_A(f_S_N: np.ndarray, tau_S_Nm: np.ndarray, R_AS: np.ndarray,
                p_AS_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Force and moment about O in {A} from an F/T reading in {S}, (55); batched over rows.

    Parameters
    ----------
    f_S_N : ndarray, shape (3,) or (n, 3)
        Force measured by the sensor, in {S} (N).
    tau_S_Nm : ndarray, shape (3,) or (n, 3)
        Moment measured by the sensor about its origin, in {S} (N m).
    R_AS : ndarray, shape (3, 3)
        Orientation of {S} in {A}.
    p_AS_m : ndarray, shape (3,)
        Origin of {S} in {A} (m), relative to O.

    Returns
    -------
    f_A_N : ndarray, shape like ``f_S_N``
        The force in {A} (N).
    tau_A_Nm : ndarray, shape like ``tau_S_Nm``
        The moment about O in {A} (N m).
    """
    f_A = np.asarray(f_S_N) @ R_AS.T
    tau_A = np.asarray(tau_S_Nm) @ R_AS.T + np.cross(p_AS_m, f_A)
    return f_A, tau_A


def weight_moment_A(rig: Rig, R_BA: np.ndarray) -> np.ndarray:
    """Moment of the platform's weight about O, in {A} (N m): (56) with coincident origins; batched.

    ``r_G x (R^T m g)``; the physics is :func:`csjm_opt.model.cable_terms.weight_moment`
    (the numpy reference).

    Parameters
    ----------
    rig : Rig
        Supplies the platform mass, centre of mass in {A} and gravity in {B}.
    R_BA : ndarray, shape (3, 3) or (n, 3, 3)
        Orientation(s) of {A} in {B}.

    Returns
    -------
    ndarray, shape (3,) or (n, 3)
        Weight moment about O in {A} (N m).
    """
    return weight_moment(R_BA, rig.platform_mass_kg * np.asarray(rig.com_A_m), rig.gravity_B_m_per_s2)
