"""Start-up cost: ``import csjm_opt`` and ``csjm --help`` against a bare interpreter and numpy (same run).

Run: python benchmarks/bench_import.py [--repeat 15]
Each figure is the median wall time of a fresh interpreter (subprocess) over
``--repeat`` runs; the package's own cost is the difference to ``import numpy``,
which the package needs anyway. The goal is ``import csjm_opt`` within 0.4 s.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time

import numpy as np

CASES = {
    "python -c pass": [sys.executable, "-c", "pass"],
    "import numpy": [sys.executable, "-c", "import numpy"],
    "import scipy.stats": [sys.executable, "-c", "import scipy.stats"],
    "import csjm_opt": [sys.executable, "-c", "import csjm_opt"],
    "import csjm_opt; paper_rig()": [sys.executable, "-c", "import csjm_opt; csjm_opt.paper_rig()"],
    "csjm --help": [sys.executable, "-m", "csjm_opt.cli", "--help"],
    # what `csjm diagnose` imports before its first fit (scipy.stats is not among it: 0.5 s)
    "import the diagnosis": [sys.executable, "-c", "import csjm_opt.diagnose.selection.decision, "
                             "csjm_opt.diagnose.suggest.experiment, csjm_opt.measurement.logfile; import sys; "
                             "assert 'scipy.stats' not in sys.modules"],
}


def wall(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=15)
    args = ap.parse_args()
    for cmd in CASES.values():   # warm the file cache and numba's on-disk cache
        wall(cmd)
    med = {}
    for name, cmd in CASES.items():
        med[name] = float(np.median([wall(cmd) for _ in range(args.repeat)]))
    base = med["import numpy"]
    print(f"fresh interpreter, median of {args.repeat}:")
    for name, t in med.items():
        print(f"  {name:32s} {t * 1e3:8.1f} ms   ({t / base:5.2f}x import numpy)")
    verdict = "within" if med["import csjm_opt"] <= 0.4 else "OVER"
    print(f"import csjm_opt: {med['import csjm_opt']:.3f} s, {verdict} the 0.4 s goal; "
          f"{(med['import csjm_opt'] - base) * 1e3:.0f} ms more than numpy alone")


if __name__ == "__main__":
    main()
