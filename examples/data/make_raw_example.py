"""Write ``raw_example.csv``: a raw instrument file (the ``csjm preprocess`` format) of a simulated experiment.

Usage: python examples/data/make_raw_example.py [OUT.csv]

Two load cycles of the testbed's quasi-static plant on the paper rig (instrument noise on), written
as a lab's instruments would record them: tracker points of the base and of the platform in the
tracker frame {L}, the F/T reading in the sensor frame {S}, the commanded rest lengths. The format
is documented in docs/guide/input-files.md ("Raw instrument files").
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from csjm_opt import so3
from csjm_opt.model.rig import paper_rig
from csjm_opt.testbed import simulate_experiment
from csjm_opt.testbed.raw_instruments import raw_text_from_log

R_LB = so3.exp(np.array([0.02, -0.01, 1.2]))        # tracker frame {L} from {B}
P_LB = np.array([0.8, -0.3, 0.45])                    # m
R_AS = so3.exp(np.array([0.0, 0.0, np.pi / 6]))      # F/T sensor {S} in {A}
P_AS = np.array([0.0, 0.0, 0.12])                     # m
BASE_B = np.array([[0.12, 0.0, -0.08], [-0.06, 0.104, -0.08], [-0.06, -0.104, -0.08], [0.0, 0.0, -0.15]])
PLATFORM_A = np.array([[0.05, 0.0, 0.1], [-0.03, 0.04, 0.1], [-0.03, -0.04, 0.1], [0.0, 0.0, 0.16]])


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0]) if argv else Path(__file__).with_name("raw_example.csv")
    rig = paper_rig()
    log = simulate_experiment(rig, 2, np.random.default_rng(7))
    text = raw_text_from_log(log, rig, R_LB, P_LB, R_AS, P_AS, BASE_B, np.random.default_rng(8),
                             point_sigma_m=5e-5, platform_points_A=PLATFORM_A)
    out.write_text(text)
    print(f"{out}: {len(log)} samples, {len(text.splitlines())} lines")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
