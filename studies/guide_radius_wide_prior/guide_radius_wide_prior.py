"""The eyelet logs whose injected radius is beyond ``guide_radius``'s 10 mm prior range, with the range widened.

The confusion study scales an outside effect to 3x the noise floor without a plausibility cap; on
random rigs 1 (12 cycles) and 8 (24 cycles) the eyelet then needs 16.2 and 10.3 mm, and the verdict
is ``unexplained`` ("guide_radius needs implausible parameters"). This diagnoses the same logs with
the range widened to 20 mm, as a lab with larger guides would state it.

Usage::

    python -m studies.guide_radius_wide_prior.guide_radius_wide_prior    # one JSON line per log on stdout
"""

from __future__ import annotations

import json

from studies.diagnose_confusion.diagnose_confusion import simulate_job  # noqa: E402


def main() -> None:
    from csjm_opt.diagnose import diagnose

    for rig_id, cycles in ((1, 12), (8, 24)):
        job = {"kind": "outside", "effects": ["guide_radius"], "multiple": 3.0, "rig": rig_id, "rep": 0,
               "cycles": cycles, "plant": "quasistatic"}
        rig, _, log, severities, _ = simulate_job(job)
        j = diagnose(rig, log, ranges={"guide_radius_m": (0.0, 0.02)}).as_json()
        c = next(c for c in j["candidates"] if c["effect"] == "guide_radius")
        print(json.dumps({"rig": rig_id, "cycles": cycles, "r_true_mm": 3.0 * severities[0],
                          "selected": j["selected"], "secondary": j["secondary"]["effect"],
                          "warnings": j["verdict"]["warnings"], "r_fit_mm": 1e3 * c["params"]["guide_radius_m"]}),
              flush=True)


if __name__ == "__main__":
    main()
