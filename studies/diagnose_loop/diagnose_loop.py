"""The sim-to-real loop (issue 20): ambiguous log -> ``--suggest`` -> simulated rows -> diagnose again.

For each case a log is simulated on a random rig (the testbed's plant, cycles starting where
the previous one settled), diagnosed as a new user would, and, when the diagnosis asks for one,
the suggested experiment (at most ``--rows`` rows, default load set) is run on the *same* plant
with the same hidden truth, continuing its history (friction state included), with fresh
instrument noise; ``diagnose(log, extra=rows)`` then gives the new verdict. Cases:

* ``lookalike``: stiffness_scale, link_compliance at 3x; cable_hardening + link_compliance,
  hole_offsets + mass_com, tracker_registration + mass_com, tracker_registration + sensor_bias,
  stiffness_scale + mass_com at 3x each (22-cycle... ``--cycles`` logs);
* ``short``: every single effect at 3x on a 4-cycle log;
* ``weak``: every single effect at 1.5x.

A suggested load is a dead weight: the plant takes its first moment (mass x point in {A}),
so its moment follows the pose the plant settles at, and the F/T reading is that moment
with the plant's bias and noise, as ``csjm simulate PROTOCOL --after LOG`` does it.

Usage::

    python -m studies.diagnose_loop.diagnose_loop [--rigs 10] [--rows 60] [--workers 2]
        [--out studies/diagnose_loop/diagnose_loop]
        [--plants quasistatic mujoco] [--summarise]

One JSON line per case in ``OUT.jsonl`` (resumable), tables in ``OUT.md``, figure ``OUT.png``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from studies._runner import finished, pool_stream, read_records, run_and_append  # noqa: E402

LOOKALIKE = [["stiffness_scale"], ["link_compliance"], ["cable_hardening", "link_compliance"],
             ["hole_offsets", "mass_com"], ["tracker_registration", "mass_com"],
             ["tracker_registration", "sensor_bias"], ["stiffness_scale", "mass_com"]]


def jobs(n_rigs: int, cycles: int, plants: list[str]) -> list[dict]:
    """The study's cases."""
    from csjm_opt.testbed import EFFECT_NAMES, VARIANT_NAMES

    out = []
    singles = list(EFFECT_NAMES) + list(VARIANT_NAMES)
    for plant in plants:
        for rig in range(n_rigs):
            def add(group, effects, mult, cyc, rig=rig, plant=plant):
                out.append({"id": f"loop:{plant}:{group}:{'+'.join(effects)}:{mult:g}:{cyc}:{rig}", "group": group,
                            "kind": "pair" if len(effects) > 1 else "single", "effects": effects,
                            "multiple": mult, "rig": rig, "rep": 0, "cycles": cyc, "plant": plant})
            for eff in LOOKALIKE:
                add("lookalike", eff, 3.0, cycles)
            for e in singles:
                add("short", [e], 3.0, 4)
            for e in singles:
                add("weak", [e], 1.5, cycles)
    return out


def _simulate_with_inputs(rig, plant, cycles: int, seed: list[int], noise):
    """Log of ``cycles`` designed cycles and the inputs behind it (true moments, rest lengths)."""
    from csjm_opt.errors import NoEquilibrium
    from csjm_opt.testbed.cycles import design_cycles

    for attempt in range(4):
        rng = np.random.default_rng(seed + [attempt])
        cs = design_cycles(rig, cycles, rng)
        cyc = np.concatenate([np.full(len(c.alphas), i) for i, c in enumerate(cs)])
        l = np.concatenate([np.repeat(c.rest_lengths_m[None], len(c.alphas), 0) for c in cs])
        tau = np.concatenate([c.tau_ext_A_Nm for c in cs])
        R0 = np.concatenate([np.repeat(c.R_ref[None], len(c.alphas), 0) for c in cs])
        try:
            settled = _respond(plant, {"l": l, "tau": tau, "cycle": cyc, "R0": R0, "mr": np.zeros_like(tau)})
            return {"cycle": cyc, "l": l, "tau": tau, "R0": R0, "settled": settled}
        except NoEquilibrium:
            continue
    raise NoEquilibrium("no design of this experiment has an equilibrium on the plant", "diverged", float("nan"))


#: Wall seconds spent in the plant by this process (the records take differences of it).
PLANT_SECONDS = [0.0]


def _respond(plant, inputs: dict) -> tuple[np.ndarray, int]:
    """True poses of the whole history ``inputs`` and the number of rows that did not come to rest
    within the plant's bound (MuJoCo plant: flagged rows, see ``MujocoRow.settled``; else 0)."""
    args = (inputs["l"], inputs["tau"], inputs["cycle"], inputs["R0"], inputs["mr"])
    t0 = time.perf_counter()
    try:
        if hasattr(plant, "respond_rows"):
            rows = plant.respond_rows(*args)
            return np.stack([r.R_tool for r in rows]), int(sum(not r.settled for r in rows))
        return plant.respond(*args), 0
    finally:
        PLANT_SECONDS[0] += time.perf_counter() - t0


def _measure(plant, inputs: dict, noise, rng, start: int = 0, settled=None):
    """Noisy log of the rows ``start:`` of the whole history ``inputs`` (the plant steps all of it,
    unless ``settled``, its result from :func:`_respond`, is given) and the history's unsettled rows."""
    from csjm_opt import so3
    from csjm_opt.measurement.logfile import MeasurementLog
    from csjm_opt.model import kinematics as kin

    mr = inputs.setdefault("mr", np.zeros_like(inputs["tau"]))
    R_true, unsettled = _respond(plant, inputs) if settled is None else settled
    tau = inputs["tau"] + kin.weight_moment(R_true, mr, np.asarray(plant.rig.gravity_B_m_per_s2))
    tau_meas = plant.measured_moment(tau)[start:]
    n = len(tau_meas)
    tau_meas = tau_meas + rng.normal(size=(n, 3)) * np.asarray(noise.tau_sigma_Nm)
    R_meas = plant.measured_pose(R_true[start:]) @ so3.exp(rng.normal(size=(n, 3)) * noise.angle_sigma_rad)
    return MeasurementLog.from_arrays(inputs["cycle"][start:], inputs["l"][start:], tau_meas, R_meas), unsettled


def _names(j: dict) -> set[str]:
    return {j["selected"], j["secondary"]["effect"]} - {"none"} if j["selected"] not in ("none", "unexplained") \
        else {j["selected"]}


def run_one(job: dict) -> dict:
    from csjm_opt.errors import CsjmError

    try:
        return _run_one(job)
    except CsjmError as exc:
        return {**job, "error": f"{type(exc).__name__}: {exc}"}
    except Exception as exc:     # a defect: recorded (with its kind) so the rest of the study still runs
        return {**job, "error": f"defect: {type(exc).__name__}: {exc}"}


def _run_one(job: dict) -> dict:
    from csjm_opt.diagnose import diagnose
    from csjm_opt.diagnose.suggest.experiment import suggest_experiment
    from studies.diagnose_confusion.diagnose_confusion import build_plant, job_seed, truth

    t0, plant0 = time.perf_counter(), PLANT_SECONDS[0]
    rig, noise, plant, severities, factor = build_plant(job)
    seed = job_seed(job)
    inputs = _simulate_with_inputs(rig, plant, job["cycles"], seed + [7], noise)
    # the plant is deterministic: the history simulated to find a design with an equilibrium is the log's
    log, unsettled = _measure(plant, inputs, noise, np.random.default_rng(seed + [8]),
                              settled=inputs.pop("settled"))
    d = diagnose(rig, log)
    j = d.as_json()
    want = truth(job)
    rec = {**job, "truth": sorted(want), "severities": severities, "noise_factor": factor, "rows": len(log),
           "unsettled_rows": unsettled, "before": sorted(_names(j)), "right_before": _names(j) == want,
           "warnings_before": j["verdict"]["warnings"]}
    t1 = time.perf_counter()
    s = suggest_experiment(rig, d, job.get("max_rows", 60), seed=int(sum(seed)) % 2 ** 31)
    rec["seconds_suggest"] = time.perf_counter() - t1
    rec["ambiguous"] = s is not None
    if s is None:
        return {**rec, "seconds": time.perf_counter() - t0, "seconds_plant": PLANT_SECONDS[0] - plant0}
    sj = s.as_json()
    rec.update({"purpose": s.purpose, "hypotheses": s.hypotheses, "extra_rows": sj["rows"],
                "expected_separation_sd": sj["smallest_expected_separation_sd"],
                "truth_in_hypotheses": any(set(h.split("+")) == want for h in s.hypotheses)})
    whole = {"cycle": np.r_[inputs["cycle"], s.cycle], "l": np.r_[inputs["l"], s.rest_lengths_m],
             "tau": np.r_[inputs["tau"], np.zeros((len(s.cycle), 3))],
             "R0": np.concatenate([inputs["R0"], s.planned_R]),
             "mr": np.r_[np.zeros_like(inputs["tau"]),
                         [np.zeros(3) if ld is None else ld.mass_kg * np.asarray(ld.point_A_m) for ld in s.loads]]}
    extra, unsettled2 = _measure(plant, whole, noise, np.random.default_rng(seed + [9]), start=len(log))
    d2 = diagnose(rig, log, extra=extra)
    j2 = d2.as_json()
    rec.update({"unsettled_rows_after": unsettled2, "after": sorted(_names(j2)), "right_after": _names(j2) == want,
                "warnings_after": j2["verdict"]["warnings"], "seconds": time.perf_counter() - t0,
                "seconds_plant": PLANT_SECONDS[0] - plant0,
                "truth_vs_before_sd": _separation(sj["expected_separation_sd"], want, set(rec["before"])),
                "detected_after": [c["effect"] for c in j2["candidates"] if c.get("significant")],
                "truth_rank_after": _evidence_rank(j2, want), "truth_after": _truth_status(j2, want)})
    return rec


def _truth_status(j: dict, want: set) -> dict | None:
    """The true model's tests in diagnosis ``j`` (significant, plausible, closes the gap, share explained)."""
    keys = ("significant", "plausible", "closes_gap", "fraction_explained")
    for c in j["candidates"] if len(want) == 1 else j["pairs"]:
        if set([c["effect"]] if len(want) == 1 else c.get("effects", [])) == want:
            return {k: c.get(k) for k in keys}
    return None


def _separation(seps: dict, a: set, b: set) -> float | None:
    """Expected separation (sd) of the hypotheses named ``a`` and ``b`` (sets of effects), if both were targets."""
    for k, v in seps.items():
        x, y = (set(h.split("+")) for h in k.split(" vs "))
        if {frozenset(x), frozenset(y)} == {frozenset(a), frozenset(b)}:
            return v
    return None


def _evidence_rank(j: dict, want: set) -> int | None:
    """Rank (0 = best) of the true model's log evidence among the fitted plausible models of diagnosis ``j``."""
    ev = {frozenset([c["effect"]]): c["log_evidence"] for c in j["candidates"]
          if c.get("plausible") and c.get("log_evidence") is not None}
    ev.update({frozenset(p["effects"]): p["log_evidence"] for p in j["pairs"]
               if p.get("fitted") and p.get("plausible") and p.get("log_evidence") is not None})
    if frozenset(want) not in ev:
        return None
    return sum(v > ev[frozenset(want)] for v in ev.values())


FAILURE_CLASSES = ("truth not among the hypotheses the rows were designed for",
                   "no rows within the limits and budget separate truth and verdict by 2 sd",
                   "the truth has the best evidence after, the decision rule names another model",
                   "separation expected, the data do not bear it out (truth not best by evidence)",
                   "the true model, fitted to log and rows, is significant but does not close the gap")


def failure_class(r: dict) -> str:
    """Why an ambiguous log is still wrong after the experiment (the record's diagnostics).

    A true model that is significant and plausible but leaves part of the gap after the new
    rows (its fit fails on them, or the plant's effect is not the vocabulary's law); otherwise
    the first of: truth not targeted, no separating rows, decision rule, data.
    """
    t = r.get("truth_after")
    if t and t.get("significant") and t.get("plausible") and t.get("closes_gap") is False:
        return FAILURE_CLASSES[4]
    if not r.get("truth_in_hypotheses"):
        return FAILURE_CLASSES[0]
    sep = r.get("truth_vs_before_sd")
    if sep is not None and sep < 2.0:
        return FAILURE_CLASSES[1]
    if r.get("truth_rank_after") == 0:
        return FAILURE_CLASSES[2]
    return FAILURE_CLASSES[3]


def summarise(records: list[dict], failed: list[dict] | None = None) -> str:
    """The study's tables (per plant); ``failed``: cases that ended in an error (counted, listed)."""
    def rate(rs, ok):
        return f"{sum(map(ok, rs))}/{len(rs)} ({sum(map(ok, rs)) / len(rs):.0%})" if rs else "-"

    failed = failed or []
    lines = []
    for plant in sorted({r["plant"] for r in records}):
        rp = [r for r in records if r["plant"] == plant]
        amb = [r for r in rp if r["ambiguous"]]
        lines += [f"## Plant: {plant}", "", f"Cases: {len(rp)}; the diagnosis asked for an experiment on {len(amb)}.",
                  "", "| group | cases | right before | ambiguous | ambiguous: right before | ambiguous: right after "
                  "one suggested experiment (target >= 80 %) | median rows | median expected separation (sd) |",
                  "|---|---|---|---|---|---|---|---|"]
        for g in ["lookalike", "short", "weak", "all"]:
            rs = rp if g == "all" else [r for r in rp if r["group"] == g]
            a = [r for r in rs if r["ambiguous"]]
            rows = np.median([r["extra_rows"] for r in a]) if a else float("nan")
            sep = np.median([r["expected_separation_sd"] or 0 for r in a]) if a else float("nan")
            lines.append(f"| {g} | {len(rs)} | {rate(rs, lambda r: r['right_before'])} | {len(a)} | "
                         f"{rate(a, lambda r: r['right_before'])} | {rate(a, lambda r: r['right_after'])} | "
                         f"{rows:.0f} | {sep:.1f} |")
        fp = [r for r in failed if r["plant"] == plant]
        if fp:
            lines += ["", f"Cases that ended in an error (not counted above): {len(fp)}: "
                      + "; ".join(f"{'+'.join(r['effects'])} ({r['group']}, rig {r['rig']}): {r['error']}" for r in fp)]
        timed = [r for r in rp if "seconds_plant" in r]
        if timed:
            wall, plant_s = (np.median([r[k] for r in timed]) for k in ("seconds", "seconds_plant"))
            lines += ["", f"Wall time per case (median, shared box): {wall:.0f} s, "
                      f"of which in the plant {plant_s:.0f} s; rows that did not "
                      f"come to rest within the plant's bound (flagged, certified): "
                      f"{sum(r.get('unsettled_rows', 0) + r.get('unsettled_rows_after', 0) for r in timed)} "
                      f"in {len(timed)} cases."]
        wrong = [r for r in amb if not r["right_after"]]
        lines += ["", f"Ambiguous logs wrong after the experiment: {len(wrong)} (right before -> wrong after: "
                      f"{sum(r['right_before'] for r in wrong)}). Why:", "", "| class | logs |", "|---|---|"]
        for c in FAILURE_CLASSES:
            lines.append(f"| {c} | {sum(failure_class(r) == c for r in wrong)} |")
        lines += ["", f"Clear verdicts (no experiment asked) that were right: "
                      f"{rate([r for r in rp if not r['ambiguous']], lambda r: r['right_before'])}.",
                  f"Ambiguous logs whose truth was among the hypotheses separated: "
                  f"{rate(amb, lambda r: r.get('truth_in_hypotheses', False))}.",
                  f"Median time of --suggest: {np.median([r['seconds_suggest'] for r in rp]):.1f} s.", "",
                  "| case | truth | before | hypotheses | rows | expected sep. (sd) | after |",
                  "|---|---|---|---|---|---|---|"]
        for r in sorted(amb, key=lambda r: r["id"]):
            lines.append(f"| {r['group']} rig {r['rig']} | {'+'.join(r['truth'])} | {'+'.join(r['before'])} | "
                         f"{', '.join(r['hypotheses'])} | {r['extra_rows']} | {r['expected_separation_sd'] or 0:.1f} | "
                         f"{'+'.join(r['after'])} |")
        lines.append("")
    return "\n".join(lines) + "\n"


def figure(records: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    ax = axes[0]
    groups = ["lookalike", "short", "weak"]
    plants = sorted({r["plant"] for r in records})
    width = 0.8 / (2 * len(plants))
    for k, plant in enumerate(plants):
        for m, (key, label) in enumerate((("right_before", "before"), ("right_after", "after"))):
            ys = []
            for g in groups:
                a = [r for r in records if r["plant"] == plant and r["group"] == g and r["ambiguous"]]
                ys.append(np.mean([r[key] for r in a]) if a else 0.0)
            ax.bar(np.arange(len(groups)) + (2 * k + m - len(plants) + 0.5) * width, ys, width,
                   label=f"{plant}: {label}")
    ax.axhline(0.8, color="k", ls=":", lw=1)
    ax.set_xticks(range(len(groups)), groups)
    ax.set_ylabel("ambiguous logs named right")
    ax.set_title("one suggested experiment (<= 60 rows)")
    ax.legend(fontsize=7)
    ax = axes[1]
    a = [r for r in records if r["ambiguous"]]
    for ok, mk in ((True, "o"), (False, "x")):
        rs = [r for r in a if r["right_after"] == ok]
        ax.scatter([max(r["expected_separation_sd"] or 0.01, 0.01) for r in rs], [r["extra_rows"] for r in rs],
                   marker=mk, label="right after" if ok else "wrong after")
    ax.set_xscale("log")
    ax.set_xlabel("expected smallest separation of the hypotheses (noise sd)")
    ax.set_ylabel("suggested rows")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rigs", type=int, default=10)
    ap.add_argument("--rig-ids", nargs="+", type=int, default=None, help="only these rigs (of range(--rigs))")
    ap.add_argument("--cycles", type=int, default=12)
    ap.add_argument("--rows", type=int, default=60, help="largest suggested experiment")
    ap.add_argument("--plants", nargs="+", default=["quasistatic"], choices=["quasistatic", "mujoco"])
    ap.add_argument("--groups", nargs="+", default=["lookalike", "short", "weak"])
    ap.add_argument("--only", nargs="+", default=None, help="only cases injecting these effects")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--limit", type=int, default=None)
    ap.add_argument("--out", default="studies/diagnose_loop/diagnose_loop")
    ap.add_argument("--summarise", action="store_true")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(argv)
    out = Path(args.out)
    path = out.with_suffix(".jsonl")
    done = read_records(path)
    if not args.summarise:
        todo = [{**j, "max_rows": args.rows} for j in jobs(args.rigs, args.cycles, args.plants)
                if j["id"] not in done and j["group"] in args.groups
                and (args.rig_ids is None or j["rig"] in args.rig_ids)
                and (args.only is None or set(j["effects"]) <= set(args.only))]
        # a fixed random order: a partial run is a random sample of the cases (every rig, group, plant)
        todo = [todo[i] for i in np.random.default_rng(0).permutation(len(todo))]
        todo = todo[:args.limit] if args.limit else todo
        run_and_append(pool_stream(run_one, todo, args.workers), len(todo), path, done, "loop study",
                       args.no_progress)
    records = finished(done, path)
    if not records:
        return 0
    text = summarise(records, [r for r in done.values() if "error" in r])
    out.with_suffix(".md").write_text(text)
    figure(records, out.with_suffix(".png"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
