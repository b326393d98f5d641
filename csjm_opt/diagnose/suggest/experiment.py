"""The next experiment: rows that best tell the leading hypotheses of a diagnosis apart.

When a verdict has non-separable alternatives, is ``unexplained``, or names an
effect near the noise floor, :func:`suggest_experiment` proposes up to ``N`` new
rows within the rig's limits:

* **candidate cycles**: a reference pose (tilt up to ``MAX_TILT_RAD``, any azimuth,
  twist up to ``MAX_TWIST_RAD``), a pretension (rest lengths planned for reference
  tensions anywhere in the middle of the tension range: changes of pretension
  go through the rest lengths), and one load point of the load set
  (:mod:`.loads`) with its masses hung in increasing then decreasing order
  (``0, m1, m2, ..., m2, m1, 0``: both branches, for friction). A cycle is kept
  only where the nominal rig holds every row with tensions in ``[t_min, t_max]``
  (:func:`csjm_opt.model.statics.solve_equilibrium` with the weights as point
  forces); a load the rig cannot hold at a pose is left out of that cycle;
* **hypotheses**: the selected model (a pair: and each of its singles), its
  non-separable alternatives and the pairs they form, the best singles and pairs
  when the verdict is ``unexplained``,
  and always the null model (at most ``MAX_HYPOTHESES``), each with its fitted
  parameters. The null keeps the rows showing the gap itself: rows that only tell
  two look-alike explanations apart but show neither would leave the held-out
  tests of the re-diagnosis (over cycles) without the effect to see. Each predicts every candidate row (forward
  statics, path state carried on from the end of the log, on the path the fit used:
  :func:`csjm_opt.diagnose.fitting.friction_path.end_state`);
* **design**: if ``b`` is true, the new rows show ``b``'s predictions; ``a`` refitted to
  the log and the new rows absorbs what its parameters can (linearised: its pose
  sensitivities on the new rows, with the information the log and the prior already
  give it). The separation of ``a`` and ``b`` is what it cannot absorb, in noise
  units (``delta^T delta - r^T N^-1 r``, whitened by the floor per component), the
  smaller of the two directions. Cycles are added greedily, each time the one that
  most raises the *smallest* separation over the pairs of hypotheses (then their sum),
  each counted up to ``RESOLVED_SD`` (a pair that far apart is resolved: further rows go
  to the others), until ``N`` rows are used; ``sqrt`` of it (noise sd) is reported per
  pair. Pairs no feasible rows of this size separate by ``EQUIVALENT_SD`` are reported
  as equivalent and not targeted. A plain distance
  between the fitted predictions would be optimistic: 6 m hole offsets refitted
  to the new rows mimic much of what they did not predict.

The candidate cycles are in :mod:`.candidates`; the protocol (:mod:`.protocol`) is the log
format (docs/conventions.md) with the planned rest lengths and empty measured columns, plus
the intended loads.
"""

from __future__ import annotations

import itertools
from types import SimpleNamespace
from typing import Callable, Sequence

import numpy as np

from ... import so3
from ...errors import InvalidInput
from ...model import kinematics as kin
from ...model.rig import Rig
from ..data.tails import norm_isf
from ..decision_rule import ALPHA, LEAD_NATS
from ..effects import EFFECTS
from ..fitting.augmented import Rows, cable_steps, log_steps
from ..fitting.evidence import prior_of
from ..fitting.friction_path import end_state
from ..fitting.gauss_newton import data_jacobian
from ..selection.result import Diagnosis
from ..selection.scoring import CandidateScore
from .dead_weights import DeadWeight, default_dead_weights
from .load_cycles import N_CANDIDATES, candidate_cycles
from .suggestion import PROTOCOL_COLUMNS, Suggestion, protocol_text, suggestion_markdown

MAX_HYPOTHESES = 6
#: Two hypotheses no candidate row can separate by this many noise sd are reported as equivalent.
EQUIVALENT_SD = 1.0
#: An effect is "near the floor" when the systematic gap it explains is below this many floors.
NEAR_FLOOR = 3.0
#: A pair of hypotheses is resolved at this separation (noise sd): a one-sided test at ``ALPHA`` over the
#: vocabulary's candidates detects it with power 0.9. Beyond it, rows go to the pairs not yet resolved.
RESOLVED_SD = norm_isf(ALPHA / len(EFFECTS)) + norm_isf(0.1)


def hypotheses(d: Diagnosis) -> tuple[str, list[tuple[str, CandidateScore]]]:
    """``(purpose, [(name, score), ...])``: why an experiment is needed and which models to separate.

    The leading hypotheses are the selected model, each single of a selected pair, every model a
    warning of the verdict names (look-alikes, unsettled rivals, alternatives: the log does not rule
    them out), the plausible singles and fitted pairs whose log evidence (:mod:`.evidence`) is within
    ``LEAD_NATS`` of the best, and the null model last, always (at most ``MAX_HYPOTHESES``).

    Parameters
    ----------
    d : Diagnosis

    Returns
    -------
    tuple
        ``purpose`` is ``""`` when the verdict needs no further experiment.
    """
    pool: dict[str, tuple[float, CandidateScore]] = {}
    for n, sc in d.candidates.items():
        t = d.tests.get(n, {})
        if t.get("plausible", False) and np.isfinite(t.get("log_evidence", np.nan)):
            pool[n] = (t["log_evidence"], sc)
    for p in d.pairs:
        k = tuple(p["effects"])
        if p.get("fitted") and p.get("plausible") and k in d.pair_scores:
            pool["+".join(k)] = (p["log_evidence"], d.pair_scores[k])
    sel, sec = d.selected, d.secondary.effect
    floor = d.noise_floor_rad
    reasons = []
    out: dict[str, CandidateScore] = {}
    if sel not in ("none", "unexplained"):
        out[f"{sel}+{sec}" if sec != "none" else sel] = d.selected_score
    best = max((v[0] for v in pool.values()), default=-np.inf)
    ranked = sorted(pool, key=lambda n: -pool[n][0])
    lead = [n for n in ranked if pool[n][0] >= best - LEAD_NATS]
    if sel == "unexplained":
        reasons.append("the verdict is unexplained")
        lead = ranked[:3] if len(lead) < 2 else lead
    elif sel == "none":
        near = [n for n in d.candidates if d.tests[n].get("improvement_rad", 0) > 0.5 * floor]
        if near:
            reasons.append("no effect was named, but " + ", ".join(near) + " improve on the nominal model by "
                           "more than half a noise floor")
            out["none"] = d.baseline
            lead = sorted(near, key=lambda n: d.candidates[n].heldout_mse)[:2]
        else:
            lead = []
    else:
        # every model a warning names (look-alikes of a flexible verdict, unsettled rivals, alternatives) leads
        named = [*d.verdict.look_alikes, *(r["model"] for r in d.verdict.unsettled_rivals), *d.verdict.alternatives,
                 *(f"{sel}+{x}" for x in d.verdict.stand_ins)]
        lead = list(dict.fromkeys([*(n for n in named if n in pool or n in d.candidates), *lead]))
        others = [n for n in lead if n not in out and n != f"{sec}+{sel}"]
        if others:
            reasons.append(f"the log cannot tell {next(iter(out))} decisively from {', '.join(others)}")
        if sec != "none":                   # a pair against each of its singles: is the second effect real?
            if not d.secondary.separable:
                reasons.append(f"{sel} and {sec} are not separable on this log")
            out.setdefault(sel, d.candidates[sel])
            out.setdefault(sec, d.candidates[sec])
        improvement = d.tests.get(sel, {}).get("improvement_rad", np.inf)
        if improvement < NEAR_FLOOR * floor:
            reasons.append(f"{sel} improves on the nominal model by only {improvement / floor:.1f} noise floors")
    for n in lead:
        if n not in out:
            out[n] = pool[n][1] if n in pool else d.candidates[n]
    # the null model last, always: the rows must show the gap itself, not only the differences
    # between its explanations (held-out tests compare cycles: rows that show nothing dilute them)
    items = [(n, sc) for n, sc in out.items() if n != "none"][:MAX_HYPOTHESES - 1] + [("none", d.baseline)]
    if not reasons or len(items) < 2:
        return "", []
    return "; ".join(reasons) + ": the rows separate these models", items


def _predict(sc: CandidateScore, d: Diagnosis, cands: list[dict], rig: Rig) -> tuple[np.ndarray, Rows]:
    """Poses (n, 3, 3) hypothesis ``sc`` predicts for every candidate row, and the candidate rows.

    The path state is carried on from the log's end.
    """
    model, theta = sc.fit.model, sc.fit.theta
    train = d.train
    # the state the log leaves, on the path the fit itself used (measured steps or the predicted path)
    last_state, last_len = end_state(model, sc.fit.rows if sc.fit.rows is not None else train.rows,
                                     train.R_meas, theta)
    l = np.concatenate([np.repeat(c["rest_lengths_m"][None], len(c["loads"]), 0) for c in cands])
    tau = np.concatenate([c["tau"] for c in cands])
    R0 = np.concatenate([c["R"] for c in cands])
    cyc = np.concatenate([np.full(len(c["loads"]), i) for i, c in enumerate(cands)])
    n = len(cyc)
    lengths, _ = kin.cable_terms(R0, np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m))
    m = l.shape[1]
    rest = np.zeros((n, m))
    first = np.r_[True, cyc[1:] != cyc[:-1]]
    rest[first] = l[first] - train.rows.rest_lengths_m[-1]
    entry_s = np.full((n, m), np.nan)
    entry_l = np.full((n, m), np.nan)
    if last_state is not None:
        entry_s[first], entry_l[first] = last_state, last_len

    rows = Rows(l, tau, cyc, cable_steps(cyc, lengths), log_steps_m=log_steps(lengths), rest_steps_m=rest,
                entry_state=entry_s, entry_lengths_m=entry_l)
    return model.predict_poses(rows, theta, R0).R, rows


def _information(sc: CandidateScore, noise_scale: float) -> np.ndarray:
    """What the log and the prior already say about ``sc``'s scaled parameters (precision matrix)."""
    fit = sc.fit
    m, sd = prior_of(fit)
    J = fit.jac_x[:fit.n_obs] if fit.jac_x is not None else np.zeros((1, len(m)))
    return J.T @ J / noise_scale ** 2 + np.diag((fit.model.scales / sd) ** 2)


def _row_jacobian(sc: CandidateScore, rows: Rows, R: np.ndarray, sigma: float) -> np.ndarray:
    """(n, 3, p) sensitivity of ``sc``'s predicted poses on ``rows`` to its scaled parameters, over ``sigma``."""
    table = SimpleNamespace(rows=rows, R_meas=R, whiten=np.broadcast_to(np.eye(3) / sigma, (len(rows), 3, 3)))
    J = data_jacobian(sc.fit.model, table, sc.fit.theta)       # type: ignore[arg-type]
    return J.reshape(len(rows), 3, -1)

def suggest_experiment(rig: Rig, d: Diagnosis, max_rows: int, loads: Sequence[DeadWeight] | None = None,
                       seed: int = 0, progress: Callable | None = None) -> Suggestion | None:
    """Up to ``max_rows`` rows that best separate the diagnosis's leading hypotheses (module doc).

    Parameters
    ----------
    rig : Rig
        The rig of the diagnosis.
    d : Diagnosis
    max_rows : int
        Largest number of rows.
    loads : sequence of DeadWeight, optional
        The lab's load set (default :func:`~csjm_opt.diagnose.suggest.dead_weights.default_dead_weights`).
    seed : int, optional
        Seed of the candidate draw.
    progress : callable, optional
        ``tqdm``-like factory.

    Returns
    -------
    Suggestion or None
        ``None`` when the verdict needs no further experiment.

    Raises
    ------
    InvalidInput
        ``max_rows`` below 3, or a load set the rig cannot hold.
    """
    if int(max_rows) < 3:
        raise InvalidInput(f"--suggest needs at least 3 rows (one load cycle), got {max_rows}", "suggest")
    purpose, hyps = hypotheses(d)
    reach = float(np.max(np.linalg.norm(d.train.rows.tau_meas_A_Nm, axis=1), initial=0.0))
    loads = list(loads) if loads is not None else default_dead_weights(rig, reach)
    rng = np.random.default_rng(seed)
    bar = progress(total=2 + len(hyps), desc="suggest: designing rows") if progress else None
    cands = [c for c in candidate_cycles(rig, loads, rng) if len(c["loads"]) <= max_rows]
    if bar:
        bar.update(1)
    if not hyps:
        if bar:
            bar.close()
        return None
    sigma = d.noise_floor_rad / np.sqrt(3.0)          # per pose component
    scale = float(d.noise_estimates.get("noise_scale", 1.0))
    preds, jacs, info = [], [], []
    for _, sc in hyps:
        R, rows = _predict(sc, d, cands, rig)
        preds.append(R)
        jacs.append(_row_jacobian(sc, rows, R, sigma))
        info.append(_information(sc, scale))
        if bar:
            bar.update(1)
    sizes = [len(c["loads"]) for c in cands]
    bounds = np.cumsum([0] + sizes)
    usable = _usable(rig, rows.rest_lengths_m, preds, bounds)
    names = [n for n, _ in hyps]
    pairs = list(itertools.combinations(range(len(hyps)), 2))
    # per candidate cycle and direction (truth b, refit a): J^T J, J^T delta, delta^T delta (whitened)
    terms = {}
    for a, b in pairs:
        dz = so3.log(np.swapaxes(preds[a], 1, 2) @ preds[b]) / sigma
        for t, f in ((b, a), (a, b)):          # truth t, refitted hypothesis f
            delta = dz if f == a else -dz
            J = jacs[f]
            A = np.stack([np.einsum("nij,nik->jk", J[lo:hi], J[lo:hi]) for lo, hi in zip(bounds[:-1], bounds[1:])])
            bvec = np.stack([np.einsum("nij,ni->j", J[lo:hi], delta[lo:hi]) for lo, hi in zip(bounds[:-1], bounds[1:])])
            e = np.add.reduceat(np.sum(delta ** 2, axis=1), bounds[:-1])
            terms[(t, f)] = (A, bvec, e)

    def separation(sel: list[int]) -> np.ndarray:
        """Per pair: the smaller, over which is true, of what the other's refit cannot absorb (squared sd)."""
        out = np.empty(len(pairs))
        for k, (a, b) in enumerate(pairs):
            vals = []
            for t, f in ((b, a), (a, b)):
                A, bvec, e = terms[(t, f)]
                N = info[f] + A[sel].sum(axis=0)
                r = bvec[sel].sum(axis=0)
                vals.append(float(e[sel].sum() - r @ np.linalg.lstsq(N, r, rcond=None)[0]))
            out[k] = max(min(vals), 0.0)
        return out

    # hypotheses no feasible experiment of this size can tell apart are equivalent here: not a target
    spread = np.sum([terms[(b, a)][2] for a, b in pairs], axis=0)
    reachable = separation([i for i in np.argsort(-spread) if usable[i]][:max(1, max_rows // max(min(sizes), 1))])
    target = np.sqrt(reachable) >= EQUIVALENT_SD
    if not target.any():
        target[:] = True

    def utility(sep2: np.ndarray) -> tuple[float, float]:
        """Smallest separation over the target pairs, then their sum; each counted up to ``RESOLVED_SD``."""
        v = np.minimum(np.sqrt(sep2[target]), RESOLVED_SD)
        return float(v.min()), float(v.sum())
    chosen: list[int] = []
    total = np.zeros(len(pairs))
    used = 0
    while True:
        options = [i for i in range(len(cands)) if usable[i] and i not in chosen and used + sizes[i] <= max_rows]
        if not options:
            break
        scores = {i: separation(chosen + [i]) for i in options}
        best = max(options, key=lambda i: (*utility(scores[i]), -sizes[i]))
        chosen.append(best)
        total = scores[best]
        used += sizes[best]
    if bar:
        bar.update(1)
        bar.close()
    before = _separation_on_log(d, hyps, sigma ** 2)
    first_cycle = int(np.max(d.train.cycle)) + 1
    sel = [cands[i] for i in chosen]
    cyc = np.concatenate([np.full(len(c["loads"]), first_cycle + j) for j, c in enumerate(sel)])
    return Suggestion(purpose, names, cyc,
                      np.concatenate([np.repeat(c["rest_lengths_m"][None], len(c["loads"]), 0) for c in sel]),
                      [ld for c in sel for ld in c["loads"]], np.concatenate([c["tau"] for c in sel]),
                      np.concatenate([c["R"] for c in sel]),
                      {f"{names[a]} vs {names[b]}": float(np.sqrt(total[k])) for k, (a, b) in enumerate(pairs)},
                      before, [f"{names[a]} vs {names[b]}" for k, (a, b) in enumerate(pairs) if not target[k]])


def _usable(rig: Rig, rest_lengths_m: np.ndarray, preds: list[np.ndarray], bounds: np.ndarray) -> np.ndarray:
    """Candidate cycles (bool, one each) whose rows keep every cable of the rig file's model taut where predicted.

    Every hypothesis's predicted pose of every row counts (a cable is taut where it is longer than its rest length,
    ``rest_lengths_m`` of the candidate rows, cycles from ``bounds``); all cycles are usable when none is.

    At a pose where a cable of the rig file's model is slack (a hypothesis such as a link compliance moves the
    measured body away from the cable platform's pose), the model is nearly singular and the diagnosis leaves the
    row out or is swamped by it (``data.residuals.ill_conditioned_rows``: a suggested row with two such cables had
    100 times the log's pose noise).
    """
    holes = np.asarray(rig.platform_holes_A_m), np.asarray(rig.base_holes_B_m)
    taut = np.all([np.all(kin.cable_terms(R, *holes)[0] > rest_lengths_m, axis=1) for R in preds], axis=0)
    ok = np.logical_and.reduceat(taut, bounds[:-1])
    return ok if ok.any() else np.ones(len(ok), bool)


def _separation_on_log(d: Diagnosis, hyps, var: float) -> dict:
    """How far apart the hypotheses' fits are on the log's own rows (noise sd), for comparison."""
    out = {}
    for (na, a), (nb, b) in itertools.combinations(hyps, 2):
        dz = a.train_zeta_rad - b.train_zeta_rad
        out[f"{na} vs {nb}"] = float(np.sqrt(np.sum(dz ** 2) / var))
    return out


__all__ = ["N_CANDIDATES", "PROTOCOL_COLUMNS", "Suggestion", "candidate_cycles", "hypotheses", "protocol_text",
           "suggest_experiment", "suggestion_markdown"]
