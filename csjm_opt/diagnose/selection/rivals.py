"""Rivals the log does not rule out: a verdict the evidence does not single out says which.

A lab acts on a verdict, so a named model must carry a warning naming every other model of the
vocabulary that explains the log about as well. A *rival* is a fitted single or pair, other than
the verdict ``V``, that is plausible and closes the gap (the same two conditions a verdict must
meet), or closes it *within the noise*: its own estimate of the closed share falls short of
``CLOSE_FRACTION``, but ``V``, which closes, does not beat it on held-out cycles (one-sided paired
test of per-cycle held-out MSE, ``p >= HELDOUT_ALPHA``), so the shortfall is not significant. It
is *unsettled* when neither of the diagnosis's two yardsticks rules it out:

* **It adds to the verdict** (``V`` plus one more effect ``X``) and it is more probable than ``V``
  with the prior odds of one addition among many: the prior gives "``V`` plus some other effect" the
  same weight as ``V`` alone, shared by the ``m`` additions the diagnosis fitted, so each has prior
  odds ``1/m`` and is the more probable model when its log evidence exceeds ``V``'s by ``ln m``
  (2.4 nats for 11 additions). The priors then prefer ``X`` present, while the held-out test did
  not confirm it (a confirmed ``X`` would have been named). ``X`` may be present too; the log does
  not decide. With even odds for each addition (a bare "evidence higher"), some addition among
  eleven came out ahead by chance on 10 of 110 correctly named single effects in the step-loaded
  confusion study (12 cycles), where ``V`` was the whole truth.
  Where the verdict or the rival is *set-valued* (settled friction: a stick set per row), the
  evidence cannot rank an addition, and only the held-out clause below lists it: the Laplace
  evidence of a likelihood with kinks at every stick set's boundary carries several nats of
  approximation, and it favours the larger model (on the validation logs, physically absent effects
  added to settled friction gained 3-23 nats, and relinearising the single moved those gains by up
  to 7 nats either way; in the 12-cycle step-loaded confusion study, 8 of 20 correctly named
  friction logs had an absent effect more than ``EVIDENCE_MIN`` ahead, 5.7-13.7 nats, none of them
  better on held-out cycles at ``HELDOUT_ALPHA``).
  A superfluous ``X`` pays its Occam factor (about ``log(prior sd / posterior sd)`` per
  parameter the log determines), but one the log barely determines pays little.
* **It replaces the verdict** (neither contains the other) and its evidence is higher than
  ``V``'s, or within ``EVIDENCE_MIN`` nats of it (not decisively less probable: a Bayes factor
  below 100) while ``V`` does not beat it on held-out cycles (``p >= HELDOUT_ALPHA``): it closes
  the same gap within the noise.
* **It beats the verdict on held-out cycles** (either kind): its per-cycle held-out MSE is lower
  in the one-sided paired test at ``HELDOUT_ALPHA`` divided by the number of rivals that close the
  gap (Bonferroni: when the verdict is right and every rival as good, a false warning of this kind
  has probability at most ``HELDOUT_ALPHA``). The verdict is the evidence's pick among the
  models that close the gap; the held-out errors prefer the rival, the same kind of confirmation
  the evidence route of the decision asks of a pair.

A model that is part of the verdict (``A`` for ``V = A + B``) is no rival: the pair beat it on
held-out cycles or by a decisive Bayes factor, or it would not have been named.

**Evidence as fitted.** The evidence a warning compares is the Laplace approximation centred at
each model's *fitted* parameters (:func:`~csjm_opt.diagnose.fitting.evidence.log_evidence` with
``at_fit=True``), not at the mode its linearisation predicts: a warning states that a rival is more
probable, and that must hold for the rival as fitted. The two differ where the fit is not at the
mode of its own linearisation. On correctly named link-compliance logs, the pair that adds a
second compliance effect (stiffness scale, cable hardening) reached a *higher* misfit than the
named single it contains, while its linearised step promised 35 less (a drop in chi^2 that one
added parameter of a correct model reaches with probability about 1e-9): some 10-24 nats of
evidence that no fit of the pair realises. On the noise-free logs the added effect fits to zero
and the single is the more probable model. Entries of ``models`` without
``log_evidence_at_fit`` fall back to ``log_evidence``.
"""

from __future__ import annotations

from typing import Collection, Mapping

import numpy as np

from ..decision_rule import EVIDENCE_MIN, HELDOUT_ALPHA, LEAD_NATS
from .scoring import CandidateScore, cycle_nll_of, evidence_of, paired_heldout_test


class _Cycles:
    """Per-cycle held-out MSE (and log scores) in the form :func:`~.scoring.paired_heldout_test` reads."""

    def __init__(self, cycle_mse, cycle_nll=None, set_scale: float | None = None):
        self._mse = dict(enumerate(cycle_mse)) if not isinstance(cycle_mse, Mapping) else dict(cycle_mse)
        self._nll = None if cycle_nll is None else (
            dict(enumerate(cycle_nll)) if not isinstance(cycle_nll, Mapping) else dict(cycle_nll))
        self.set_scale = set_scale              # a set-valued model's own noise scale (None: a point model)

    @classmethod
    def of(cls, m: Mapping) -> _Cycles:
        """From a model entry (``cycle_mse``, optionally ``cycle_nll`` and ``set_scale``)."""
        return cls(m["cycle_mse"], m.get("cycle_nll"), m.get("set_scale"))

    def cycle_mse(self) -> dict:
        return self._mse

    def cycle_nll(self) -> dict | None:
        return self._nll


def _effects(name: str) -> frozenset[str]:
    return frozenset(name.split("+"))


def _as_fitted(m: Mapping) -> float:
    """The model's log evidence at its fitted parameters (the linearised one where that is not given)."""
    ev = m.get("log_evidence_at_fit")
    return float(m["log_evidence"] if ev is None or not np.isfinite(ev) else ev)


def unsettled_rivals(models: Mapping[str, Mapping], verdict: str, skip: Collection[str] = ()) -> list[dict]:
    """The rivals of ``verdict`` that the log does not rule out (see module doc), most probable first.

    Parameters
    ----------
    models : mapping
        Model name (``"a"`` or ``"a+b"``) -> ``{"log_evidence": float, "plausible": bool,
        "closes_gap": bool, "cycle_mse": sequence or mapping of per-cycle held-out MSE}``, and
        optionally ``"log_evidence_at_fit"`` (the evidence compared when given, see module doc).
        Must hold ``verdict``.
    verdict : str
        The named model (a single, or ``"a+b"``).
    skip : collection of str, optional
        Models already named by another warning (compared as sets of effects).

    Returns
    -------
    list of dict
        ``{"model", "nats" (its log evidence minus the verdict's, both at the fitted parameters),
        "nats_linearised" (the same at the linearised modes), "heldout_p" (one-sided p that the
        verdict's per-cycle held-out MSE is lower), "heldout_better_p" (the same, that the rival's
        is lower), "heldout_better" (significant, Bonferroni over the rivals that close the gap),
        "adds" (the effects it adds to the verdict, or ``[]`` when it replaces it), "closes_gap"
        (its own estimate reaches ``CLOSE_FRACTION``)}``.
    """
    v = models[verdict]
    named = _effects(verdict)
    skipped = {_effects(s) for s in skip}
    ev_v, lin_v = _as_fitted(v), float(v["log_evidence"])
    rivals = {name: m for name, m in models.items() if not _effects(name) <= named and m.get("plausible")
              and m.get("log_evidence") is not None and np.isfinite(m["log_evidence"])
              and len(m.get("cycle_mse") or ())}
    n_closing = max(sum(bool(m.get("closes_gap")) for m in rivals.values()), 1)
    # each addition's prior odds against the verdict: 1 / the number of additions fitted (module doc)
    addition_nats = float(np.log(max(sum(named < _effects(n) for n in models), 1)))
    out = []
    for name, m in rivals.items():
        eff = _effects(name)
        if eff in skipped:
            continue
        nats = _as_fitted(m) - ev_v
        p = paired_heldout_test(_Cycles.of(m), _Cycles.of(v))   # type: ignore[arg-type]
        p_better = paired_heldout_test(_Cycles.of(v), _Cycles.of(m))  # type: ignore[arg-type]
        tied = p >= HELDOUT_ALPHA                   # the verdict does not beat it on held-out cycles
        if not (m.get("closes_gap") or tied):
            continue
        adds = sorted(eff - named) if named < eff else []
        # a set-valued rival (settled friction: a stick set holds almost any held-out pose) is not confirmed by
        # its held-out errors alone when it is decisively less probable
        better = (bool(m.get("closes_gap")) and p_better < HELDOUT_ALPHA / n_closing
                  and not (m.get("set_valued") and nats <= -EVIDENCE_MIN))
        # an addition needs the prior odds of one among m; a stick model's Laplace evidence (a likelihood with
        # kinks at every stick set's boundary) favours the larger model, so it cannot rank an addition at all:
        # held-out errors only (``better``)
        if not adds:
            more = nats > 0.0
        else:
            more = not (v.get("set_valued") or m.get("set_valued")) and nats > addition_nats
        if more or better or (not adds and nats > -EVIDENCE_MIN and tied):
            out.append({"model": name, "nats": nats, "nats_linearised": float(m["log_evidence"]) - lin_v,
                        "heldout_p": p, "adds": adds,
                        "closes_gap": bool(m.get("closes_gap")), "heldout_better_p": p_better,
                        "heldout_better": better})
    return sorted(out, key=lambda r: -r["nats"])


def inseparable_alternatives(models: Mapping[str, Mapping], selected: str, single_verdict: bool = True) -> list[dict]:
    """Detected effects the log cannot tell from ``selected`` (look-alikes), each with the route that lists it.

    An effect ``X`` is a look-alike of the selected effect ``V`` when it is detected and their parameter
    blocks are not separable on this log (Fisher block correlation above the limit,
    :mod:`csjm_opt.diagnose.selection.pairs`). It is listed (not ruled out) when

    * ``"evidence"``: its log evidence is within ``LEAD_NATS`` of ``V``'s (a leading hypothesis), or
    * ``"fit"`` (``V`` a single): it is a few-number model (not *flexible*,
      :func:`csjm_opt.diagnose.selection.decision.flexible`), plausible, closes the gap, ``V`` does not
      beat it on held-out cycles (one-sided paired test at ``HELDOUT_ALPHA``), and it fits the log about
      as well: its misfit ``chi^2`` (whitened training RSS over the diagnosis's noise variance) exceeds
      ``V``'s by less than ``2 EVIDENCE_MIN`` (a likelihood ratio below ``exp(EVIDENCE_MIN)``, not
      decisive). Two few-number models the log cannot separate, both fitting it as well, then differ in
      evidence only by the price of their parameters under the priors (the Occam factor: a 6-number
      link compliance pays about 10 nats more than a 3-number sensor gain for the same deflections),
      which the log cannot check; a lab must hear of both. A flexible rival (36 hole offsets, which fit
      any few-number verdict's log as well) is ruled out by parsimony when ``V`` explains the log as
      well (the rule's "parsimony that holds"), and is listed only by the evidence route.

    Parameters
    ----------
    models : mapping
        Effect name -> ``{"detected", "plausible", "closes_gap", "separable" (from ``selected``; the
        selected entry's own is ignored), "log_evidence", "chi2", "cycle_mse"}`` and optionally
        ``"flexible"`` (default False). Must hold ``selected``.
    selected : str
    single_verdict : bool, optional
        The verdict is ``selected`` alone (the ``"fit"`` route compares a single with the verdict's
        model, so it applies only then).

    Returns
    -------
    list of dict
        ``{"model", "route", "nats" (its evidence minus ``V``'s), "chi2_excess" (its chi^2 minus
        ``V``'s), "heldout_p" (one-sided p that ``V``'s held-out errors are lower)}``, in the order of
        ``models``.
    """
    v = models[selected]
    out = []
    for name, m in models.items():
        if name == selected or not m.get("detected") or m.get("separable", True):
            continue
        nats = float(m["log_evidence"]) - float(v["log_evidence"])
        excess = float(m.get("chi2", np.nan)) - float(v.get("chi2", np.nan))
        p = paired_heldout_test(_Cycles.of(m), _Cycles.of(v))   # type: ignore[arg-type]
        if nats >= -LEAD_NATS:
            route = "evidence"
        elif (single_verdict and not m.get("flexible") and m.get("plausible") and m.get("closes_gap")
              and p >= HELDOUT_ALPHA and excess < 2.0 * EVIDENCE_MIN):
            route = "fit"
        else:
            continue
        out.append({"model": name, "route": route, "nats": nats, "chi2_excess": excess, "heldout_p": p})
    return out


def alternatives_warnings(selected: str, found: list[dict]) -> list[str]:
    """The warnings that name the look-alikes of :func:`inseparable_alternatives` (none when there are none).

    Parameters
    ----------
    selected : str
    found : list of dict

    Returns
    -------
    list of str
    """
    def inseparable(names: str) -> str:
        return (f"{selected} is not separable on this log from {names} "
                "(detected too; Fisher block correlation above the separability limit)")

    out = []
    lead = [a["model"] for a in found if a["route"] == "evidence"]
    if lead:
        out.append(inseparable(", ".join(lead)))
    for a in (a for a in found if a["route"] == "fit"):
        out.append(f"{inseparable(a['model'])}: {a['model']} fits the log as well (chi^2 {a['chi2_excess']:+.1f} "
                   f"against {selected}'s, held-out p = {a['heldout_p']:.2f}) and has {-a['nats']:.1f} nats less "
                   "evidence only as the price of its parameters under their priors, which this log cannot check: "
                   f"the log does not single out {selected}; --suggest designs rows that separate them")
    return out


def rival_warning(verdict: str, rival: dict) -> str:
    """The warning that names one unsettled rival (:func:`unsettled_rivals`).

    Parameters
    ----------
    verdict : str
    rival : dict
        One entry of :func:`unsettled_rivals`.

    Returns
    -------
    str
    """
    closes = ("closes the gap" if rival.get("closes_gap", True) else
              f"closes the gap within the noise ({verdict} does not beat it on held-out cycles, "
              f"p = {rival['heldout_p']:.2f})")
    if rival.get("heldout_better") and rival["nats"] <= 0:
        what = (f"{' + '.join(rival['adds'])} may be present too" if rival["adds"] else
                f"the log does not single out {verdict}")
        return (f"{rival['model']} closes the gap with lower held-out errors than {verdict} (paired test "
                f"p = {rival['heldout_better_p']:.3f}) but {-rival['nats']:.1f} nats less evidence: the two "
                f"yardsticks disagree; {what}")
    if rival["adds"]:
        x = " + ".join(rival["adds"])
        return (f"{rival['model']} {closes} and has {rival['nats']:.1f} nats more evidence than {verdict} alone, but "
                f"{x} did not improve it significantly on held-out cycles: {x} may be present too; the log does not "
                "decide")
    if rival["nats"] > 0:
        return (f"{rival['model']} {closes} and has {rival['nats']:.1f} nats more evidence than {verdict}: "
                f"the log does not single out {verdict}")
    return (f"{rival['model']} closes the gap as well within the noise: its evidence is within {EVIDENCE_MIN:g} nats "
            f"of {verdict}'s ({rival['nats']:+.1f}) and {verdict} does not beat it on held-out cycles "
            f"(p = {rival['heldout_p']:.2f}): the log does not single out {verdict}")


def scored_models(evidence, singles: Mapping[str, CandidateScore], tests: Mapping[str, Mapping],
                  pairs: list, pair_scores: Mapping[tuple, CandidateScore],
                  noise_scale: float | None = None) -> dict[str, dict]:
    """The ``models`` argument of :func:`unsettled_rivals` from a diagnosis's scores.

    Parameters
    ----------
    evidence : callable
        ``CandidateScore -> log evidence`` (the diagnosis context's, one noise scale for all).
    singles : mapping
        Single effect -> its score.
    tests : mapping
        Single effect -> its test entry (``plausible``, ``closes_gap``).
    pairs : list of dict
        Pair entries (``effects``, ``fitted``, ``plausible``, ``closes_gap``).
    pair_scores : mapping
        ``(a, b)`` -> score of each fitted pair.
    noise_scale : float, optional
        The noise scale of ``evidence``, for each model's evidence at its fitted parameters
        (``log_evidence_at_fit``); by default the ``sigma`` of the context ``evidence`` is a method of.
        Without either, only the linearised evidence is given.

    Returns
    -------
    dict
    """
    if noise_scale is None:
        noise_scale = getattr(getattr(evidence, "__self__", None), "sigma", None)

    def at_fit(sc) -> float | None:
        fit = getattr(sc, "fit", None)
        return None if noise_scale is None or fit is None else evidence_of(sc, float(noise_scale), at_fit=True)

    out = {n: {"log_evidence": evidence(sc), "log_evidence_at_fit": at_fit(sc), "cycle_mse": sc.cycle_mse(),
               "cycle_nll": cycle_nll_of(sc), "plausible": bool(tests[n].get("plausible")),
               "closes_gap": bool(tests[n].get("closes_gap")),
               "set_valued": getattr(sc, "heldout_density", None) is not None,
               "set_scale": getattr(sc, "set_scale", None)}
           for n, sc in singles.items()}
    for p in pairs:
        key = tuple(p["effects"])
        if p.get("fitted") and key in pair_scores:
            sc = pair_scores[key]
            out["+".join(key)] = {"log_evidence": evidence(sc), "log_evidence_at_fit": at_fit(sc),
                                  "cycle_mse": sc.cycle_mse(), "cycle_nll": cycle_nll_of(sc),
                                  "set_valued": getattr(sc, "heldout_density", None) is not None,
                                  "set_scale": getattr(sc, "set_scale", None),
                                  "plausible": bool(p.get("plausible")), "closes_gap": bool(p.get("closes_gap"))}
    return out
