"""Probe: why does a correctly named single get a rival that adds a second effect?

For one confusion-study log (its ``id``), re-make the log, diagnose it, and for every unsettled
rival that adds an effect ``X`` to the verdict ``V``:

* the Laplace evidence of ``V`` and ``V + X`` split into its terms (whitened misfit at the fit and
  after the linearised MAP step, prior term, Occam log-det, half-normal truncation);
* ``X``'s fitted block against its prior mean, in posterior sds (Mahalanobis over the block, and
  its chi^2 p-value): is ``X`` away from "absent" by more than its uncertainty?
* the same two models fitted to the noise-free log (instrument noise off, whitened by the true
  noise), with the oracle's expected evidence: does the truth itself prefer ``V + X``?

Usage::

    python -m studies.rival_nested_probe.rival_nested_probe ID [ID ...] --out studies/out/mjcover_rival_probe.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def evidence_terms(fit, s: float) -> dict:
    """The terms of :func:`csjm_opt.diagnose.fitting.evidence.log_evidence` (same algebra, kept apart)."""
    from scipy.special import log_ndtr

    from csjm_opt.diagnose.fitting.evidence import TRUST_PRIOR_SDS, _prior

    scales = fit.model.scales
    n = fit.n_obs
    J, r0, x0 = fit.jac_x[:n], fit.res_x[:n], fit.theta / scales
    m, sd, side = _prior(fit)
    m, sd = m / scales, sd / scales
    s2 = s * s
    P = np.diag(1.0 / sd ** 2)
    A = J.T @ J / s2 + P
    b = J.T @ r0 / s2 + P @ (x0 - m)
    dx = -np.linalg.solve(A, b)
    far = np.abs(dx) > TRUST_PRIOR_SDS * sd
    if far.any():
        near = ~far
        dx = np.zeros_like(dx)
        if near.any():
            dx[near] = -np.linalg.solve(A[np.ix_(near, near)], b[near])
    r = r0 + J @ dx
    x = x0 + dx
    M = np.eye(len(x)) + (sd[:, None] * (J.T @ J) * sd[None, :]) / s2
    logdet = float(np.linalg.slogdet(M)[1])
    h = np.flatnonzero(side)
    post_cov = np.linalg.inv(A)
    trunc = 0.0
    if h.size:
        post_sd = np.sqrt(np.maximum(np.diag(post_cov)[h], 1e-300))
        trunc = float(np.sum(np.log(2.0) + log_ndtr(side[h] * (x[h] - m[h]) / post_sd)))
    return {"chi2_fit": float(r0 @ r0 / s2), "chi2_map": float(r @ r / s2),
            "prior": float(np.sum(((x - m) / sd) ** 2)), "logdet": logdet, "trunc": trunc,
            "far": int(far.sum()),
            "log_evidence": float(-0.5 * (r @ r / s2 + np.sum(((x - m) / sd) ** 2)) - 0.5 * logdet + trunc),
            "_x": x, "_m": m, "_sd": sd, "_cov": post_cov, "_side": side}


def block_z(fit, terms: dict, effect_index: int) -> dict:
    """``X``'s block (effect ``effect_index`` of ``fit.model``) against its prior mean, in posterior sds."""
    off = fit.model._offsets
    sl = slice(int(off[effect_index + 1]), int(off[effect_index + 2]))
    x, m, cov = terms["_x"][sl], terms["_m"][sl], terms["_cov"][sl, sl]
    d = x - m
    from scipy.stats import chi2

    maha2 = float(d @ np.linalg.solve(cov, d))
    prior_sd = terms["_sd"][sl]
    return {"maha2": maha2, "dim": len(d), "p_absent": float(chi2.sf(maha2, len(d))),
            "z_each": [float(v) for v in d / np.sqrt(np.diag(cov))],
            "post_over_prior_sd": [float(v) for v in np.sqrt(np.diag(cov)) / prior_sd],
            "params": dict(zip(fit.model.effects[effect_index].param_names,
                               [float(v) for v in (x * fit.model.scales[sl])]))}


def probe(job: dict) -> dict:
    """The probe record of one log (see module doc)."""
    import csjm_opt.diagnose.decision_rule as dec
    from csjm_opt.diagnose import diagnose, make_effect
    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.evidence import log_evidence
    from csjm_opt.diagnose.selection.scoring import fit_on_path
    from csjm_opt.measurement.instruments import InstrumentNoise
    from studies.diagnose_confusion.diagnose_confusion import _simulate, build_plant, job_seed
    from studies.diagnose_identifiability.diagnose_identifiability import expected_log_evidence

    t0 = time.perf_counter()
    ctxs: list = []
    orig = dec._Context.__init__

    def init(self, *a, **k):
        orig(self, *a, **k)
        ctxs.append(self)

    dec._Context.__init__ = init
    try:
        rig, noise, plant, _, _ = build_plant(job)
        log = _simulate(rig, job["cycles"], job_seed(job) + [7], plant, noise)
        d = diagnose(rig, log)
    finally:
        dec._Context.__init__ = orig
    s = ctxs[-1].sigma
    v = d.verdict
    final = d.final
    out = {"id": job["id"], "selected": d.selected, "secondary": d.secondary.effect,
           "sigma": float(s), "warnings": v.warnings, "rivals": []}
    tv = evidence_terms(final.fit, s)
    clean = None
    # every pair that adds one effect to the verdict and leads it by the linearised evidence (the rule before)
    named = [e.name for e in final.fit.model.effects]
    ev_v = log_evidence(final.fit, s)
    cands = []
    for key, sc in d.pair_scores.items():
        if set(named) < set(key) and log_evidence(sc.fit, s) > ev_v:
            cands.append({"model": "+".join(key), "adds": sorted(set(key) - set(named)),
                          "nats": log_evidence(sc.fit, s) - ev_v})
    for riv in cands:
        key = tuple(riv["model"].split("+"))
        sc = d.pair_scores[key]
        names = [e.name for e in sc.fit.model.effects]
        xi = names.index(riv["adds"][0])
        tp = evidence_terms(sc.fit, s)
        rec = {"model": riv["model"], "adds": riv["adds"], "nats": riv["nats"],
               "verdict_terms": {k: v_ for k, v_ in tv.items() if not k.startswith("_")},
               "rival_terms": {k: v_ for k, v_ in tp.items() if not k.startswith("_")},
               "x_block": block_z(sc.fit, tp, xi)}
        # the noise-free log, whitened by the true noise (scale 1): the same two models
        if clean is None:
            clean_log = _simulate(rig, job["cycles"], job_seed(job) + [7], plant, InstrumentNoise.none())
            clean = compute_residuals(rig, clean_log, noise)
        fits = {}
        for label, effs in (("verdict", [e.name for e in final.fit.model.effects]), ("rival", names)):
            model = AugmentedModel(rig, [make_effect(n, rig) for n in effs])
            f = fit_on_path(model, clean)[0]
            t = evidence_terms(f, 1.0)
            fits[label] = {"expected_log_evidence": expected_log_evidence(f), "chi2": float(f.rss),
                           **{k: v_ for k, v_ in t.items() if not k.startswith("_")}}
            if label == "rival":
                fits[label]["x_block"] = block_z(f, t, effs.index(riv["adds"][0]))
        fits["margin_rival_minus_verdict"] = fits["rival"]["expected_log_evidence"] - fits["verdict"][
            "expected_log_evidence"]
        rec["noise_free"] = fits
        out["rivals"].append(rec)
    out["seconds"] = time.perf_counter() - t0
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("ids", nargs="+")
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    for i in args.ids:
        plant, kind, effs, mult, rig, rep = i.split(":")
        job = {"id": i, "kind": kind, "effects": [] if effs == "-" else effs.split("+"), "multiple": float(mult),
               "rig": int(rig), "rep": int(rep), "cycles": 12, "plant": plant}
        rec = probe(job)
        with open(args.out, "a") as fh:
            fh.write(json.dumps(rec, default=float) + "\n")
        print(json.dumps(rec, default=float, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
