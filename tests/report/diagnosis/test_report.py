"""The diagnosis page from diagnosis.json: every verdict, new and older JSON, numbers equal the JSON."""

from __future__ import annotations

import copy

import pytest

from csjm_opt.report.diagnosis.report import document, headline, unit_of
from csjm_opt.report.render import render_html, render_markdown
from tests.report_html import mismatches, parse

LOC = {"by_axis": {"x": {"rms_before_rad": 0.005, "rms_after_rad": 0.0015}},
       "by_tilt": [{"group": "[0.05, 0.1] rad", "rows": 14, "rms_before_rad": 0.0128, "rms_after_rad": 0.0032}],
       "hysteresis_before": {"pairs": 12, "rms_up_minus_down_rad": 0.026, "expected_from_noise_rad": 0.0036,
                             "p_value": 1e-9},
       "hysteresis_after": {"pairs": 12, "rms_up_minus_down_rad": 0.0034}}

NEW = {  # the keys of csjm_opt.diagnose.selection.result (as of the selection with pairs and plausibility)
    "baseline": {"heldout_rms_rad": 0.01336, "train_rms_rad": 0.01336},
    "nominal_refit": {"heldout_rms_rad": 0.013366, "train_rms_rad": 0.013354, "bic": 525.06,
                      "params": {"dl_common_m": -1.2e-4}, "param_sd": {"dl_common_m": 1.1e-4}},
    "noise_floor_rad": 0.003036,
    "candidates": [
        {"effect": "friction", "heldout_rms_rad": 0.002824, "train_rms_rad": 0.002877, "improvement_rad": 0.01306,
         "p_value": 6.3e-5, "f_p_value": 3.1e-83, "level": 0.00125, "bic": 139.97, "significant": True,
         "plausible": True, "implausible_params": [], "fraction_explained": 1.0, "rank": 9, "n_params": 9,
         "condition": 25.9, "identifiable": True,
         "params": {"mu_beta_1": 0.029, "stick_travel_factor": 0.13}, "param_sd": {"mu_beta_1": 0.002},
         "prior_ranges": {"mu_beta_1": [0.0, 0.3], "stick_travel_factor": [0.0, 2.0]},
         "nuisance": {"dl_common_m": 2.6e-5}, "derived": {"tension_band_percent": [2.94, 2.5]}},
        {"effect": "sensor_bias", "heldout_rms_rad": 0.0131, "train_rms_rad": 0.0131, "improvement_rad": 0.0,
         "p_value": 0.54, "f_p_value": 0.83, "level": 0.00125, "bic": 538.8, "significant": False,
         "plausible": False, "implausible_params": ["bias_x_Nm"], "fraction_explained": 0.02, "rank": 5,
         "n_params": 5, "condition": 1.74, "params": {"bias_x_Nm": 0.9}, "param_sd": {"bias_x_Nm": 0.1}},
        {"effect": "mass_com", "error": "fit failed: singular", "significant": False, "plausible": False}],
    "selected": "friction", "secondary": {"effect": "none"},
    "pairs": [{"effects": ["friction", "sensor_bias"], "separable": True, "max_correlation": 0.31, "fitted": True,
               "heldout_rms_rad": 0.0028, "fraction_explained": 1.0, "p_value_vs_first": 0.4, "significant": False,
               "plausible": True, "implausible_params": []}],
    "steps": [{"model": "nominal_refit", "heldout_rms_rad": 0.013366, "fraction_explained": 0.0},
              {"model": "friction", "heldout_rms_rad": 0.002824, "fraction_explained": 1.0}],
    "confounded_with": [],
    "verdict": {"selected": "friction", "warnings": [], "reason": "friction closes the gap on held-out cycles"},
    "significance": {"alpha": 0.01, "per_candidate_alpha": 0.00125, "test": "paired t-test"},
    "heldout": "grouped K-fold by cycle",
    "gap": {"before_rad": 0.01336, "after_rad": 0.002824, "fraction_explained": 1.0, "systematic_before_rad": 0.013,
            "systematic_after_rad": 0.0, "fraction_explained_by_nominal_refit": -0.0004},
    "remaining_signature": {"p_value": 0.2, "significant": False, "systematic_rad": 0.0},
    "localisation": LOC, "rows": {"train": 54, "test": 0}}

OLD = {  # an older diagnosis: p_value is the F-test, heldout_p_value the paired test, secondary "tried"
    "baseline": {"heldout_rms_rad": 0.01368, "train_rms_rad": 0.01368},
    "nominal_refit": {"heldout_rms_rad": 0.013457, "train_rms_rad": 0.013454, "bic": 1053.7},
    "noise_floor_rad": 0.002523,
    "candidates": [{"effect": "friction", "heldout_rms_rad": 0.002533, "train_rms_rad": 0.002447, "bic": 152.7,
                    "p_value": 2.6e-194, "heldout_p_value": 3.6e-8, "significant": True, "rank": 10,
                    "n_params": 10, "condition": 18.0, "fraction_explained": 0.98, "identifiable": True,
                    "params": {"mu_beta_1": 0.031}, "param_sd": {"mu_beta_1": 0.0015},
                    "nuisance": {"log_k_scale": 0.0022}, "derived": {}}],
    "selected": "friction", "confounded_with": [],
    "secondary": {"effect": "none", "tried": [{"effect": "sensor_bias", "heldout_rms_rad": 0.00251, "p_value": 0.07,
                                               "heldout_p_value": 0.23, "significant": False}]},
    "significance": {"alpha": 0.01, "per_candidate_alpha": 0.0017, "heldout_alpha": 0.1, "test": "F and t"},
    "heldout": "grouped K-fold by cycle",
    "gap": {"before_rad": 0.01368, "after_rad": 0.002533, "fraction_explained": 0.98},
    "remaining_signature": {}, "localisation": LOC, "rows": {"train": 108, "test": 0}}


def _page(tmp_path, j):
    path = tmp_path / "index.html"
    path.write_text(render_html(document(j, "log.csv")))
    return parse(path)


@pytest.mark.parametrize("j", [NEW, OLD], ids=["new", "old"])
def test_page_numbers_equal_the_json(tmp_path, j):
    page = _page(tmp_path, j)
    assert mismatches(page, j) == [] and len(page.cells) >= 15
    titles = [s["title"] for s in page.sections]
    assert titles[0] == "Verdict" and page.sections[0]["figures"] == 4
    assert "Candidates" in titles and "Where the gap lies" in titles
    assert "{'" not in render_markdown(document(j, "log.csv"))


def test_verdict_sentences():
    text, status = headline(NEW)
    assert status == "ok" and text.startswith("`friction` explains the model-rig gap: held-out error 13.4 -> 2.82 mrad")
    assert "p = 6.3e-05 (threshold 0.0013)" in text and "improvement 13.1 mrad" in text
    text, _ = headline(OLD)
    assert "p = 3.6e-08" in text and "F-test p = 2.6e-194" in text          # the paired test, then the F-test

    warned = copy.deepcopy(NEW)
    warned["verdict"]["warnings"] = ["friction and sensor_bias are not separable"]
    assert headline(warned)[1] == "warn" and "not separable" in headline(warned)[0]

    unexplained = copy.deepcopy(NEW)
    unexplained["selected"] = "unexplained"
    unexplained["verdict"] = {"selected": "unexplained", "warnings": [], "reason": "no plausible single effect"}
    text, status = headline(unexplained)
    assert status == "warn" and text.startswith("A systematic gap remains that no candidate explains")

    none = copy.deepcopy(NEW)
    none["selected"] = "none"
    none["verdict"] = {"selected": "none", "warnings": [], "reason": "no candidate improves significantly"}
    assert headline(none)[0].startswith("No unmodelled effect is needed")


def test_units_from_names():
    assert unit_of("dA1_x_m") == ("mm", 1e3)
    assert unit_of("C_11_rad_per_Nm") == ("rad/(N m)", 1.0)
    assert unit_of("bias_x_Nm") == ("N m", 1.0)
    assert unit_of("hardening_per_m") == ("1/m", 1.0)
    assert unit_of("mu_beta_1") == ("", 1.0)


def test_implausible_parameters_and_failed_fits_are_shown(tmp_path):
    html = render_html(document(NEW, "log.csv"))
    assert "no (bias_x_Nm)" in html and "fit failed: singular" in html
    assert "friction + sensor_bias" in html and "0 to 300" not in html and "0 to 0.300" in html
