"""Tables 3-4 of the paper: reproduction from printed numbers and the errata checks."""

import json

import numpy as np
import pytest

from csjm_opt import so3
from csjm_opt.cli import main
from csjm_opt.errors import NotARotation
from csjm_opt.identification import paper_data as pd
from csjm_opt.identification.paper_tables import check_printed_R0, paper_report, table3, table4


def test_printed_R0_rejected_with_measured_error():
    with pytest.raises(NotARotation) as info:
        check_printed_R0()
    # measured independently: ||R0^T R0 - I||_F of the printed matrix
    err = np.linalg.norm(pd.R0_PRINTED.T @ pd.R0_PRINTED - np.eye(3))
    assert abs(info.value.orthogonality_error - err) < 1e-12
    assert f"{err:.3g}" in str(info.value) and "0.809" in str(info.value)
    with pytest.raises(NotARotation):
        table4(pd.R0_PRINTED)


def test_corrected_R0_is_a_rotation_to_1e_3():
    R = pd.R0_CORRECTED
    assert np.linalg.norm(R.T @ R - np.eye(3)) < 1e-3
    assert np.linalg.det(R) > 0


def test_table4_column_C_reproduced_from_K_D_and_corrected_R0():
    t4 = table4()
    assert np.all(t4["col_C_max_entry_error_K_D"] < 2e-3)
    # direct recomputation, (61)-(62) with K_D, from the raw printed numbers
    for i in range(5):
        R = pd.R0_CORRECTED @ so3.exp(np.linalg.solve(pd.TABLE3_K_D, pd.TABLE4_DTAU_A_NM[i]))
        assert np.max(np.abs(R - pd.TABLE4_R_EST[i])) < 2e-3
    # the text's K^-1 does not reproduce it (erratum 4: errors 0.013-0.020)
    assert np.all(t4["col_C_max_entry_error_K_printed"] > 0.01)


def test_E_theta_per_65_from_columns_B_and_C():
    e = table4()["E_theta_from_B_C"]
    # erratum 5 values, computed from the printed matrices
    np.testing.assert_allclose(e, [0.054, 0.052, 0.039, 0.040, 0.046], atol=1.5e-3)
    # and they disagree with the printed column D in 4 of 5 cases
    assert np.sum(np.abs(e - pd.TABLE4_E_THETA_RAD) > 5e-3) == 4


def test_table3_corrected_K_L_and_printed_sums():
    t3 = table3()
    tau0 = pd.TAU0_A_NM
    np.testing.assert_allclose(t3["K_L"], [[0, tau0[2] / 2, -tau0[1] / 2],
                                           [-tau0[2] / 2, 0, tau0[0] / 2],
                                           [tau0[1] / 2, -tau0[0] / 2, 0]], atol=1e-15)
    assert t3["K_L_printed_vs_minus_hat_tau0"] < 5e-3      # printed K_L = -hat(tau0)
    assert t3["K_printed_vs_K_D_plus_K_L_printed"] <= 0.0101  # printed K = K_D + K_L, to rounding
    assert t3["symmetry_error_corrected"] < t3["symmetry_error_printed"]


def test_cli_paper_json_keys(capsys, tmp_path):
    assert main(["paper", "--json", "-"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data["table3"]) >= {"K_D", "K_L", "K"}
    assert [row["case"] for row in data["table4"]] == [1, 2, 3, 4, 5]
    assert all({"R_est", "E_theta_rad"} <= set(row) for row in data["table4"])
    assert any("0.809" in e for e in data["errata"])
    assert main(["paper"]) == 0
    assert "Table 4" in capsys.readouterr().out
    assert json.loads(json.dumps(paper_report()))["table3"]["K"][0][0] == pytest.approx(29.39)
