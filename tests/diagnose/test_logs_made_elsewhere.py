"""The standard command on logs the project did not make (``studies/validation_shared/logs``: MuJoCo with the effects
in the engine, loads hung in steps and settled by the rig's own dynamics), judged by the makers' answers.

The whole folders are scored by ``csjm validate`` in the study; these are the issue's headline shapes: Coulomb
cable friction that settled by the rig's dynamics, and a force spike in one row of a log.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from csjm_opt.diagnose import diagnose
from csjm_opt.diagnose.selection.validation import accepted
from csjm_opt.measurement.logfile import MeasurementLog
from csjm_opt.model.rig import load_rig

LOGS = Path(__file__).resolve().parents[2] / "studies" / "validation_shared" / "logs"


def _case(folder: str, name: str):
    answer = json.loads((LOGS / folder / "answers.json").read_text())[name]
    rig = load_rig(LOGS / folder / answer["rig"])
    train, test = (MeasurementLog.from_csv(LOGS / folder / answer[k]) for k in ("train", "test"))
    return answer, rig, train, test


def test_settled_coulomb_friction_is_named_on_a_mujoco_log():
    answer, rig, train, test = _case("mujoco_b", "b1_tendon_friction")
    j = diagnose(rig, train, test, workers=1).as_json()
    assert accepted(answer["accept"], answer["effects"], j) and j["selected"] == "friction"
    assert j["left_out_rows"] == []


FOUR = ["stiffness_scale", "sensor_gain", "link_compliance", "mass_com"]


@pytest.fixture(scope="module")
def stiffness_case():
    """``mujoco_b/b1_stiffness_scale`` and its clean diagnosis over four look-alike effects (made once)."""
    answer, rig, train, test = _case("mujoco_b", "b1_stiffness_scale")
    return answer, rig, train, test, diagnose(rig, train, test, effects=FOUR, workers=1)


@pytest.mark.parametrize("kind", ["moment", "pose"])
def test_a_spoiled_row_of_a_mujoco_log_is_left_out_and_the_verdict_holds(kind, stiffness_case):
    """One training row spoiled as labs see it (a 0.5 N m force spike, a 30 mrad tracker glitch): that row is left
    out, and the verdict and noise floor are the clean log's (the spike kept raised the floor from 3.5 to 5.6 mrad
    and named ``sensor_gain``)."""
    from csjm_opt import so3

    answer, rig, train, test, clean = stiffness_case
    i = 40
    tau, R = np.array(train.tau_ext_A_Nm, float), np.array(train.R, float)
    if kind == "moment":
        tau[i, 0] += 0.5
    else:
        R[i] = R[i] @ so3.exp(np.array([0.0, 0.03, 0.0]))
    spoiled = MeasurementLog.from_arrays(train.cycle, train.rest_lengths_m, tau, R, sample=train.sample)
    d = diagnose(rig, spoiled, test, effects=FOUR, workers=1)
    assert [(r["sample"], r["reason"]) for r in d.left_out_rows] == [(int(train.sample[i]), "gross_residual")]
    assert d.selected == clean.selected == answer["effects"][0]
    assert d.noise_floor_rad == pytest.approx(clean.noise_floor_rad, rel=0.05)


def test_a_spike_is_judged_by_the_model_that_fits_the_log():
    """A spike on a cable-hardening log: the 36 hole offsets fit this log badly (median whitened residual 16 times
    cable hardening's) but happen to come within 1.1 times their median of the spoiled row; the nearest model row
    by row vouched for it (ratio 4.2). Judged by the model that fits the log, it is left out."""
    from studies.gross_outliers.gross_outliers import spoiled

    answer, rig, train, test = _case("mujoco_b", "b1_cable_hardening")
    log, sample = spoiled(train, "moment", "mujoco_b/b1_cable_hardening", 0.5, 0.03)
    d = diagnose(rig, log, test, effects=["cable_hardening", "hole_offsets", "stiffness_scale", "mass_com"],
                 workers=1)
    assert [(r["sample"], r["reason"]) for r in d.left_out_rows] == [(sample, "gross_residual")]
    assert d.selected == answer["effects"][0]


def test_a_friction_path_fit_that_runs_out_of_evaluations_goes_on_to_its_optimum():
    """Friction along its loading path + mass/COM on a MuJoCo cable-hardening log: the play operator's corners shrink
    ``least_squares``' trust region to a crawl. The fit ends where a second solver run from its end, ten times as
    long, gains under half a nat (at 200 evaluations and without runs again from the end it stopped 50 nats short).
    """
    from scipy.optimize import least_squares

    from csjm_opt.diagnose.data.residuals import compute_residuals
    from csjm_opt.diagnose.effects import make_effect
    from csjm_opt.diagnose.fitting.augmented import AugmentedModel
    from csjm_opt.diagnose.fitting.gauss_newton import fit_model, objective

    _, rig, train, _ = _case("mujoco_b", "b2_cable_hardening")
    table = compute_residuals(rig, train)
    model = AugmentedModel(rig, [make_effect("friction", rig, law="coulomb", memory="carried"),
                                 make_effect("mass_com", rig)])
    fit = fit_model(model, table)
    scales = model.scales

    def res(x):
        return fit.residuals(x * scales) if not np.isfinite(model.prior_sd).any() else np.r_[
            fit.residuals(x * scales), (x * scales)[np.isfinite(model.prior_sd)] / model.prior_sd[
                np.isfinite(model.prior_sd)]]

    ref = least_squares(res, fit.theta / scales, bounds=(model.lower_bounds / scales, model.upper_bounds / scales),
                        method="trf", x_scale=1.0, xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=2000)
    start = objective(model, table, fit.theta)
    assert 0.5 * start - ref.cost < 0.5, (0.5 * start, ref.cost)
