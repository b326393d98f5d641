"""A small hole-geometry design sweep: workspace and stiffness of four designs.

    python examples/design_sweep_small.py [OUT_DIR]

Writes a sweep description (``sweep.toml``, the format ``csjm sweep`` reads) that
varies the shape of the platform hexagon around the paper's design, evaluates
it in this process (``csjm sweep`` runs the same on several processes or a Dask
cluster) into ``results.jsonl`` (resumable: run again and finished designs are
skipped) and prints workspace fraction and minimum stiffness per design.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from csjm_opt.design import SweepSpec, run_sweep

SWEEP = """\
[sweep]
method = "grid"

[base]                                  # the paper's hole circles and heights
platform_radius_m = 0.05795112883571237
base_radius_m = 0.07538567503179898
base_gamma_deg = 116.2
oo_a_m = 0.08
oo_b_m = 0.08

[parameters.platform_gamma_deg]         # central angle of chord A1A2 (the paper: 9.9 deg)
values = [9.9, 30.0, 60.0, 90.0]

[sampling]
orientations = 200
max_tilt_deg = 45.0
max_torsion_deg = 30.0
seed = 0

[loads]                                 # N m in {A}, platform weight excluded
tau_ext = [[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0]]

[metrics]
shaping_poses = 4
"""


def main(out_dir: Path) -> list[dict]:
    sweep_file = out_dir / "sweep.toml"
    if not sweep_file.exists():
        sweep_file.write_text(SWEEP)
    result = run_sweep(SweepSpec.from_toml(sweep_file), out_dir / "results.jsonl", workers=1, progress=False)
    designs = result.as_json()["designs"]
    for d in designs:
        print(f"platform_gamma_deg = {d['params']['platform_gamma_deg']:5.1f}: "
              f"workspace fraction {d['workspace_fraction']:.3f}, "
              f"min stiffness {d['min_stiffness_Nm_per_rad']:.2f} N m/rad")
    print(f"outputs in {out_dir}")
    return designs


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="csjm_example_"))
    out.mkdir(parents=True, exist_ok=True)
    main(out)
