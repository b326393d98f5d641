"""Confusion study of ``csjm diagnose`` over random rigs (issue 11).

Logs are simulated by the testbed on random rigs (:func:`csjm_opt.testbed.random_rig`:
geometry, stiffness 2,000-10,000 N/m, mass, centre of mass, tension range and
instrument noise drawn from stated ranges, each rig validated) and diagnosed with
the default instrument model, as a new user would. Kinds of log:

* ``none``: effect-free;
* ``single``: one vocabulary effect at 1.5x, 3x, 6x, 10x the noise floor;
* ``pair``: two vocabulary effects at 3x each;
* ``outside``: an effect the vocabulary has no model for (eyelet radius, sensor
  drift, drum slip) at 3x and 6x.

Severity in noise-floor multiples: the effect is injected once at severity 1 on a
noise-free copy of the experiment; the RMS held-in pose residual there of the nominal
model refitted with its nuisance (common pretension offset; what that absorbs is no
gap), over the instrument noise floor, gives the scale, and the severity is set to reach the
wanted multiple (the injected magnitudes are linear in severity for a given draw). An effect
is never injected beyond :data:`csjm_opt.testbed.injection.PLAUSIBLE_SEVERITY` (the magnitude
a real rig can show: the diagnosis's prior ranges); where the multiple needs more, the
log's instrument noise is lowered by the missing factor instead (``noise_factor`` in the
record).

Usage::

    python -m studies.diagnose_confusion.diagnose_confusion [--rigs 10] [--none-per-rig 10] [--cycles 12]
        [--workers 2 | --scheduler HOST:PORT | --dask] [--out studies/diagnose_confusion/diagnose_confusion]
        [--summarise]

Results are appended to ``OUT.jsonl`` as logs finish (a rerun skips finished logs:
resumable); ``OUT.md`` gets the tables and ``OUT.png`` the figure.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from csjm_opt._fileio import atomic_write_text  # noqa: E402
from studies._runner import finished, pool_stream, read_records, run_and_append  # noqa: E402

MULTIPLES = (1.5, 3.0, 6.0, 10.0)
OUTSIDE_MULTIPLES = (3.0, 6.0)


def jobs(n_rigs: int, none_per_rig: int, cycles: int, pair_rigs: int, plant: str = "quasistatic",
         first_rig: int = 0, loading: str = "ramp", static_friction_ratio: float = 1.0) -> list[dict]:
    """The study's logs, most informative first (a partial run still answers the main questions).

    Rigs ``first_rig, ..., first_rig + n_rigs - 1`` (a check set of rigs not looked at: ``first_rig=10``).
    ``loading="step"`` hangs every row's load at once on the plant, with static friction
    ``static_friction_ratio`` times the sliding one (the jobs' ids say so; ramped jobs keep theirs).
    """
    from csjm_opt.testbed import EFFECT_NAMES, OUTSIDE_NAMES, VARIANT_NAMES

    out: list[dict] = []
    singles = EFFECT_NAMES + tuple(VARIANT_NAMES)
    step = {} if loading == "ramp" else {"loading": loading, "static_friction_ratio": float(static_friction_ratio)}
    tag = "" if loading == "ramp" else f":{loading}{float(static_friction_ratio):g}"

    def add(kind, effects, mult, rig, rep=0):
        out.append({"id": f"{plant}:{kind}:{'+'.join(effects) or '-'}:{mult:g}:{rig}:{rep}{tag}", "kind": kind,
                    "effects": list(effects), "multiple": mult, "rig": rig, "rep": rep, "cycles": cycles,
                    "plant": plant, **step})

    rigs = range(first_rig, first_rig + n_rigs)
    for rig in rigs:
        for rep in range(none_per_rig):
            add("none", [], 0.0, rig, rep)
    for rig in rigs:
        for e in singles:
            add("single", [e], 3.0, rig)
        for e in OUTSIDE_NAMES:
            add("outside", [e], 3.0, rig)
    for i, pair in enumerate(itertools.combinations(EFFECT_NAMES, 2)):
        for r in range(pair_rigs):
            add("pair", list(pair), 3.0, first_rig + (i + r * 7) % n_rigs)
    for rig in rigs:
        for e in singles:
            add("single", [e], 10.0, rig)
    for rig in rigs:
        for e in singles:
            add("single", [e], 1.5, rig)
            add("single", [e], 6.0, rig)
        for e in OUTSIDE_NAMES:
            add("outside", [e], 6.0, rig)
    return out


def run_one(job: dict) -> dict:
    """Simulate one log on its random rig and diagnose it (a worker's task); failures are recorded."""
    from csjm_opt.errors import CsjmError

    try:
        return _run_one(job)
    except CsjmError as exc:
        return {**job, "error": f"{type(exc).__name__}: {exc}"}


#: Testbed effects of its ``outside`` list that the vocabulary now models, and their right name.
MODELLED_OUTSIDE = {"guide_radius": "guide_radius", "eyelet_radius": "guide_radius"}  # the old name too
NOT_NAMED = ("none", "unexplained")


def truth(job: dict) -> set[str]:
    """The vocabulary names a diagnosis should give the job's injected effects."""
    from csjm_opt.testbed import VARIANT_NAMES

    return {MODELLED_OUTSIDE.get(e, VARIANT_NAMES.get(e, e)) for e in job["effects"]}


def study_plant(job: dict, plant):
    """The job's plant: the testbed's quasi-static ``plant``, or the MuJoCo plant with the same effects.

    Loaded as the job says (``loading``, ``static_friction_ratio``; default ramped, one friction bound).
    """
    import dataclasses

    loading = {"loading": job.get("loading", "ramp"), "static_friction_ratio": job.get("static_friction_ratio", 1.0)}
    if job.get("plant", "quasistatic") != "mujoco":
        return dataclasses.replace(plant, **loading) if loading["loading"] != "ramp" else plant
    from csjm_opt.testbed.mujoco.plant import as_mujoco

    return as_mujoco(plant, **loading)


def build_plant(job: dict):
    """``(rig, noise, plant, severities, noise_factor)`` of one study log (deterministic in ``job``)."""
    from csjm_opt.diagnose.data.residuals import compute_residuals, pose_residuals, rms
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.gauss_newton import fit_model
    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.testbed import inject, make_plant, random_rig
    from csjm_opt.testbed.injection import PLAUSIBLE_SEVERITY
    from csjm_opt.testbed.rigs import RigRanges

    ranges = RigRanges(hole_scatter_m=job.get("scatter_mm", 0.0) / 1000.0)
    rig, noise = random_rig(np.random.default_rng([1234, job["rig"]]), ranges)
    seed = job_seed(job)
    severities = []
    for k, e in enumerate(job["effects"]):       # calibrate each effect to its multiple of the floor
        plant = make_plant(rig, e, 1.0, np.random.default_rng(seed + [k]))
        clean = _simulate(rig, 4, seed + [99], plant, InstrumentNoise.none())
        t = compute_residuals(rig, clean, noise)
        null = AugmentedModel(rig)            # what the nuisance (pretension) cannot absorb
        sol = null.predict_poses(t.rows, fit_model(null, t).theta, t.R_meas)
        gap1 = rms(pose_residuals(sol.R, t.R_meas))
        severities.append(job["multiple"] * t.instrument_floor_rad / max(gap1, 1e-12))
    # an effect stays within its plausible range; a larger multiple comes from a better instrument
    factor = min([1.0] + [PLAUSIBLE_SEVERITY[e] / s for e, s in zip(job["effects"], severities)
                          if e in PLAUSIBLE_SEVERITY])
    severities = [s * factor for s in severities]
    noise = InstrumentNoise(tuple(factor * v for v in noise.tau_sigma_Nm), factor * noise.angle_sigma_rad)
    plant = make_plant(rig, None, 1.0, np.random.default_rng(0))
    for k, (e, s) in enumerate(zip(job["effects"], severities)):
        plant = inject(plant, e, s, np.random.default_rng(seed + [k]))
    return rig, noise, study_plant(job, plant), severities, factor


#: Effects renamed since their records were made: seeded by the old name, so that a log is remade as it was.
SEED_NAMES = {"guide_radius": "eyelet_radius"}


def job_seed(job: dict) -> list[int]:
    return [job["rig"], job["rep"], int(10 * job["multiple"]),
            *[hash_name(SEED_NAMES.get(e, e)) for e in job["effects"]]]


def simulate_job(job: dict):
    """``(rig, noise, log, severities, noise_factor)`` of one study log (deterministic in ``job``)."""
    rig, noise, plant, severities, factor = build_plant(job)
    log = _simulate(rig, job["cycles"], job_seed(job) + [7], plant, noise)
    return rig, noise, log, severities, factor


def _simulate(rig, cycles: int, seed: list[int], plant, noise):
    """The experiment on ``plant``; a design the effect drives into slack is redesigned, as a lab would."""
    from csjm_opt.errors import NoEquilibrium
    from csjm_opt.testbed import simulate_experiment

    for attempt in range(3):
        try:
            return simulate_experiment(rig, cycles, np.random.default_rng(seed + [attempt]), effect=plant,
                                       noise=noise)
        except NoEquilibrium:
            pass
    return simulate_experiment(rig, cycles, np.random.default_rng(seed + [3]), effect=plant, noise=noise)


def _run_one(job: dict) -> dict:
    from csjm_opt.diagnose import diagnose

    t0 = time.perf_counter()
    rig, noise, log, severities, factor = simulate_job(job)
    t1 = time.perf_counter()
    d = diagnose(rig, log)
    j = d.as_json()
    sel_cand = next((c for c in j["candidates"] if c["effect"] == j["selected"]), None)
    return {**job, "truth": sorted(truth(job)), "severities": severities, "noise_factor": factor, "rows": len(log),
            "selected": j["selected"],
            "secondary": j["secondary"]["effect"], "secondary_separable": j["secondary"].get("separable"),
            "pair_separable": next((p["separable"] for p in j["pairs"] if set(p["effects"]) == truth(job)),
                                   None) if job["kind"] == "pair" else None,
            "gap": j["gap"], "noise_floor_rad": j["noise_floor_rad"],
            "warnings": j["verdict"]["warnings"], "alternatives": j["verdict"].get("alternatives", []),
            "secondary_alternatives": j["verdict"].get("secondary_alternatives", []),
            "selected_plausible": sel_cand["plausible"] if sel_cand else None,
            "true_plausible": all(c.get("plausible", False) for c in j["candidates"] if c["effect"] in truth(job)),
            "remaining_p": j["remaining_signature"]["p_value"], "gap_signature_p": j["gap_signature"]["p_value"],
            "detected": [c["effect"] for c in j["candidates"] if c.get("significant")],
            "left_out_rows": [[r["log"], r["sample"], r["reason"]] for r in j["left_out_rows"]],
            "outlier_ratio_max": j["outlier_ratio_max"],
            "models": model_summary(j, d),
            "seconds_diagnose": time.perf_counter() - t1, "seconds": time.perf_counter() - t0}


def model_summary(j: dict, d=None) -> dict:
    """Per single and fitted pair: what the verdict's rules read (evidence, tests, closure, separability).

    Kept in each record so that a warning rule can be evaluated again on stored logs; with the
    diagnosis ``d``, also each model's per-cycle held-out MSE (for paired held-out tests between models).
    """
    keys = ("log_evidence", "significant", "plausible", "closes_gap", "fraction_explained", "p_value",
            "p_value_vs_first", "improvement_rad", "separable", "max_correlation", "evidence_gain",
            "supported_by_evidence", "significant_heldout", "tested_against", "fitted", "residual_signature_p")
    out = {c["effect"]: {k: c.get(k) for k in keys if k in c} for c in j["candidates"]}
    out.update({"+".join(p["effects"]): {k: p.get(k) for k in keys if k in p} for p in j["pairs"]})
    if d is not None:
        scores = [("nominal_refit", d.baseline), *d.candidates.items(),
                  *(("+".join(k), sc) for k, sc in d.pair_scores.items())]
        for name, sc in scores:
            out.setdefault(name, {})["cycle_mse"] = [v for _, v in sorted(sc.cycle_mse().items())]
    return out


def hash_name(name: str) -> int:
    return sum((i + 1) * ord(ch) for i, ch in enumerate(name))


def stream(todo: list[dict], workers: int, scheduler: str | None, use_dask: bool) -> Iterator[dict]:
    """Records as logs finish: a process pool, or a Dask cluster (``csjm sweep``'s options)."""
    if scheduler or use_dask:
        from distributed import Client, LocalCluster, as_completed

        cluster = None if scheduler else LocalCluster(n_workers=workers, threads_per_worker=1,
                                                      dashboard_address=None)
        client = Client(scheduler) if scheduler else Client(cluster)
        try:
            futures = [client.submit(run_one, j, pure=False) for j in todo]
            for f in as_completed(futures):
                yield f.result()
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
        return
    yield from pool_stream(run_one, todo, workers)


def _rate(rs: list[dict], ok: Callable[[dict], bool]) -> str:
    return f"{sum(map(ok, rs))}/{len(rs)} ({sum(map(ok, rs)) / len(rs):.0%})" if rs else "-"


def _pair_or_alternative(r: dict) -> bool:
    """Both named, or the first named and the other among the second's non-separable alternatives."""
    named = {r["selected"], r["secondary"], *r.get("secondary_alternatives", [])}
    return r["selected"] in r["truth"] and set(r["truth"]) <= named


def summarise(records: list[dict]) -> str:
    """Markdown tables: the targets of issue 11, the confusion matrix, gap closure."""
    from csjm_opt.diagnose import VOCABULARY

    named = [v for v in VOCABULARY]
    none = [r for r in records if r["kind"] == "none"]
    lines = [f"Logs: {len(records)} on {len({r['rig'] for r in records})} random rigs, "
             f"{records[0]['rows']} rows each.", "",
             "| check | target | measured |", "|---|---|---|",
             f"| effect-free logs -> `none` | >= 95 % | {_rate(none, lambda r: r['selected'] == 'none')} |",
             f"| effect-free logs: false alarm (any effect named) | <= alpha = 1 % | "
             f"{_rate(none, lambda r: r['selected'] not in ('none', 'unexplained'))} |",
             f"| effect-free logs: remaining-signature test significant | about alpha = 1 % | "
             f"{_rate(none, lambda r: (r['remaining_p'] or 1) < 0.01)} |"]
    inr = [r for r in records if r["kind"] == "single" and r["multiple"] >= 3.0 and r.get("true_plausible")]
    lines.append(f"| single effects >= 3x floor whose true fit is within the prior ranges: named right | >= 95 % | "
                 f"{_rate(inr, lambda r: r['selected'] == r['truth'][0])} |")
    inr = [r for r in inr if r["truth"][0] != "hole_offsets"]
    lines.append(f"| the same without hole_offsets | >= 95 % | "
                 f"{_rate(inr, lambda r: r['selected'] == r['truth'][0])} |")
    right = [r for r in records if r["kind"] == "single" and r["selected"] == r["truth"][0]]
    lines.append(f"| correctly named single effects: remaining-signature test significant | about alpha = 1 % | "
                 f"{_rate(right, lambda r: (r['remaining_p'] or 1) < 0.01)} |")
    for lo in (3.0, 1.5):
        s = [r for r in records if r["kind"] == "single" and r["multiple"] >= lo]
        lines.append(f"| single effects >= {lo:g}x floor named right | >= 95 % (at >= 3x) | "
                     f"{_rate(s, lambda r: r['selected'] == r['truth'][0])} |")
    s3 = [r for r in records if r["kind"] == "single" and r["multiple"] >= 3.0]
    lines.append(f"| single effects >= 3x floor: named right, or named as a non-separable alternative | - | "
                 f"{_rate(s3, lambda r: r['truth'][0] in [r['selected'], *r.get('alternatives', [])])} |")
    pairs = [r for r in records if r["kind"] == "pair"]
    sep = [r for r in pairs if r["pair_separable"]]
    lines += [f"| pairs at 3x each, separable on the log: both named | >= 80 % | "
              f"{_rate(sep, lambda r: {r['selected'], r['secondary']} == set(r['truth']))} |",
              f"| pairs at 3x each, separable: both named, or the second named with the true one as a "
              f"non-separable alternative | - | "
              f"{_rate(sep, _pair_or_alternative)} |",
              f"| pairs at 3x each, not separable: reported so (warning or one named) | all | "
              f"{_rate([r for r in pairs if not r['pair_separable']], lambda r: r['pair_separable'] is False)} |"]
    modelled = [r for r in records if r["kind"] == "outside" and set(r["effects"]) & set(MODELLED_OUTSIDE)]
    out = [r for r in records if r["kind"] == "outside" and r not in modelled]
    lines += [f"| eyelet radius (now in the vocabulary as `guide_radius`): named `guide_radius` | - | "
              f"{_rate(modelled, lambda r: r['selected'] == 'guide_radius')} |",
              f"| eyelet radius: another name without a warning | never | "
              f"{_rate(modelled, lambda r: r['selected'] not in (*NOT_NAMED, 'guide_radius') and not r['warnings'])} |"]
    # a warning that the named model is implausible, or may stand in for an effect outside the vocabulary
    # (the residual-structure warning and the flexibility warning both say so)
    honest = lambda r: r["selected"] == "unexplained" or any(  # noqa: E731
        "implausible" in w or "outside the vocabulary" in w for w in r["warnings"])
    lines.append(f"| outside the vocabulary: `unexplained`, or a warning that the named model is implausible "
                 f"or leaves structure | >= 80 % | "
                 f"{_rate(out, honest)} |")
    coul = [r for r in records if r["kind"] == "single" and r["effects"] == ["coulomb_friction"] and r["multiple"] >= 3]
    lines.append(f"| Coulomb cable friction (>= 3x) named `friction` | >= 95 % | "
                 f"{_rate(coul, lambda r: r['selected'] == 'friction')} |")
    clear = [r for r in records if (r["kind"] == "none" and r["selected"] == "none")
             or (r["kind"] == "single" and r["multiple"] >= 3 and r["selected"] == r["truth"][0])]
    lines.append(f"| warnings on effect-free logs | rare | {_rate(none, lambda r: bool(r['warnings']))} |")
    lines.append(f"| warnings on correctly named single effects (>= 3x) and `none` verdicts | rare | "
                 f"{_rate([r for r in clear if r['kind'] == 'single'], lambda r: bool(r['warnings']))} |")
    lines.append(f"| outside the vocabulary: a confident wrong name with the gap closed | never | "
                 f"{_rate(out, lambda r: r['selected'] not in ('none', 'unexplained') and not r['warnings'])} |")
    lines.append(f"| outside the vocabulary: called `none` (an effect at >= 3x the floor missed) | - | "
                 f"{_rate(out, lambda r: r['selected'] == 'none')} |")
    nm = [r for r in records if r["selected"] not in ("none", "unexplained")]
    lines.append(f"| named verdicts closing >= 80 % of the systematic gap | all | "
                 f"{_rate(nm, lambda r: (r['gap']['fraction_explained'] or 0) >= 0.8)} |")
    lines += ["", "Confusion (rows: injected; columns: selected):", "",
              "| injected | " + " | ".join(named) + " |", "|---" * (len(named) + 1) + "|"]
    keys = sorted({(r["kind"], "+".join(r["effects"]) or "none") for r in records if r["kind"] != "pair"})
    for kind, eff in keys:
        rs = [r for r in records if r["kind"] == kind and ("+".join(r["effects"]) or "none") == eff]
        lines.append(f"| {eff} | " + " | ".join(str(sum(r['selected'] == v for r in rs)) for v in named) + " |")
    lines += ["", "Single effects by severity (named right / logs; median fraction of the systematic gap closed "
              "when named):", "", "| effect | " + " | ".join(f"{m:g}x" for m in MULTIPLES) + " |",
              "|---" * (len(MULTIPLES) + 1) + "|"]
    for eff in sorted({r["effects"][0] for r in records if r["kind"] == "single"}):
        cells = []
        for m in MULTIPLES:
            rs = [r for r in records if r["kind"] == "single" and r["effects"][0] == eff and r["multiple"] == m]
            ok = [r for r in rs if r["selected"] == r["truth"][0]]
            fr = np.median([r["gap"]["fraction_explained"] for r in ok]) if ok else float("nan")
            cells.append(f"{len(ok)}/{len(rs)} ({fr:.2f})" if rs else "-")
        lines.append(f"| {eff} | " + " | ".join(cells) + " |")
    if pairs:
        lines += ["", "Pairs at 3x each:", "", "| pair | separable | verdict |", "|---|---|---|"]
        for r in sorted(pairs, key=lambda r: r["id"]):
            lines.append(f"| {'+'.join(r['effects'])} | {r['pair_separable']} | {r['selected']} + {r['secondary']} |")
    lowered = [r["noise_factor"] for r in records if r.get("noise_factor", 1.0) < 1.0]
    if lowered:
        lines += ["", f"{len(lowered)} logs reached their multiple with the instrument noise lowered (the effect "
                      f"capped at its plausible size): median noise factor {np.median(lowered):.2f}, "
                      f"smallest {min(lowered):.2f}."]
    ratios = [(max(r["outlier_ratio_max"].values()), r["id"]) for r in records if r.get("outlier_ratio_max")]
    if ratios:
        left = [r["id"] for r in records if any(x[2] == "gross_residual" for x in r.get("left_out_rows", []))]
        lines += ["", f"Rows left out as gross outliers: {len(left)} of {len(ratios)} logs"
                      + (f" ({', '.join(left[:5])})" if left else "")
                      + f"; the largest row outlier ratio of a log: {max(ratios)[0]:.2f} ({max(ratios)[1]})."]
    secs = [r["seconds_diagnose"] for r in records]
    lines += ["", f"Median diagnosis time per log (all singles and pairs): {np.median(secs):.1f} s."]
    return "\n".join(lines) + "\n"


def figure(records: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from csjm_opt.diagnose import VOCABULARY

    keys = sorted({"+".join(r["effects"]) or "none" for r in records if r["kind"] in ("none", "single", "outside")})
    if not keys:
        return
    M = np.array([[sum(1 for r in records if r["kind"] != "pair" and ("+".join(r["effects"]) or "none") == k
                       and r["selected"] == v) for v in VOCABULARY] for k in keys], float)
    M /= np.maximum(M.sum(axis=1, keepdims=True), 1)
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5))
    ax = axes[0]
    ax.imshow(M, cmap="Blues", vmin=0, vmax=1)
    ax.set_xticks(range(len(VOCABULARY)), VOCABULARY, rotation=60, ha="right")
    ax.set_yticks(range(len(keys)), keys)
    ax.set_xlabel("selected")
    ax.set_ylabel("injected")
    ax.set_title("share of logs")
    for i, j in zip(*np.nonzero(M)):
        ax.text(j, i, f"{M[i, j]:.2f}", ha="center", va="center", fontsize=7)
    ax = axes[1]
    for eff in sorted({r["effects"][0] for r in records if r["kind"] == "single"}):
        xs, ys = [], []
        for m in MULTIPLES:
            rs = [r for r in records if r["kind"] == "single" and r["effects"][0] == eff and r["multiple"] == m]
            if rs:
                xs.append(m)
                ys.append(np.mean([r["selected"] == r["truth"][0] for r in rs]))
        ax.plot(xs, ys, "o-", label=eff)
    ax.axhline(0.95, color="k", ls=":", lw=1)
    ax.set_xscale("log")
    ax.set_xlabel("systematic gap / noise floor")
    ax.set_ylabel("named right")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rigs", type=int, default=10)
    ap.add_argument("--none-per-rig", type=int, default=10)
    ap.add_argument("--first-rig", type=int, default=0,
                    help="first random rig (e.g. 10: a check set of rigs not used while developing)")
    ap.add_argument("--pair-rigs", type=int, default=2, help="rigs per pair of effects")
    ap.add_argument("--cycles", type=int, default=12, help="9 rows per cycle")
    ap.add_argument("--plants", nargs="+", default=["quasistatic"], choices=["quasistatic", "mujoco"],
                    help="plants to simulate on (the testbed's quasi-static plant, the MuJoCo plant)")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--scheduler", default=None, help="Dask scheduler address (as csjm sweep --scheduler)")
    ap.add_argument("--dask", action="store_true", help="a local Dask cluster instead of a process pool")
    ap.add_argument("--limit", type=int, default=None, help="stop after this many new logs")
    ap.add_argument("--multiples", nargs="+", type=float, default=None, help="only these severities")
    ap.add_argument("--only", nargs="+", default=None, help="only logs injecting these effects")
    ap.add_argument("--including", nargs="+", default=None,
                    help="only logs injecting all of these effects (e.g. every pair with friction)")
    ap.add_argument("--kinds", nargs="+", default=["none", "single", "pair", "outside"],
                    help="kinds of log to run (several runs may append to the same OUT.jsonl)")
    ap.add_argument("--loading", choices=["ramp", "step"], default="ramp",
                    help="how each row's load reaches the plant: ramped (default) or hung at once and settled "
                         "(csjm simulate --loading)")
    ap.add_argument("--static-friction-ratio", type=float, default=1.0,
                    help="static over sliding friction with --loading step (default 1)")
    ap.add_argument("--scatter-mm", type=float, default=0.0,
                    help="random rigs with every hole moved off its hexagon by up to this much (no symmetry)")
    ap.add_argument("--out", default="studies/diagnose_confusion/diagnose_confusion")
    ap.add_argument("--summarise", action="store_true", help="only summarise OUT.jsonl")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    path = out.with_suffix(".jsonl")
    done = read_records(path)
    if not args.summarise:
        per_plant = [jobs(args.rigs, args.none_per_rig, args.cycles, args.pair_rigs, plant, args.first_rig,
                          args.loading, args.static_friction_ratio) for plant in args.plants]
        # the plants' logs interleaved: a partial run answers for every plant
        todo = [j for group in itertools.zip_longest(*per_plant) for j in group
                if j is not None and j["id"] not in done and j["kind"] in args.kinds
                and (args.multiples is None or j["multiple"] in args.multiples)
                and (args.only is None or set(j["effects"]) <= set(args.only))
                and (args.including is None or set(args.including) <= set(j["effects"]))]
        if args.scatter_mm > 0.0:
            todo = [{**j, "scatter_mm": args.scatter_mm, "id": f"{j['id']}-scatter{args.scatter_mm:g}mm"} for j in todo]
            todo = [j for j in todo if j["id"] not in done]
        todo = todo[:args.limit] if args.limit else todo
        run_and_append(stream(todo, args.workers, args.scheduler, args.dask), len(todo), path, done,
                       "confusion study", args.no_progress)
    records = [r for r in finished(done, path, "logs") if "truth" in r]
    if not records:
        return 0
    plants = sorted({r.get("plant", "quasistatic") for r in records})
    text = "".join(f"## Plant: {p}\n\n" + summarise([r for r in records if r.get("plant", "quasistatic") == p]) + "\n"
                   for p in plants)
    atomic_write_text(out.with_suffix(".md"), text)
    for p in plants:
        figure([r for r in records if r.get("plant", "quasistatic") == p],
               out.with_suffix(".png") if p == "quasistatic" or out.name.endswith(f"_{p}") else Path(f"{out}_{p}.png"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
