"""Identifiability oracle for the confusion study: can the log name its truth at all?

The confusion study (``diagnose_confusion.py``) counts a pair as *separable* when the tool's
Fisher-block correlation of the two TRUE effects is below the limit. A pair can be separable
from each other and still be mimicked by a third model of the vocabulary (hole offsets + sensor
bias by sensor bias + mass/COM). The statistically right ground truth is identifiability
against the whole vocabulary, which this oracle measures for each study log:

1. the same plant, rig, design and seed as the study log, with the instrument noise OFF
   (the noise-free truth log);
2. every model of the vocabulary (the null model, each single, each pair; friction's law and
   memory chosen per model by the evidence of its fit, as the diagnosis does) fitted to it, whitened with the log's TRUE
   instrument noise (so the noise scale is 1);
3. each model's *expected* log evidence over the noise, ``log Z(noise-free) + p_eff / 2``
   (:func:`csjm_opt.diagnose.fitting.evidence.effective_parameters`; the ``-n/2`` shared by all models
   dropped): the noise-free misfit, the Laplace Occam terms, and the noise a model can follow;
4. the truth's expected margin over its best rival (every other model of the vocabulary).

A log whose expected margin is below ``LEAD_NATS`` (the decision's lead,
:mod:`csjm_opt.diagnose.decision_rule`) does not identify its truth decisively: no method can
be expected to name it right from that log, the rule or the priors notwithstanding. The oracle
is the study's, not the tool's: it knows the noise and the plant, the diagnosis never does.

Usage::

    python -m studies.diagnose_identifiability.diagnose_identifiability \
        --records studies/diagnose_confusion/diagnose_confusion_pairs.jsonl \
        --out studies/diagnose_identifiability [--kinds pair] [--plants quasistatic]
    python -m studies.diagnose_identifiability.diagnose_identifiability \
        --out studies/diagnose_identifiability --summarise \
        --records studies/diagnose_confusion_pairs2.jsonl

Results: one JSON line per log in ``OUT.jsonl`` (resumable); with ``--records`` the summary
joins them with the confusion records (same log ``id``) and reports the pair figures under both
definitions (Fisher-block separability of the true pair; identifiability against the vocabulary).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

from studies._runner import finished, read_records, run_and_append  # noqa: E402


def expected_log_evidence(fit) -> float:
    """Expected log evidence over the noise (noise scale 1, ``-n/2`` dropped)."""
    from csjm_opt.diagnose.fitting.evidence import effective_parameters, log_evidence

    return float(log_evidence(fit, 1.0) + 0.5 * effective_parameters(fit, 1.0))


def oracle(job: dict) -> dict:
    """The oracle record of one confusion-study log (see module doc)."""
    from csjm_opt.errors import CsjmError

    try:
        return _oracle(job)
    except (CsjmError, np.linalg.LinAlgError) as exc:
        return {"id": job["id"], "error": f"{type(exc).__name__}: {exc}"}


def _oracle(job: dict) -> dict:
    from csjm_opt.diagnose import EFFECTS, make_effect
    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.evidence import effective_parameters
    from csjm_opt.diagnose.fitting.gauss_newton import fit_model
    from csjm_opt.diagnose.selection.decision import VARIANTS
    from csjm_opt.diagnose.selection.scoring import fit_on_path
    from csjm_opt.measurement.instruments import InstrumentNoise
    from studies.diagnose_confusion.diagnose_confusion import _simulate, build_plant, job_seed, truth

    t0 = time.perf_counter()
    rig, noise, plant, _, _ = build_plant(job)
    clean = _simulate(rig, job["cycles"], job_seed(job) + [7], plant, InstrumentNoise.none())
    table = compute_residuals(rig, clean, noise)          # whitened by the TRUE noise: scale 1
    names = list(EFFECTS)
    models = [()] + [(n,) for n in names] + list(itertools.combinations(names, 2))
    ev: dict[str, float] = {}
    chi2: dict[str, float] = {}
    peff: dict[str, float] = {}
    chosen: dict[str, dict] = {}
    with np.errstate(all="ignore"):
        for m in models:
            key = "+".join(m) or "nominal_refit"
            # every variant of a variant effect (friction's law and memory), the best one kept: per model
            varied = [n for n in m if VARIANTS.get(n)]
            best = None
            for opt in (VARIANTS[varied[0]] if varied else [{}]):
                try:
                    model = AugmentedModel(rig, [make_effect(n, rig, **(opt if n in varied else {})) for n in m])
                    f = fit_model(model, table) if varied else fit_on_path(model, table)[0]
                except (np.linalg.LinAlgError, FloatingPointError) as exc:
                    print(f"{job['id']}: {key} {opt} failed: {exc}", file=sys.stderr)
                    continue
                e = expected_log_evidence(f)
                if best is None or e > best[0]:
                    best = (e, f, opt)
            if best is not None and varied:          # the chosen variant along its own predicted path
                f = fit_on_path(best[1].model, table)[0]
                best = (expected_log_evidence(f), f, best[2])
            if best is None:
                ev[key] = float("nan")
                continue
            ev[key], f, chosen[key] = best[0], best[1], best[2]
            chi2[key] = float(f.rss)
            peff[key] = effective_parameters(f, 1.0)
    if job["kind"] == "outside":       # no true model in the vocabulary: how well can the best one mimic it?
        best = max((k for k in ev if np.isfinite(ev[k])), key=ev.get)
        return {"id": job["id"], "kind": job["kind"], "effects": job["effects"], "rig": job["rig"],
                "plant": job.get("plant", "quasistatic"), "truth": sorted(truth(job)), "best_model": best,
                "best_chi2": chi2[best], "best_p_eff": peff[best],
                "null_chi2": chi2.get("nominal_refit"), "rows": len(clean), "log_evidence": ev, "chi2": chi2,
                "p_eff": peff, "variants": {k: v for k, v in chosen.items() if v},
                "seconds": time.perf_counter() - t0}
    true = sorted(truth(job), key=names.index)
    tkey = "+".join(true) or "nominal_refit"
    rivals = {k: v for k, v in ev.items() if k != tkey and np.isfinite(v)}
    best_rival = max(rivals, key=rivals.get)
    return {"id": job["id"], "kind": job["kind"], "effects": job["effects"], "rig": job["rig"],
            "plant": job.get("plant", "quasistatic"), "truth": true, "truth_model": tkey,
            "margin_nats": float(ev[tkey] - rivals[best_rival]), "best_rival": best_rival,
            "truth_chi2": chi2.get(tkey), "rival_chi2": chi2.get(best_rival), "rows": len(clean),
            "log_evidence": ev, "chi2": chi2, "p_eff": peff, "variants": {k: v for k, v in chosen.items() if v},
            "seconds": time.perf_counter() - t0}


def summarise(oracles: dict[str, dict], records: list[dict], lead: float) -> str:
    """Pair figures under both definitions of the ground truth (markdown)."""
    pairs = [r for r in records if r["kind"] == "pair" and "truth" in r and r["id"] in oracles
             and "margin_nats" in oracles[r["id"]]]
    both = lambda r: {r["selected"], r["secondary"]} == set(r["truth"])  # noqa: E731

    def rate(rs, ok):
        return f"{sum(map(ok, rs))}/{len(rs)} ({sum(map(ok, rs)) / len(rs):.0%})" if rs else "-"

    ident = [r for r in pairs if oracles[r["id"]]["margin_nats"] >= lead]
    ahead = [r for r in pairs if oracles[r["id"]]["margin_nats"] > 0]
    sep = [r for r in pairs if r.get("pair_separable")]
    lines = [f"Pair logs with an oracle record: {len(pairs)}.", "",
             "| ground truth: the pair counts when ... | pairs | both named |", "|---|---|---|",
             f"| (old) the Fisher-block correlation of the two true effects is below the limit | {len(sep)} | "
             f"{rate(sep, both)} |",
             f"| (new) its expected evidence margin over every other model of the vocabulary is >= LEAD_NATS = "
             f"{lead:g} | {len(ident)} | {rate(ident, both)} |",
             f"| the same, margin > 0 (the truth is the most probable model in expectation) | {len(ahead)} | "
             f"{rate(ahead, both)} |",
             f"| old and new both | {len([r for r in ident if r in sep])} | "
             f"{rate([r for r in ident if r in sep], both)} |",
             f"| all pairs | {len(pairs)} | {rate(pairs, both)} |", "",
             "| pair | rig | separable (old) | margin (nats) | best rival | verdict |", "|---|---|---|---|---|---|"]
    for r in sorted(pairs, key=lambda r: (r["effects"], r["rig"])):
        o = oracles[r["id"]]
        lines.append(f"| {'+'.join(r['effects'])} | {r['rig']} | {r.get('pair_separable')} | "
                     f"{o['margin_nats']:.1f} | {o['best_rival']} | {r['selected']} + {r['secondary']} |")
    out = [r for r in records if r["kind"] == "outside" and r["id"] in oracles and "best_chi2" in oracles[r["id"]]]
    if out:
        lines += ["", "Outside the vocabulary: the vocabulary model with the highest expected evidence on the "
                  "noise-free log, and its whitened misfit there (chi^2 with unit noise: the non-centrality a test "
                  "of the remaining residual can use). Even an ideal test that knew the misfit's direction "
                  "detects it at 1 % with probability Phi(sqrt(chi^2) - 2.33) on one log (column 'ideal power'): "
                  "where that is small, no rule can tell the effect from the named model on that log. A test that does "
                  "not know the direction, such as the residual signature (3 regressors per cycle), has at most "
                  "the power of a chi^2 test with 3 x cycles degrees of freedom and that non-centrality "
                  "(column 'signature power', an upper bound: the misfit need not lie in those regressors).", "",
                  "| effect | rig | best vocabulary model | its misfit chi^2 | ideal power | signature power | "
                  "null model's chi^2 | verdict |", "|---|---|---|---|---|---|---|---|"]
        for r in sorted(out, key=lambda r: (r["effects"], r["rig"])):
            o = oracles[r["id"]]
            lines.append(f"| {'+'.join(r['effects'])} | {r['rig']} | {o['best_model']} | {o['best_chi2']:.1f} | "
                         f"{_ideal_power(o['best_chi2']):.2f} | {_chi2_power(o['best_chi2'], 3 * r['cycles']):.2f} | "
                         f"{o['null_chi2']:.1f} | "
                         f"{r['selected']} + {r['secondary']}"
                         f"{' [warned]' if r['warnings'] else ''} |")
    return "\n".join(lines) + "\n"


def _ideal_power(chi2: float, z: float = 2.326) -> float:
    """Power at 1 % (one-sided) of the test along a known direction with non-centrality ``chi2``."""
    from math import erf, sqrt

    return 0.5 * (1.0 + erf((sqrt(max(chi2, 0.0)) - z) / sqrt(2.0)))


def _chi2_power(chi2: float, dof: int, alpha: float = 0.01) -> float:
    """Power at ``alpha`` of a chi^2 test with ``dof`` degrees of freedom and non-centrality ``chi2``."""
    from scipy.stats import chi2 as chi2_dist
    from scipy.stats import ncx2

    return float(ncx2.sf(chi2_dist.isf(alpha, dof), dof, max(chi2, 1e-12)))


def main(argv: list[str] | None = None) -> int:
    from csjm_opt.diagnose.selection.decision import LEAD_NATS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", nargs="+", default=[], help="confusion-study JSONL files whose logs to judge")
    ap.add_argument("--kinds", nargs="+", default=["pair"])
    ap.add_argument("--plants", nargs="+", default=["quasistatic", "mujoco"])
    ap.add_argument("--only", nargs="+", default=None, help="only these log ids")
    ap.add_argument("--out", default="studies/diagnose_identifiability/diagnose_identifiability")
    ap.add_argument("--summarise", action="store_true", help="only summarise")
    ap.add_argument("--limit", type=int, default=None)
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    path = out.with_suffix(".jsonl")
    done = read_records(path)
    records: dict[str, dict] = {}
    for f in args.records:
        records.update({k: r for k, r in read_records(Path(f)).items() if "truth" in r})
    if not args.summarise:
        keys = ("id", "kind", "effects", "multiple", "rig", "rep", "cycles", "plant", "scatter_mm")
        todo = [{k: r[k] for k in keys if k in r} for r in records.values()
                if r["id"] not in done and r["kind"] in args.kinds and r.get("plant", "quasistatic") in args.plants
                and (args.only is None or r["id"] in args.only)]
        todo = todo[:args.limit] if args.limit else todo
        run_and_append(map(oracle, todo), len(todo), path, done, "identifiability oracle", args.no_progress)
    oracles = {r["id"]: r for r in finished(done, path, "logs")}
    text = summarise(oracles, list(records.values()), LEAD_NATS)
    out.with_suffix(".md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
