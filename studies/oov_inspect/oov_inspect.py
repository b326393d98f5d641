"""Re-make confusion-study logs by id and save them for ``csjm diagnose`` (a study log is not stored).

For each id (as in a ``diagnose_confusion*.jsonl`` record): the study's rig, plant, severities and
seed give the same log again; it is written with its rig file to ``OUT/<id>/`` (``log.csv``,
``rig.toml``) and, with ``--diagnose``, diagnosed there (``diagnosis.json``, the CLI's ``--json``).
For the MuJoCo plant the per-row settling record (:class:`csjm_opt.testbed.MujocoRow`) is summarised
too (rows not at rest by the settle bound, the friction certificate's worst margin).

Usage::

    python -m studies.oov_inspect.oov_inspect \
        --records studies/diagnose_confusion/diagnose_confusion_oov_quasistatic.jsonl \
        --ids 'quasistatic:outside:drum_slip:3:4:0' [--diagnose] [--out /tmp/oov-inspect]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from studies._runner import read_records  # noqa: E402


def remake(rec: dict, out: Path, run_diagnosis: bool) -> dict:
    """Write the log of study record ``rec`` (and its diagnosis) under ``out``; a summary dict."""
    from studies.diagnose_confusion.diagnose_confusion import job_seed, simulate_job

    keys = ("id", "kind", "effects", "multiple", "rig", "rep", "cycles", "plant", "scatter_mm")
    job = {k: rec[k] for k in keys if k in rec}
    d = out / job["id"].replace(":", "_")
    d.mkdir(parents=True, exist_ok=True)
    rows = _record_mujoco_rows()
    rig, noise, log, severities, factor = simulate_job(job)
    log.to_csv(d / "log.csv", overwrite=True)
    rig.to_toml(d / "rig.toml", overwrite=True)
    info = {"id": job["id"], "dir": str(d), "severities": severities, "noise_factor": factor,
            "seed": job_seed(job)}
    if rows:
        info["mujoco_rows"] = len(rows)
        info["rows_not_settled"] = [i for i, r in enumerate(rows) if not r.settled]
        info["max_speed_rad_per_s"] = max(r.speed_rad_per_s for r in rows)
    if run_diagnosis:
        from csjm_opt.diagnose import diagnose

        j = diagnose(rig, log).as_json()
        (d / "diagnosis.json").write_text(json.dumps(j, indent=1, default=float))
        info.update(selected=j["selected"], secondary=j["secondary"]["effect"],
                    warnings=j["verdict"]["warnings"], margin=j["verdict"].get("evidence_margin"))
    return info


def _record_mujoco_rows() -> list:
    """Every MuJoCo row settled from now on is appended to the returned list (respond wrapped)."""
    from csjm_opt.testbed.mujoco.plant import MujocoTestbedPlant

    rows: list = []
    inner = getattr(MujocoTestbedPlant.respond_rows, "__wrapped__", MujocoTestbedPlant.respond_rows)

    def respond_rows(self, *a, **k):
        out = inner(self, *a, **k)
        rows.extend(out)
        return out

    respond_rows.__wrapped__ = inner  # type: ignore[attr-defined]
    MujocoTestbedPlant.respond_rows = respond_rows  # type: ignore[method-assign]
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", nargs="+", required=True)
    ap.add_argument("--ids", nargs="+", required=True)
    ap.add_argument("--out", default="/tmp/oov-inspect")
    ap.add_argument("--diagnose", action="store_true")
    args = ap.parse_args(argv)
    recs: dict[str, dict] = {}
    for f in args.records:
        recs.update(read_records(Path(f)))
    for i in args.ids:
        print(json.dumps(remake(recs[i], Path(args.out), args.diagnose), default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
