"""Sweep speed for m = 4, 6, 8, 12 cables (designs/s), and m = 6 against the code before the m-cable change.

Run: python benchmarks/bench_sweep_cables.py [--designs 24] [--repeats 3] [--baseline DIR]

Fixed work per design, as ``benchmarks/bench_sweep.py``: 1,000 orientations (tilt <= 45 deg,
|torsion| <= 30 deg, scrambled Halton), the 7-load set of ``studies/paper_sweep.toml``, all metrics
(feasibility, tilt cone, planned tensions and K at every feasible orientation, shaping range at 16
poses: C(m, 3) 2^(m - 3) basic solutions per pose and axis). Designs: a Latin hypercube over the two
pair angles (platform 5-45 %, base 55-95 % of the pair spacing 720/m deg) on the paper's circles, in
one process (``workers = 1``). Reported: the median over ``--repeats`` runs of the designs/s computed
from the per-design times (the first run of each m also compiles nothing new: kernels are warmed on
one design first). ``--baseline DIR`` (a checkout of main before the change) times m = 6 with
``PYTHONPATH=DIR`` in a subprocess, alternating with the current code so both see the same load.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LOADS = [[0, 0, 0], [3, 0, 0], [-3, 0, 0], [0, 3, 0], [0, -3, 0], [0, 0, 1], [0, 0, -1]]
RADII = {"platform_radius_m": 0.05795112883571237, "base_radius_m": 0.07538567503179898}


def spec_dict(m: int | None, designs: int) -> dict:
    """The sweep of one m (``None``: the six-cable hexagon without the n_cables key, for old code)."""
    spacing = 720.0 / (m or 6)
    base = dict(RADII, oo_a_m=0.08, oo_b_m=0.08)
    if m is not None:
        base["n_cables"] = m
    return {"sweep": {"method": "lhs", "designs": designs, "seed": 0}, "base": base,
            "parameters": {"platform_gamma_deg": {"min": 0.05 * spacing, "max": 0.45 * spacing},
                           "base_gamma_deg": {"min": 0.55 * spacing, "max": 0.95 * spacing}},
            "sampling": {"orientations": 1000, "max_tilt_deg": 45.0, "max_torsion_deg": 30.0},
            "loads": {"tau_ext": LOADS}, "metrics": {"shaping_poses": 16}}


def measure(m: int | None, designs: int) -> dict:
    """Designs/s of one sweep in this process (the code on ``sys.path``)."""
    from csjm_opt.design.design_evaluation import evaluate_design
    from csjm_opt.design.sweep.runner import run_sweep
    from csjm_opt.design.sweep.spec import SweepSpec

    spec = SweepSpec.from_dict(spec_dict(m, designs), "bench")
    evaluate_design(spec.designs()[0], spec.settings)              # compile the kernels first
    with tempfile.TemporaryDirectory() as tmp:
        result = run_sweep(spec, Path(tmp) / "r.jsonl", workers=1, progress=False)
    seconds = [r["seconds"] for r in result.records]
    ok = sum(r["status"] == "ok" for r in result.records)
    return {"m": m or 6, "designs_per_s": len(seconds) / sum(seconds), "ok": ok, "designs": len(seconds)}


def _run(code_dir: Path, m: int | None, designs: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(code_dir)}
    out = subprocess.run([sys.executable, __file__, "--one", json.dumps([m, designs])], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--designs", type=int, default=24)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--baseline", type=Path, default=None)
    parser.add_argument("--counts", default="4,6,8,12")
    parser.add_argument("--one", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one is not None:
        m, designs = json.loads(args.one)
        print(json.dumps(measure(m, designs)))
        return
    counts = [int(c) for c in args.counts.split(",")]
    rates: dict[str, list[float]] = {}
    for _ in range(args.repeats):
        for m in counts:
            rates.setdefault(str(m), []).append(_run(ROOT, m, args.designs)["designs_per_s"])
        if args.baseline is not None:
            rates.setdefault("6 (baseline)", []).append(_run(args.baseline, None, args.designs)["designs_per_s"])
    six = statistics.median(rates["6"]) if "6" in rates else float("nan")
    print(f"{'m':>14} {'designs/s':>10} {'vs m = 6':>9}   (median of {args.repeats}, {args.designs} designs each)")
    for key, values in rates.items():
        med = statistics.median(values)
        print(f"{key:>14} {med:10.2f} {med / six:9.2f}")


if __name__ == "__main__":
    main()
