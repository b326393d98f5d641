"""The shipped raw instrument file (examples/data/raw_example.csv) is accepted by ``csjm preprocess``."""

from pathlib import Path

import numpy as np

from csjm_opt.cli import main
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.measurement.rig_fit import check_log_rig
from csjm_opt.model.rig import paper_rig

RAW = Path(__file__).resolve().parents[2] / "examples" / "data" / "raw_example.csv"


def test_csjm_preprocess_accepts_the_example_raw_file(tmp_path):
    out = tmp_path / "log.csv"
    assert main(["preprocess", str(RAW), "-o", str(out)]) == 0
    log = MeasurementLog.from_csv(out)
    assert len(log) == 18 and log.cycle_ids == [0, 1]
    # the platform poses came from tracked points: the log is of the paper rig, in equilibrium with its cables
    fit = check_log_rig(paper_rig(), log)
    assert fit.median_N < 0.5 * fit.tolerance_N
    assert np.all(np.linalg.norm(log.rotvec_rad, axis=1) < 0.5)
