"""Two effects at once: separability through the Fisher information, and the greedy pair search.

Separability of effects ``E`` and ``F`` on *this* log: the joint model
nominal + ``E`` + ``F`` is linearised at the parameters their single fits
found; its whitened Jacobian ``J`` (scaled parameters) and ridge priors give
the information ``I = J^T J + P`` and the covariance ``C = I^-1``. The
canonical correlations between the parameter blocks of ``E`` and ``F`` in
``C`` say how far one block's estimate can trade off against the other's;
the largest, ``rho``, above :data:`SEPARABLE_MAX_CORR` (variance inflated
more than tenfold) means the log cannot tell the two apart, and the pair is
reported as not separable rather than guessed.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ...errors import CsjmError
from ...model.rig import Rig
from ..data.residuals import ResidualTable
from ..decision_rule import LEAD_NATS
from ..effects import Effect
from ..fitting.augmented import N_NUISANCE, AugmentedModel
from ..fitting.gauss_newton import data_jacobian
from ..fitting.model_fits import path_twin
from .scoring import CandidateScore

#: Largest canonical correlation of two effects' parameter blocks for them to count as separable.
SEPARABLE_MAX_CORR = 0.95


def _inv_sqrt(S: np.ndarray) -> np.ndarray:
    w, V = np.linalg.eigh(0.5 * (S + S.T))
    w = np.where(w > w.max(initial=0.0) * 1e-12, w, np.inf)
    return (V / np.sqrt(w)) @ V.T


def block_correlation(info: np.ndarray, i1: np.ndarray, i2: np.ndarray) -> float:
    """Largest canonical correlation between parameter blocks ``i1`` and ``i2`` of ``inv(info)``."""
    eps = 1e-9 * max(float(np.max(np.diag(info))), 1e-300)
    C = np.linalg.pinv(info + eps * np.eye(len(info)), hermitian=True)
    M = _inv_sqrt(C[np.ix_(i1, i1)]) @ C[np.ix_(i1, i2)] @ _inv_sqrt(C[np.ix_(i2, i2)])
    s = np.linalg.svd(M, compute_uv=False)
    return float(np.clip(s.max(initial=0.0), 0.0, 1.0))


def separability(rig: Rig, table: ResidualTable, e1: Effect, th1: np.ndarray, e2: Effect,
                 th2: np.ndarray) -> dict:
    """``{"max_correlation", "separable"}`` of two effects on ``table`` (see module doc).

    Parameters
    ----------
    rig : Rig
    table : ResidualTable
        Training rows.
    e1, e2 : Effect
    th1, th2 : numpy.ndarray
        Full parameter vectors (nuisance first) of the single fits of ``e1`` and ``e2``.

    Returns
    -------
    dict
    """
    model = AugmentedModel(rig, [e1, e2])
    theta = np.concatenate([0.5 * (th1[:N_NUISANCE] + th2[:N_NUISANCE]), th1[N_NUISANCE:], th2[N_NUISANCE:]])
    theta = np.clip(theta, model.lower_bounds, model.upper_bounds)
    J = data_jacobian(model, table, theta)
    J = np.where(np.isfinite(J), J, 0.0)
    prior = model.prior_sd
    precision = np.where(np.isfinite(prior), (model.scales / prior) ** 2, 0.0)
    info = J.T @ J + np.diag(precision)
    i1 = np.arange(N_NUISANCE, N_NUISANCE + e1.n_params)
    i2 = np.arange(N_NUISANCE + e1.n_params, model.n_params)
    rho = block_correlation(info, i1, i2)
    return {"max_correlation": rho, "separable": bool(rho < SEPARABLE_MAX_CORR)}


def all_separabilities(rig: Rig, table: ResidualTable, singles: dict[str, CandidateScore],
                       names: Sequence[str]) -> dict[tuple[str, str], dict]:
    """Separability of every pair of fitted singles (in vocabulary order).

    A settled single (a stick set: its parameters have no point Jacobian, and would count as separable from
    anything) is linearised as its loading-path twin (:func:`~..fitting.model_fits.path_twin`).
    """
    out = {}
    fitted = [n for n in names if n in singles]
    for i, a in enumerate(fitted):
        for b in fitted[i + 1:]:
            fa, fb = singles[a].fit, singles[b].fit
            try:
                out[(a, b)] = separability(rig, table, *path_twin(fa.model.effects[0], fa.theta, rig),
                                           *path_twin(fb.model.effects[0], fb.theta, rig))
            except (np.linalg.LinAlgError, CsjmError) as exc:      # reported, never guessed
                out[(a, b)] = {"max_correlation": float("nan"), "separable": False, "error": str(exc)}
    return out


def secondary_alternatives(ctx, pairs: list, pair_scores: dict, final: CandidateScore,
                           first: str, second: str) -> list[str]:
    """Effects that could replace ``second`` next to ``first``: the log cannot tell which.

    A pair verdict ``first + second`` is honest only when no other effect ``c`` does the second
    effect's job as well: ``first + c`` is fitted, detected, plausible and closes the gap, its
    log evidence is within ``LEAD_NATS`` of the named pair's, and ``c`` and ``second`` are not
    separable on this log (their parameter blocks' canonical correlation is above the limit).
    Such a ``c`` is reported, not guessed away (e.g. small hole offsets next to friction act as a
    constant pose offset, as a sensor bias does).

    Parameters
    ----------
    ctx : object
        The diagnosis context (its ``evidence(score)`` gives a model's log evidence).
    pairs : list of dict
        The pair entries of the diagnosis (separability of every pair; fitted ones scored).
    pair_scores : dict
        Scores of the fitted pairs (unused; kept for symmetry with the verdict).
    final : CandidateScore
        The named pair's score.
    first, second : str
        The named pair.

    Returns
    -------
    list of str
    """
    if second in ("none", "") or first == "unexplained":
        return []
    ev = ctx.evidence(final)
    out = []
    for p in pairs:
        a, b = p["effects"]
        if not p.get("fitted") or first not in (a, b) or second in (a, b):
            continue
        c = b if a == first else a
        sep = next((q for q in pairs if set(q["effects"]) == {c, second}), None)
        if sep is None or sep["separable"]:
            continue
        if p["significant"] and p["plausible"] and p["closes_gap"] and p["log_evidence"] >= ev - LEAD_NATS:
            out.append(c)
    return out
