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

from .._fileio import atomic_write_json, atomic_write_text
from .._plotting import save
from ..errors import CsjmError
from ..identification.figures import convergence_curve, plot_convergence, plot_verification
from ..identification.identify_pose import identify_stiffness
from ..identification.param_fit import check_fit, fit_parameters
from ..identification.stiffness_fits import n_parameters
from ..identification.verify import verify_log
from ..measurement.instruments import InstrumentNoise
from ..measurement.logfile import MeasurementLog
from ..model.numeric import Model
from ..model.rig import Rig
from ..report.document import Cell, Column, Document, Figure, Hyperlink, Section, Table, sig
from ..report.render import write_document
from ._step import DemoContext, StepOutput

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


def run_demo(rig: Rig, log: MeasurementLog, out_dir: Path, test_log: MeasurementLog | None = None,
             noise: InstrumentNoise | None = None) -> dict[str, Any]:
    """Identify, verify and fit on ``log`` (held-out: ``test_log`` or a split of ``log``).

    Parameters
    ----------
    rig : Rig
        The nominal rig.
    log : MeasurementLog
        The (simulated) identification experiment.
    out_dir : Path
        Folder for ``identify.json``, figures and the verification table.
    test_log : MeasurementLog, optional
        Held-out log (default: every other load row of each cycle of ``log``).
    noise : InstrumentNoise, optional
        The instruments' noise; when given, the held-out error it alone would cause is
        reported (``verification_expected_from_noise_rad``).

    Returns
    -------
    dict
        JSON-able summary; ``figures`` and ``files`` are relative to ``out_dir``.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model = Model(rig)
    if test_log is None:
        train_rows, test_rows = split_rows(log)
        train, test = log.subset(train_rows), log.subset(test_rows)
    else:
        train, test = log, test_log
    estimates, cycles, skipped = [], [], []
    figures: list[str] = []
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
            save(ax.figure, out_dir / f"identify_convergence_cycle{c}.png")
            figures.append(f"identify_convergence_cycle{c}.png")
    summary: dict[str, Any] = {"cycles": cycles, "skipped_cycles": skipped, "n_train_rows": len(train),
                               "n_test_rows": len(test), "figures": figures}
    if estimates and len(test):
        v_kd = verify_log(estimates, test, model, use="K_D")
        v_k = verify_log(estimates, test, model, use="K")
        ax = plot_verification([v_kd, v_k], title="Held-out verification (61)-(65): K_D vs K")
        save(ax.figure, out_dir / "identify_verification.png")
        figures.append("identify_verification.png")
        atomic_write_text(out_dir / "identify_verification.txt",
                          "Predicted with K_D (right to first order)\n" + v_kd.table()
                          + "\n\nPredicted with K = K_D + K_L (text's (61))\n" + v_k.table() + "\n")
        summary["verification"] = {"K_D": {"rms_rad": v_kd.rms_rad, "max_rad": v_kd.max_rad},
                                   "K": {"rms_rad": v_k.rms_rad, "max_rad": v_k.max_rad}}
        if noise is not None:
            summary["verification_expected_from_noise_rad"] = expected_heldout_rms_rad(estimates, noise)
    try:
        fit = fit_parameters(train, rig, model=model)
        summary["param_fit"] = fit.summary() | {"train_rms_rad": _rms(fit.pose_errors_rad(train))}
        if len(test):
            summary["param_fit"] |= check_fit(fit, test)
    except CsjmError as exc:
        summary["param_fit"] = {"error": str(exc)}
    atomic_write_json(out_dir / "identify.json", summary)
    summary["files"] = ["identify.json"] + figures + (
        ["identify_verification.txt"] if "verification" in summary else [])
    return summary


def expected_heldout_rms_rad(estimates: list, noise: InstrumentNoise) -> float:
    """Held-out prediction error (3-D RMS, rad) that instrument noise alone causes.

    The check predicts ``zeta = K^-1 (tau - tau_ref)`` and compares it with the
    measured rotation from the reference row: two orientation readings (noise
    ``angle_sigma`` per axis each) and two moment readings (``tau_sigma`` per
    axis, mapped through ``K^-1``), averaged over the cycles' identified K.
    """
    sa2 = 2 * 3 * noise.angle_sigma_rad ** 2
    st = np.asarray(noise.tau_sigma_Nm)
    terms = []
    for e in estimates:
        K = np.asarray(e.K_sym)
        terms.append(sa2 + 2 * np.sum((np.linalg.inv(K) * st[None, :]) ** 2))
    return float(np.sqrt(np.mean(terms)))


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.asarray(x) ** 2)))


# ------------------------------------------------------------------ demo step and report section
NAME = "simulate experiment, identify, verify"
#: Held-out error up to this multiple of the noise-only expectation counts as "at the noise level".
NOISE_LEVEL_FACTOR = 1.5


def step(ctx: DemoContext) -> StepOutput:
    """A simulated identification experiment (paper noise), then identify, verify, fit parameters."""
    from ..testbed.identification import simulate_identification_experiment

    noise = InstrumentNoise.paper()
    log = simulate_identification_experiment(ctx.rig, n_cycles=3 if ctx.quick else 6, rng=ctx.rng,
                                             loads_per_cycle=20, noise=noise)
    data = ctx.out_dir / "experiment"
    data.mkdir(exist_ok=True)
    log.to_csv(data / "log.csv", overwrite=True)
    out = run_demo(ctx.rig, log, data, noise=noise)  # held out: every other load row of each cycle
    out["log"] = "experiment/log.csv"
    out["n_cycles"] = len(log.cycle_ids)
    out["rig_cable_stiffness_N_per_m"] = np.asarray(ctx.rig.cable_stiffness_N_per_m).tolist()
    sec = section(out)
    write_document(Document("Identification, verification and parameter fit", _LEAD, [sec],
                            data_file="identify.json", links=_links()), data)
    return StepOutput(out, section(out).rebase("experiment"))


_LEAD = ("A simulated identification experiment on the paper rig with the paper's instrument noise: per cycle, "
         "the platform is loaded with a sequence of external moments from a reference pose and K is identified "
         "from the measured rotations (paper (49)-(50)); held-out rows check the identified K; the physical "
         "parameters (per-cable stiffness and rest-length offsets) are fitted over the whole log.")


def _links() -> list[Hyperlink]:
    return [Hyperlink("identify.json", "identify.json", "every number of this page"),
            Hyperlink("log.csv", "log.csv", "the simulated measurement log"),
            Hyperlink("identify_verification.txt", "identify_verification.txt", "per-row verification table")]


def section(s: dict) -> Section:
    """The report section of the identification summary (paths relative to its folder)."""
    cycles = s["cycles"]
    eig = np.array([c["eig_K_sym"] for c in cycles]) if cycles else np.zeros((0, 3))
    v = s.get("verification")
    expected = s.get("verification_expected_from_noise_rad")
    text = (f"Simulated {s.get('n_cycles', len(cycles))} identification cycles with the paper's instrument noise "
            f"and identified K per cycle on {s['n_train_rows']} rows"
            + (f" (eigenvalues {sig(eig.min())} to {sig(eig.max())} N m/rad)" if len(eig) else "") + ". ")
    status = "info"
    if v:
        rms, rms_k = v["K_D"]["rms_rad"], v["K"]["rms_rad"]
        text += (f"On {s['n_test_rows']} held-out rows the predicted rotation misses the measured one by "
                 f"{sig(rms, 3, 1e3)} mrad RMS with K_D ({sig(rms_k, 3, 1e3)} with K)")
        if expected:
            at_noise = rms <= NOISE_LEVEL_FACTOR * expected
            status = "ok" if at_noise else "warn"
            text += (f": {'at' if at_noise else 'ABOVE'} the level the instrument noise alone causes "
                     f"({sig(expected, 3, 1e3)} mrad).")
        else:
            text += "."
    if s["skipped_cycles"]:
        text += f" {len(s['skipped_cycles'])} cycles skipped (see identify.json)."
        status = "warn"
    blocks: list = []
    if v:
        rows = [["K_D (right to first order)", Cell(v["K_D"]["rms_rad"], src=("verification", "K_D", "rms_rad")),
                 Cell(v["K_D"]["max_rad"], src=("verification", "K_D", "max_rad"))],
                ["K = K_D + K_L", Cell(v["K"]["rms_rad"], src=("verification", "K", "rms_rad")),
                 Cell(v["K"]["max_rad"], src=("verification", "K", "max_rad"))]]
        if expected:
            rows.append(["instrument noise alone (expected)",
                         Cell(expected, src=("verification_expected_from_noise_rad",)), None])
        blocks.append(Table([Column("prediction with"), Column("held-out RMS", "mrad", scale=1e3),
                             Column("held-out max", "mrad", scale=1e3)], rows,
                            "Held-out verification (61)-(65)"))
    cols = [Column("cycle", fmt="int"), Column("rows", fmt="int"), Column("fit order", fmt="int"),
            Column("eigenvalue 1", "N m/rad"), Column("eigenvalue 2", "N m/rad"), Column("eigenvalue 3", "N m/rad"),
            Column("condition"), Column("symmetry error", fmt="sig2"), Column("residual RMS", "N m", "sig2")]
    blocks.append(Table(cols, [[Cell(c["cycle"], src=("cycles", i, "cycle")),
                                Cell(c["n_rows"], src=("cycles", i, "n_rows")),
                                Cell(c["order"], src=("cycles", i, "order"))]
                               + [Cell(c["eig_K_sym"][k], src=("cycles", i, "eig_K_sym", k)) for k in range(3)]
                               + [Cell(c[key], src=("cycles", i, key))
                                  for key in ("condition", "symmetry_error", "residual_rms_Nm")]
                               for i, c in enumerate(cycles)],
                        "Identified K per cycle (symmetric estimate; K, K_D, confidence intervals: identify.json)"))
    figs = s.get("figures", [])
    if "identify_verification.png" in figs:
        blocks.append(Figure("identify_verification.png", "Held-out prediction error per case, with K_D and with K."))
    conv = [f for f in figs if f.startswith("identify_convergence")]
    if conv:
        blocks.append(Figure(conv[0], "Convergence of det K with the number of measurements (Figure 5 of the "
                                      "paper); the other cycles' curves are beside it in the folder."))
    sec = Section("Identification and verification", text, status, blocks)
    fit = s.get("param_fit", {})
    if "parameters" in fit:
        sec.subsections.append(_param_section(s, fit))
    elif "error" in fit:
        sec.subsections.append(Section("Parameter fit", f"Parameter fit failed: {fit['error']}", "warn"))
    return sec


def _param_section(s: dict, fit: dict) -> Section:
    p = fit["parameters"]
    k_true = s.get("rig_cable_stiffness_N_per_m")
    n = sum(1 for name in p if name.startswith("k"))
    within, rows = 0, []
    for i in range(1, n + 1):
        k, dl = p[f"k{i}"], p.get(f"dl{i}", {"value": None, "std": None})
        if k_true is not None:
            within += abs(k["value"] - k_true[i - 1]) <= 3 * k["std"]
            within += dl["value"] is not None and abs(dl["value"]) <= 3 * dl["std"]
        rows.append([f"{i}", Cell(k["value"], "sig4", src=("param_fit", "parameters", f"k{i}", "value")),
                     Cell(k["std"], "sig2", src=("param_fit", "parameters", f"k{i}", "std")),
                     Cell(dl["value"], "sig2", src=("param_fit", "parameters", f"dl{i}", "value")),
                     Cell(dl["std"], "sig2", src=("param_fit", "parameters", f"dl{i}", "std"))])
    ks = [p[f"k{i}"]["value"] for i in range(1, n + 1)]
    text = (f"Fitted each cable's stiffness and rest-length offset over the log: k from {sig(min(ks))} to "
            f"{sig(max(ks))} N/m")
    status = "info"
    if k_true is not None:
        status = "ok" if within >= 2 * n - 1 else "warn"
        text += (f" against the rig's {sig(float(np.mean(k_true)))} N/m; {within} of {2 * n} parameters within 3 "
                 "standard errors of the truth (the log was simulated without unmodelled effects, so the truth "
                 "is the rig file: offsets 0)")
    if "heldout_rms_rad" in fit:
        text += f". Held-out pose error with the fitted parameters {sig(fit['heldout_rms_rad'], 3, 1e3)} mrad RMS."
    table = Table([Column("cable"), Column("stiffness k", "N/m"), Column("sd", "N/m"),
                   Column("rest-length offset", "mm", scale=1e3), Column("sd", "mm", scale=1e3)], rows,
                  f"Fitted parameters (+- 1 standard error; condition {sig(fit.get('condition'))})")
    return Section("Parameter fit", text, status, [table])
