"""The identification part of ``csjm demo``: identify, verify on held-out data, fit parameters.

:func:`run_demo` takes a (simulated) measurement log, identifies K per cycle
(paper (49)-(50), affine LS with CIs, symmetric GLS), verifies the identified
stiffness on held-out rows (Section IV-C, with K_D and with K), fits the
physical parameters over the log and checks the poses they predict, writes
figures and a JSON file into ``out_dir`` and returns a JSON-able summary.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..errors import CsjmError
from .._fileio import atomic_write_json, atomic_write_text
from .._plotting import save
from ..identification.identify import identify_stiffness
from ..identification.figures import convergence_curve, plot_convergence
from ..measurement.logfile import MeasurementLog
from ..model.numeric import Model
from ..identification.param_fit import check_fit, fit_parameters
from ..model.rig import Rig
from ..identification.stiffness_fits import n_parameters
from ..identification.verify import plot_verification, verify_log

#: Rows per cycle from which the quadratic (order 2) fit is used.
ORDER2_MIN_ROWS = 16
MAX_FIGURE_CYCLES = 3


def split_rows(log: MeasurementLog) -> tuple[np.ndarray, np.ndarray]:
    """Held-out split inside each cycle: reference and every other row train, the rest test."""
    train, test = [], []
    for c in log.cycle_ids:
        rows = log.cycle_rows(c)
        if len(rows) < 10:          # too short to split: all rows train
            train.append(rows)
            continue
        train.append(np.r_[rows[0], rows[2::2]])
        test.append(rows[1::2])
    cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0, int)  # noqa: E731
    return np.sort(cat(train)), np.sort(cat(test))


def run_demo(rig: Rig, log: MeasurementLog, out_dir: Path, test_log: MeasurementLog | None = None) -> dict[str, Any]:
    """Identify, verify and fit on ``log`` (held-out: ``test_log`` or a split of ``log``)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model = Model(rig)
    if test_log is None:
        train_rows, test_rows = split_rows(log)
        train, test = log.subset(train_rows), log.subset(test_rows)
    else:
        train, test = log, test_log
    estimates: list = []
    cycles: list = []
    skipped: list = []
    figures: list = []
    for c in train.cycle_ids:
        rows = train.cycle_rows(c)
        order = 2 if len(rows) >= ORDER2_MIN_ROWS else 1
        try:
            e = identify_stiffness(train.R[rows], train.tau_ext_A_Nm[rows], model, order=order, cycle=c)
        except CsjmError as exc:
            skipped.append({"cycle": c, "reason": str(exc)})
            continue
        estimates.append(e)
        cycles.append({k: v for k, v in e.as_dict().items()
                       if k in ("cycle", "n_rows", "order", "K_D", "K", "K_sym", "K_paper", "K_ci", "K_std",
                                "condition", "symmetry_error", "symmetry_z", "det_K", "eig_K_sym",
                                "residual_rms_Nm")})
        if len(figures) < MAX_FIGURE_CYCLES:
            curve = convergence_curve(train.R[rows], train.tau_ext_A_Nm[rows], model,
                                      n_min=n_parameters(order) + 1, order=order)
            ax = plot_convergence(curve, title=f"Cycle {c}: det K against measurements")
            figures.append(str(save(ax.figure, out_dir / f"identify_convergence_cycle{c}.png")))
    summary: dict[str, Any] = {"cycles": cycles, "skipped_cycles": skipped, "n_train_rows": len(train),
                               "n_test_rows": len(test), "figures": figures}
    if estimates and len(test):
        v_kd = verify_log(estimates, test, model, use="K_D")
        v_k = verify_log(estimates, test, model, use="K")
        ax = plot_verification([v_kd, v_k], title="Held-out verification (61)-(65): K_D vs K")
        figures.append(str(save(ax.figure, out_dir / "identify_verification.png")))
        atomic_write_text(out_dir / "identify_verification.txt",
                          "Predicted with K_D (right to first order)\n" + v_kd.table()
                          + "\n\nPredicted with K = K_D + K_L (text's (61))\n" + v_k.table() + "\n")
        summary["verification"] = {"K_D": {"rms_rad": v_kd.rms_rad, "max_rad": v_kd.max_rad},
                                   "K": {"rms_rad": v_k.rms_rad, "max_rad": v_k.max_rad}}
    try:
        fit = fit_parameters(train, rig, model=model)
        summary["param_fit"] = fit.summary() | {"train_rms_rad": _rms(fit.pose_errors_rad(train))}
        if len(test):
            summary["param_fit"] |= check_fit(fit, test)
    except CsjmError as exc:
        summary["param_fit"] = {"error": str(exc)}
    atomic_write_json(out_dir / "identify.json", summary)
    summary["files"] = [str(out_dir / "identify.json")] + figures + (
        [str(out_dir / "identify_verification.txt")] if "verification" in summary else [])
    return summary


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))
