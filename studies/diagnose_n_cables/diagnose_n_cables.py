"""Study: each single effect injected at 3x the noise floor on the 8- and 4-cable rigs: is it named?

For each shipped m-cable rig (``rigs/eight_cable.toml``, ``rigs/four_cable.toml``; the paper's
instruments) and each effect the diagnosis models (the testbed's vocabulary effects, Coulomb cable
friction, which should be named ``friction``, and the guide radius), one log: the effect is
calibrated as in studies/diagnose_confusion (injected at severity 1 on a noise-free 4-cycle copy of
the experiment, the RMS pose gap the nominal refit leaves, over the instrument floor, sets the
severity for 3x the floor; an effect is held at its plausible severity,
:data:`csjm_opt.testbed.injection.PLAUSIBLE_SEVERITY`, and the instrument made better by the
missing factor instead), injected into the testbed's quasi-static plant, simulated over
``--cycles`` cycles with the (scaled) instrument noise and diagnosed with that noise stated
(:func:`csjm_opt.diagnose.diagnose`). Named: the selected effect is the injected one.

What tells the effect apart: on the same noise-free calibration log every *other* single effect of the
vocabulary is refitted; the smallest RMS pose gap one leaves, over the nominal refit's, is the effect's
*distinct share* (``distinct_share``, the refit ``nearest``). At 3x the floor the part no other single
reproduces is about ``3 x distinct_share`` floors: hole offsets at 3x are 0.2-0.3 floors away from drive
offsets (a hole moved along its cable is a rest-length change; drive offsets are m of the 6 m hole
directions). ``--distinct`` calibrates that part instead: the severity puts the distinct gap (not the
whole gap) at 3x the floor (ids get ``:distinct``; the plausible severity is kept, the instruments made
better by the missing factor as above).

Usage::

    python -m studies.diagnose_n_cables.diagnose_n_cables [--cycles 8] [--reps 1] [--workers 2]
        [--rigs eight_cable four_cable] [--effects NAME ...] [--distinct] [--summarise]

Records go to ``studies/diagnose_n_cables/diagnose_n_cables.jsonl`` as cases finish (a rerun
resumes); the table to ``diagnose_n_cables.md``.
"""

from __future__ import annotations

import argparse
import sys
import time
import zlib
from pathlib import Path

import numpy as np

from studies._runner import finished, pool_stream, read_records, run_and_append

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
OUT = HERE / "diagnose_n_cables"
#: The diagnosis's name for each injected effect that is not its own name.
NAMED_AS = {"coulomb_friction": "friction"}


def effects() -> tuple[str, ...]:
    from csjm_opt.testbed import EFFECT_NAMES, VARIANT_NAMES

    return EFFECT_NAMES + tuple(VARIANT_NAMES) + ("guide_radius",)


def cases(rigs: list[str], names: list[str], reps: int, cycles: int, distinct: bool = False) -> list[dict]:
    tail = ":distinct" if distinct else ""
    return [{"id": f"{r}:{e}:{k}:{cycles}{tail}", "rig": r, "effect": e, "rep": k, "cycles": cycles,
             "calibration": "distinct" if distinct else "gap"}
            for r in rigs for k in range(reps) for e in names]


def distinct_part(rig, table, effect: str) -> tuple[float, str]:
    """``(RMS pose gap the best other single leaves, its name)`` on a noise-free calibration table (rad)."""
    from csjm_opt.diagnose.data.residuals import pose_residuals, rms
    from csjm_opt.diagnose.effects import EFFECTS, make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.gauss_newton import fit_model
    from csjm_opt.errors import CsjmError

    best = (np.inf, "none")
    for other in EFFECTS:
        if other == NAMED_AS.get(effect, effect):
            continue
        model = AugmentedModel(rig, [make_effect(other, rig)])
        try:
            fit = fit_model(model, table)
            gap = rms(pose_residuals(model.predict_poses(table.rows, fit.theta, table.R_meas).R, table.R_meas))
        except (CsjmError, np.linalg.LinAlgError):
            continue
        best = min(best, (float(gap), other))
    return best


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


def run_one(case: dict) -> dict:
    from csjm_opt.errors import CsjmError

    try:
        return _run_one(case)
    except CsjmError as exc:
        return {**case, "error": f"{type(exc).__name__}: {exc}"}


def _run_one(case: dict) -> dict:
    from csjm_opt.diagnose import diagnose
    from csjm_opt.diagnose.data.residuals import compute_residuals, pose_residuals, rms
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.gauss_newton import fit_model
    from csjm_opt.measurement.instruments import InstrumentNoise
    from csjm_opt.model.rig import Rig
    from csjm_opt.testbed import inject, make_plant
    from csjm_opt.testbed.injection import PLAUSIBLE_SEVERITY

    t0 = time.perf_counter()
    rig = Rig.from_toml(ROOT / "rigs" / f"{case['rig']}.toml")
    effect = case["effect"]
    seed = [case["rep"], zlib.crc32(effect.encode())]
    noise = InstrumentNoise.paper()
    clean = _simulate(rig, 4, seed + [99], make_plant(rig, effect, 1.0, np.random.default_rng(seed + [1])),
                      InstrumentNoise.none())
    t = compute_residuals(rig, clean, noise)
    null = AugmentedModel(rig)
    gap1 = rms(pose_residuals(null.predict_poses(t.rows, fit_model(null, t).theta, t.R_meas).R, t.R_meas))
    distinct, nearest = distinct_part(rig, t, effect)
    share = min(distinct / max(gap1, 1e-12), 1.0)
    # the whole gap at 3x the floor, or (--distinct) the part no other single effect reproduces
    severity = 3.0 * t.instrument_floor_rad / max(gap1 * (share if case.get("calibration") == "distinct" else 1.0),
                                                  1e-12)
    factor = min(1.0, PLAUSIBLE_SEVERITY.get(effect, np.inf) / severity)
    severity *= factor
    noise = InstrumentNoise(tuple(factor * v for v in noise.tau_sigma_Nm), factor * noise.angle_sigma_rad)
    plant = inject(make_plant(rig, None, 1.0, np.random.default_rng(0)), effect, severity,
                   np.random.default_rng(seed + [1]))
    log = _simulate(rig, case["cycles"], seed + [7], plant, noise)
    t1 = time.perf_counter()
    d = diagnose(rig, log, noise=noise, progress=False)
    j = d.as_json()
    want = NAMED_AS.get(effect, effect)
    cand = {c["effect"]: c for c in j["candidates"]}
    return {**case, "m": rig.n_cables, "truth": want, "selected": j["selected"], "named": j["selected"] == want,
            "severity": severity, "noise_factor": factor, "gap1_rad": gap1, "rows": len(log),
            "calibration": case.get("calibration", "gap"), "distinct_share": share, "nearest": nearest,
            "distinct_floors": 3.0 * share if case.get("calibration", "gap") == "gap" else 3.0,
            "secondary": j["secondary"]["effect"], "warnings": j["verdict"]["warnings"],
            "alternatives": j["verdict"].get("alternatives", []), "gap": j["gap"],
            "noise_floor_rad": j["noise_floor_rad"],
            "truth_candidate": {k: cand[want].get(k) for k in ("significant", "plausible", "log_evidence",
                                                                  "rms_rad", "gain") if k in cand.get(want, {})},
            "selected_candidate": {k: cand[j["selected"]].get(k) for k in ("log_evidence", "rms_rad")
                                   if k in cand.get(j["selected"], {})},
            "seconds_diagnose": time.perf_counter() - t1, "seconds": time.perf_counter() - t0}


def summarise(records: list[dict]) -> str:
    lines = ["# Single effects at 3x the floor on the 8- and 4-cable rigs", "",
             "Made by `python -m studies.diagnose_n_cables.diagnose_n_cables` (see the README for the options).", ""]
    for cal in ("gap", "distinct"):
        for rig in sorted({r["rig"] for r in records}):
            mine = sorted((r for r in records if r["rig"] == rig and r.get("calibration", "gap") == cal),
                          key=lambda r: (r["effect"], r["rep"]))
            if not mine:
                continue
            named = sum(r["named"] for r in mine)
            alt = sum(not r["named"] and r["truth"] in r.get("alternatives", []) for r in mine)
            what = "" if cal == "gap" else ", the distinct part at 3x the floor"
            lines += [f"## {rig} (m = {mine[0]['m']}{what}): {named}/{len(mine)} named"
                      + (f", {alt} more as the undecided alternative" if alt else ""), "",
                      "| effect | rep | cycles | severity | noise factor | distinct (floors) | nearest | selected "
                      "| secondary | alternatives | warnings | s |",
                      "|---|---|---|---|---|---|---|---|---|---|---|---|"]
            for r in mine:
                sel = r["selected"] if r["named"] else f"**{r['selected']}**"
                dist = f"{r['distinct_floors']:.2f}" if "distinct_floors" in r else "-"
                lines.append(f"| {r['effect']} | {r['rep']} | {r['cycles']} | {r['severity']:.3g} "
                             f"| {r['noise_factor']:.2f} | {dist} | {r.get('nearest', '-')} | {sel} | {r['secondary']} "
                             f"| {', '.join(r.get('alternatives', [])) or '-'} | {len(r['warnings'])} "
                             f"| {r['seconds']:.0f} |")
            lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rigs", nargs="*", default=["eight_cable", "four_cable"])
    ap.add_argument("--effects", nargs="*", default=None)
    ap.add_argument("--reps", type=int, default=1)
    ap.add_argument("--cycles", type=int, default=8)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--distinct", action="store_true",
                    help="calibrate the part no other single effect reproduces (not the whole gap) to 3x the floor")
    ap.add_argument("--summarise", action="store_true", help="only write the table from the records")
    args = ap.parse_args(argv)
    path = OUT.with_suffix(".jsonl")
    done = read_records(path)
    if not args.summarise:
        todo = [c for c in cases(args.rigs, args.effects or list(effects()), args.reps, args.cycles, args.distinct)
                if c["id"] not in done]
        run_and_append(pool_stream(run_one, todo, args.workers), len(todo), path, done, "cases")
    records = finished(done, path)
    OUT.with_suffix(".md").write_text(summarise(records) + "\n")
    for r in records:
        print(f"{r['rig']:12s} {r['effect']:22s} {r.get('calibration', 'gap'):8s} -> {r['selected']:22s} "
              f"{'named' if r['named'] else 'NOT named'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
