"""Quadratic models of the sweep-metric twins (F, S) and the trust-region steps taken on them.

One evaluation of the twins at a design ``u`` (scaled to its bounds, in
``[0, 1]^n``) gives their values, gradients and exact Hessians
(:func:`model_function`); :class:`QuadModel` is the second-order Taylor model
around ``u``. :func:`best_step` maximises one model over the box
``0 <= u + d <= 1`` intersected with a trust region ``|d|_inf <= radius``,
optionally with the other model held at least at a value: the step of a
trust-region Newton method (ascent) or of a sequential quadratically
constrained programme (the epsilon-constraint front). Solving a model costs
no evaluation of the twins: it is a small dense problem in ``n`` variables,
solved by SLSQP from several starting steps (the model need not be concave).
:func:`next_point` finds the model's front point a given length beyond the
last one; :func:`trust_radius` updates the trust region from the ratio of
actual to predicted change (:func:`ratio`). :func:`ascent` is the
trust-region Newton ascent of one twin, :func:`race_starts` the ascents from
several starts whose largest local maximum anchors the front.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import casadi as ca
import numpy as np
from scipy.optimize import minimize

from ..evaluation_settings import EvaluationSettings
from .settings import OptimiseSettings
from .surrogates import sweep_surrogate

#: Smallest and largest trust-region radius (scaled variables, infinity norm).
MIN_RADIUS, MAX_RADIUS = 1e-3, 0.25
#: The largest-workspace search stops when the model promises less than this gain in F.
F_TOL = 5e-4
#: Most trust-region steps of the largest-workspace search.
ANCHOR_STEPS = 8
#: Designs closer than this (scaled variables, infinity norm) lead to the same local maximum.
APART = 0.1


@dataclasses.dataclass(frozen=True)
class QuadModel:
    """Second-order Taylor models of F (fraction) and S (stiffness, N m/rad) around ``u``."""

    u: np.ndarray
    F: float
    S: float
    gF: np.ndarray
    gS: np.ndarray
    HF: np.ndarray
    HS: np.ndarray

    def predict(self, d: np.ndarray) -> tuple[float, float]:
        """Model values of (F, S) at ``u + d``.

        Parameters
        ----------
        d : ndarray
            Step in scaled variables.

        Returns
        -------
        (float, float)
        """
        return (self.F + self.gF @ d + 0.5 * d @ self.HF @ d, self.S + self.gS @ d + 0.5 * d @ self.HS @ d)

    def part(self, name: str) -> tuple[float, np.ndarray, np.ndarray]:
        """Value, gradient and Hessian of ``"F"`` or ``"S"``.

        Parameters
        ----------
        name : str

        Returns
        -------
        (float, ndarray, ndarray)
        """
        return (self.F, self.gF, self.HF) if name == "F" else (self.S, self.gS, self.HS)


def model_function(settings: OptimiseSettings, evaluation: EvaluationSettings) -> Any:
    """``u -> QuadModel``: the twins of the sweep's metrics with exact gradients and Hessians.

    Parameters
    ----------
    settings : OptimiseSettings
        Optimised variables and bounds.
    evaluation : EvaluationSettings
        The sweep's evaluator settings (samples and loads of both metrics).

    Returns
    -------
    callable
        ``evaluate(u) -> QuadModel``; one call is one evaluation of the twins over every sample.
    """
    f = sweep_surrogate(settings, evaluation)
    u = ca.MX.sym("u", len(settings.names))
    F, S, _, _ = f(u)
    HF, gF = ca.hessian(F, u)
    HS, gS = ca.hessian(S, u)
    fun = ca.Function("sweep_twins_2nd_order", [u], [F, S, gF, gS, HF, HS])

    def evaluate(x: np.ndarray) -> QuadModel:
        out = [np.array(v, float) for v in fun(np.asarray(x, float))]
        return QuadModel(np.array(x, float), out[0].item(), out[1].item(), out[2].ravel(), out[3].ravel(),
                         0.5 * (out[4] + out[4].T), 0.5 * (out[5] + out[5].T))

    return evaluate


def best_step(model: QuadModel, objective: str, radius: float, floor: tuple[str, float] | None = None,
              seed: int = 0) -> tuple[np.ndarray, bool]:
    """Maximise one model over the box and the trust region, optionally keeping the other above a floor.

    Parameters
    ----------
    model : QuadModel
    objective : str
        ``"F"`` or ``"S"``, the model maximised.
    radius : float
        Trust-region radius (infinity norm, scaled variables).
    floor : (str, float), optional
        ``(name, value)``: the model of ``name`` at least ``value`` at the step.
    seed : int
        Seed of the random starting steps.

    Returns
    -------
    d : ndarray
        The step (the one with the smallest floor violation when no step meets the floor).
    feasible : bool
        Whether the floor holds at ``d`` (always True without a floor).
    """
    n = len(model.u)
    lo, hi = np.maximum(-model.u, -radius), np.minimum(1.0 - model.u, radius)
    v0, g, H = model.part(objective)

    def neg(d: np.ndarray) -> tuple[float, np.ndarray]:
        return -(g @ d + 0.5 * d @ H @ d), -(g + H @ d)

    cons: list[dict[str, Any]] = []
    if floor is not None:
        c0, cg, cH = model.part(floor[0])
        cons = [{"type": "ineq", "fun": lambda d: c0 + cg @ d + 0.5 * d @ cH @ d - floor[1],
                 "jac": lambda d: cg + cH @ d}]
    rng = np.random.default_rng(seed)
    inits = [np.zeros(n), np.clip(g * radius / (np.max(np.abs(g)) + 1e-300), lo, hi),
             *(lo + (hi - lo) * rng.random(n) for _ in range(4 * n))]
    if floor is not None:
        inits.append(np.clip(cg * radius / (np.max(np.abs(cg)) + 1e-300), lo, hi))
    best: tuple[float, float, np.ndarray] | None = None
    for d0 in inits:
        r = minimize(neg, d0, jac=True, method="SLSQP", bounds=list(zip(lo, hi)), constraints=cons,
                     options={"maxiter": 200, "ftol": 1e-12})
        d = np.clip(r.x, lo, hi)
        gap = 0.0 if floor is None else max(floor[1] - model.predict(d)[0 if floor[0] == "F" else 1], 0.0)
        key = (round(gap, 9), float(neg(d)[0]))
        if best is None or key < best[:2]:
            best = (key[0], key[1], d)
    assert best is not None
    return best[2], best[0] <= 1e-9


def on_box(u: np.ndarray) -> np.ndarray:
    """Clip to the box, snapping round-off at the bounds onto them."""
    u = np.clip(u, 0.0, 1.0)
    return np.where(u < 1e-9, 0.0, np.where(u > 1.0 - 1e-9, 1.0, u))


def ratio(actual: float, predicted: float) -> float:
    """Actual over predicted change (1 when both vanish)."""
    return actual / predicted if abs(predicted) > 1e-12 else (1.0 if abs(actual) < 1e-9 else 0.0)


def trust_radius(radius: float, rho: float, d: np.ndarray) -> float:
    """Next trust radius: halved about a rejected step, doubled past a good step on its boundary.

    After an accepted step inside it, twice that step: the model's reach is known only that far.
    """
    size = float(np.max(np.abs(d)))
    if rho < 0.25:
        return max(0.5 * min(radius, size), MIN_RADIUS)
    if size > 0.9 * radius:
        return min(2.0 * radius, MAX_RADIUS) if rho > 0.75 else radius
    return float(np.clip(2.0 * size, MIN_RADIUS, radius))


def next_point(m: QuadModel, radius: float, F0: float, S0: float, scale: tuple[float, float],
                step: float) -> tuple[float, np.ndarray, bool]:
    """The model's front point ``step`` beyond (F0, S0): its epsilon, its step from ``m.u``, whether F binds."""
    def solve(delta: float) -> tuple[np.ndarray, float, bool]:
        d, _ = best_step(m, "S", radius, floor=("F", F0 - delta))
        F_d, S_d = m.predict(d)
        return d, float(np.hypot((F0 - F_d) / scale[0], (S_d - S0) / scale[1])), F_d < F0 - delta + 1e-6
    lo, hi = 0.0, step * scale[0]
    d, length, binds = solve(hi)
    while binds and length < step and hi < 0.5 * scale[0]:     # the model's front is steep: go further
        lo, hi = hi, 2.0 * hi
        d, length, binds = solve(hi)
    if length <= step:                              # F is free: the stiffest design within the region is near
        return F0 - hi, d, binds
    for _ in range(12):                             # bisection on the step length
        mid = 0.5 * (lo + hi)
        d_mid, length_mid, binds_mid = solve(mid)
        if length_mid > step:
            hi, d, binds = mid, d_mid, binds_mid
        else:
            lo = mid
    return F0 - hi, d, binds


def ascent(work: Any, m: QuadModel, part: str, steps: int, keep: int,
           known: list[np.ndarray] | None = None) -> QuadModel:
    """Trust-region Newton ascent of ``part`` (``"F"`` or ``"S"``) from ``m``, keeping ``keep`` evaluations.

    Parameters
    ----------
    work : object
        The evaluation counter: ``left()`` evaluations left, ``twins(u)`` one evaluation.
    m : QuadModel
        The start.
    part : str
        ``"F"`` or ``"S"``.
    steps : int
        Most trust-region steps.
    keep : int
        Evaluations left untouched.
    known : list of ndarray, optional
        Local maxima already reached: the ascent stops within :data:`APART` of one (it leads there).

    Returns
    -------
    QuadModel
        The model at the last accepted design (the ascent stops where its model promises less than
        :data:`F_TOL`, relative to S for ``"S"``).
    """
    radius, tol = MAX_RADIUS, F_TOL * (1.0 if part == "F" else max(abs(m.S), 1.0))
    for _ in range(steps):
        if work.left() <= keep:
            break
        d, _ = best_step(m, part, radius)
        value = m.part(part)[0]
        gain = m.predict(d)[0 if part == "F" else 1] - value
        if gain < tol:
            break
        trial = work.twins(on_box(m.u + d))
        rho = ratio(trial.part(part)[0] - value, gain)
        radius = trust_radius(radius, rho, d)
        if rho > 0.1:
            m = trial
            if known and min(np.max(np.abs(m.u - k)) for k in known) < APART:
                break
    return m


def race_starts(work: Any, models: list[QuadModel], race: int,
                min_left: int) -> tuple[list[QuadModel], list[QuadModel]]:
    """Ascend F from the ``race`` starts of largest F that lie apart; the local maxima, largest first.

    A start's F says little about the local maximum its ascent reaches (on a space with several
    local maxima the best start may sit in the basin of a lower one, and one quadratic model does not
    predict a distant maximum), so the branch is chosen by the maxima themselves: the first ascent
    keeps half of the evaluations left, each further one half of what is left then, and stops when it
    comes within APART of a maximum already reached (it leads there). Maxima within APART of a better
    one are the same maximum and dropped.

    Parameters
    ----------
    work : object
        The evaluation counter (as for :func:`ascent`).
    models : list of QuadModel
        The evaluated starts.
    race : int
        Most starts ascended.
    min_left : int
        A further start is ascended only with this many evaluations left.

    Returns
    -------
    anchors : list of QuadModel
        The distinct local maxima reached (largest F first).
    rest : list of QuadModel
        The other starts that hold a pose, largest F first (for further branches).
    """
    order = [int(k) for k in np.argsort([-m.F for m in models]) if models[k].F > 0.0]
    reached: list[QuadModel] = []
    raced: list[int] = []
    for k in order:
        if len(raced) >= max(race, 1) or (raced and work.left() < min_left):
            break
        if any(np.max(np.abs(models[k].u - x.u)) < APART for x in [models[j] for j in raced] + reached):
            continue
        raced.append(k)
        reached.append(ascent(work, models[k], "F", ANCHOR_STEPS, keep=max((work.left() + 1) // 2, 2),
                              known=[x.u for x in reached]))
    anchors: list[QuadModel] = []
    for m in sorted(reached, key=lambda x: -x.F):
        if all(np.max(np.abs(m.u - a.u)) >= APART for a in anchors):
            anchors.append(m)
    return anchors, [models[k] for k in order if k not in raced]
