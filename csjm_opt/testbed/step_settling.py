"""Coming to rest after a load step on the quasi-static plant: overdamped motion under Coulomb friction.

A lab hangs each load at once: from the pose where the previous row settled (nothing relaxed in
between), the platform moves under the new inputs and comes to rest under its own dynamics. The
quasi-static plant models that motion as an overdamped path (gradient flow, unit damping) in the
body-frame rotation vector ``zeta`` of the measured body (``R exp(hat(zeta))``)::

    d zeta / dt = q(R) + A(R) f,   |f_j| <= b_j,   f_j = b_j sign(sliding of element j) while it slides

``q`` is the frictionless net moment (cable tensions, weight, load: :meth:`TestbedPlant.frictionless_net`),
``A`` the moment of a unit friction force in each friction element (a cable: its column of ``J^T``,
the friction force adding to the tension the platform feels, a rigid platform-side segment as
MuJoCo's tendon ``frictionloss``; the ball joint: an axis of {A}) and ``b`` the *sliding* (kinetic)
bounds. In an overdamped system the velocity is the smallest element of ``q + A [-b, b]``: ``f``
solves a box-constrained least-squares problem, an element with ``|f_j| < b_j`` does not slide, one
that slides has ``f_j`` on its bound opposing the sliding.

Breakaway and stop are one rule, the static Coulomb condition of
:func:`~csjm_opt.testbed.static_certificate.certify_static` with the *static* bounds
``ratio * b`` (the certificate the MuJoCo plant's rows pass): the platform does not move when the
previous pose is held under the new inputs, and otherwise stops at the *first* point of its path
where it is held. With ``ratio = 1`` that is the end of the sliding motion (a point on the edge of
the stick band, approached from outside, reached within the certificate's imbalance of
``HOLD_TOL_NM``); with ``ratio > 1`` the motion stops as soon as it enters the wider static band,
short of where sliding friction alone would leave it: an overdamped motion is slow, and a slow
motion sticks as soon as static friction can hold it. (MuJoCo's platform, with inertia, slides on
nearly to where sliding friction alone stops it; its static ratio mostly decides whether a row
moves at all.)

Time stepping is linearly implicit: ``(I / h + gamma K) delta = q + A f`` with ``f`` the
box-constrained minimiser of ``|q + A f|`` in the metric ``(I / h + gamma K)^-1`` (``K`` the
symmetric part of the frictionless tangent stiffness ``-dq/dzeta``; ``gamma = 1/2``, the
trapezoidal rule, on the way, and ``1``, implicit Euler, at the end). A step moves at most
``MAX_STEP_RAD``, with ``h lambda_max(K) <= PATH_H_LAMBDA`` (the fast directions relax over several
steps, as on the continuous path) until the end of the sliding motion is within ``FINISH_RAD``;
then ``h`` grows freely (the last steps are Newton steps on the sliding equilibrium). Only the
*path* depends on these settings (on the paper rig at 3x the typical Coulomb friction, the rest
poses are within 0.03 mrad of a path with steps eight times finer, ``ratio`` 1 and 1.5); where the
motion stops is decided by the certificate, exactly: on the step whose end is held, the first
held point of the step's chord is found by regula falsi on the certificate's utilisation
(``t = 1`` on the static band's edge).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from scipy.optimize import lsq_linear

from .. import so3
from ..errors import NoEquilibrium
from ..model import kinematics as kin
from .static_certificate import FrictionCertificate, certify_static

#: Longest step (rad) of the path.
MAX_STEP_RAD = 2e-3
#: Largest ``h lambda_max(K)`` while the motion still has a way to go (path fidelity).
PATH_H_LAMBDA = 1.0
#: Remaining sliding travel (rad) below which the time step grows freely (Newton steps to the end).
FINISH_RAD = 1e-5
#: Growth of the time step from one step to the next.
GROWTH = 2.0
#: Steps after which a motion that has not come to rest is refused.
MAX_STEPS = 2000
#: Imbalance (N m, per axis) the certificate allows (:func:`certify_static`'s ``tol_Nm``).
HOLD_TOL_NM = 1e-7
#: A point is certified by the LP only when the box least-squares distance is below this multiple of
#: the tolerance (the LP's row-wise tolerance allows at most ``sqrt(3)`` of it: a cheap exact screen).
SCREEN_FACTOR = 10.0
#: Regula falsi on the chord: stop when the utilisation is within this of the edge, or the bracket is this short.
EDGE_TOL = 1e-9
#: Finite-difference step (rad) of the tangent stiffness (the path's metric only).
TANGENT_STEP_RAD = 1e-7
#: Rotation (rad) from the start beyond which the platform has fallen over.
FALL_RAD = np.pi / 4

#: ``net(R) -> (q, A, b)`` for poses (n, 3, 3): frictionless net moment (n, 3), friction directions
#: (n, 3, k) and sliding bounds (n, k).
NetFunction = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclasses.dataclass(frozen=True)
class StepRest:
    """Where the platform came to rest after a step of its inputs.

    Attributes
    ----------
    R : (3, 3) array
        The rest pose.
    certificate : FrictionCertificate
        The static Coulomb certificate of the rest pose (static bounds).
    moved : bool
        Whether the step broke the previous pose loose.
    steps : int
        Time steps of the path.
    """

    R: np.ndarray
    certificate: FrictionCertificate
    moved: bool
    steps: int


def _screen(q: np.ndarray, A: np.ndarray, bounds: np.ndarray, metric_chol: np.ndarray | None = None,
            f_warm: np.ndarray | None = None):
    """Box least squares ``min_{|f| <= bounds} |q + A f|`` (in the metric ``L^-T L^-1`` when ``L`` is given).

    Returns the minimiser ``f`` (elements with a zero bound get 0) and the distance. ``f_warm``: a
    guess whose active set is tried first (:func:`_warm`).
    """
    L = np.eye(len(q)) if metric_chol is None else metric_chol
    f = None if f_warm is None else _warm(q, A, bounds, L, f_warm)
    if metric_chol is not None:
        q = np.linalg.solve(metric_chol, q)
        A = np.linalg.solve(metric_chol, A)
    if f is None:
        f = np.zeros(A.shape[1])
        live = bounds > 0
        if np.any(live):
            sol = lsq_linear(A[:, live], -q, bounds=(-bounds[live], bounds[live]), method="bvls")
            f[live] = np.clip(sol.x, -bounds[live], bounds[live])
    return f, float(np.linalg.norm(q + A @ f))


def _warm(q: np.ndarray, A: np.ndarray, bounds: np.ndarray, L: np.ndarray, f_prev: np.ndarray) -> np.ndarray | None:
    """The box least squares of :func:`_screen` from the previous step's active set, or ``None``.

    Elements on a bound there stay on it, the others are solved for (least squares); the answer
    is kept when it is within the bounds and the gradient pushes every bound element outwards
    (the problem's optimality conditions), so the general solver runs only when the set changes.
    """
    upper = f_prev >= bounds * (1.0 - 1e-9)
    lower = f_prev <= -bounds * (1.0 - 1e-9)
    fixed = (upper | lower) & (bounds > 0)
    free = (bounds > 0) & ~fixed
    f = np.where(upper, bounds, np.where(lower, -bounds, 0.0))
    Cq = np.linalg.solve(L, q + A @ f)
    CA = np.linalg.solve(L, A)
    if np.any(free):
        f[free] = np.linalg.lstsq(CA[:, free], -Cq, rcond=None)[0]
        if np.any(np.abs(f[free]) > bounds[free]):
            return None
    grad = CA.T @ (np.linalg.solve(L, q + A @ f))
    tol = 1e-12 * max(1.0, float(np.abs(CA).max() * np.abs(Cq).max()))
    if np.any(grad[upper & fixed] > tol) or np.any(grad[lower & fixed] < -tol):
        return None
    return f


def _certificate(q: np.ndarray, A: np.ndarray, b: np.ndarray, ratio: float,
                 f_warm: np.ndarray | None = None) -> tuple[FrictionCertificate | None, np.ndarray]:
    """The static certificate of a pose (net ``q``, directions ``A``, sliding bounds ``b``) when it is held.

    Also the screen's friction forces (a warm start for the next pose's screen).
    """
    f, dist = _screen(q, A, ratio * b, f_warm=f_warm)
    if dist > SCREEN_FACTOR * HOLD_TOL_NM:
        return None, f
    cert = certify_static(q, A, ratio * b, HOLD_TOL_NM)
    return (cert if cert.certified else None), f


def _utilisation(net: NetFunction, R: np.ndarray, ratio: float) -> FrictionCertificate:
    q, A, b = (x[0] for x in net(R[None]))
    return certify_static(q, A, ratio * b, HOLD_TOL_NM)


def _first_held(net: NetFunction, R0: np.ndarray, delta: np.ndarray, ratio: float,
                end: FrictionCertificate) -> tuple[np.ndarray, FrictionCertificate]:
    """The first held point of the chord ``R0 exp(s delta)``, ``s in (0, 1]`` (``s = 1`` is held)."""
    q, A, b = (x[0] for x in net(R0[None]))
    if not np.any(b > 0):                     # no friction: the end is the equilibrium (within the tolerance)
        return R0 @ so3.exp(delta), end
    c0 = certify_static(q, A, ratio * b, HOLD_TOL_NM)
    s_lo, t_lo = 0.0, c0.utilisation          # t > 1 (not held); inf: no forces balance it (then bisect)
    s_hi, t_hi, c_hi = 1.0, min(end.utilisation, 1.0), end
    side = 0
    for _ in range(60):
        if s_hi - s_lo < EDGE_TOL or 1.0 - c_hi.utilisation < EDGE_TOL:
            break
        if np.isfinite(t_lo):
            s = s_lo + (t_lo - 1.0) * (s_hi - s_lo) / (t_lo - t_hi)
            s = min(max(s, s_lo + 1e-3 * (s_hi - s_lo)), s_hi - 1e-3 * (s_hi - s_lo))
        else:
            s = 0.5 * (s_lo + s_hi)
        c = _utilisation(net, R0 @ so3.exp(s * delta), ratio)
        if c.certified:
            s_hi, t_hi, c_hi = s, min(c.utilisation, 1.0), c
            if side == 1:                      # Illinois: the other end's weight halved
                t_lo = 1.0 + 0.5 * (t_lo - 1.0)
            side = 1
        else:
            s_lo, t_lo = s, c.utilisation
            if side == -1:
                t_hi = 1.0 - 0.5 * (1.0 - t_hi)
            side = -1
    return R0 @ so3.exp(s_hi * delta), c_hi


def settle_after_step(net: NetFunction, R_start: np.ndarray, static_friction_ratio: float = 1.0) -> StepRest:
    """Where the platform comes to rest after its inputs stepped at the pose ``R_start`` (see the module doc).

    Parameters
    ----------
    net : callable
        ``net(R)`` for poses ``(n, 3, 3)``: the frictionless net moment ``(n, 3)`` (N m), the moments of unit
        friction forces ``(n, 3, k)`` and the sliding bounds ``(n, k)`` of the ``k`` friction elements,
        all under the *new* inputs.
    R_start : (3, 3) array
        The pose the platform rested at under the previous inputs.
    static_friction_ratio : float, optional
        Static over sliding bounds (>= 1).

    Returns
    -------
    StepRest

    Raises
    ------
    NoEquilibrium
        The motion did not come to rest within ``MAX_STEPS`` steps, or fell over.
    """
    ratio = float(static_friction_ratio)
    R = np.array(R_start, float)
    q, A, b = (x[0] for x in net(R[None]))
    cert, f_static = _certificate(q, A, b, ratio)
    if cert is not None:
        return StepRest(R, cert, False, 0)
    turns = np.stack(kin.basis_rotations(TANGENT_STEP_RAD))
    h = np.inf
    finishing = False
    f = np.zeros(A.shape[1])
    q_turned = net(R @ turns)[0]
    for step in range(1, MAX_STEPS + 1):
        G = (q_turned - q).T / TANGENT_STEP_RAD          # dq/dzeta, columns by axis
        K = -0.5 * (G + G.T)
        lam = np.linalg.eigvalsh(K)
        lam_min, lam_max = float(lam[0]), float(lam[-1])
        h_cap = 0.5 / -lam_min if lam_min < 0 else np.inf               # I / h + K positive definite
        if not finishing and lam_max > 0:
            h_cap = min(h_cap, PATH_H_LAMBDA / lam_max)
        if step == 1:
            h = 0.1 * (PATH_H_LAMBDA / lam_max if lam_max > 0 else MAX_STEP_RAD / max(float(np.linalg.norm(q)), 1e-12))
        h = float(min(h, h_cap))
        for _ in range(40):
            M = np.eye(3) / h + (K if finishing else 0.5 * K)
            L = np.linalg.cholesky(M)
            f = _screen(q, A, b, L, f_warm=f)[0]
            delta = np.linalg.solve(M, q + A @ f)
            size = float(np.linalg.norm(delta))
            if size <= MAX_STEP_RAD * (1.0 + 1e-9):
                break
            h *= 0.9 * MAX_STEP_RAD / size
        if not finishing and lam_min > 0:
            finishing = float(np.linalg.norm(np.linalg.solve(K, q + A @ f))) < FINISH_RAD
        R_next = R @ so3.exp(delta)
        if so3.angle_between(R_next, R_start) > FALL_RAD or not np.all(np.isfinite(R_next)):
            raise NoEquilibrium("the quasi-static plant fell over after a load step (more than 45 deg from the "
                                "previous row's pose)", "fell", float(np.linalg.norm(q)))
        Q, AA, BB = net(np.concatenate([R_next[None], R_next @ turns]))    # the pose and its tangent's turns
        q_next, A_next, b_next, q_turned = Q[0], AA[0], BB[0], Q[1:]
        cert, f_static = _certificate(q_next, A_next, b_next, ratio, f_static)
        if cert is not None:
            R_rest, cert = _first_held(net, R, delta, ratio, cert)
            return StepRest(R_rest, cert, True, step)
        R, q, A, b = R_next, q_next, A_next, b_next
        h *= GROWTH
    raise NoEquilibrium(f"the quasi-static plant did not come to rest within {MAX_STEPS} steps after a load step",
                        "diverged", float(np.linalg.norm(q)))
