"""Verification of an identified stiffness (Section IV-C): predicted pose under a load increment.

(61)-(62): ``dzeta_est = K^-1 dtau``, ``R_est = R0 exp(hat(dzeta_est))``;
(63)-(65): ``E_theta = ||log(R_act^T R_est)||``.

Which matrix? ``K_D = dtau_load/dzeta`` is, by its definition (48a), the
first-order map from a displacement to the change of the load's {A}
components, so ``dtau = K_D dzeta`` to first order and ``K_D^-1`` is the right
predictor for a measured increment of the moment's components. ``K = K_D -
1/2 hat(tau_load)`` is the covariant (energy-Hessian) stiffness; it differs
from ``K_D`` by the connection term and using it in (61), as the paper's text
says, is off by ``1/2 hat(tau_load)``. The paper's Table 4 column C was in
fact computed with ``K_D`` (erratum 4). Both are offered (``use="K_D"``, the
default, or ``use="K"``).

The load increment is either given as a total-load increment (the paper's
Column A) or, with a model, as an external increment: the weight moment's
change at the (unknown) new pose is then found by a fixed-point iteration.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Sequence

import numpy as np

from .. import so3
from .._validate import as_array, as_rotation, as_rotations
from ..errors import InvalidInput
from ..measurement.logfile import MeasurementLog
from ..model.numeric import Model
from .estimate import StiffnessEstimate


def predict_pose(R0: np.ndarray, K: np.ndarray, dtau_A_Nm: np.ndarray) -> np.ndarray:
    """Pose after a load increment, (61)-(62): ``R0 exp(hat(K^-1 dtau))``.

    Parameters
    ----------
    R0 : ndarray, shape (3, 3)
        Reference orientation of {A} in {B}.
    K : ndarray, shape (3, 3)
        Stiffness (N m/rad) used as predictor; ``K_D`` predicts a measured increment of
        the moment's {A} components to first order (erratum 4 in docs/conventions.md).
    dtau_A_Nm : array_like, shape (3,) or (n, 3)
        Load increment(s) in {A} (N m).

    Returns
    -------
    ndarray, shape (3, 3) or (n, 3, 3)
        Predicted orientation(s) of {A} in {B}.

    Raises
    ------
    NotARotation
        If ``R0`` is not a rotation.
    InvalidInput
        If the shapes are wrong, a value is not finite, or ``K`` is singular.
    """
    R0 = as_rotation(R0, "R0")
    K = as_array(K, (3, 3), "K")
    dtau = _increments(dtau_A_Nm, "dtau_A_Nm")
    return R0 @ so3.exp(_solve(K, dtau.T, "K").T)


def _increments(value: Any, name: str) -> np.ndarray:
    """(3,) or (n, 3) finite floats, else :class:`InvalidInput`."""
    arr = np.asarray(value, dtype=float) if not isinstance(value, str) else np.empty(0)
    if arr.ndim not in (1, 2) or arr.shape[-1] != 3 or not np.all(np.isfinite(arr)):
        raise InvalidInput(f"{name}: expected finite (3,) or (n, 3), got shape {arr.shape}", name)
    return arr


def _solve(K: np.ndarray, b: np.ndarray, name: str) -> np.ndarray:
    """``K^-1 b``, with a singular ``K`` reported as :class:`InvalidInput`."""
    try:
        return np.linalg.solve(K, b)
    except np.linalg.LinAlgError:
        raise InvalidInput(f"{name} is singular: no pose follows from it", name) from None


def predict_pose_external(R0: np.ndarray, K_D: np.ndarray, tau_load_ref_A_Nm: np.ndarray,
                          tau_ext_A_Nm: np.ndarray, model: Model, iterations: int = 50,
                          tol_rad: float = 1e-13) -> np.ndarray:
    """Pose under a new external moment, the weight moment re-evaluated at the predicted pose.

    Solves ``tau_ext + tau_weight(R0 exp(dzeta)) - tau_load_ref = K_D dzeta`` by fixed point.

    Parameters
    ----------
    R0 : ndarray, shape (3, 3)
        Reference orientation of {A} in {B}.
    K_D : ndarray, shape (3, 3)
        ``dtau_load/dzeta`` at the reference (N m/rad).
    tau_load_ref_A_Nm : array_like, shape (3,)
        Total load at the reference, in {A} (N m).
    tau_ext_A_Nm : array_like, shape (3,) or (n, 3)
        New external moment(s) in {A} (N m), platform weight excluded.
    model : Model
        Numeric model of the rig (for the weight moment).
    iterations : int, optional
        Largest number of fixed-point iterations.
    tol_rad : float, optional
        Stop when ``dzeta`` changes by less than this (rad).

    Returns
    -------
    ndarray, shape (3, 3) or (n, 3, 3)
        Predicted orientation(s) of {A} in {B}, one per row of ``tau_ext_A_Nm``.

    Raises
    ------
    NotARotation
        If ``R0`` is not a rotation.
    InvalidInput
        If the shapes are wrong, a value is not finite, or ``K_D`` is singular.
    """
    R0 = as_rotation(R0, "R0")
    K_D = as_array(K_D, (3, 3), "K_D")
    tau_ref = as_array(tau_load_ref_A_Nm, (3,), "tau_load_ref_A_Nm")
    tau_ext = np.atleast_2d(_increments(tau_ext_A_Nm, "tau_ext_A_Nm"))
    dzeta = np.zeros_like(tau_ext)
    for _ in range(iterations):
        R = R0 @ so3.exp(dzeta)
        new = _solve(K_D, (tau_ext + model.weight_moment(R) - tau_ref).T, "K_D").T
        done = np.max(np.abs(new - dzeta)) < tol_rad
        dzeta = new
        if done:
            break
    out = R0 @ so3.exp(dzeta)
    return out if np.ndim(tau_ext_A_Nm) == 2 else out[0]


def estimation_error(R_act: np.ndarray, R_est: np.ndarray) -> np.ndarray:
    """Estimation error (63)-(65): ``E_theta = ||log(R_act^-1 R_est)||`` (rad), batched.

    Parameters
    ----------
    R_act, R_est : array_like, shape (..., 3, 3)
        Actual and estimated orientations.

    Returns
    -------
    ndarray, shape (...)
        Angles in ``[0, pi]`` (rad).

    Raises
    ------
    InvalidInput
        If the shapes are wrong or do not broadcast.
    """
    return so3.angle_between(R_act, R_est)


@dataclasses.dataclass(frozen=True, eq=False)
class Verification:
    """Predicted against measured poses over a set of load increments."""

    use: str                      # "K_D" or "K"
    dtau_A_Nm: np.ndarray         # (n, 3) load increments (total load)
    R_act: np.ndarray             # (n, 3, 3)
    R_est: np.ndarray             # (n, 3, 3)
    labels: tuple[str, ...] = ()

    @property
    def E_theta_rad(self) -> np.ndarray:
        """(n,) estimation error ``E_theta`` (65) of each case (rad)."""
        return estimation_error(self.R_act, self.R_est)

    @property
    def rms_rad(self) -> float:
        """Root mean square of ``E_theta`` over the cases (rad; nan without cases)."""
        return float(np.sqrt(np.mean(self.E_theta_rad ** 2))) if len(self.R_act) else float("nan")

    @property
    def max_rad(self) -> float:
        """Largest ``E_theta`` over the cases (rad; nan without cases)."""
        return float(np.max(self.E_theta_rad)) if len(self.R_act) else float("nan")

    def table(self) -> str:
        """Plain-text table of the verification: case, load increment, ``E_theta``.

        Returns
        -------
        str
        """
        lines = [f"{'case':>10}  {'dtau_x':>8} {'dtau_y':>8} {'dtau_z':>8}  {'E_theta (rad)':>13}"]
        for i, (d, e) in enumerate(zip(self.dtau_A_Nm, self.E_theta_rad)):
            label = self.labels[i] if i < len(self.labels) else str(i + 1)
            lines.append(f"{label:>10}  {d[0]:8.3f} {d[1]:8.3f} {d[2]:8.3f}  {e:13.5f}")
        lines.append(f"{'rms':>10}  {'':26}  {self.rms_rad:13.5f}   (predicted with {self.use})")
        return "\n".join(lines)

    def as_dict(self) -> dict[str, Any]:
        """The verification as a JSON-able dict.

        Returns
        -------
        dict
            ``{"use", "rms_rad", "max_rad", "cases": [...]}``.
        """
        return {"use": self.use, "rms_rad": self.rms_rad, "max_rad": self.max_rad,
                "cases": [{"case": self.labels[i] if i < len(self.labels) else i + 1,
                           "dtau_A_Nm": self.dtau_A_Nm[i].tolist(), "R_est": self.R_est[i].tolist(),
                           "R_act": self.R_act[i].tolist(), "E_theta_rad": float(e)}
                          for i, e in enumerate(self.E_theta_rad)]}


def verify_increments(R0: np.ndarray, K: np.ndarray, dtau_A_Nm: np.ndarray, R_act: np.ndarray,
                      use: str = "K_D", labels: Sequence[str] = ()) -> Verification:
    """Table 4 of the paper: predict each pose from ``R0``, ``K`` and a load increment; compare.

    Parameters
    ----------
    R0 : ndarray, shape (3, 3)
        Reference orientation of {A} in {B}.
    K : ndarray, shape (3, 3)
        Stiffness used as predictor (N m/rad).
    dtau_A_Nm : array_like, shape (n, 3)
        Load increments in {A} (N m).
    R_act : array_like, shape (n, 3, 3)
        Actual (measured) orientations.
    use : str, optional
        Label of the predictor, reported in the result.
    labels : sequence of str, optional
        One label per case.

    Returns
    -------
    Verification
        Predicted poses and ``E_theta`` (rad) per case.

    Raises
    ------
    NotARotation
        If ``R0`` or a row of ``R_act`` is not a rotation.
    InvalidInput
        If the shapes disagree, a value is not finite, or ``K`` is singular.
    """
    dtau = as_array(dtau_A_Nm, (None, 3), "dtau")
    R_act = as_rotations(R_act, "R_act")
    return Verification(use, dtau, R_act, predict_pose(R0, K, dtau), tuple(labels))


def verify_log(estimates: Sequence[StiffnessEstimate], log: MeasurementLog, model: Model,
               use: str = "K_D", load: str = "total") -> Verification:
    """Predict the pose of every row of ``log`` from an identified stiffness, (61)-(65).

    Each row is predicted from the estimate of its cycle (same cycle id), else from the estimate
    whose reference pose is nearest.

    Parameters
    ----------
    estimates : sequence of StiffnessEstimate
        From :func:`~csjm_opt.identification.identify_log` (on training rows).
    log : MeasurementLog
        The rows to predict (held out from the identification).
    model : Model
        Numeric model of the rig (weight moment at the measured or predicted pose).
    use : {"K_D", "K"}, optional
        Which matrix predicts; ``K_D`` is right to first order (erratum 4).
    load : {"total", "external"}, optional
        ``"total"``: the increment of the total load at the actual pose (the paper's Column A);
        ``"external"``: only the external moment is known and the weight moment is re-evaluated at
        the predicted pose (needs ``use="K_D"``).

    Returns
    -------
    Verification
        Load increments, actual and predicted poses, ``E_theta`` per row, ``rms_rad``, ``max_rad``.

    Raises
    ------
    InvalidInput
        If ``use`` or ``load`` is unknown, there are no estimates, or a matrix is singular.
    """
    if use not in ("K_D", "K") or load not in ("total", "external"):
        raise InvalidInput(f"use must be K_D or K and load total or external, got {use!r}, {load!r}", "use")
    if not estimates:
        raise InvalidInput("no stiffness estimates to verify", "estimates")
    R = log.R
    refs = np.array([e.R_ref for e in estimates])
    nearest = np.argmin(so3.angle_between(refs[None], R[:, None]), axis=1)
    by_cycle = {e.cycle: j for j, e in enumerate(estimates) if e.cycle is not None}
    nearest = np.array([by_cycle.get(int(c), j) for c, j in zip(log.cycle, nearest)])
    tau_load = log.tau_ext_A_Nm + model.weight_moment(R)
    R_est = np.empty_like(R)
    dtau = np.empty((len(R), 3))
    for i, j in enumerate(nearest):
        e = estimates[j]
        dtau[i] = tau_load[i] - e.tau_load_ref_A_Nm
        if load == "external":
            R_est[i] = predict_pose_external(e.R_ref, getattr(e, use), e.tau_load_ref_A_Nm,
                                             log.tau_ext_A_Nm[i], model)
        else:
            R_est[i] = predict_pose(e.R_ref, getattr(e, use), dtau[i])
    labels = tuple(f"{int(c)}/{int(s)}" for c, s in zip(log.cycle, log.sample))
    return Verification(use, dtau, R, R_est, labels)
